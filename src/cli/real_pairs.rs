//! `day2night real-pairs`: real night test/training pairs from captures (docs/real-pairs.md).
use super::args::{choice, Typed};
use super::dataset::{OutFolder, RunFlags};
use super::{usage, CmdResult, Failure};
use day2night::isp::release::Isp;
use day2night::realpairs::{self, Layout, LayoutChoice, PairOptions, RunOptions, TargetKind};
use std::path::PathBuf;

/// `--layout` (docs/real-pairs.md). Its values have no doc comments: they would be clap's
/// help of each value, which turns the whole `--help` into the long layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LayoutArg {
    // Detect from the folder.
    Auto,
    // A folder per scene of RAW_0_00<ISO>*.dng frames.
    Release,
    // The release's night_real/{clean,clean_raw,dng/iso_<ISO>}/NNN.*.
    ReleaseProcessed,
    // A folder per scene of DNGs, grouped by the ISO in each DNG.
    Simple,
}

impl From<LayoutArg> for LayoutChoice {
    fn from(l: LayoutArg) -> LayoutChoice {
        match l {
            LayoutArg::Auto => LayoutChoice::Auto,
            LayoutArg::Release => LayoutChoice::Fixed(Layout::Release),
            LayoutArg::ReleaseProcessed => LayoutChoice::Fixed(Layout::ReleaseProcessed),
            LayoutArg::Simple => LayoutChoice::Fixed(Layout::Simple),
        }
    }
}

/// `--target` (no doc comments on the values, as [`LayoutArg`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TargetArg {
    // 8-bit sRGB PNG.
    Png,
    // Linear EXR.
    Exr,
    // Both.
    Both,
}

impl From<TargetArg> for TargetKind {
    fn from(t: TargetArg) -> TargetKind {
        match t {
            TargetArg::Png => TargetKind::Png,
            TargetArg::Exr => TargetKind::Exr,
            TargetArg::Both => TargetKind::Both,
        }
    }
}

/// Arguments of `day2night real-pairs`.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("out_dir", |a| a.value_name("OUT").help("Output folder (manifest.jsonl and real/)")),
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
    /// -o/--output OUT (shared with `dataset`).
    #[command(flatten)]
    pub out: OutFolder,
    /// Input layout (docs/real-pairs.md).
    #[arg(long, value_enum, default_value_t = LayoutArg::Auto, value_name = "LAYOUT")]
    pub layout: LayoutArg,
    /// Release layouts: the noisy ISOs expected (frames RAW_0_00<ISO, 4 digits>*, or
    /// dng/iso_<ISO>/NNN.dng in the processed tree); a missing one is an error.
    #[arg(long, default_value_t = isos_text(&realpairs::RELEASE_NOISY_ISOS), value_name = "ISO,ISO")]
    pub iso: String,
    /// Largest motion accepted between the burst's frames, or between the merged raw and a
    /// noisy input, in raw pixels.
    #[arg(long = "max-motion", default_value_t = realpairs::DEFAULT_MAX_MOTION_PX, value_name = "PX")]
    pub max_motion: f64,
    /// Targets (png: 8-bit sRGB, exr: linear).
    #[arg(long, value_enum, default_value_t = TargetArg::Png, value_name = "KIND")]
    pub target: TargetArg,
    /// ISP of the rendered targets: release is the authors' release ISP as `render --isp
    /// release` does it (its own crop and orientation; docs/isp.md). A target copied from
    /// the release's processed tree is copied either way.
    #[arg(long, default_value_t = Typed::<Isp>::default(), value_parser = choice::<Isp>(), value_name = "ISP")]
    pub isp: Typed<Isp>,
    /// --jobs, --overwrite, --json, --quiet (shared with `dataset`).
    #[command(flatten)]
    pub run: RunFlags,
}

/// `--iso`'s default: the release's noisy ISOs as `--iso` spells them (`1600,3200`).
fn isos_text(isos: &[u32]) -> String {
    let text: Vec<String> = isos.iter().map(u32::to_string).collect();
    text.join(",")
}

/// `--iso`: `synth`'s ISO list ([`day2night::synth::config::parse_isos`]: duplicates
/// dropped, order kept), less `none` and the clean burst's ISO.
fn parse_isos(s: &str) -> Result<Vec<u32>, Failure> {
    let v = day2night::synth::config::parse_isos(s).map_err(|e| usage(format!("--iso: {e}")))?;
    if v.is_empty() || v.contains(&realpairs::RELEASE_LOW_ISO) {
        return Err(usage(format!(
            "--iso {s:?}: expected noisy ISOs other than {} (the clean burst's), separated by commas",
            realpairs::RELEASE_LOW_ISO
        )));
    }
    Ok(v)
}

/// Run `day2night real-pairs`.
pub fn run(args: RealPairsArgs) -> CmdResult {
    if !(args.max_motion.is_finite() && args.max_motion >= 0.0) {
        return Err(usage(format!(
            "--max-motion {}: expected a number of pixels >= 0",
            realpairs::motion::px_text(args.max_motion)
        )));
    }
    let jobs = args.run.jobs()?;
    let pairs = PairOptions {
        layout: args.layout.into(),
        release_isos: parse_isos(&args.iso)?,
        max_motion_px: args.max_motion,
        target: args.target.into(),
        release_isp: args.isp.value == Isp::Release,
    };
    let opts = RunOptions {
        scenes_dir: args.scenes.clone(),
        out_dir: args.out.out_dir.clone(),
        jobs,
        overwrite: args.run.overwrite,
        on_scene: (!args.run.quiet).then_some(scene_line as fn(&realpairs::SceneDone<'_>)),
        checkpoint: None,
    };
    // a scene id too long for its file names is bad usage (exit 2), found before the run
    if let Err(e) = realpairs::discover::find_scenes(
        &opts.scenes_dir,
        std::slice::from_ref(&opts.out_dir),
        pairs.layout,
    ) {
        if matches!(e.root(), day2night::error::Error::Limits(_)) {
            return Err(usage(e));
        }
    }
    let summary = realpairs::run(&opts, &pairs)?;
    args.run.print_summary(&summary.describe(), &summary)?;
    args.out.fail_on(summary.failed, summary.scenes, "scenes")
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
