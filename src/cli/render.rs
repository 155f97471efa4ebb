//! `day2night render IN.dng -o OUT.exr|png|tif`: the software ISP on one DNG.
use super::args::{choice, lib, parse_neutral, parse_zip_level, Typed};
use super::{usage, CmdResult};
use day2night::encode::exr::{
    encodes_rows, standard_attributes, write_exr, ExrCompression, ExrOptions,
};
use day2night::encode::png::{write_png, write_tiff, PngOptions};
use day2night::encode::target_files::TargetFiles;
use day2night::isp::opcodes::OpcodeMode;
use day2night::isp::release::Isp;
use day2night::isp::render::{render, render_bands, resolve_neutral, Output, RenderOptions};
use day2night::isp::tone::DisplayTone;
use day2night::isp::Demosaic;
use day2night::output::OutputPolicy;
use std::path::PathBuf;

/// Arguments of `day2night render`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Output format from the extension: .exr = linear Rec.709/sRGB (D65) \
half floats (or --float); .png = display sRGB, 8-bit (or --bits 16); .tif/.tiff = display \
sRGB, 16-bit (or --bits 8).\n\nExamples:\n  day2night render day.dng -o day.exr\n  \
day2night render day.dng -o day.png --demosaic menon --tone release\n  \
day2night render day.dng -o input.exr --camera-rgb --neutral 0.5,1,0.7"
)]
pub struct RenderArgs {
    /// Input DNG.
    #[arg(value_name = "IN.dng")]
    pub input: PathBuf,
    /// Output file (.exr, .png, .tif or .tiff).
    #[arg(short, long, visible_alias = "out", value_name = "OUT")]
    pub output: PathBuf,
    /// Demosaicing method.
    #[arg(long, default_value_t = Typed::<Demosaic>::default(), value_parser = choice::<Demosaic>(), value_name = "METHOD")]
    pub demosaic: Typed<Demosaic>,
    /// White balance by this camera neutral instead of the file's AsShotNeutral.
    #[arg(long, value_name = "R,G,B")]
    pub neutral: Option<String>,
    /// EXR: 16-bit half samples (the default).
    #[arg(long, conflicts_with = "float")]
    pub half: bool,
    /// EXR: 32-bit float samples.
    #[arg(long)]
    pub float: bool,
    /// EXR compression.
    #[arg(long, default_value_t = Typed::<ExrCompression>::default(), value_parser = choice::<ExrCompression>(), value_name = "C")]
    pub exr_compression: Typed<ExrCompression>,
    /// Compression effort of zip/zips EXRs: 1 (default, fastest, own encoder) to 9
    /// (miniz_oxide level 9: about 2 % smaller, much slower).
    #[arg(long = "exr-zip-level", default_value_t = 1, value_name = "N")]
    pub exr_zip_level: u8,
    /// PNG/TIFF display encoding (release: gamma 2.2 + smoothstep).
    #[arg(long, default_value_t = Typed::<DisplayTone>::default(), value_parser = choice::<DisplayTone>(), value_name = "TONE")]
    pub tone: Typed<DisplayTone>,
    /// PNG/TIFF bits per sample: 8 or 16 (default: 8 for PNG, 16 for TIFF).
    #[arg(long, value_name = "N")]
    pub bits: Option<u8>,
    /// Write the network input instead: white-balanced demosaiced camera RGB, no colour matrix.
    #[arg(long)]
    pub camera_rgb: bool,
    /// Do not apply DefaultCrop (keep the whole active area).
    #[arg(long)]
    pub no_crop: bool,
    /// Do not apply the Orientation tag.
    #[arg(long)]
    pub no_orient: bool,
    /// DNG opcode lists (lens shading GainMap, distortion WarpRectilinear, ...): applied as
    /// the Adobe DNG SDK does, or ignored as LibRaw and the authors' renders do.
    #[arg(long, default_value_t = Typed::<OpcodeMode>::default(), value_parser = choice::<OpcodeMode>(), value_name = "MODE")]
    pub opcodes: Typed<OpcodeMode>,
    /// Replace an existing output.
    #[arg(long)]
    pub overwrite: bool,
    /// ISP: release is the authors' release's target render reproduced (docs/isp.md): Menon
    /// demosaic, its colour matrices, gamma 2.2 + s-curve, its own crop and orientation,
    /// opcodes and DefaultCrop ignored. With release, --demosaic, --tone and --opcodes may
    /// only name what it does (menon, release, ignore); --camera-rgb, --no-crop, --bits 16
    /// and TIFF are refused; .exr gets its linear sRGB.
    #[arg(long, default_value_t = Typed::<Isp>::default(), value_parser = choice::<Isp>(), value_name = "ISP")]
    pub isp: Typed<Isp>,
}

enum Format {
    Exr,
    Png,
    Tiff,
}

/// The output's format (from its extension) and whether it is 16-bit (`--bits`, else TIFF
/// 16 and the others 8).
/// The output policy of a render (the input is never overwritten), an existing output
/// refused before the (slow) read and render, and the input read, its metadata warnings
/// printed.
fn policy_and_input(
    args: &RenderArgs,
) -> Result<(OutputPolicy, day2night::raw::RawImage), super::Failure> {
    let policy = OutputPolicy {
        overwrite: args.overwrite,
        inputs: vec![args.input.clone()],
        ..OutputPolicy::default()
    };
    policy.check(&args.output).map_err(lib)?;
    let img = day2night::dng::read::read_dng(&args.input).map_err(lib)?;
    super::print_meta_warnings(&args.input, &img.meta);
    Ok((policy, img))
}

/// `--neutral` (None: the file's AsShotNeutral), `--exr-compression` and
/// `--exr-zip-level`, each a usage error when bad: the options both ISPs read.
fn neutral_and_exr(
    args: &RenderArgs,
) -> Result<(Option<[f64; 3]>, ExrCompression, u8), super::Failure> {
    let neutral = args
        .neutral
        .as_deref()
        .map(parse_neutral)
        .transpose()
        .map_err(usage)?;
    let compression = args.exr_compression.value;
    let zip_level = parse_zip_level(args.exr_zip_level)?;
    Ok((neutral, compression, zip_level))
}

fn output_format(args: &RenderArgs) -> Result<(Format, bool), super::Failure> {
    let ext = args
        .output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let format = match ext.as_str() {
        "exr" => Format::Exr,
        "png" => Format::Png,
        "tif" | "tiff" => Format::Tiff,
        _ => {
            return Err(usage(format!(
                "{}: output must end in .exr, .png, .tif or .tiff",
                args.output.display()
            )))
        }
    };
    let sixteen = match (args.bits, &format) {
        (Some(8), _) => false,
        (Some(16), _) => true,
        (Some(b), _) => return Err(usage(format!("--bits {b}: use 8 or 16"))),
        (None, Format::Tiff) => true,
        (None, _) => false,
    };
    Ok((format, sixteen))
}

/// Run `day2night render`.
pub fn run(args: RenderArgs) -> CmdResult {
    if args.isp.value == Isp::Release {
        return run_release(&args);
    }
    let (demosaic, tone, opcodes) = (args.demosaic.value, args.tone.value, args.opcodes.value);
    let (neutral, compression, zip_level) = neutral_and_exr(&args)?;
    let (format, sixteen) = output_format(&args)?;
    let (policy, img) = policy_and_input(&args)?;
    let in_file = |e: day2night::Error| lib(e.in_file(&args.input));
    let n = resolve_neutral(&img.meta, neutral).map_err(in_file)?;
    // Optional opcodes that cannot be applied are skipped with a warning; others are errors,
    // and so is opcode work over the budget (before any pixel work). Opcodes that make their
    // samples constant and a TrimBounds that changes the size warn.
    let checked =
        day2night::isp::opcodes::check::check_render(&img, opcodes, !args.no_crop, !args.no_orient)
            .map_err(in_file)?;
    super::warn_all(&args.input, &checked.warnings);
    // A render that comes out constant is said too (watched band by band).
    let flat = day2night::isp::flat::FlatCheck::new();
    let say_flat = || {
        super::warn_all(&args.input, &flat.warning("the render"));
    };
    let opts = RenderOptions {
        output: if args.camera_rgb {
            Output::Camera
        } else {
            Output::Linear
        },
        demosaic,
        neutral: Some(n),
        crop: !args.no_crop,
        orient: !args.no_orient,
        opcodes,
    };
    let mut attrs = standard_attributes(&args.input, n);
    attrs.push(("day2night:demosaic".into(), demosaic.name().into()));
    attrs.push((
        "day2night:content".into(),
        if args.camera_rgb {
            "white-balanced camera RGB (network input)".into()
        } else {
            "linear Rec.709/sRGB, D65".into()
        },
    ));
    let exr_opts = ExrOptions {
        half: !args.float,
        compression,
        zip_level,
    };
    // EXR (ZIP, ZIPS, none) and 8-bit PNG are written band by band as the render makes them
    // (the same bytes as the whole-image writers); the rest from the whole image.
    let streamed = match format {
        Format::Exr if encodes_rows(&exr_opts) => {
            stream(&img, &opts, &policy, &flat, |dims, policy| {
                TargetFiles::create(dims, Some(&args.output), (&exr_opts, &attrs), None, policy)
            })
            .map_err(in_file)?
        }
        Format::Png if !sixteen => stream(&img, &opts, &policy, &flat, |dims, policy| {
            TargetFiles::create(
                dims,
                None,
                (&exr_opts, &[]),
                Some((&args.output, tone)),
                policy,
            )
        })
        .map_err(in_file)?,
        _ => false,
    };
    if streamed {
        say_flat();
        return Ok(());
    }
    let rgb = render(&img, &opts).map_err(in_file)?;
    flat.image(&rgb);
    say_flat();
    match format {
        Format::Exr => {
            write_exr(&rgb, &args.output, &exr_opts, &attrs, &policy).map_err(lib)?;
        }
        Format::Png => write_png(
            &rgb,
            &args.output,
            &PngOptions {
                sixteen_bit: sixteen,
                tone,
            },
            &policy,
        )
        .map_err(lib)?,
        Format::Tiff => write_tiff(
            &rgb,
            &args.output,
            &PngOptions {
                sixteen_bit: sixteen,
                tone,
            },
            &policy,
        )
        .map_err(lib)?,
    }
    Ok(())
}

/// The flags `--isp release` fixes, with the one value each may name: a contradiction is a
/// usage error naming the flag.
fn release_conflicts(args: &RenderArgs) -> Option<String> {
    // as typed: `--demosaic malvar` is not the default's spelling
    let given = [
        ("demosaic", args.demosaic.text.as_str()),
        ("tone", args.tone.text.as_str()),
        ("opcodes", args.opcodes.text.as_str()),
    ];
    if let Some(c) = day2night::isp::release::conflicts(given) {
        let (flag, value, own) = (c.option, c.value, c.own);
        return Some(format!(
            "--{flag} {value}: --isp release uses --{flag} {own} (leave it out)"
        ));
    }
    let refused = [
        ("--camera-rgb", args.camera_rgb),
        ("--no-crop", args.no_crop),
        ("--bits 16", args.bits == Some(16)),
    ];
    refused
        .iter()
        .find(|(_, set)| *set)
        .map(|(flag, _)| format!("{flag}: --isp release renders as the release does (its own crop, 8-bit PNG or linear EXR)"))
}

/// `render --isp release`: the release's 8-bit PNG, or its linear sRGB as EXR.
fn run_release(args: &RenderArgs) -> CmdResult {
    if let Some(msg) = release_conflicts(args) {
        return Err(usage(msg));
    }
    let (format, _) = output_format(args)?;
    if matches!(format, Format::Tiff) {
        return Err(usage(format!(
            "{}: --isp release writes .png (the release's 8-bit render) or .exr",
            args.output.display()
        )));
    }
    let (neutral, compression, zip_level) = neutral_and_exr(args)?;
    let (policy, img) = policy_and_input(args)?;
    let in_file = |e: day2night::Error| lib(e.in_file(&args.input));
    // The white balance is resolved (or refused) before any pixel work.
    let meta = day2night::isp::release::ReleaseMeta::of(&img, neutral).map_err(in_file)?;
    let (orient, neutral) = (!args.no_orient, Some(meta.neutral));
    match format {
        Format::Exr => {
            let r = day2night::isp::release::render_f32(&img, neutral, orient).map_err(in_file)?;
            super::warn_all(&args.input, &r.warnings);
            let mut attrs = standard_attributes(&args.input, meta.neutral);
            attrs.push(("day2night:isp".into(), "release".into()));
            attrs.push((
                "day2night:content".into(),
                "the release's linear sRGB (before its gamma and s-curve)".into(),
            ));
            let opts = ExrOptions {
                half: !args.float,
                compression,
                zip_level,
            };
            let rgb = r.image.into_rgb_image();
            write_exr(&rgb, &args.output, &opts, &attrs, &policy).map_err(lib)
        }
        _ => {
            let r = day2night::isp::release::render_u8(&img, neutral, orient).map_err(in_file)?;
            super::warn_all(&args.input, &r.warnings);
            day2night::encode::png_rows::write_png_rgb8(
                &r.image.data,
                r.image.width,
                r.image.height,
                DisplayTone::Release,
                &args.output,
                &policy,
            )
            .map_err(lib)
        }
    }
}

/// Render band by band into the files `open` makes once the output size is known (`synth`'s
/// target writer); false when the render cannot be made in bands (Menon, a TrimBounds in
/// OpcodeList3, a LinearRaw network input): nothing was written then. On an
/// error the unfinished file is removed.
fn stream<'p>(
    img: &day2night::raw::RawImage,
    opts: &RenderOptions,
    policy: &'p OutputPolicy,
    flat: &day2night::isp::flat::FlatCheck,
    open: impl FnOnce((usize, usize), &'p OutputPolicy) -> day2night::Result<TargetFiles<'p>>,
) -> day2night::Result<bool> {
    let files = std::sync::OnceLock::new();
    let start = |w: usize, h: usize| {
        let f = open((w, h), policy)?;
        files
            .set(f)
            .map_err(|_| day2night::Error::invalid("the render was started twice"))
    };
    let band = |y0: usize, w: usize, rows: &[f32]| match files.get() {
        Some(f) => {
            flat.rows(rows);
            f.band(y0, w, rows)
        }
        None => Err(day2night::Error::invalid(
            "a band came before the render started",
        )),
    };
    let made = render_bands(img, opts, start, band)?;
    match (made, files.get()) {
        (Some(_), Some(f)) => f.finish().map(|_| true),
        _ => Ok(false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neutral_parsing() {
        assert_eq!(parse_neutral("0.5, 1,0.7").unwrap(), [0.5, 1.0, 0.7]);
        assert!(parse_neutral("0.5,1").is_err());
        assert!(parse_neutral("0.5,0,1").is_err());
        assert!(parse_neutral("a,b,c").is_err());
    }
}
