//! `day2night eval PRED TARGET [--json]`: PSNR, SSIM and mean Delta E 2000.
use super::args::{choice, lib, Typed};
use super::{usage, CmdResult};
use day2night::encode::read::open_bands;
use day2night::metrics::banded::{evaluate, DEFAULT_BAND_ROWS};
use day2night::metrics::{NonFinite, SsimOptions, SsimWindow};
use std::path::PathBuf;

/// Arguments of `day2night eval`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "PNG/TIFF integers are read as display sRGB in [0, 1], EXR and float \
TIFF as linear light. When one image is linear and the other display-encoded, the linear one \
is sRGB-encoded (clipped to [0, 1]) for PSNR and SSIM; Delta E always decodes each image to \
linear sRGB -> XYZ -> Lab (D65). SSIM is scikit-image's default (7x7 uniform window, sample \
covariance); --ssim-window gaussian gives Wang et al. 2004's 11x11 Gaussian. PSNR of identical \
images is infinite (null in JSON). NaN or Inf samples in either image are an error (naming the \
file and the count) unless --nonfinite zero, which replaces them by 0 with a warning and says so \
in the JSON.\n\n\
Examples:\n  day2night eval pred.png target.png\n  day2night eval out.exr ref.exr --json"
)]
pub struct EvalArgs {
    /// Predicted image (PNG, TIFF or EXR).
    #[arg(value_name = "PRED")]
    pub pred: PathBuf,
    /// Reference image (PNG, TIFF or EXR).
    #[arg(value_name = "TARGET")]
    pub target: PathBuf,
    /// Print JSON {"psnr", "ssim", "delta_e_2000", ...} instead of text.
    #[arg(long)]
    pub json: bool,
    /// Data range for PSNR and SSIM.
    #[arg(long, default_value_t = 1.0, value_name = "R")]
    pub data_range: f64,
    /// SSIM window (uniform: scikit-image's; gaussian: Wang et al. 2004's).
    #[arg(long, default_value_t = Typed::<SsimWindow>::default(), value_parser = choice::<SsimWindow>(), value_name = "W")]
    pub ssim_window: Typed<SsimWindow>,
    /// NaN/Inf samples: refused, naming the file and the count, or replaced by 0 with a
    /// warning (the JSON says so).
    #[arg(long, default_value_t = Typed::<NonFinite>::default(), value_parser = choice::<NonFinite>(), value_name = "MODE")]
    pub nonfinite: Typed<NonFinite>,
}

/// Run `day2night eval`.
pub fn run(args: EvalArgs) -> CmdResult {
    let window = args.ssim_window.value;
    let zero = args.nonfinite.value == NonFinite::Zero;
    if !(args.data_range.is_finite() && args.data_range > 0.0) {
        return Err(usage(format!(
            "--data-range {}: must be positive",
            args.data_range
        )));
    }
    let p = open_bands(&args.pred).map_err(lib)?;
    let t = open_bands(&args.target).map_err(lib)?;
    if (p.width(), p.height()) != (t.width(), t.height()) {
        return Err(anyhow::anyhow!(
            "{}: size {}x{} differs from {} ({}x{})",
            args.pred.display(),
            p.width(),
            p.height(),
            args.target.display(),
            t.width(),
            t.height()
        )
        .into());
    }
    // Band by band: memory grows with the band, not the image (docs/limits.md).
    let r = evaluate(
        &p,
        &t,
        &SsimOptions {
            data_range: args.data_range,
            window,
        },
        DEFAULT_BAND_ROWS,
    )
    .map_err(lib)?;
    let mut warnings = day2night::Diagnostics::new();
    for (path, n) in [
        (&args.pred, r.non_finite[0]),
        (&args.target, r.non_finite[1]),
    ] {
        if n > 0 && !zero {
            return Err(super::Failure {
                code: 1,
                error: anyhow::anyhow!(
                    "{}: {n} NaN/Inf samples: metrics would be meaningless (use \
                     --nonfinite zero to replace them by 0)",
                    path.display()
                ),
            });
        }
        if n > 0 {
            let w = day2night::Warning::new(
                day2night::Code::NonfiniteReplaced,
                format!("{n} NaN/Inf samples replaced by 0 (--nonfinite zero)"),
            )
            .about(path.display().to_string());
            super::warn(&w, "");
            warnings.push(w);
        }
    }
    let (ps, ss, de) = (r.psnr, r.ssim, r.delta_e_2000);
    let a = &r;
    if args.json {
        let mut v = serde_json::json!({
            "psnr": if ps.is_finite() { Some(ps) } else { None },
            "ssim": ss,
            "delta_e_2000": de,
            "pred": args.pred.display().to_string(),
            "target": args.target.display().to_string(),
            "width": a.width,
            "height": a.height,
            "data_range": args.data_range,
            "ssim_window": window.name(),
            "nonfinite": args.nonfinite.value.name(),
            "nonfinite_replaced": r.non_finite,
        });
        // The warnings with their codes, when there are any.
        if !warnings.is_empty() {
            v["warnings"] = serde_json::to_value(&warnings)?;
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("psnr: {ps:.4} dB");
        println!("ssim: {ss:.6}");
        println!("delta_e_2000: {de:.4}");
    }
    Ok(())
}
