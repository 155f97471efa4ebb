//! Peak signal-to-noise ratio over all samples of all channels
//! (`skimage.metrics.peak_signal_noise_ratio` semantics).

use super::check_same_size;
use crate::error::{Error, Result};
use crate::isp::RgbImage;

/// PSNR in dB of `pred` against `target` for a given data range: `10 log10(range^2 / MSE)`.
/// Identical images give `f64::INFINITY`.
pub fn psnr(pred: &RgbImage, target: &RgbImage, data_range: f64) -> Result<f64> {
    check_same_size(pred, target)?;
    if !(data_range.is_finite() && data_range > 0.0) {
        return Err(Error::invalid(format!(
            "data range {data_range} must be positive"
        )));
    }
    let se: f64 = pred
        .data
        .iter()
        .zip(&target.data)
        .map(|(&a, &b)| {
            let d = a as f64 - b as f64;
            d * d
        })
        .sum();
    let mse = se / pred.data.len() as f64;
    Ok(10.0 * (data_range * data_range / mse).log10())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_value_and_errors() {
        let a = RgbImage::new(2, 2);
        let mut b = RgbImage::new(2, 2);
        b.data[0] = 0.1; // MSE = 0.01 / 12
        let p = psnr(&b, &a, 1.0).unwrap();
        assert!((p - 10.0 * (12.0f64 / 0.01).log10()).abs() < 1e-4, "{p}");
        assert_eq!(psnr(&a, &a, 1.0).unwrap(), f64::INFINITY);
        assert!(psnr(&a, &RgbImage::new(3, 2), 1.0).is_err());
        assert!(psnr(&a, &a, 0.0).is_err());
    }
}
