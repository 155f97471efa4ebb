//! Calibration dictionaries: night illuminants (gray-card chromaticities) and night
//! brightness, from JSON files or the embedded default ([`embedded`]).
//!
//! Accepted illuminant files (JSON object, first key found wins):
//! - `"illuminants_rgb_over_g"`, `"illuminants"` or `"chromaticities"`: a list of
//!   `[r/g, 1, b/g]` (or any `[r, g, b]`, divided by g) or `[r/g, b/g]` entries;
//! - `"mean": [r/g, b/g]` with `"covariance": [[..],[..]]`: a fitted Gaussian directly.
//!
//! - an xy dictionary of lamp chromaticities (`"xy"` or `"lamps"`), camera-independent, and
//!   the camera a file was measured on (`"camera"`): see [`xy`].
//!
//! Accepted brightness files: `"values"`, `"mean_intensities"` or `"brightness"`: a list of
//! mean normalized intensities of real night raws (0..1], or `"mean"` with `"std"`.

pub mod cie_lamps;
pub mod embedded;
pub mod xy;

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;

/// A night illuminant dictionary: chromaticities `[r/g, b/g]` of one camera, optionally
/// weighted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IlluminantDict {
    /// Name used in messages (file path or "embedded ...").
    pub name: String,
    /// Provenance / attribution.
    pub source: String,
    /// The chromaticities.
    pub chromaticities: Vec<[f64; 2]>,
    /// One weight per chromaticity (a count of gray cards), or empty for weight 1 each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub weights: Vec<f64>,
}

/// An illuminant file's camera-RGB part reduced to what the sampler needs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum IlluminantSource {
    /// Chromaticities to fit.
    Dict(IlluminantDict),
    /// A Gaussian given by the file: (name, mean, covariance).
    Gaussian(String, [f64; 2], [[f64; 2]; 2]),
}

// File size, entry counts, illuminant ratios (r/g, b/g within [1/MAX_NEUTRAL_RATIO,
// MAX_NEUTRAL_RATIO]) and Gaussian parameters (within +-MAX_CHROMA): the one table.
pub use crate::bounds::{
    read_calibration_text, MAX_CALIBRATION_FILE_BYTES, MAX_CHROMA, MAX_DICT_ENTRIES,
    MAX_NEUTRAL_RATIO,
};

fn check_count(key: &str, n: usize) -> Result<()> {
    crate::bounds::count(key, n, MAX_DICT_ENTRIES)
}

fn read_json(path: &Path) -> Result<Value> {
    let text = read_calibration_text(path)?;
    serde_json::from_str(&text).map_err(|e| Error::malformed(format!("JSON: {}", e)).in_file(path))
}

fn num(v: &Value, what: &str) -> Result<f64> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| Error::malformed(format!("{}: {} is not a finite number", what, v)))
}

fn pair(v: &Value, what: &str) -> Result<[f64; 2]> {
    match v.as_array().map(|a| a.as_slice()) {
        Some([a, b]) => Ok([num(a, what)?, num(b, what)?]),
        _ => Err(Error::malformed(format!("{}: expected two numbers", what))),
    }
}

/// Parse an illuminant dictionary JSON value (see the module docs).
pub fn parse_illuminants(name: &str, v: &Value) -> Result<IlluminantSource> {
    for key in ["illuminants_rgb_over_g", "illuminants", "chromaticities"] {
        if let Some(list) = v.get(key).and_then(|l| l.as_array()) {
            check_count(key, list.len())?;
            let mut out = Vec::with_capacity(list.len());
            for (i, e) in list.iter().enumerate() {
                let what = format!("{}[{}]", key, i);
                let a = e
                    .as_array()
                    .ok_or_else(|| Error::malformed(format!("{}: not a list", what)))?;
                let c = match a.as_slice() {
                    [r, b] => [num(r, &what)?, num(b, &what)?],
                    [r, g, b] => {
                        let g = num(g, &what)?;
                        if g <= 0.0 {
                            return Err(Error::malformed(format!("{}: green <= 0", what)));
                        }
                        [num(r, &what)? / g, num(b, &what)? / g]
                    }
                    _ => {
                        return Err(Error::malformed(format!(
                            "{}: expected [r/g, b/g] or [r, g, b]",
                            what
                        )))
                    }
                };
                crate::bounds::ratios(&format!("{what} (r/g, b/g)"), &c, MAX_NEUTRAL_RATIO)
                    .map_err(crate::bounds::malformed)?;
                out.push(c);
            }
            if out.is_empty() {
                return Err(Error::malformed(format!("{}: no illuminants", key)));
            }
            let source = v
                .get("source")
                .and_then(|s| s.as_str())
                .unwrap_or("")
                .to_string();
            return Ok(IlluminantSource::Dict(IlluminantDict {
                name: name.to_string(),
                source,
                chromaticities: out,
                weights: Vec::new(),
            }));
        }
    }
    if let (Some(m), Some(c)) = (v.get("mean"), v.get("covariance").or_else(|| v.get("cov"))) {
        let mean = pair(m, "mean")?;
        let rows = c
            .as_array()
            .filter(|r| r.len() == 2)
            .ok_or_else(|| Error::malformed("covariance: expected a 2x2 matrix"))?;
        let cov = [pair(&rows[0], "covariance")?, pair(&rows[1], "covariance")?];
        let all = [mean[0], mean[1], cov[0][0], cov[0][1], cov[1][0], cov[1][1]];
        for (name, x) in [
            "mean[0]",
            "mean[1]",
            "covariance[0][0]",
            "covariance[0][1]",
            "covariance[1][0]",
            "covariance[1][1]",
        ]
        .iter()
        .zip(all)
        {
            crate::bounds::in_range(name, x, -MAX_CHROMA, MAX_CHROMA)
                .map_err(crate::bounds::malformed)?;
        }
        if !(cov[0][0] > 0.0 && cov[1][1] > 0.0) {
            return Err(Error::malformed(
                "covariance: the variances (diagonal) must be > 0",
            ));
        }
        return Ok(IlluminantSource::Gaussian(name.to_string(), mean, cov));
    }
    Err(Error::malformed(
        "no illuminant list (illuminants_rgb_over_g / illuminants / chromaticities), \
         mean+covariance, or xy dictionary (xy / lamps)",
    ))
}

/// Read an illuminant dictionary file.
pub fn load_illuminants(path: &Path) -> Result<IlluminantSource> {
    let v = read_json(path)?;
    parse_illuminants(&path.display().to_string(), &v).map_err(|e| e.in_file(path))
}

/// A night brightness dictionary reduced to a normal distribution of target mean intensities.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BrightnessDict {
    /// Name (file path).
    pub name: String,
    /// Mean of the normalized night intensities.
    pub mean: f64,
    /// Standard deviation (unbiased when fitted from values; 0 with one value).
    pub std: f64,
    /// Number of values fitted (0 when the file gave mean and std). Draws are kept in (0, 1].
    pub count: usize,
}

/// Parse a brightness dictionary JSON value.
pub fn parse_brightness(name: &str, v: &Value) -> Result<BrightnessDict> {
    for key in ["values", "mean_intensities", "brightness"] {
        if let Some(list) = v.get(key).and_then(|l| l.as_array()) {
            check_count(key, list.len())?;
            let vals = list
                .iter()
                .map(|x| num(x, key))
                .collect::<Result<Vec<f64>>>()?;
            if vals.is_empty() {
                return Err(Error::malformed(format!("{}: empty", key)));
            }
            if let Some((i, x)) = vals
                .iter()
                .enumerate()
                .find(|(_, &x)| !(x > 0.0 && x <= 1.0))
            {
                return Err(Error::malformed(format!(
                    "{key}[{i}]: {} is outside (0, 1] (normalized intensities)",
                    crate::bounds::short(*x)
                )));
            }
            let n = vals.len() as f64;
            let mean = vals.iter().sum::<f64>() / n;
            let std = if vals.len() > 1 {
                (vals.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            } else {
                0.0
            };
            return Ok(BrightnessDict {
                name: name.into(),
                mean,
                std,
                count: vals.len(),
            });
        }
    }
    if let (Some(m), Some(s)) = (v.get("mean"), v.get("std")) {
        let (mean, std) = (num(m, "mean")?, num(s, "std")?);
        if !(mean > 0.0 && mean <= 1.0) {
            return Err(Error::malformed(format!(
                "brightness mean: {} is outside (0, 1]",
                crate::bounds::short(mean)
            )));
        }
        crate::bounds::in_range("brightness std", std, 0.0, 1.0)
            .map_err(crate::bounds::malformed)?;
        return Ok(BrightnessDict {
            name: name.into(),
            mean,
            std,
            count: 0,
        });
    }
    Err(Error::malformed(
        "no brightness values (values / mean_intensities / brightness) or mean+std",
    ))
}

/// Read a brightness dictionary file.
pub fn load_brightness(path: &Path) -> Result<BrightnessDict> {
    let v = read_json(path)?;
    parse_brightness(&path.display().to_string(), &v).map_err(|e| e.in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_illuminant_ratios_and_gaussians_are_refused_naming_the_field() {
        let err = |json: &str| {
            let v: Value = serde_json::from_str(json).unwrap();
            parse_illuminants("x", &v).unwrap_err().to_string()
        };
        let e = err(r#"{"illuminants_rgb_over_g": [[0.5, 1.0, 0.3], [1e6, 1.0, 1.0]]}"#);
        assert!(
            e.contains("illuminants_rgb_over_g[1] (r/g, b/g)[0]: 1e6 is outside [0.001, 1000]"),
            "{e}"
        );
        let e = err(r#"{"illuminants": [[1e-4, 0.5]]}"#);
        assert!(
            e.contains("illuminants[0] (r/g, b/g)[0]: 1e-4 is outside"),
            "{e}"
        );
        // At the bound: used.
        let v: Value = serde_json::from_str(r#"{"illuminants": [[1e3, 1e-3]]}"#).unwrap();
        assert!(parse_illuminants("x", &v).is_ok());
        let e = err(r#"{"mean": [2000, 0.3], "covariance": [[0.1, 0], [0, 0.1]]}"#);
        assert!(e.contains("mean[0]: 2000 is outside [-1000, 1000]"), "{e}");
    }

    #[test]
    fn parses_release_style_and_pairs_and_gaussian() {
        let v: Value = serde_json::from_str(
            r#"{"illuminants_rgb_over_g": [[0.5, 1.0, 0.3], [1.0, 2.0, 0.8]]}"#,
        )
        .unwrap();
        match parse_illuminants("x", &v).unwrap() {
            IlluminantSource::Dict(d) => assert_eq!(d.chromaticities, vec![[0.5, 0.3], [0.5, 0.4]]),
            _ => panic!(),
        }
        let v: Value =
            serde_json::from_str(r#"{"mean": [0.7, 0.3], "covariance": [[0.01, 0], [0, 0.01]]}"#)
                .unwrap();
        assert!(matches!(
            parse_illuminants("x", &v).unwrap(),
            IlluminantSource::Gaussian(..)
        ));
        let v: Value = serde_json::from_str(r#"{"illuminants": []}"#).unwrap();
        assert!(parse_illuminants("x", &v).is_err());
        let v: Value = serde_json::from_str(r#"{"illuminants": [[1, 0, 1]]}"#).unwrap();
        assert!(parse_illuminants("x", &v).is_err());
    }

    #[test]
    fn brightness_fit() {
        let v: Value = serde_json::from_str(r#"{"values": [0.1, 0.2, 0.3]}"#).unwrap();
        let b = parse_brightness("b", &v).unwrap();
        assert!((b.mean - 0.2).abs() < 1e-12 && (b.std - 0.1).abs() < 1e-12);
        let v: Value = serde_json::from_str(r#"{"values": [0.1, 2.0]}"#).unwrap();
        assert!(parse_brightness("b", &v).is_err());
    }
}
