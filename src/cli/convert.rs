//! `day2night convert IN OUT [--compression none|ljpeg] [--raw-ifd main|sub] [--overwrite]`:
//! re-write a DNG through the reader and writer (same pixels, same meaning, fresh layout).
use super::CmdResult;
use day2night::dng::read::read_dng;
use day2night::dng::write::{write_dng, Compression, RawIfd, WriteOptions};
use day2night::output::OutputPolicy;
use std::path::PathBuf;

/// Raw compression choice on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum CompressionArg {
    /// Uncompressed strips (most compatible).
    None,
    /// Lossless JPEG tiles (about half the size).
    Ljpeg,
}

/// Raw IFD choice on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum RawIfdArg {
    /// Raw image in IFD0.
    Main,
    /// Raw image in a SubIFD behind a small RGB thumbnail.
    Sub,
}

/// Arguments of `day2night convert`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Example:\n  day2night convert fixtures/day.dng /tmp/day_lj92.dng \
                        --compression ljpeg --raw-ifd sub"
)]
pub struct ConvertArgs {
    /// Input DNG.
    #[arg(value_name = "IN.dng")]
    pub input: PathBuf,
    /// Output DNG (refused if it exists, unless --overwrite; never the input); or -o.
    #[arg(value_name = "OUT.dng", required_unless_present = "out")]
    pub output: Option<PathBuf>,
    /// Output DNG, as an option (the same as the positional OUT.dng).
    #[arg(
        short = 'o',
        long = "output",
        visible_alias = "out",
        value_name = "OUT.dng",
        conflicts_with = "output"
    )]
    pub out: Option<PathBuf>,
    /// Raw image compression.
    #[arg(long, value_enum, default_value = "none")]
    pub compression: CompressionArg,
    /// IFD that holds the raw image.
    #[arg(long, value_enum, default_value = "main")]
    pub raw_ifd: RawIfdArg,
    /// Replace an existing output file.
    #[arg(long)]
    pub overwrite: bool,
}

/// Run `day2night convert`.
pub fn run(args: ConvertArgs) -> CmdResult {
    let Some(output) = args.out.clone().or(args.output.clone()) else {
        return Err(super::usage(
            "convert needs an output: OUT.dng or -o OUT.dng",
        ));
    };
    let policy = OutputPolicy {
        overwrite: args.overwrite,
        inputs: vec![args.input.clone()],
        ..OutputPolicy::default()
    };
    // Fail before reading a large input when the output is refused anyway.
    policy.check(&output)?;
    let img = read_dng(&args.input)?;
    super::print_meta_warnings(&args.input, &img.meta);
    let opts = WriteOptions {
        compression: match args.compression {
            CompressionArg::None => Compression::None,
            CompressionArg::Ljpeg => Compression::Ljpeg,
        },
        raw_ifd: match args.raw_ifd {
            RawIfdArg::Main => RawIfd::Main,
            RawIfdArg::Sub => RawIfd::Sub,
        },
        ..WriteOptions::default()
    };
    write_dng(&img, &output, &opts, &policy)?;
    Ok(())
}
