//! Dimming (docs/synthesis.md, "3. Dim"): `y_e = y_w * s`. This file draws `s` (the plan's
//! [`DimPlan`]); the multiplication runs in the fused row pass of synth/relight.rs (the
//! stage `dim` of the sidecar).
//!
//! Default (released code): `s ~ U(0.55, 0.90)`. With a brightness dictionary: a target mean
//! intensity is drawn from the dictionary's fitted normal distribution (redrawn until it lies
//! in (0, 1], bounded tries) and `s = target / mean(y_w)` is computed when the plan runs
//! (`s = 1` for an all-black frame, whose mean is 0).

use super::dictionaries::BrightnessDict;
use super::rng::SynthRng;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// The dimming of a plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum DimPlan {
    /// No dimming (mode `day`).
    None,
    /// A fixed factor `s`, drawn uniformly in `range`.
    Uniform {
        /// The factor.
        s: f64,
        /// The range it was drawn from.
        range: [f64; 2],
    },
    /// Scale so that the mean white-balanced intensity equals `target_mean`.
    TargetMean {
        /// Target mean normalized intensity.
        target_mean: f64,
        /// Dictionary it was drawn from.
        dictionary: String,
    },
}

/// Draw the dimming.
pub fn sample_dim(
    rng: &mut SynthRng,
    range: [f64; 2],
    brightness: Option<&BrightnessDict>,
) -> Result<DimPlan> {
    match brightness {
        None => {
            if !(range[0] > 0.0 && range[0] <= range[1] && range[1].is_finite()) {
                return Err(Error::invalid(format!(
                    "dimming range [{}, {}] must satisfy 0 < lo <= hi",
                    range[0], range[1]
                )));
            }
            Ok(DimPlan::Uniform {
                s: rng.range(range[0], range[1]),
                range,
            })
        }
        Some(d) => {
            for _ in 0..1000 {
                let t = d.mean + d.std * rng.normal();
                if t > 0.0 && t <= 1.0 {
                    return Ok(DimPlan::TargetMean {
                        target_mean: t,
                        dictionary: d.name.clone(),
                    });
                }
            }
            Err(Error::invalid(format!(
                "could not draw a brightness in (0, 1] from dictionary {} (mean {}, std {})",
                d.name, d.mean, d.std
            )))
        }
    }
}

/// What the whole-frame mean `mean(y_w)` of a clean pass depends on besides the image:
/// the plan's day neutral and its range settings (`day_neutral`, `keep_negative`,
/// `keep_highlights`, `range_per_site`; the neutral as bit patterns).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeanKey {
    day_neutral: [u64; 3],
    keep_negative: bool,
    keep_highlights: bool,
    range_per_site: bool,
}

impl MeanKey {
    /// The key of a clean pass with these settings (a plan's: `Plan::mean_key`).
    pub fn new(
        day_neutral: [f64; 3],
        keep_negative: bool,
        keep_highlights: bool,
        range_per_site: bool,
    ) -> MeanKey {
        MeanKey {
            day_neutral: day_neutral.map(f64::to_bits),
            keep_negative,
            keep_highlights,
            range_per_site,
        }
    }
}

/// A plan's memo of its image's `mean(y_w)` (`Plan::frame_mean`), with the
/// key it was computed under: used only while the plan's key is still the same. It takes
/// no part in comparing plans (two plans that differ only here are equal).
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameMean(Option<(MeanKey, f64)>);

impl FrameMean {
    /// The memo of `mean`, computed under `key`.
    pub fn new(key: MeanKey, mean: f64) -> FrameMean {
        FrameMean(Some((key, mean)))
    }

    /// The memo, if it was computed under `key`.
    pub fn get(&self, key: MeanKey) -> Option<f64> {
        self.0.filter(|(k, _)| *k == key).map(|(_, m)| m)
    }
}

impl PartialEq for FrameMean {
    fn eq(&self, _: &FrameMean) -> bool {
        true
    }
}

/// The factor `s` of a plan given the mean white-balanced intensity of the image.
pub fn dim_factor(dim: &DimPlan, mean_y_w: impl FnOnce() -> f64) -> f64 {
    match dim {
        DimPlan::None => 1.0,
        DimPlan::Uniform { s, .. } => *s,
        DimPlan::TargetMean { target_mean, .. } => {
            let m = mean_y_w();
            if m > 0.0 && m.is_finite() {
                target_mean / m
            } else {
                1.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_in_range_and_target() {
        let mut rng = SynthRng::new(0, "d", 0);
        for _ in 0..1000 {
            match sample_dim(&mut rng, [0.55, 0.9], None).unwrap() {
                DimPlan::Uniform { s, .. } => assert!((0.55..0.9).contains(&s)),
                _ => panic!(),
            }
        }
        assert!(sample_dim(&mut rng, [0.0, 0.9], None).is_err());
        let d = BrightnessDict {
            name: "b".into(),
            mean: 0.05,
            std: 0.02,
            count: 3,
        };
        let p = sample_dim(&mut rng, [0.55, 0.9], Some(&d)).unwrap();
        let s = dim_factor(&p, || 0.5);
        match p {
            DimPlan::TargetMean { target_mean, .. } => {
                assert!((s - target_mean / 0.5).abs() < 1e-15)
            }
            _ => panic!(),
        }
        assert_eq!(dim_factor(&p, || 0.0), 1.0);
        let bad = BrightnessDict {
            name: "neg".into(),
            mean: -5.0,
            std: 0.0,
            count: 1,
        };
        assert!(sample_dim(&mut rng, [0.55, 0.9], Some(&bad))
            .unwrap_err()
            .to_string()
            .contains("neg"));
    }
}
