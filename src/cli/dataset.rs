//! `day2night dataset`: a whole dataset from a folder of day DNGs (see docs/dataset.md).
use super::synth::SynthOpts;
use super::{usage, CmdResult, Failure};
use day2night::dataset::synthesis::SynthProcessor;
use day2night::dataset::{self, RunOptions, Shard, SplitRule};
use std::path::PathBuf;

/// Arguments of `day2night dataset`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  day2night dataset day/ -o night_set/ --val 10 --jobs 4
  day2night dataset day/ -o night_set/ --val-fraction 0.1 --variants 3 --shard 0/8

A rerun resumes: (input, variant) units whose outputs exist and match manifest.jsonl (same
input bytes, options and seed) are skipped. Exit code 1 if any input failed.")]
pub struct DatasetArgs {
    /// Folder of day DNGs (searched recursively for *.dng in any letter case).
    #[arg(value_name = "DAY_DIR")]
    pub day_dir: PathBuf,
    /// -o/--output OUT_DIR (shared with `real-pairs`).
    #[command(flatten)]
    pub out: OutFolder,
    /// Put the last N inputs (by sorted relative path) in val, as the paper (60/10).
    #[arg(long, value_name = "N", conflicts_with = "val_fraction")]
    pub val: Option<usize>,
    /// Put each input in val with probability F, by a seeded hash of its path.
    #[arg(long, value_name = "F")]
    pub val_fraction: Option<f64>,
    /// Synthesized variants per input.
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub variants: u32,
    /// Process only shard I of N (0-based), by a stable hash of each input's path.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// --jobs, --overwrite, --json, --quiet (shared with `real-pairs`).
    #[command(flatten)]
    pub run: RunFlags,
    /// When another day2night process is writing a unit's outputs, wait for it instead of
    /// failing the unit.
    #[arg(long)]
    pub wait: bool,
    /// Also write the HTML report (OUT_DIR/report/index.html) at the end.
    #[arg(long)]
    pub report: bool,
    /// Synthesis and output options: `synth`'s, with the same names, values and defaults.
    #[command(flatten)]
    pub synth: Box<SynthOpts>,
}

/// The output folder of `dataset` and `real-pairs` (`real-pairs` names it OUT, with its
/// own help line).
#[derive(Debug, clap::Args)]
pub struct OutFolder {
    /// Output folder (train/ and val/ layouts, manifest.jsonl).
    #[arg(
        short = 'o',
        long = "output",
        visible_alias = "out",
        value_name = "OUT_DIR"
    )]
    pub out_dir: PathBuf,
}

impl OutFolder {
    /// Exit code 1 when `failed` of the run's `total` units (or scenes: `what`) failed.
    pub fn fail_on(&self, failed: usize, total: usize, what: &str) -> CmdResult {
        if failed == 0 {
            return Ok(());
        }
        Err(Failure {
            code: 1,
            error: anyhow::anyhow!(
                "{}: {failed} of {total} {what} failed (see the summary above and the manifest)",
                self.out_dir.display()
            ),
        })
    }
}

/// The flags of a whole-folder run, the same in `dataset` and `real-pairs`.
#[derive(Debug, clap::Args)]
pub struct RunFlags {
    /// Inputs (scenes for `real-pairs`) processed in parallel (= images in memory);
    /// default: number of CPUs.
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Recompute everything, ignoring the manifest (and accept a non-empty output folder
    /// without one).
    #[arg(long)]
    pub overwrite: bool,
    /// Print the run summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// No progress output (the summary is still printed on stderr).
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

impl RunFlags {
    /// Worker threads: --jobs (checked), else the number of CPUs.
    pub fn jobs(&self) -> Result<usize, Failure> {
        match self.jobs {
            Some(n) => {
                day2night::bounds::jobs("--jobs", n).map_err(usage)?;
                Ok(n)
            }
            None => Ok(std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)),
        }
    }

    /// The summary's text on stderr, and with --json the summary as JSON on stdout.
    pub fn print_summary<S: serde::Serialize>(&self, text: &str, summary: &S) -> CmdResult {
        eprintln!("{text}");
        if self.json {
            let json = serde_json::to_string_pretty(summary)
                .map_err(|e| anyhow::anyhow!("summary JSON: {e}"))?;
            println!("{json}");
        }
        Ok(())
    }
}

/// The synthesis processor: `synth`'s job from the same options (`--replay` excluded).
fn processor(f: &SynthOpts, variants: u32) -> Result<SynthProcessor, Failure> {
    if f.replay().is_some() {
        return Err(usage(
            "--replay applies to `synth` only (replay one sidecar with `day2night synth DAY.dng --replay meta/<id>.json`)",
        ));
    }
    Ok(SynthProcessor {
        job: f.job(variants)?,
    })
}

/// Run `day2night dataset`.
pub fn run(args: DatasetArgs) -> CmdResult {
    let split = match (args.val, args.val_fraction) {
        (Some(n), _) => SplitRule::LastN(n),
        (None, Some(f)) => {
            if !(0.0..=1.0).contains(&f) {
                return Err(usage(format!("--val-fraction {f} is not within [0, 1]")));
            }
            SplitRule::Fraction {
                fraction: f,
                seed: args.synth.seed(),
            }
        }
        (None, None) => SplitRule::AllTrain,
    };
    let shard = match &args.shard {
        Some(s) => Shard::parse(s).map_err(usage)?,
        None => Shard::ALL,
    };
    if args.variants == 0 {
        return Err(usage("--variants must be at least 1"));
    }
    let jobs = args.run.jobs()?;
    let proc = processor(&args.synth, args.variants)?;
    let opts = RunOptions {
        day_dir: args.day_dir.clone(),
        out_dir: args.out.out_dir.clone(),
        split,
        variants: args.variants,
        seed: args.synth.seed(),
        shard,
        jobs,
        overwrite: args.run.overwrite,
        wait: args.wait,
        progress: super::progress::dataset_progress(args.run.quiet),
    };
    let summary = match dataset::run(&opts, &proc) {
        Ok(s) => s,
        Err(e) => {
            // "--val N" larger than the inputs is a usage error.
            let code = if matches!(e.root(), day2night::Error::InvalidParam(m) if m.starts_with("--val"))
            {
                2
            } else {
                1
            };
            return Err(Failure {
                code,
                error: e.into(),
            });
        }
    };
    args.run.print_summary(&summary.describe(), &summary)?;
    if args.report {
        let r =
            super::report::build_report(&args.out.out_dir, Some(args.day_dir.clone()), 12, 320)?;
        eprintln!("dataset: report written to {}", r.page.display());
    }
    args.out.fail_on(summary.failed, summary.units, "units")
}
