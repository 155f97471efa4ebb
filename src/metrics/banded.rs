//! `day2night eval` band by band: PSNR, SSIM and mean Delta E 2000 of two images read a band
//! of rows at a time ([`BandSource`]), so that memory grows with the band, not the image
//! (two 134-megapixel EXRs stay well under 2 GiB). Each band of `band_rows` rows is read
//! with the `window - 1` rows below it that SSIM's window needs; sums are accumulated in f64
//! and divided at the end, which equals the whole-image computation up to the order of the
//! floating-point additions (tested within 1e-12 relative).

use super::deltae::mean_delta_e_2000;
use super::ssim::{check_ssim, plane, ssim_channel_sum, window_len, SsimOptions};
use crate::color::srgb::oetf as srgb_oetf;
use crate::encode::read::BandSource;
use crate::error::{Error, Result};
use crate::isp::RgbImage;

/// Default rows per band.
pub const DEFAULT_BAND_ROWS: usize = 256;

/// What `eval` reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvalResult {
    /// PSNR in dB (infinite for identical images).
    pub psnr: f64,
    /// Mean SSIM over channels.
    pub ssim: f64,
    /// Mean CIEDE2000.
    pub delta_e_2000: f64,
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// NaN/Inf samples replaced (pred, target).
    pub non_finite: [usize; 2],
}

/// Evaluate `pred` against `target` in bands of `band_rows` rows (see the module docs).
/// Replace every NaN or infinite sample by 0; the number replaced.
pub fn zero_non_finite(img: &mut RgbImage) -> usize {
    let mut n = 0;
    for v in img.data.iter_mut().filter(|v| !v.is_finite()) {
        *v = 0.0;
        n += 1;
    }
    n
}

/// Non-finite samples (NaN, +-Inf) are replaced by 0 and counted (`eval` refuses them unless
/// `--nonfinite zero`, see [`EvalResult::non_finite`]).
pub fn evaluate(
    pred: &BandSource,
    target: &BandSource,
    opts: &SsimOptions,
    band_rows: usize,
) -> Result<EvalResult> {
    let (w, h) = (pred.width(), pred.height());
    if (w, h) != (target.width(), target.height()) {
        return Err(Error::invalid(format!(
            "image sizes differ: {}x{} vs {}x{}",
            w,
            h,
            target.width(),
            target.height()
        )));
    }
    if w == 0 || h == 0 {
        return Err(Error::invalid("empty images"));
    }
    check_ssim(w, h, opts)?;
    let band_rows = band_rows.max(1);
    let k = window_len(opts.window);
    let (pl, tl) = (pred.linear(), target.linear());
    let mut non_finite = [0usize; 2];
    let (mut se, mut de_sum) = (0.0f64, 0.0f64);
    let mut ssim_sum = [0.0f64; 3];
    let mut ssim_n = 0usize;
    let mut y0 = 0;
    while y0 < h {
        let y1 = (y0 + band_rows).min(h);
        // Rows y0..y1 plus the k - 1 below them for SSIM's window.
        let yin = (y1 + k - 1).min(h);
        let mut a = pred.rows(y0, yin)?;
        let mut b = target.rows(y0, yin)?;
        non_finite[0] += zero_non_finite(&mut a);
        non_finite[1] += zero_non_finite(&mut b);
        let own = |img: &RgbImage| RgbImage {
            width: w,
            height: y1 - y0,
            data: img.data[..3 * w * (y1 - y0)].to_vec(),
        };
        // Delta E on the band's own rows, each image decoded from its own encoding.
        let (ao, bo) = (own(&a), own(&b));
        de_sum += mean_delta_e_2000(&ao, &bo, pl, tl)? * (w * (y1 - y0)) as f64;
        drop((ao, bo));
        if pl != tl {
            let enc = |img: &mut RgbImage| {
                img.data
                    .iter_mut()
                    .for_each(|v| *v = srgb_oetf(v.clamp(0.0, 1.0)))
            };
            if pl {
                enc(&mut a)
            } else {
                enc(&mut b)
            }
        }
        se += a.data[..3 * w * (y1 - y0)]
            .iter()
            .zip(&b.data[..3 * w * (y1 - y0)])
            .map(|(&p, &t)| {
                let d = p as f64 - t as f64;
                d * d
            })
            .sum::<f64>();
        let hb = yin - y0;
        if hb >= k {
            for (c, acc) in ssim_sum.iter_mut().enumerate() {
                let (s, n) = ssim_channel_sum(&plane(&a, c), &plane(&b, c), w, hb, opts);
                *acc += s;
                if c == 0 {
                    ssim_n += n;
                }
            }
        }
        y0 = y1;
    }
    let range = opts.data_range;
    let mse = se / (3 * w * h) as f64;
    Ok(EvalResult {
        psnr: 10.0 * (range * range / mse).log10(),
        ssim: ssim_sum.iter().map(|s| s / ssim_n as f64).sum::<f64>() / 3.0,
        delta_e_2000: de_sum / (w * h) as f64,
        width: w,
        height: h,
        non_finite,
    })
}
