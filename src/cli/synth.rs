//! `day2night synth`: clean and noisy night DNGs, targets and a sidecar per input and
//! variant (docs/cli.md), made by the library's [`SynthJob`] (the same code as `dataset`).
//! Inputs are processed one after another (each with rayon inside); an input that cannot
//! be used is reported and skipped, and the exit code is 1 at the end.

use super::args::{flag, parse_zip_level};
use super::{usage, CmdResult, Failure};
use day2night::dng::write::Compression;
use day2night::encode::exr::{ExrCompression, ExrOptions};
use day2night::error::Error;
use day2night::output::{stop_requested, OutputPolicy, OutputSetLock};
use day2night::synth::burst::checks::{BurstRequest, Names};
use day2night::synth::burst::BurstOptions;
use day2night::synth::config::{parse_isos, parse_neutral, JobConfig};
use day2night::synth::job::{DayInput, DirSink, SynthJob, Target};
use day2night::synth::sidecar::Sidecar;
use day2night::synth::{Covariance, Mode, Planned, RelightFormula, SynthOptions};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Relighting mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// Several local lights (the paper's method).
    Local,
    /// One night illuminant.
    Global,
    /// Dimmed day image (baseline).
    Dimmed,
    /// The day image itself (baseline).
    Day,
}

/// Compatibility preset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CompatArg {
    /// The authors' released code where it is deterministic.
    Release,
}

/// Local relighting formula.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormulaArg {
    /// The authors' released code.
    Release,
    /// The paper's equation.
    Paper,
}

/// Targets to render.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TargetArg {
    /// Linear EXR.
    Exr,
    /// sRGB PNG.
    Png,
    /// Both.
    Both,
    /// None.
    None,
}

/// DNG compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CompressionArg {
    /// Uncompressed.
    None,
    /// Lossless JPEG.
    Ljpeg,
}

/// Covariance estimator of the illuminant fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CovArg {
    /// 1/(M-1) (released code).
    Unbiased,
    /// 1/M (the paper's equation 2).
    Ml,
}

/// Arguments of `day2night synth`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
  day2night synth day.dng -o night/                      # clean + ISO 1600/3200 + target.exr\n  \
  day2night synth a.dng b.dng -o out/ --seed 7 --variants 3 --iso 800,6400 --target both\n  \
  day2night synth day.dng -o again/ --replay night/day.json   # byte-identical outputs\n  \
  day2night synth day.dng -o burst/ --burst 8 --iso 3200     # 8 hand-held frames per ISO\n\n\
Outputs per input <stem> and variant K (the _vK part, K = 1.., only when --variants > 1):\n  \
<stem>[_vK]_clean.dng, <stem>[_vK]_iso<ISO>.dng (--burst N: <stem>[_vK]_iso<ISO>_f<NN>.dng),\n  \
<stem>[_vK]_target.exr|png, <stem>[_vK]_input.exr (--input-exr), <stem>[_vK].json (sidecar).")]
pub struct SynthArgs {
    /// Day DNG files.
    #[arg(required = true, value_name = "DAY.dng")]
    pub inputs: Vec<PathBuf>,
    /// Output directory (created if missing; a file is refused).
    #[arg(
        short = 'o',
        long = "output",
        visible_alias = "out",
        value_name = "DIR"
    )]
    pub out: PathBuf,
    /// Variants per input.
    #[arg(long, default_value_t = 1)]
    pub variants: u32,
    /// Synthesis and output options (shared with `dataset`).
    #[command(flatten)]
    pub synth: SynthOpts,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Replace existing outputs.
    #[arg(long)]
    pub overwrite: bool,
    /// When another day2night process is writing the same output set, wait for it instead
    /// of failing that input.
    #[arg(long)]
    pub wait: bool,
    /// Do not list the files written (errors and warnings are still printed).
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

/// Synthesis and output options: the same flags, values and defaults in `synth` and
/// `dataset` (one definition, so the two commands cannot drift apart).
#[derive(Debug, clap::Args)]
pub struct SynthOpts {
    /// Master seed; each (input, variant) has its own random stream keyed by (seed, input
    /// name, variant), never by position or thread count (dataset: the name is the path
    /// relative to DAY_DIR).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// ISOs of the noisy outputs, comma-separated, or `none`.
    #[arg(long, default_value = "1600,3200", value_name = "LIST|none")]
    pub iso: String,
    /// Relighting mode.
    #[arg(long, value_enum, default_value = "local")]
    pub mode: ModeArg,
    /// Local relighting formula.
    #[arg(long = "relight-formula", value_enum, default_value = "release")]
    pub relight_formula: FormulaArg,
    /// Saturated bulbs (default 5 with the release formula, 0 with the paper's).
    #[arg(long)]
    pub bulbs: Option<u32>,
    /// Calibration files and finer options (boxed to keep the subcommand enum small).
    #[command(flatten)]
    pub extra: Box<ExtraArgs>,
    /// Targets to render from the clean night raw.
    #[arg(long, value_enum, default_value = "exr")]
    pub target: TargetArg,
    /// Also write the network input (normalized, white-balanced, demosaiced noisy raw).
    #[arg(long = "input-exr")]
    pub input_exr: bool,
    /// DNG compression.
    #[arg(long, value_enum, default_value = "none")]
    pub compression: CompressionArg,
    /// Truncate instead of rounding when denormalizing (released code, -0.5 DN bias).
    #[arg(long)]
    pub truncate: bool,
    /// Reproduce the authors' released code where it is deterministic: implies --truncate
    /// and --mask-eval release, truncates the noisy raws too, divides by the day neutral as
    /// stored (not normalized to green = 1), does not cut illuminant draws at Mahalanobis 3
    /// and samples every camera's lights from the paper phone's dictionary (unless
    /// --illuminants says otherwise). See docs/synthesis.md, "Release compatibility".
    #[arg(long, value_enum, value_name = "PRESET")]
    pub compat: Option<CompatArg>,
}

/// Less common `synth` options.
#[derive(Debug, clap::Args)]
pub struct ExtraArgs {
    /// Local lights besides the ambient (default 4 release; paper: 4 to 6 drawn).
    #[arg(long)]
    pub lights: Option<u32>,
    /// Night illuminant dictionary: `paper` (the paper phone's gray cards, its camera RGB),
    /// `cie` (CIE 015:2018 night lamps through each file's colour matrices) or a JSON file
    /// (camera neutrals, a Gaussian, xy lamps; `./paper` for a file named paper). Default:
    /// `paper` for the paper's phone (Samsung SM-G780*/SM-G781*) and under --compat release,
    /// `cie` for every other camera.
    #[arg(long, value_name = "paper|cie|FILE.json")]
    pub illuminants: Option<PathBuf>,
    /// Illuminant covariance estimator.
    #[arg(long, value_enum, default_value = "unbiased")]
    pub covariance: CovArg,
    /// Night brightness dictionary (JSON): dim to a drawn mean instead of U(0.55, 0.9).
    #[arg(long, value_name = "FILE.json")]
    pub brightness: Option<PathBuf>,
    /// Noise model (day2night-noise-model/1 JSON); default: the input's NoiseProfile, else
    /// (the paper's phone: its embedded table) an estimate from the image at its ISO, else
    /// the embedded paper phone table with a warning. See docs/noise.md.
    #[arg(long = "noise-model", value_name = "FILE.json")]
    pub noise_model: Option<PathBuf>,
    /// Re-run a sidecar's plan on its input (one input): byte-identical outputs.
    #[arg(long, value_name = "SIDECAR.json")]
    pub replay: Option<PathBuf>,
    /// Day neutral r,g,b overriding (or replacing a missing) AsShotNeutral.
    #[arg(long = "day-neutral", value_name = "R,G,B")]
    pub day_neutral: Option<String>,
    /// Mask evaluation: separable (default), exact, truncated:K (K sigmas), or release (the
    /// authors' sampled kernel resized bilinearly).
    #[arg(long = "mask-eval", default_value = "separable")]
    pub mask_eval: String,
    /// EXR compression (lossless: zip (default, the fastest), piz (slower; larger on synth
    /// targets, smaller on noisy images), zips,
    /// rle, none; lossy for half: pxr24, b44, b44a). See docs/benchmarks.md.
    #[arg(long = "exr-compression", default_value = "zip", value_name = "KIND")]
    pub exr_compression: String,
    /// Compression effort of zip/zips EXRs: 1 (default, fastest: day2night's run-length +
    /// Huffman encoder) or 2 to 9 (miniz_oxide's zlib levels: 6 is 1.4 % smaller, 9 is 2 %
    /// smaller, at 18x and 50x the compression time). Lossless at every level. See
    /// docs/benchmarks.md.
    #[arg(long = "exr-zip-level", default_value_t = 1, value_name = "N")]
    pub exr_zip_level: u8,
    /// DNG opcode lists of the input in the rendered targets and inputs: apply (default) or
    /// ignore (implied by --compat release). The night DNGs keep the lists either way.
    #[arg(long, value_name = "MODE")]
    pub opcodes: Option<String>,
    /// Frames per ISO: a night burst of N noisy DNGs <stem>[_vK]_iso<ISO>_f<NN>.dng (1 to
    /// 64; 1 = one noisy DNG per ISO, as without a burst). See docs/synthesis.md, "Bursts".
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub burst: u32,
    /// Motion between the frames of a burst: none (a tripod) or shake (a hand-held camera,
    /// the default).
    #[arg(long, value_name = "none|shake")]
    pub motion: Option<String>,
    /// Hand-held walk: standard deviation of each frame's translation step per axis, in
    /// pixels [default: 0.6].
    #[arg(long = "shake-step", value_name = "PX")]
    pub shake_step: Option<f64>,
    /// Hand-held walk: standard deviation of each frame's rotation step, in degrees
    /// [default: 0.015].
    #[arg(long = "shake-roll", value_name = "DEG")]
    pub shake_roll: Option<f64>,
    /// Interpolant of the burst warp: catmull-rom (default), lanczos3 or bilinear.
    #[arg(long = "warp-interp", value_name = "KIND")]
    pub warp_interp: Option<String>,
}

impl ExtraArgs {
    /// The burst these flags ask for (the library's one check of the burst options: the
    /// motion flags need a burst, the shake flags need --motion shake).
    fn burst(&self) -> Result<BurstOptions, Failure> {
        BurstRequest {
            frames: Some(i128::from(self.burst)),
            motion: self.motion.clone(),
            shake_step: self.shake_step,
            shake_roll: self.shake_roll,
            warp_interp: self.warp_interp.clone(),
        }
        .resolve(&Names::CLI)
        .map_err(usage)
    }
}

impl SynthOpts {
    /// The library's [`JobConfig`] these flags spell (nothing loaded yet).
    pub fn config(&self, variants: u32) -> Result<JobConfig, Failure> {
        let options = SynthOptions {
            mode: match self.mode {
                ModeArg::Local => Mode::Local,
                ModeArg::Global => Mode::Global,
                ModeArg::Dimmed => Mode::Dimmed,
                ModeArg::Day => Mode::Day,
            },
            formula: match self.relight_formula {
                FormulaArg::Release => RelightFormula::Release,
                FormulaArg::Paper => RelightFormula::Paper,
            },
            bulbs: self.bulbs,
            local_lights: self.extra.lights,
            isos: flag("--iso", parse_isos(&self.iso))?,
            truncate: self.truncate,
            covariance: match self.extra.covariance {
                CovArg::Unbiased => Covariance::Unbiased,
                CovArg::Ml => Covariance::MaximumLikelihood,
            },
            day_neutral: self
                .extra
                .day_neutral
                .as_deref()
                .map(|s| flag("--day-neutral", parse_neutral(s)))
                .transpose()?,
            mask_eval: flag("--mask-eval", self.extra.mask_eval.parse())?,
            ..SynthOptions::default()
        };
        let mut options = match self.compat {
            Some(CompatArg::Release) => flag("--compat release", options.release_compat())?,
            None => options,
        };
        if let Some(m) = &self.extra.opcodes {
            options.opcodes = flag("--opcodes", m.parse())?;
        }
        options.burst = self.extra.burst()?;
        options.validate().map_err(usage)?;
        Ok(JobConfig {
            options,
            illuminants: self.extra.illuminants.clone(),
            brightness: self.extra.brightness.clone(),
            noise_model: self.extra.noise_model.clone(),
            variants,
            target: match self.target {
                TargetArg::Exr => Target::Exr,
                TargetArg::Png => Target::Png,
                TargetArg::Both => Target::Both,
                TargetArg::None => Target::None,
            },
            input_exr: self.input_exr,
            compression: match self.compression {
                CompressionArg::None => Compression::None,
                CompressionArg::Ljpeg => Compression::Ljpeg,
            },
            exr: ExrOptions {
                compression: flag(
                    "--exr-compression",
                    self.extra.exr_compression.parse::<ExrCompression>(),
                )?,
                zip_level: parse_zip_level(self.extra.exr_zip_level)?,
                ..ExrOptions::default()
            },
        })
    }

    /// The job these flags describe, calibration files loaded.
    pub fn job(&self, variants: u32) -> Result<SynthJob, Failure> {
        Ok(self.config(variants)?.build()?)
    }
}

pub fn run(args: SynthArgs) -> CmdResult {
    if args.variants == 0 {
        return Err(usage("--variants must be at least 1"));
    }
    if let Some(n) = args.jobs {
        day2night::bounds::jobs("--jobs", n).map_err(usage)?;
    }
    let (job, seed, replay) = match &args.synth.extra.replay {
        Some(p) => {
            if args.inputs.len() != 1 {
                return Err(usage(
                    "--replay takes exactly one input (the sidecar's day DNG)",
                ));
            }
            let sc = Sidecar::read(p)?;
            (SynthJob::from_sidecar(&sc)?, sc.plan.seed, Some(sc))
        }
        None => (args.synth.job(args.variants)?, args.synth.seed, None),
    };
    let policy = OutputPolicy {
        overwrite: args.overwrite,
        inputs: args.inputs.clone(),
        ..OutputPolicy::default()
    };
    if args.out.exists() && !args.out.is_dir() {
        return Err(usage(format!(
            "{}: the output must be a directory (synth writes several files per input)",
            args.out.display()
        )));
    }
    // Created before the first variant is written, so that no empty folder is left when
    // every input fails.
    let created_out = !args.out.exists();
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = args.jobs {
        builder = builder.num_threads(n);
    }
    let pool = builder.build().map_err(|e| {
        Failure::from(anyhow::anyhow!(
            "cannot start {} worker threads: {e}",
            args.jobs.unwrap_or(0)
        ))
    })?;

    let total = args.inputs.len() as u64 * job.variants as u64;
    let bar = if std::io::stderr().is_terminal() && !args.quiet {
        let b = indicatif::ProgressBar::new(total);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} {msg} [{elapsed_precise}]",
        ) {
            b.set_style(style);
        }
        Some(b)
    } else {
        None
    };
    let run = Run {
        job: &job,
        seed,
        out: &args.out,
        policy: &policy,
        replay: replay.as_ref(),
        bar: bar.as_ref(),
        wait: args.wait,
        quiet: args.quiet,
    };
    let mut failed = 0usize;
    for input in &args.inputs {
        // Interrupted (SIGINT/SIGTERM): start no new input; cli::main reports it.
        if stop_requested().is_some() {
            break;
        }
        if let Some(b) = &bar {
            b.set_message(input.display().to_string());
        }
        if let Err(e) = pool.install(|| run.input(input)) {
            if stop_requested().is_some() {
                break;
            }
            failed += 1;
            run.say(format!("day2night: {}", e.in_file(input)));
        }
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if created_out {
        // Nothing written (every input failed): leave no empty folder (remove_dir only
        // removes an empty one).
        let _ = std::fs::remove_dir(&args.out);
    }
    if failed > 0 && args.inputs.len() == 1 {
        // The input's own line said why.
        return Err(super::reported(1));
    }
    if failed > 0 {
        return Err(Failure::from(anyhow::anyhow!(
            "{}: {} of {} inputs failed",
            args.out.display(),
            failed,
            args.inputs.len()
        )));
    }
    Ok(())
}

/// Everything decided once per run.
struct Run<'a> {
    job: &'a SynthJob,
    seed: u64,
    out: &'a Path,
    policy: &'a OutputPolicy,
    replay: Option<&'a Sidecar>,
    bar: Option<&'a indicatif::ProgressBar>,
    /// Wait for an output set another process is writing (else fail the input).
    wait: bool,
    /// Do not list the files written.
    quiet: bool,
}

impl Run<'_> {
    /// A line on stderr (above the progress bar when there is one).
    fn say(&self, msg: String) {
        match self.bar {
            Some(b) => b.println(msg),
            None => eprintln!("{msg}"),
        }
    }

    /// Every variant of one input (the sidecar's one with --replay).
    fn input(&self, input: &Path) -> day2night::Result<()> {
        let day = DayInput::read(input)?;
        if !self.quiet && matches!(self.job.options.mode, Mode::Global | Mode::Local) {
            // Where this input's lamp colours come from (its warnings come with the plan;
            // when there is no dictionary, the plan's error lists it with every other
            // problem of the input).
            if let Ok(ill) = self.job.illuminants(&day) {
                self.say(format!(
                    "day2night: {}: night illuminants: {}",
                    input.display(),
                    ill.provenance.summary()
                ));
            }
        }
        let name = input
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| input.display().to_string());
        let stem = input
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| name.clone());
        match self.replay {
            Some(sc) => {
                if sc.input.sha256 != day.sha256 {
                    return Err(Error::invalid(format!(
                        "input does not match the sidecar (sha256 {} expected {})",
                        day.sha256, sc.input.sha256
                    )));
                }
                self.variant(input, &day, &stem, &sc.planned())?;
            }
            None => {
                for v in 0..self.job.variants {
                    if stop_requested().is_some() {
                        return Err(Error::Interrupted);
                    }
                    let planned = self.job.plan(&day, &name, self.seed, v)?;
                    self.variant(input, &day, &stem, &planned)?;
                }
            }
        }
        Ok(())
    }

    /// One planned variant: warnings, outputs, progress.
    fn variant(
        &self,
        input: &Path,
        day: &DayInput,
        stem: &str,
        planned: &Planned,
    ) -> day2night::Result<()> {
        for w in &planned.report.warnings {
            self.say(format!("day2night: {}: warning: {}", input.display(), w));
        }
        std::fs::create_dir_all(self.out).map_err(|e| Error::from(e).in_file(self.out))?;
        // One process at a time checks and writes this output set (docs/concurrency.md).
        let base = self.job.base_name(stem, &planned.plan);
        let _set = OutputSetLock::acquire(self.out, &base, self.wait)?;
        let sink = DirSink::new(self.out, base, self.policy);
        let written = self.job.run_variant(day, planned, &sink)?;
        for w in &written.warnings {
            self.say(format!("day2night: {}: warning: {}", input.display(), w));
        }
        if let Some(b) = self.bar {
            b.inc(1);
        }
        if !self.quiet {
            for f in &written.files {
                self.say(format!("wrote {}", self.out.join(f).display()));
            }
        }
        Ok(())
    }
}
