//! `day2night merge`: average an aligned burst into one low-noise DNG.
use super::CmdResult;
use day2night::calibrate::merge::{repeated_frame, Merger};
use day2night::dng::read_dng;
use day2night::dng::write::{write_dng, Compression, WriteOptions};
use day2night::error::ResultExt;
use day2night::output::OutputPolicy;
use std::path::PathBuf;

/// Arguments of `day2night merge`.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Frames must share size, ActiveArea, CFA, black/white levels and ISO. The output keeps the
full precision of the mean in a 16-bit container: with N frames and N*white <= 65535 the
samples are the exact sums and BlackLevel/WhiteLevel are multiplied by N; otherwise they are
round(sum*K/N) with K = floor(65535/white). NoiseProfile is divided by N; a site saturated in
any frame stays saturated. Metadata comes from the first frame.

Example:
  day2night merge scene01_iso50_*.dng -o scene01_gt.dng")]
pub struct MergeArgs {
    /// Frames of the burst (at least 2).
    #[arg(required = true, value_name = "FRAME.dng")]
    pub frames: Vec<PathBuf>,
    /// Output DNG.
    #[arg(short, long, visible_alias = "out", value_name = "OUT.dng")]
    pub output: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    pub overwrite: bool,
    /// Raw compression of the output.
    #[arg(long, value_enum, default_value = "none")]
    pub compression: CompressionArg,
    /// Print a JSON report on stdout.
    #[arg(long)]
    pub json: bool,
}

/// `--compression` values.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum CompressionArg {
    /// Uncompressed strips.
    None,
    /// Lossless JPEG tiles.
    Ljpeg,
}

/// Run `day2night merge`.
pub fn run(args: MergeArgs) -> CmdResult {
    if let Some(why) = repeated_frame(&args.frames) {
        return Err(super::usage(why));
    }
    let mut it = args.frames.iter();
    let Some(first) = it.next() else {
        return Err(super::usage("merge needs at least 2 frames"));
    };
    let policy = OutputPolicy {
        overwrite: args.overwrite,
        inputs: args.frames.clone(),
        ..OutputPolicy::default()
    };
    // Refuse a bad output path before reading the whole burst.
    policy.check(&args.output)?;
    let pb = super::calibrate::progress(args.frames.len());
    let mut merger = Merger::new(read_dng(first).in_file(first)?).in_file(first)?;
    pb.inc(1);
    for p in it {
        let img = read_dng(p).in_file(p)?;
        merger.add(&img).in_file(p)?;
        pb.inc(1);
    }
    pb.finish_and_clear();
    let (img, report) = merger.finish().in_file(first)?;
    let opts = WriteOptions {
        compression: match args.compression {
            CompressionArg::None => Compression::None,
            CompressionArg::Ljpeg => Compression::Ljpeg,
        },
        ..WriteOptions::default()
    };
    write_dng(&img, &args.output, &opts, &policy)?;
    eprintln!(
        "merged {} frames -> {} ({}, levels x{}: black {}, white {}, {} saturated sites)",
        report.frames,
        args.output.display(),
        if report.exact {
            "exact sums"
        } else {
            "rounded mean"
        },
        report.scale_factor,
        report.black,
        report.white,
        report.saturated_sites
    );
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    }
    Ok(())
}
