//! `day2night convert IN OUT [--compression none|ljpeg] [--raw-ifd main|sub]
//! [--bad-opcode-lists refuse|drop] [--overwrite]`: re-write a DNG through the reader and
//! writer (same pixels, same meaning, fresh layout). An opcode list the renders could not
//! use is refused (default) or dropped with a warning: a written DNG always renders.
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

/// What `convert` does with an opcode list that day2night's renders cannot use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BadOpcodeListsArg {
    /// Refuse the file, naming the list and the reason (nothing is written).
    Refuse,
    /// Write the file without that list, with a warning naming it and the reason.
    Drop,
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
    /// An opcode list day2night's renders cannot use (malformed, a mandatory opcode they
    /// cannot apply, a TrimBounds outside the image): refuse the file, or drop the list
    /// with a warning. A written DNG always renders.
    #[arg(long, value_enum, default_value = "refuse", value_name = "WHAT")]
    pub bad_opcode_lists: BadOpcodeListsArg,
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
    let mut img = read_dng(&args.input)?;
    super::print_meta_warnings(&args.input, &img.meta);
    // Never write a DNG that day2night's own renders refuse (LinearRaw files are refused by
    // the writer anyway, with their own reason).
    if img.meta.linear_raw.is_none() {
        for (list, e) in day2night::isp::opcodes::check::unrenderable_lists(&img) {
            let tag = list.tag_name();
            if args.bad_opcode_lists == BadOpcodeListsArg::Refuse {
                return Err(anyhow::anyhow!(
                    "{}: {e}: renders of the file would fail, so convert refuses it \
                     (--bad-opcode-lists drop writes it without {tag})",
                    args.input.display()
                )
                .into());
            }
            super::warn_all(
                &args.input,
                &[day2night::Warning::new(
                    day2night::Code::OpcodeListDropped,
                    format!("{e}: {tag} dropped (--bad-opcode-lists drop)"),
                )],
            );
            img.meta.opcode_lists[list.index()] = None;
        }
    }
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
