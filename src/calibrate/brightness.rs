//! Night brightness dictionary (docs/synthesis.md, "3. Dim": the paper's dictionary D): the normalized
//! mean intensity of each real night raw (active area, the shared normalize path, negatives
//! clipped at 0 as in step 1), and the normal fit `N(mean, std^2)` (unbiased std) that
//! `synth --brightness` samples target means from (draws outside (0, 1] are redrawn), computed
//! by synth's own reader. With one image `std = 0` (always that brightness): a documented
//! fallback, reported as a warning.

use super::format::{
    BrightnessDictionary, BrightnessFit, BrightnessMeasurement, BRIGHTNESS_FORMAT,
};
use crate::error::{Error, Result};
use crate::normalize::{normalize, NormalizeOptions};
use crate::raw::RawImage;
use crate::synth::dictionaries::parse_brightness;

/// Normalized mean intensity of one night image.
pub fn measure(img: &RawImage, file: &str) -> Result<BrightnessMeasurement> {
    let p = normalize(img, NormalizeOptions::default())?;
    let n = p.data.len().max(1) as f64;
    let mean = p.data.iter().map(|&v| v as f64).sum::<f64>() / n;
    if !(mean > 0.0 && mean.is_finite()) {
        return Err(Error::invalid(format!(
            "normalized mean intensity is {mean:e}: the image is black (nothing above the black level)"
        )));
    }
    Ok(BrightnessMeasurement {
        file: file.to_string(),
        mean,
        iso: img.meta.exif.iso,
        exposure_time: img.meta.exif.exposure_time,
    })
}

/// The normal fit synth samples from, computed by synth's own reader
/// ([`parse_brightness`]) so that the file and the sampler agree; plus min/max.
pub fn fit(values: &[f64]) -> Result<BrightnessFit> {
    let b = parse_brightness(
        "calibrate brightness",
        &serde_json::json!({ "values": values }),
    )
    .map_err(|e| Error::invalid(e.root().to_string()))?;
    Ok(BrightnessFit {
        distribution: "normal, truncated to (0, 1]".into(),
        mean: b.mean,
        std: b.std,
        min: values.iter().cloned().fold(f64::INFINITY, f64::min),
        max: values.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        count: b.count,
    })
}

/// Assemble the dictionary file.
pub fn build_dictionary(files: Vec<BrightnessMeasurement>) -> Result<BrightnessDictionary> {
    let values: Vec<f64> = files.iter().map(|f| f.mean).collect();
    Ok(BrightnessDictionary {
        format: BRIGHTNESS_FORMAT.into(),
        what: "Night brightness dictionary D: normalized mean intensity of real night raws (active area, black-subtracted, divided by white - black), with the normal fit synth samples target means from (draws kept in (0, 1])".into(),
        fit: fit(&values)?,
        values,
        files,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::Bayer;

    #[test]
    fn mean_and_fit() {
        let meta = RawMeta::new_bayer(Bayer::RGGB, 10, 64.0, 1023.0);
        let img = RawImage {
            width: 4,
            height: 2,
            data: vec![64, 64 + 959, 0, 64 + 959, 64, 64, 64, 64],
            meta,
        };
        // (0 + 1 + 0 (clipped) + 1) / 8
        let m = measure(&img, "a").unwrap();
        assert!((m.mean - 0.25).abs() < 1e-9, "{m:?}");
        let f = fit(&[0.01, 0.1]).unwrap();
        assert!((f.mean - 0.055).abs() < 1e-12);
        assert!((f.std - 0.09 / 2f64.sqrt()).abs() < 1e-12);
        let one = fit(&[0.05]).unwrap();
        assert_eq!((one.std, one.count), (0.0, 1));
        assert!(fit(&[]).is_err() && fit(&[0.0]).is_err());
    }

    #[test]
    fn black_image_is_an_error() {
        let meta = RawMeta::new_bayer(Bayer::RGGB, 10, 64.0, 1023.0);
        let img = RawImage {
            width: 2,
            height: 2,
            data: vec![60; 4],
            meta,
        };
        assert!(measure(&img, "a")
            .unwrap_err()
            .to_string()
            .contains("black"));
    }
}
