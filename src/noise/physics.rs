//! Physics-based noise model (docs/noise.md, "Physics-based model"; Wei et al. CVPR 2020 /
//! TPAMI 2021, Zhang et al. ICCV 2021), per ISO:
//!
//! `noisy = clip(round(black + K * Poisson((x - black) / K) + read + row), 0, white)`
//!
//! with `K` the system gain (DN per electron), `read` Tukey-lambda with shape `lambda` and
//! standard deviation `sigma_read` DN (Gaussian when `gaussian_read`), `row` one
//! `N(0, sigma_row^2)` offset per active-area row, and the rounding the quantization. The
//! parameters are common to the four CFA positions (gain and readout belong to the pixel,
//! not to its colour filter); the black level is per site.
//!
//! Between calibrated ISOs `a < t < b`: `K` linear in ISO; `ln sigma_read`, `ln sigma_row`
//! and `lambda` linear in `ln K` (the ELD joint model, piecewise through the calibrated
//! points). Outside the calibrated range: `K = c * ISO` (least squares through the origin)
//! and `ln sigma = intercept + slope * ln K`, the joint least-squares line over all
//! calibrated ISOs (slope 1 with a single point: sigma proportional to K), whose residual
//! standard deviation is recorded in [`JointFit`]; `lambda` and the Gaussian flag of the
//! nearest calibrated ISO.
//!
//! Files: JSON with `"model": "physics"` and `"format": "day2night-physics-noise-model/1"`;
//! [`crate::noise::NoiseModel::from_json`] recognizes them and carries the model as its
//! `physics` field (the Gaussian `isos` being the equivalent at the file's levels).

use super::params::{IsoPoint, NoiseParams};
use super::tukey;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Format tag of physics noise model files.
pub const PHYSICS_FORMAT: &str = "day2night-physics-noise-model/1";
/// Value of the `model` key that marks a physics model file.
pub const PHYSICS_MODEL_TAG: &str = "physics";
/// Units sentence written into physics model files.
pub const PHYSICS_UNITS: &str = "DN of linear (post-LinearizationTable) values: k = DN per \
electron; sigma_read, sigma_row = standard deviations in DN; lambda = Tukey-lambda shape of \
the read noise; black and white = levels of the calibration frames";
/// Default electron count above which the shot noise uses the normal approximation
/// `N(e, e)` instead of an exact Poisson draw (docs/noise.md, measured table).
pub const DEFAULT_POISSON_MAX_ELECTRONS: f64 = 1000.0;
/// Largest exact-Poisson threshold (larger values, including infinity, are lowered to it;
/// beyond 1e12 electrons the normal approximation's CDF error is below 1e-7).
pub const POISSON_MAX_CAP: f64 = 1e12;
/// Smallest sigma used in the log-log joint fit (smaller values are raised to it).
pub const LOG_SIGMA_FLOOR: f64 = 1e-3;
/// Accepted range of K (DN per electron) and the largest read/row sigma (DN): the one table.
pub use crate::bounds::{K_RANGE, MAX_SIGMA_DN};

/// Parameters at one ISO: what a plan carries and sampling uses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhysicsParams {
    /// System gain K, DN per electron.
    pub k: f64,
    /// Read noise standard deviation, DN.
    pub sigma_read: f64,
    /// Tukey-lambda shape of the read noise (ignored when `gaussian_read`).
    pub lambda: f64,
    /// Read noise is Gaussian.
    #[serde(default)]
    pub gaussian_read: bool,
    /// Row noise standard deviation, DN.
    pub sigma_row: f64,
    /// Electron counts at or below this are drawn from an exact Poisson distribution,
    /// larger ones from the normal approximation `N(e, e)`.
    #[serde(default = "default_poisson_max")]
    pub poisson_max_electrons: f64,
}

fn default_poisson_max() -> f64 {
    DEFAULT_POISSON_MAX_ELECTRONS
}

impl PhysicsParams {
    /// Error unless every value is finite and in range.
    pub fn check(&self, what: &str) -> Result<()> {
        let ok = self.k.is_finite()
            && self.k >= K_RANGE.0
            && self.k <= K_RANGE.1
            && self.sigma_read.is_finite()
            && self.sigma_read >= 0.0
            && self.sigma_row.is_finite()
            && self.sigma_row >= 0.0
            && self.lambda.is_finite()
            && (self.gaussian_read
                || (tukey::LAMBDA_MIN..=tukey::LAMBDA_MAX).contains(&self.lambda))
            && self.poisson_max_electrons >= 0.0
            && self.poisson_max_electrons <= POISSON_MAX_CAP;
        if !ok {
            return Err(Error::invalid(format!(
                "{what}: physics noise parameters out of range (k {} in [{:e}, {:e}], \
                 sigma_read {} and sigma_row {} finite >= 0, lambda {} in [{}, {}] unless \
                 gaussian_read, poisson_max_electrons {} in [0, 1e12])",
                self.k,
                K_RANGE.0,
                K_RANGE.1,
                self.sigma_read,
                self.sigma_row,
                self.lambda,
                tukey::LAMBDA_MIN,
                tukey::LAMBDA_MAX,
                self.poisson_max_electrons
            )));
        }
        Ok(())
    }

    /// The equivalent heteroscedastic Gaussian in the normalized NoiseProfile form, the same
    /// at every position: `S = K / scale`, `O = (sigma_read^2 + sigma_row^2) / scale^2` with
    /// `scale = white - black_max` (DN variance `K * (x - black) + sigma_read^2 +
    /// sigma_row^2`). Quantization is not included (the Gaussian path rounds too).
    pub fn to_noise_params(&self, scale: f64) -> NoiseParams {
        let scale = if scale > 0.0 && scale.is_finite() {
            scale
        } else {
            1.0
        };
        NoiseParams::uniform(
            self.k / scale,
            (self.sigma_read.powi(2) + self.sigma_row.powi(2)) / (scale * scale),
        )
    }

    /// Read-noise excess kurtosis of these parameters (0 when Gaussian).
    pub fn read_excess_kurtosis(&self) -> f64 {
        if self.gaussian_read {
            0.0
        } else {
            tukey::excess_kurtosis(self.lambda)
        }
    }
}

/// One calibrated ISO of a file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhysicsPoint {
    /// ISO.
    pub iso: u32,
    /// System gain K, DN per electron.
    pub k: f64,
    /// Read noise standard deviation, DN.
    pub sigma_read: f64,
    /// Tukey-lambda shape.
    pub lambda: f64,
    /// Read noise is Gaussian.
    #[serde(default)]
    pub gaussian_read: bool,
    /// Row noise standard deviation, DN.
    pub sigma_row: f64,
}

/// `ln sigma = intercept + slope * ln K` over the calibrated ISOs.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct LogLine {
    /// Intercept.
    pub intercept: f64,
    /// Slope.
    pub slope: f64,
    /// Residual standard deviation in `ln sigma` (`sqrt(sum r^2 / (n - 2))`, 0 for n <= 2).
    pub residual_std: f64,
}

impl LogLine {
    fn fit(ln_k: &[f64], sigma: &[f64]) -> LogLine {
        let y: Vec<f64> = sigma.iter().map(|s| s.max(LOG_SIGMA_FLOOR).ln()).collect();
        let n = ln_k.len();
        let xm = ln_k.iter().sum::<f64>() / n as f64;
        let ym = y.iter().sum::<f64>() / n as f64;
        let sxx: f64 = ln_k.iter().map(|x| (x - xm).powi(2)).sum();
        let sxy: f64 = ln_k.iter().zip(&y).map(|(x, y)| (x - xm) * (y - ym)).sum();
        // One point or all K equal: sigma proportional to K.
        let slope = if n >= 2 && sxx > 1e-12 {
            sxy / sxx
        } else {
            1.0
        };
        let intercept = ym - slope * xm;
        let ss: f64 = ln_k
            .iter()
            .zip(&y)
            .map(|(x, y)| (y - intercept - slope * x).powi(2))
            .sum();
        let residual_std = if n > 2 {
            (ss / (n - 2) as f64).sqrt()
        } else {
            0.0
        };
        LogLine {
            intercept,
            slope,
            residual_std,
        }
    }
    fn at(&self, ln_k: f64) -> f64 {
        (self.intercept + self.slope * ln_k).exp()
    }
}

/// The ELD joint model: log sigmas against log K.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct JointFit {
    /// `ln sigma_read` against `ln K`.
    pub read: LogLine,
    /// `ln sigma_row` against `ln K`.
    pub row: LogLine,
}

/// A physics noise model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhysicsModel {
    /// Always [`PHYSICS_MODEL_TAG`].
    pub model: String,
    /// Always [`PHYSICS_FORMAT`].
    pub format: String,
    /// [`PHYSICS_UNITS`].
    #[serde(default)]
    pub units: String,
    /// Where the figures come from.
    #[serde(default)]
    pub source: String,
    /// The camera the model was calibrated on (absent in older files).
    #[serde(
        default,
        deserialize_with = "super::provenance::deserialize_camera",
        skip_serializing_if = "Option::is_none"
    )]
    pub camera: Option<crate::raw::camera::CameraId>,
    /// Black level (max over the CFA tile) of the calibration frames, DN.
    pub black: f64,
    /// White level of the calibration frames, DN.
    pub white: f64,
    /// Exact-Poisson threshold in electrons (see [`PhysicsParams::poisson_max_electrons`]).
    #[serde(default = "default_poisson_max")]
    pub poisson_max_electrons: f64,
    /// Calibrated points, sorted by ISO on load.
    pub isos: Vec<PhysicsPoint>,
    /// The joint log-log fit (recomputed from `isos` on load, so a file may omit it;
    /// written for people).
    #[serde(default)]
    pub joint: JointFit,
}

/// A physics model evaluated at one ISO.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhysicsEvaluated {
    /// The parameters.
    pub params: PhysicsParams,
    /// True outside the calibrated ISO range.
    pub extrapolated: bool,
}

impl PhysicsModel {
    /// Build from points (sorted, checked; the joint fit computed).
    pub fn new(
        source: impl Into<String>,
        black: f64,
        white: f64,
        mut isos: Vec<PhysicsPoint>,
    ) -> Result<PhysicsModel> {
        isos.sort_by_key(|p| p.iso);
        if isos.is_empty() {
            return Err(Error::malformed("physics noise model has no ISO points"));
        }
        if !(black.is_finite() && white.is_finite() && black >= 0.0 && white > black) {
            return Err(Error::malformed(format!(
                "physics noise model: levels black {black} white {white} (need 0 <= black < white)"
            )));
        }
        for (i, p) in isos.iter().enumerate() {
            crate::bounds::iso(&format!("physics noise model isos[{i}].iso"), p.iso)
                .map_err(crate::bounds::malformed)?;
            // A file's sigmas: at most the full 16-bit range (extrapolations are bounded by
            // the plan's noise parameters instead).
            for (name, v) in [("sigma_read", p.sigma_read), ("sigma_row", p.sigma_row)] {
                crate::bounds::in_range(
                    &format!("physics noise model isos[{i}].{name}"),
                    v,
                    0.0,
                    MAX_SIGMA_DN,
                )
                .map_err(crate::bounds::malformed)?;
            }
            if i > 0 && isos[i - 1].iso == p.iso {
                return Err(Error::malformed(format!(
                    "physics noise model has ISO {} twice",
                    p.iso
                )));
            }
            Self::params_of(p, DEFAULT_POISSON_MAX_ELECTRONS)
                .check(&format!("physics noise model ISO {}", p.iso))?;
        }
        let ln_k: Vec<f64> = isos.iter().map(|p| p.k.ln()).collect();
        let read: Vec<f64> = isos.iter().map(|p| p.sigma_read).collect();
        let row: Vec<f64> = isos.iter().map(|p| p.sigma_row).collect();
        let joint = JointFit {
            read: LogLine::fit(&ln_k, &read),
            row: LogLine::fit(&ln_k, &row),
        };
        Ok(PhysicsModel {
            model: PHYSICS_MODEL_TAG.into(),
            format: PHYSICS_FORMAT.into(),
            units: PHYSICS_UNITS.into(),
            source: source.into(),
            camera: None,
            black,
            white,
            poisson_max_electrons: DEFAULT_POISSON_MAX_ELECTRONS,
            isos,
            joint,
        })
    }

    /// Set the exact-Poisson threshold (electrons, >= 0; values above [`POISSON_MAX_CAP`],
    /// infinity included, become the cap: always exact in practice).
    pub fn with_poisson_max(mut self, electrons: f64) -> Result<PhysicsModel> {
        if electrons.is_nan() || electrons < 0.0 {
            return Err(Error::invalid(format!(
                "poisson_max_electrons {electrons} (need >= 0)"
            )));
        }
        self.poisson_max_electrons = electrons.min(POISSON_MAX_CAP);
        Ok(self)
    }

    fn params_of(p: &PhysicsPoint, poisson_max: f64) -> PhysicsParams {
        PhysicsParams {
            k: p.k,
            sigma_read: p.sigma_read,
            lambda: p.lambda,
            gaussian_read: p.gaussian_read,
            sigma_row: p.sigma_row,
            poisson_max_electrons: poisson_max,
        }
    }

    /// Parse a physics model document (unknown keys are ignored).
    pub fn from_json(text: &str) -> Result<PhysicsModel> {
        let m: PhysicsModel = serde_json::from_str(text)
            .map_err(|e| Error::malformed(format!("physics noise model JSON: {}", e)))?;
        if m.model != PHYSICS_MODEL_TAG || m.format != PHYSICS_FORMAT {
            return Err(Error::malformed(format!(
                "physics noise model: model {:?} format {:?} (expected {:?}, {:?})",
                m.model, m.format, PHYSICS_MODEL_TAG, PHYSICS_FORMAT
            )));
        }
        let mut out = PhysicsModel::new(m.source, m.black, m.white, m.isos)?
            .with_poisson_max(m.poisson_max_electrons)?;
        out.camera = m.camera;
        Ok(out)
    }

    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Lowest and highest calibrated ISO.
    pub fn iso_range(&self) -> (u32, u32) {
        let lo = self.isos.first().map(|p| p.iso).unwrap_or(0);
        let hi = self.isos.last().map(|p| p.iso).unwrap_or(0);
        (lo, hi)
    }

    /// The equivalent Gaussian model points at the file's own levels.
    pub fn gaussian_points(&self) -> Vec<IsoPoint> {
        self.isos
            .iter()
            .map(|p| IsoPoint {
                iso: p.iso,
                positions: Self::params_of(p, self.poisson_max_electrons)
                    .to_noise_params(self.white - self.black)
                    .positions,
            })
            .collect()
    }

    /// Parameters at `iso` (module docs for the rules).
    pub fn at(&self, iso: u32) -> Result<PhysicsEvaluated> {
        if iso == 0 {
            return Err(Error::invalid("ISO 0"));
        }
        let pm = self.poisson_max_electrons;
        if let Some(p) = self.isos.iter().find(|p| p.iso == iso) {
            return Ok(PhysicsEvaluated {
                params: Self::params_of(p, pm),
                extrapolated: false,
            });
        }
        let (lo, hi) = self.iso_range();
        let t = iso as f64;
        let clamp_k = |k: f64| k.clamp(K_RANGE.0, K_RANGE.1);
        let params = if iso > lo && iso < hi {
            let j = self.isos.partition_point(|p| p.iso < iso);
            let (a, b) = (&self.isos[j - 1], &self.isos[j]);
            let f = (t - a.iso as f64) / (b.iso as f64 - a.iso as f64);
            let k = clamp_k(a.k + f * (b.k - a.k));
            let (la, lb) = (a.k.ln(), b.k.ln());
            // position along ln K (falls back to the ISO fraction when K is equal)
            let g = if (lb - la).abs() > 1e-12 {
                (k.ln() - la) / (lb - la)
            } else {
                f
            };
            let lerp_log = |x: f64, y: f64| {
                let (x, y) = (x.max(LOG_SIGMA_FLOOR).ln(), y.max(LOG_SIGMA_FLOOR).ln());
                (x + g * (y - x)).exp()
            };
            let lam = |p: &PhysicsPoint| {
                if p.gaussian_read {
                    tukey::LAMBDA_NORMAL
                } else {
                    p.lambda
                }
            };
            let zero = |x: f64, y: f64, v: f64| if x == 0.0 && y == 0.0 { 0.0 } else { v };
            PhysicsParams {
                k,
                sigma_read: zero(
                    a.sigma_read,
                    b.sigma_read,
                    lerp_log(a.sigma_read, b.sigma_read),
                ),
                lambda: lam(a) + g * (lam(b) - lam(a)),
                gaussian_read: a.gaussian_read && b.gaussian_read,
                sigma_row: zero(a.sigma_row, b.sigma_row, lerp_log(a.sigma_row, b.sigma_row)),
                poisson_max_electrons: pm,
            }
        } else {
            let (sxy, sxx) = self.isos.iter().fold((0.0, 0.0), |(sxy, sxx), p| {
                let x = p.iso as f64;
                (sxy + x * p.k, sxx + x * x)
            });
            let k = clamp_k(sxy / sxx * t);
            let near = if iso < lo {
                &self.isos[0]
            } else {
                &self.isos[self.isos.len() - 1]
            };
            let all_zero_row = self.isos.iter().all(|p| p.sigma_row == 0.0);
            let all_zero_read = self.isos.iter().all(|p| p.sigma_read == 0.0);
            PhysicsParams {
                k,
                sigma_read: if all_zero_read {
                    0.0
                } else {
                    self.joint.read.at(k.ln())
                },
                lambda: near.lambda,
                gaussian_read: near.gaussian_read,
                sigma_row: if all_zero_row {
                    0.0
                } else {
                    self.joint.row.at(k.ln())
                },
                poisson_max_electrons: pm,
            }
        };
        let mut params = params;
        // Keep sigmas finite for any ISO (u32::MAX with a steep joint line).
        params.sigma_read = params.sigma_read.min(1e9);
        params.sigma_row = params.sigma_row.min(1e9);
        params.check(&format!("physics noise model at ISO {iso}"))?;
        Ok(PhysicsEvaluated {
            params,
            extrapolated: !(lo..=hi).contains(&iso),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(iso: u32, k: f64, read: f64, lambda: f64, row: f64) -> PhysicsPoint {
        PhysicsPoint {
            iso,
            k,
            sigma_read: read,
            lambda,
            gaussian_read: false,
            sigma_row: row,
        }
    }

    fn model() -> PhysicsModel {
        PhysicsModel::new(
            "t",
            512.0,
            16383.0,
            vec![
                pt(800, 2.0, 4.0, 0.0, 0.8),
                pt(100, 0.25, 0.5, 0.1, 0.1),
                pt(400, 1.0, 2.0, 0.05, 0.4),
            ],
        )
        .unwrap()
    }

    #[test]
    fn calibrated_points_exact_and_between_interpolated() {
        let m = model();
        assert_eq!(m.iso_range(), (100, 800));
        let e = m.at(400).unwrap();
        assert!(!e.extrapolated);
        assert_eq!((e.params.k, e.params.sigma_read), (1.0, 2.0));
        let e = m.at(600).unwrap();
        assert!(!e.extrapolated);
        // K linear in ISO: 1.5; ln sigma linear in ln K between (ln 1, ln 2) and (ln 2, ln 4)
        assert!((e.params.k - 1.5).abs() < 1e-12);
        assert!(
            (e.params.sigma_read - 3.0).abs() < 1e-9,
            "{}",
            e.params.sigma_read
        );
        assert!((e.params.sigma_row - 0.6).abs() < 1e-9);
        let g = 1.5f64.ln() / 2f64.ln();
        assert!((e.params.lambda - 0.05 * (1.0 - g)).abs() < 1e-12);
    }

    #[test]
    fn extrapolation_uses_joint_line() {
        let m = model();
        // sigma_read = 2 K exactly for these points: slope 1, residual 0.
        assert!((m.joint.read.slope - 1.0).abs() < 1e-12);
        assert!(m.joint.read.residual_std < 1e-9);
        let e = m.at(3200).unwrap();
        assert!(e.extrapolated);
        assert!((e.params.k - 8.0).abs() < 1e-9);
        assert!((e.params.sigma_read - 16.0).abs() < 1e-6);
        assert!((e.params.sigma_row - 3.2).abs() < 1e-6);
        assert_eq!(e.params.lambda, 0.0);
        let e = m.at(50).unwrap();
        assert!(e.extrapolated);
        assert_eq!(e.params.lambda, 0.1);
    }

    #[test]
    fn extreme_isos_finite() {
        let m = model();
        for iso in [1, 2, 25, 1_000_000, u32::MAX] {
            let e = m.at(iso).unwrap();
            let p = e.params;
            assert!(p.k.is_finite() && p.sigma_read.is_finite() && p.sigma_row.is_finite());
            assert!(p.k >= K_RANGE.0 && p.k <= K_RANGE.1);
        }
        assert!(m.at(0).is_err());
    }

    #[test]
    fn equivalent_gaussian() {
        let p = model().at(400).unwrap().params;
        let g = p.to_noise_params(1000.0);
        assert_eq!(g.positions[3][0], 1e-3);
        assert!((g.positions[0][1] - (4.0 + 0.16) / 1e6).abs() < 1e-18);
    }

    #[test]
    fn json_round_trip_and_refusals() {
        let m = model();
        let j = m.to_json();
        assert!(j.contains("\"model\": \"physics\""));
        assert_eq!(PhysicsModel::from_json(&j).unwrap(), m);
        assert!(PhysicsModel::from_json(&j.replace("\"physics\"", "\"x\"")).is_err());
        assert!(PhysicsModel::from_json(&j.replace("\"k\": 0.25", "\"k\": -1.0")).is_err());
        assert!(
            PhysicsModel::from_json(&j.replace("\"lambda\": 0.1", "\"lambda\": -0.4")).is_err()
        );
        assert!(PhysicsModel::from_json("{}").is_err());
        let bad = PhysicsModel::new("t", 10.0, 5.0, vec![pt(100, 1.0, 1.0, 0.0, 0.0)]);
        assert!(bad.is_err());
    }

    #[test]
    fn zero_sigmas_stay_zero() {
        let m = PhysicsModel::new(
            "t",
            0.0,
            1023.0,
            vec![pt(100, 1.0, 0.0, 0.1, 0.0), pt(200, 2.0, 0.0, 0.1, 0.0)],
        )
        .unwrap();
        for iso in [150, 400, 50] {
            let p = m.at(iso).unwrap().params;
            assert_eq!((p.sigma_read, p.sigma_row), (0.0, 0.0), "{iso}");
        }
    }
}
