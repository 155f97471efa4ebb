//! Command-line front end (clap derive). One file per subcommand; the library stays free of
//! clap. Errors print as `day2night: <file>: <reason>` on stderr.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod args;
mod calibrate;
mod convert;
mod dataset;
mod eval;
mod info;
mod interrupt;
mod limits;
mod merge;
mod progress;
mod real_pairs;
mod render;
mod report;
mod synth;
mod synth_opts;

/// Turn daytime camera raw photos (DNG) into realistic nighttime raw photos.
#[derive(Debug, Parser)]
#[command(name = "day2night", version, about, long_about = None)]
pub struct Cli {
    /// Largest image accepted, in pixels (e.g. 300M, 1G; default 268M = 2^28; also
    /// D2N_MAX_PIXELS). Larger images are refused before anything is allocated.
    #[arg(long, global = true, value_name = "N", value_parser = args::parse_max_pixels)]
    max_pixels: Option<u64>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Describe DNG files: camera, geometry, CFA, levels, colour, ISO, noise, storage.
    Info(info::InfoArgs),
    /// Re-write a DNG through the reader and writer (same pixels, fresh valid layout).
    Convert(convert::ConvertArgs),
    /// Synthesize clean and noisy night DNGs (and targets) from day DNGs.
    Synth(synth::SynthArgs),
    /// Render a DNG through the software ISP to EXR, PNG or TIFF.
    Render(render::RenderArgs),
    /// Compare two images: PSNR, SSIM, mean Delta E 2000.
    Eval(eval::EvalArgs),
    /// Build calibration files (night illuminants, brightness, noise) from real captures.
    #[command(subcommand)]
    Calibrate(calibrate::CalibrateCommand),
    /// Average an aligned burst into one low-noise DNG.
    Merge(merge::MergeArgs),
    /// Generate a whole dataset: split, manifest, resumable, shardable.
    Dataset(dataset::DatasetArgs),
    /// Real night pairs from captures: merged clean raw, rendered target, noisy inputs.
    RealPairs(real_pairs::RealPairsArgs),
    /// Write an HTML report of a dataset (renders, masks, illuminants, histograms).
    Report(report::ReportArgs),
}

/// Error reported by a subcommand, with the exit code it maps to.
pub struct Failure {
    /// 1 = bad input / failed work, 2 = bad usage.
    pub code: u8,
    /// The message (already `<file>: <reason>` where a file is concerned).
    pub error: anyhow::Error,
}

impl<E: Into<anyhow::Error>> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure {
            code: 1,
            error: e.into(),
        }
    }
}

/// A failure already reported on stderr (e.g. per file): exit code `code`, nothing more
/// printed.
pub fn reported(code: u8) -> Failure {
    Failure {
        code,
        error: anyhow::anyhow!(""),
    }
}

/// A usage error (exit code 2).
pub fn usage(msg: impl std::fmt::Display) -> Failure {
    Failure {
        code: 2,
        error: anyhow::anyhow!("{msg}"),
    }
}

/// Result type of subcommands.
pub type CmdResult = Result<(), Failure>;

/// Entry point used by `main`.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match limits::from_args_and_env(cli.max_pixels) {
        Ok(l) => l.install(),
        Err(e) => {
            eprintln!("day2night: {e}");
            return ExitCode::from(2);
        }
    }
    // synth, dataset and real-pairs stop gracefully on a first SIGINT/SIGTERM; the others at once.
    let graceful = matches!(
        cli.command,
        Command::Synth(_) | Command::Dataset(_) | Command::RealPairs(_)
    );
    let resumable = matches!(cli.command, Command::Dataset(_) | Command::RealPairs(_));
    interrupt::install(graceful, resumable);
    let result = match cli.command {
        Command::Info(a) => info::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Synth(a) => synth::run(a),
        Command::Render(a) => render::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Calibrate(c) => calibrate::run(c),
        Command::Merge(a) => merge::run(a),
        Command::Dataset(a) => dataset::run(a),
        Command::RealPairs(a) => real_pairs::run(a),
        Command::Report(a) => report::run(a),
    };
    if let Some(sig) = day2night::output::stop_requested() {
        // Stopped by a signal: whatever failed on the way is a consequence of the stop.
        day2night::output::remove_temp_files_and_close();
        interrupt::print_once(resumable);
        return ExitCode::from(interrupt::exit_code(sig));
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            let mut msg = format!("{}", f.error);
            // Library `File` errors already print their source ("file: reason"): append
            // only causes whose text is not in the message yet.
            for cause in f.error.chain().skip(1) {
                let c = cause.to_string();
                if !msg.contains(&c) {
                    msg.push_str(&format!(": {c}"));
                }
            }
            if !msg.is_empty() {
                eprintln!("day2night: {msg}");
            }
            ExitCode::from(f.code)
        }
    }
}

/// Print one warning on stderr, once: `warning[CODE]: SUBJECT: MESSAGE`, `fallback` (the
/// file the command works on) standing for a missing subject. Every warning the command line
/// prints goes through here (docs/warnings.md lists the codes).
pub fn warn(w: &day2night::Warning, fallback: &str) {
    use std::io::Write as _;
    // A closed stderr drops the line (EPIPE must not panic).
    let _ = writeln!(std::io::stderr(), "{}", w.line(fallback));
}

/// [`warn`] for each of `warnings`, about `file` when they name nothing else.
pub fn warn_all<'a>(
    file: &std::path::Path,
    warnings: impl IntoIterator<Item = &'a day2night::Warning>,
) {
    let name = file.display().to_string();
    for w in warnings {
        warn(w, &name);
    }
}

/// Print what the metadata checks corrected in `meta` (`warning[CODE]: <file>: ...`).
pub fn print_meta_warnings(file: &std::path::Path, meta: &day2night::raw::meta::RawMeta) {
    warn_all(file, &meta.warnings);
}
