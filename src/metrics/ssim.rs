//! Structural similarity (Wang, Bovik, Sheikh, Simoncelli 2004).
//!
//! Default: exactly scikit-image's `structural_similarity(im1, im2, channel_axis=-1,
//! data_range=R)`: a 7x7 uniform window, sample covariances (normalised by N - 1, N = 49),
//! K1 = 0.01, K2 = 0.03, the SSIM map cropped by (7 - 1) / 2 = 3 pixels on every side
//! (so the filter's border mode never matters), the mean over the cropped map, then the
//! mean over channels. Option: the paper's Gaussian window (sigma 1.5, truncated at 3.5
//! sigma = 11x11, population covariances), as skimage's `gaussian_weights=True,
//! sigma=1.5, use_sample_covariance=False`.

use super::check_same_size;
use crate::error::{Error, Result};
use crate::isp::RgbImage;
use rayon::prelude::*;

/// Window of the local statistics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SsimWindow {
    /// 7x7 uniform window with sample covariance (scikit-image default).
    #[default]
    Uniform7,
    /// 11x11 Gaussian window, sigma 1.5, population covariance (Wang et al. 2004).
    Gaussian,
}

impl SsimWindow {
    /// Both windows.
    pub const ALL: [SsimWindow; 2] = [SsimWindow::Uniform7, SsimWindow::Gaussian];
}

crate::choices! {
    SsimWindow, ignore_case: true,
    unknown: |s| Error::invalid(format!(
        "SSIM window {s:?}: use {}",
        crate::choice::listed::<SsimWindow>(", ", " or ")
    )),
    Uniform7 => "uniform": "7x7 uniform window, sample covariance (scikit-image)",
    Gaussian => "gaussian": "11x11 Gaussian, sigma 1.5 (Wang et al. 2004)",
}

/// SSIM parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SsimOptions {
    /// Dynamic range of the data (1 for images in [0, 1]).
    pub data_range: f64,
    /// Window.
    pub window: SsimWindow,
}

impl Default for SsimOptions {
    fn default() -> Self {
        SsimOptions {
            data_range: 1.0,
            window: SsimWindow::Uniform7,
        }
    }
}

/// 1-D weights of the window.
fn weights(window: SsimWindow) -> Vec<f64> {
    match window {
        SsimWindow::Uniform7 => vec![1.0 / 7.0; 7],
        SsimWindow::Gaussian => {
            // scipy.ndimage.gaussian_filter, sigma 1.5, truncate 3.5: radius int(5.25 + 0.5)
            let sigma = 1.5f64;
            let radius = (3.5 * sigma + 0.5) as i64;
            let w: Vec<f64> = (-radius..=radius)
                .map(|x| (-0.5 * (x * x) as f64 / (sigma * sigma)).exp())
                .collect();
            let s: f64 = w.iter().sum();
            w.into_iter().map(|v| v / s).collect()
        }
    }
}

/// Separable weighted "valid" filtering of a `w x h` plane: output `(w-k+1) x (h-k+1)`.
fn filter_valid(p: &[f64], w: usize, h: usize, k: &[f64]) -> Vec<f64> {
    let n = k.len();
    let (ow, oh) = (w + 1 - n, h + 1 - n);
    // horizontal
    let mut tmp = vec![0.0; ow * h];
    tmp.par_chunks_mut(ow).enumerate().for_each(|(y, row)| {
        let src = &p[y * w..(y + 1) * w];
        for (x, o) in row.iter_mut().enumerate() {
            *o = k.iter().zip(&src[x..x + n]).map(|(a, b)| a * b).sum();
        }
    });
    let mut out = vec![0.0; ow * oh];
    out.par_chunks_mut(ow).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            *o = k
                .iter()
                .enumerate()
                .map(|(j, a)| a * tmp[(y + j) * ow + x])
                .sum();
        }
    });
    out
}

/// Mean SSIM of one channel.
fn ssim_channel(x: &[f64], y: &[f64], w: usize, h: usize, o: &SsimOptions) -> f64 {
    let (sum, n) = ssim_channel_sum(x, y, w, h, o);
    sum / n as f64
}

/// Side of the SSIM window (7 uniform, 11 Gaussian): a band of `n` output rows of the SSIM
/// map needs `n + window_len - 1` input rows.
pub fn window_len(window: SsimWindow) -> usize {
    weights(window).len()
}

/// Sum and count of the SSIM map of one channel plane `x`, `y` (`w` x `h`, `h` >= window):
/// the map's rows are those of the "valid" window positions, so a band of input rows gives
/// the map rows it fully contains.
pub(crate) fn ssim_channel_sum(
    x: &[f64],
    y: &[f64],
    w: usize,
    h: usize,
    o: &SsimOptions,
) -> (f64, usize) {
    let k = weights(o.window);
    let n = (k.len() * k.len()) as f64;
    let cov_norm = match o.window {
        SsimWindow::Uniform7 => n / (n - 1.0),
        SsimWindow::Gaussian => 1.0,
    };
    let prod = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(p, q)| p * q).collect() };
    let ux = filter_valid(x, w, h, &k);
    let uy = filter_valid(y, w, h, &k);
    let uxx = filter_valid(&prod(x, x), w, h, &k);
    let uyy = filter_valid(&prod(y, y), w, h, &k);
    let uxy = filter_valid(&prod(x, y), w, h, &k);
    let c1 = (0.01 * o.data_range).powi(2);
    let c2 = (0.03 * o.data_range).powi(2);
    let sum: f64 = (0..ux.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let (mx, my) = (ux[i], uy[i]);
            let vx = cov_norm * (uxx[i] - mx * mx);
            let vy = cov_norm * (uyy[i] - my * my);
            let vxy = cov_norm * (uxy[i] - mx * my);
            ((2.0 * mx * my + c1) * (2.0 * vxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum();
    (sum, ux.len())
}

/// Check the data range and window fit of an SSIM over a `w` x `h` image.
pub(crate) fn check_ssim(w: usize, h: usize, opts: &SsimOptions) -> Result<()> {
    if !(opts.data_range.is_finite() && opts.data_range > 0.0) {
        return Err(Error::invalid(format!(
            "data range {} must be positive",
            opts.data_range
        )));
    }
    let win = weights(opts.window).len();
    if w < win || h < win {
        return Err(Error::invalid(format!(
            "images of {w}x{h} are smaller than the {win}x{win} SSIM window"
        )));
    }
    Ok(())
}

/// One channel of an interleaved RGB image as f64.
pub(crate) fn plane(img: &RgbImage, c: usize) -> Vec<f64> {
    img.data
        .iter()
        .skip(c)
        .step_by(3)
        .map(|&v| v as f64)
        .collect()
}

/// Mean SSIM over channels of `pred` against `target`.
pub fn ssim(pred: &RgbImage, target: &RgbImage, opts: &SsimOptions) -> Result<f64> {
    check_same_size(pred, target)?;
    if !(opts.data_range.is_finite() && opts.data_range > 0.0) {
        return Err(Error::invalid(format!(
            "data range {} must be positive",
            opts.data_range
        )));
    }
    let win = weights(opts.window).len();
    let (w, h) = (pred.width, pred.height);
    if w < win || h < win {
        return Err(Error::invalid(format!(
            "images of {w}x{h} are smaller than the {win}x{win} SSIM window"
        )));
    }
    let mut total = 0.0;
    for c in 0..3 {
        let x: Vec<f64> = pred
            .data
            .iter()
            .skip(c)
            .step_by(3)
            .map(|&v| v as f64)
            .collect();
        let y: Vec<f64> = target
            .data
            .iter()
            .skip(c)
            .step_by(3)
            .map(|&v| v as f64)
            .collect();
        total += ssim_channel(&x, &y, w, h, opts);
    }
    Ok(total / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise_img(w: usize, h: usize, seed: u64, amp: f32) -> RgbImage {
        let mut s = seed;
        let mut img = RgbImage::new(w, h);
        for (i, v) in img.data.iter_mut().enumerate() {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let r = (s >> 33) as f32 / (1u64 << 31) as f32;
            *v = 0.5 + 0.3 * ((i / 3 % w) as f32 * 0.2).sin() + amp * (r - 0.5);
        }
        img
    }

    #[test]
    fn identical_is_one_and_noise_lowers_it() {
        let a = noise_img(20, 16, 1, 0.0);
        for window in [SsimWindow::Uniform7, SsimWindow::Gaussian] {
            let o = SsimOptions {
                data_range: 1.0,
                window,
            };
            assert!((ssim(&a, &a, &o).unwrap() - 1.0).abs() < 1e-12);
            let b = noise_img(20, 16, 2, 0.2);
            let s = ssim(&b, &a, &o).unwrap();
            assert!(s < 0.9 && s > 0.0, "{s}");
        }
        assert!(ssim(&a, &noise_img(20, 15, 1, 0.0), &SsimOptions::default()).is_err());
        assert!(ssim(
            &RgbImage::new(5, 5),
            &RgbImage::new(5, 5),
            &SsimOptions::default()
        )
        .is_err());
    }

    #[test]
    fn gaussian_weights_are_scipy_like() {
        let w = weights(SsimWindow::Gaussian);
        assert_eq!(w.len(), 11);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((w[5] - 0.2660).abs() < 1e-3, "{w:?}");
    }
}
