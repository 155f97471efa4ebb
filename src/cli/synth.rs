//! `day2night synth`: clean and noisy night DNGs, targets and a sidecar per input and
//! variant (docs/cli.md), made by the library's [`SynthJob`] (the same code as `dataset`).
//! Inputs are processed one after another (each with rayon inside); an input that cannot
//! be used is reported and skipped, and the exit code is 1 at the end.

pub use super::synth_opts::SynthOpts;
use super::{usage, CmdResult, Failure};
use day2night::error::Error;
use day2night::output::{stop_requested, OutputPolicy, OutputSetLock};
use day2night::synth::job::{DayInput, DirSink, SynthJob};
use day2night::synth::sidecar::Sidecar;
use day2night::synth::{Mode, Planned};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

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

pub fn run(args: SynthArgs) -> CmdResult {
    if args.variants == 0 {
        return Err(usage("--variants must be at least 1"));
    }
    if let Some(n) = args.jobs {
        day2night::bounds::jobs("--jobs", n).map_err(usage)?;
    }
    let (job, seed, replay) = match args.synth.replay() {
        Some(p) => {
            if args.inputs.len() != 1 {
                return Err(usage(
                    "--replay takes exactly one input (the sidecar's day DNG)",
                ));
            }
            let sc = Sidecar::read(p)?;
            (SynthJob::from_sidecar(&sc)?, sc.plan.seed, Some(sc))
        }
        None => (args.synth.job(args.variants)?, args.synth.seed(), None),
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

/// The day input of a variant: shared with the input's other variants, or handed over (the
/// last variant: its clean raw is made in the day's plane). Boxed: the input's record is
/// large beside a reference, and the plane it holds is on the heap either way.
enum Day<'a> {
    Shared(&'a DayInput),
    Owned(Box<DayInput>),
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

    /// Each warning once, `warning[CODE]: SUBJECT: MESSAGE` (above the progress bar).
    fn say_warnings<'w>(
        &self,
        warnings: impl IntoIterator<Item = &'w day2night::Warning>,
        file: &str,
    ) {
        for w in warnings {
            self.say(w.line(file));
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
                self.variant(input, Day::Owned(Box::new(day)), &stem, &sc.planned())?;
            }
            None => {
                // The last variant takes the day raw: its clean raw is made in the day's
                // plane (one plane of samples in memory instead of two).
                let last = self.job.variants.saturating_sub(1);
                for v in 0..last {
                    if stop_requested().is_some() {
                        return Err(Error::Interrupted);
                    }
                    let mut planned = self.job.plan(&day, &name, self.seed, v)?;
                    // the variants share the whole-frame mean of a brightness dimming
                    planned.plan = day.with_frame_mean(planned.plan)?;
                    self.variant(input, Day::Shared(&day), &stem, &planned)?;
                }
                if stop_requested().is_some() {
                    return Err(Error::Interrupted);
                }
                let mut planned = self.job.plan(&day, &name, self.seed, last)?;
                if last > 0 {
                    planned.plan = day.with_frame_mean(planned.plan)?;
                }
                self.variant(input, Day::Owned(Box::new(day)), &stem, &planned)?;
            }
        }
        Ok(())
    }

    /// One planned variant: outputs, then its warnings (the plan's and the run's, each
    /// once), progress.
    fn variant(
        &self,
        input: &Path,
        day: Day<'_>,
        stem: &str,
        planned: &Planned,
    ) -> day2night::Result<()> {
        std::fs::create_dir_all(self.out).map_err(|e| Error::from(e).in_file(self.out))?;
        // One process at a time checks and writes this output set (docs/concurrency.md).
        let base = self.job.base_name(stem, &planned.plan);
        let _set = OutputSetLock::acquire(self.out, &base, self.wait)?;
        let sink = DirSink::new(self.out, base, self.policy);
        let run = match day {
            Day::Shared(day) => self.job.run_variant(day, planned, &sink),
            Day::Owned(day) => self.job.run_variant_owned(*day, planned, &sink),
        };
        // The plan's warnings are said whether or not the run succeeded; the run's after it.
        let name = input.display().to_string();
        let written = match run {
            Ok(w) => w,
            Err(e) => {
                self.say_warnings(&planned.report.warnings, &name);
                return Err(e);
            }
        };
        self.say_warnings(
            planned.report.warnings.iter().chain(&written.warnings),
            &name,
        );
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
