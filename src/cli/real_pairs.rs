//! `day2night real-pairs`: real night test/training pairs from captures (docs/real-pairs.md).
use super::{usage, CmdResult, Failure};
use day2night::realpairs::{self, LayoutChoice, PairOptions, RunOptions, TargetKind};
use std::path::PathBuf;

/// Arguments of `day2night real-pairs`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Per scene: the low-ISO burst is merged into OUT/real/clean_raw/<id>.dng \
(metadata of its first frame), rendered with that frame's white balance into \
OUT/real/target/<id>.png, and the first frame of each high-ISO burst is copied to \
OUT/real/noisy_raw/<id>_iso<ISO>.dng; OUT/real/meta/<id>.json records the frames and checks, \
OUT/manifest.jsonl one line per scene.

Layouts (docs/real-pairs.md): release = a folder per scene of RAW_0_00<ISO>*.dng frames;
release-processed = the release's night_real/{clean,clean_raw,dng/iso_<ISO>}/NNN.*; simple =
a folder per scene of DNGs, grouped by the ISO in each DNG (lowest ISO = clean burst).

Examples:
  day2night real-pairs full_burst_dataset/ -o real/ --jobs 2
  day2night real-pairs night_real/ -o real/ --target both
  day2night real-pairs my_scenes/ -o real/ --layout simple --max-motion 2

A rerun resumes: scenes whose files and options are unchanged and whose outputs exist are
skipped. A scene that fails a check (one frame, no low-ISO burst, mismatched frames, motion)
fails the run with exit code 1 and its reason; the other scenes are still made."
)]
pub struct RealPairsArgs {
    /// Folder of scenes (or the release's night_real/ folder).
    #[arg(value_name = "SCENES")]
    pub scenes: PathBuf,
    /// Output folder (manifest.jsonl and real/).
    #[arg(
        short = 'o',
        long = "output",
        visible_alias = "out",
        value_name = "OUT"
    )]
    pub out_dir: PathBuf,
    /// Input layout: auto, release, release-processed or simple.
    #[arg(long, default_value = "auto", value_name = "LAYOUT")]
    pub layout: String,
    /// Release layouts: the noisy ISOs expected (frames RAW_0_00<ISO, 4 digits>*, or
    /// dng/iso_<ISO>/NNN.dng in the processed tree); a missing one is an error.
    #[arg(long, default_value = "1600,3200", value_name = "ISO,ISO")]
    pub iso: String,
    /// Largest motion accepted between the burst's frames, or between the merged raw and a
    /// noisy input, in raw pixels.
    #[arg(long = "max-motion", default_value_t = realpairs::DEFAULT_MAX_MOTION_PX, value_name = "PX")]
    pub max_motion: f64,
    /// Targets: png (8-bit sRGB), exr (linear) or both.
    #[arg(long, default_value = "png", value_name = "KIND")]
    pub target: String,
    /// ISP of the rendered targets: day2night (default) or release, the authors' release
    /// ISP as `render --isp release` does it (its own crop and orientation; docs/isp.md).
    /// A target copied from the release's processed tree is copied either way.
    #[arg(long, default_value = "day2night", value_name = "ISP")]
    pub isp: String,
    /// Scenes processed in parallel; default: number of CPUs.
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Remake every scene (and accept a non-empty OUT without a manifest).
    #[arg(long)]
    pub overwrite: bool,
    /// Print the run summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// No per-scene progress lines (the summary is still printed on stderr).
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

fn parse_isos(s: &str) -> Result<Vec<u32>, Failure> {
    let mut v = Vec::new();
    for t in s.split(',') {
        match t.trim().parse::<u32>() {
            Ok(i) if i > 0 && i != realpairs::RELEASE_LOW_ISO && !v.contains(&i) => v.push(i),
            _ => {
                return Err(usage(format!(
                    "--iso {s:?}: expected distinct ISOs above 0 other than {} (the clean burst's), separated by commas",
                    realpairs::RELEASE_LOW_ISO
                )))
            }
        }
    }
    Ok(v)
}

/// Run `day2night real-pairs`.
pub fn run(args: RealPairsArgs) -> CmdResult {
    let layout: LayoutChoice = args
        .layout
        .parse()
        .map_err(|e| usage(format!("--layout: {e}")))?;
    let release_isp = match args.isp.as_str() {
        "day2night" => false,
        "release" => true,
        i => return Err(usage(format!("--isp {i:?}: use day2night or release"))),
    };
    let target = match args.target.as_str() {
        "png" => TargetKind::Png,
        "exr" => TargetKind::Exr,
        "both" => TargetKind::Both,
        t => return Err(usage(format!("--target {t:?}: use png, exr or both"))),
    };
    if !(args.max_motion.is_finite() && args.max_motion >= 0.0) {
        return Err(usage(format!(
            "--max-motion {}: expected a number of pixels >= 0",
            realpairs::motion::px_text(args.max_motion)
        )));
    }
    let jobs = match args.jobs {
        Some(n) => {
            day2night::bounds::jobs("--jobs", n).map_err(usage)?;
            n
        }
        None => std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
    };
    let pairs = PairOptions {
        layout,
        release_isos: parse_isos(&args.iso)?,
        max_motion_px: args.max_motion,
        target,
        release_isp,
    };
    let opts = RunOptions {
        scenes_dir: args.scenes.clone(),
        out_dir: args.out_dir.clone(),
        jobs,
        overwrite: args.overwrite,
        on_scene: (!args.quiet).then_some(scene_line as fn(&realpairs::SceneDone<'_>)),
        checkpoint: None,
    };
    let summary = realpairs::run(&opts, &pairs)?;
    eprintln!("{}", summary.describe());
    if args.json {
        let text = serde_json::to_string_pretty(&summary)
            .map_err(|e| anyhow::anyhow!("summary JSON: {e}"))?;
        println!("{text}");
    }
    if summary.failed > 0 {
        return Err(Failure {
            code: 1,
            error: anyhow::anyhow!(
                "{}: {} of {} scenes failed (see the summary above and the manifest)",
                args.out_dir.display(),
                summary.failed,
                summary.scenes
            ),
        });
    }
    Ok(())
}

/// One scene's progress lines on stderr (a closed stderr drops them: EPIPE must not panic).
fn scene_line(d: &realpairs::SceneDone<'_>) {
    use std::io::Write as _;
    let mut err = std::io::stderr().lock();
    for w in d.warnings {
        let _ = writeln!(err, "{}", w.line(d.scene));
    }
    let _ = writeln!(
        err,
        "real-pairs: [{}/{}] {}: {} ({:.1} s)",
        d.index, d.total, d.scene, d.state, d.secs
    );
}
