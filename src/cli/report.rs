//! `day2night report`: an HTML page to judge a dataset at a glance.
use super::CmdResult;
use day2night::report::{self, real::LibraryVisuals, ReportOptions, ReportSummary};
use std::path::{Path, PathBuf};

/// Arguments of `day2night report`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Example:
  day2night report night_set/ --day-dir day/
  # then open night_set/report/index.html (self-contained: no network)")]
pub struct ReportArgs {
    /// A dataset folder written by `day2night dataset` (holds manifest*.jsonl).
    #[arg(value_name = "OUT_DIR")]
    pub out_dir: PathBuf,
    /// The DAY_DIR the dataset was made from (for the day renders).
    #[arg(long, value_name = "DAY_DIR")]
    pub day_dir: Option<PathBuf>,
    /// Samples shown in detail (spread evenly over the dataset).
    #[arg(long, default_value_t = 12)]
    pub samples: usize,
    /// Longest side of thumbnails in pixels.
    #[arg(long, default_value_t = 320)]
    pub thumb: usize,
    /// Print what was written as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Build the report with the real renderer.
pub fn build_report(
    out_dir: &Path,
    day_dir: Option<PathBuf>,
    samples: usize,
    thumb: usize,
) -> Result<ReportSummary, super::Failure> {
    let opts = ReportOptions {
        out_dir: out_dir.to_path_buf(),
        day_dir,
        samples,
        thumb: thumb.clamp(16, 4096),
    };
    let r = report::build(&opts, &LibraryVisuals)?;
    for w in &r.warnings {
        super::warn(w, "report");
    }
    Ok(r)
}

/// Run `day2night report`.
pub fn run(args: ReportArgs) -> CmdResult {
    let r = build_report(&args.out_dir, args.day_dir, args.samples, args.thumb)?;
    if args.json {
        let v = serde_json::json!({
            "page": r.page,
            "records": r.records,
            "samples": r.samples,
            "pngs": r.pngs.len(),
            "warnings": r.warnings,
        });
        println!("{v:#}");
    } else {
        eprintln!(
            "report: {} ({} samples, {} records)",
            r.page.display(),
            r.samples,
            r.records
        );
    }
    Ok(())
}
