//! Heteroscedastic Gaussian noise model per 2x2 CFA position and ISO (docs/synthesis.md, "7. Noise").
//!
//! The portable form is the DNG NoiseProfile form on normalized data,
//! `var(y) = S * y + O` with `y = (x - black(site)) / (white - black_max)`. A table in DN
//! (`var(x) = beta1 * x + beta2`, `x` including the black level, as in the paper's release)
//! converts with `S = beta1 / (white - black)` and `O = (beta2 + black * beta1) / (white - black)^2`.
//!
//! Between calibrated ISOs, `S` is interpolated linearly in ISO and `O` linearly in ISO^2
//! (read-noise variance grows with the square of the analog gain). Outside the calibrated
//! range, least-squares fits `S = c * ISO` and `O = a + b * ISO^2` over all calibrated points
//! extrapolate, and [`Evaluated::extrapolated`] is set so callers can warn. With a single
//! calibrated point (e.g. a DNG's own NoiseProfile) the fits degenerate to `S ∝ ISO`,
//! `O ∝ ISO^2` (a = 0). Results are clamped to `S >= 0`, `O >= 0` so a variance is never
//! negative, and non-finite parameters are refused.

use crate::error::{Error, Result};
use crate::raw::camera::CameraId;
use crate::raw::Bayer;
use serde::{Deserialize, Serialize};

/// Format tag of noise model files (`--noise-model`).
pub const NOISE_MODEL_FORMAT: &str = "day2night-noise-model/1";

/// Units sentence written into noise model files.
pub const NOISE_MODEL_UNITS: &str = "variance of the normalized signal y = (x - black(site)) / \
(white - black_max), linear (post-LinearizationTable) values: var(y) = S * y + O; positions \
are the 2x2 CFA tile relative to the ActiveArea origin, row-major (0=(0,0), 1=(0,1), 2=(1,0), 3=(1,1))";

pub use super::params::{IsoPoint, NoiseParams};

/// Most ISO points in a noise model file.
pub use crate::bounds::MAX_ISO_POINTS;

/// A noise model: calibrated `(S, O)` per position at one or more ISOs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseModel {
    /// Always [`NOISE_MODEL_FORMAT`] in files.
    pub format: String,
    /// The units, in words ([`NOISE_MODEL_UNITS`]).
    pub units: String,
    /// Where the figures come from (camera, calibration, licence).
    #[serde(default)]
    pub source: String,
    /// The camera the model was calibrated on (`calibrate noise` writes it; files without it,
    /// and the legacy string form, stay valid: see [`super::provenance::deserialize_camera`]).
    #[serde(
        default,
        deserialize_with = "super::provenance::deserialize_camera",
        skip_serializing_if = "Option::is_none"
    )]
    pub camera: Option<CameraId>,
    /// Calibrated points, any order (sorted on load), distinct ISOs.
    pub isos: Vec<IsoPoint>,
    /// The file the model was read from ([`NoiseModel::from_file`]; not serialized).
    #[serde(skip)]
    pub file: Option<String>,
    /// The physics-based model when the file was one (`"model": "physics"`); `isos` then
    /// holds its equivalent Gaussian at the file's levels. Never written for Gaussian
    /// models, so their files are unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<super::physics::PhysicsModel>,
}

/// A model evaluated at one ISO.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Evaluated {
    /// The parameters.
    pub params: NoiseParams,
    /// True when the ISO lies outside the calibrated range (least-squares extrapolation).
    pub extrapolated: bool,
}

impl NoiseModel {
    /// Build from points; sorts them and checks that they are usable.
    pub fn new(source: impl Into<String>, mut isos: Vec<IsoPoint>) -> Result<NoiseModel> {
        isos.sort_by_key(|p| p.iso);
        let m = NoiseModel {
            format: NOISE_MODEL_FORMAT.into(),
            units: NOISE_MODEL_UNITS.into(),
            source: source.into(),
            camera: None,
            isos,
            file: None,
            physics: None,
        };
        m.validate()?;
        Ok(m)
    }

    /// A model carrying a physics model (its equivalent Gaussian as `isos`).
    pub fn from_physics(p: super::physics::PhysicsModel) -> Result<NoiseModel> {
        let mut m = NoiseModel::new(p.source.clone(), p.gaussian_points())?;
        m.camera = p.camera.clone();
        m.physics = Some(p);
        Ok(m)
    }

    fn validate(&self) -> Result<()> {
        if self.format != NOISE_MODEL_FORMAT {
            return Err(Error::malformed(format!(
                "noise model format {:?} (expected {:?})",
                self.format, NOISE_MODEL_FORMAT
            )));
        }
        if self.isos.is_empty() {
            return Err(Error::malformed("noise model has no ISO points"));
        }
        if self.isos.len() > MAX_ISO_POINTS {
            return Err(Error::limits(format!(
                "noise model isos: {} points (at most {MAX_ISO_POINTS})",
                self.isos.len()
            )));
        }
        for (i, p) in self.isos.iter().enumerate() {
            crate::bounds::iso(&format!("noise model isos[{i}].iso"), p.iso)
                .map_err(crate::bounds::malformed)?;
            let big = crate::bounds::MAX_NOISE_PARAM;
            if p.positions.iter().flatten().any(|v| v.abs() > big) {
                return Err(Error::malformed(format!(
                    "noise model isos[{i}].positions: |S| and |O| must be <= {big} \
                     (normalized variance)"
                )));
            }
            if i > 0 && self.isos[i - 1].iso == p.iso {
                return Err(Error::malformed(format!(
                    "noise model has ISO {} twice",
                    p.iso
                )));
            }
            NoiseParams {
                positions: p.positions,
            }
            .check(&format!("noise model ISO {}", p.iso))?;
        }
        Ok(())
    }

    /// Build from a table in DN (`var = beta1 * x + beta2`, `x` including black), converting
    /// to the portable normalized form with the table's own black and white levels.
    /// `rows`: (iso, position, beta1, beta2).
    pub fn from_dn_table(
        source: impl Into<String>,
        rows: &[(u32, usize, f64, f64)],
        black: f64,
        white: f64,
    ) -> Result<NoiseModel> {
        let range = white - black;
        if range.is_nan() || range <= 0.0 {
            return Err(Error::invalid("noise table: white <= black"));
        }
        let mut pts: Vec<IsoPoint> = Vec::new();
        let mut seen: Vec<(u32, [bool; 4])> = Vec::new();
        for &(iso, pos, b1, b2) in rows {
            if pos > 3 {
                return Err(Error::malformed(format!(
                    "noise table: bayer_position {} > 3",
                    pos
                )));
            }
            let idx = match pts.iter().position(|p| p.iso == iso) {
                Some(i) => i,
                None => {
                    pts.push(IsoPoint {
                        iso,
                        positions: [[0.0; 2]; 4],
                    });
                    seen.push((iso, [false; 4]));
                    pts.len() - 1
                }
            };
            pts[idx].positions[pos] = [b1 / range, (b2 + black * b1) / (range * range)];
            seen[idx].1[pos] = true;
        }
        if let Some((iso, _)) = seen.iter().find(|(_, s)| s.iter().any(|x| !x)) {
            return Err(Error::malformed(format!(
                "noise table: ISO {} lacks some of the 4 CFA positions",
                iso
            )));
        }
        NoiseModel::new(source, pts)
    }

    /// A single-ISO model from a DNG NoiseProfile measured at `iso`.
    pub fn from_dng_profile(profile: &[(f64, f64)], bayer: Bayer, iso: u32) -> Result<NoiseModel> {
        let p = NoiseParams::from_dng_profile(profile, bayer)?;
        NoiseModel::new(
            format!("input DNG NoiseProfile at ISO {}", iso),
            vec![IsoPoint {
                iso,
                positions: p.positions,
            }],
        )
    }

    /// Parse a `day2night-noise-model/1` JSON document, or a physics model document
    /// (`"model": "physics"`, see [`super::physics`]).
    pub fn from_json(text: &str) -> Result<NoiseModel> {
        let v: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| Error::malformed(format!("noise model JSON: {}", e)))?;
        if v.get("model").and_then(|m| m.as_str()) == Some(super::physics::PHYSICS_MODEL_TAG) {
            return NoiseModel::from_physics(super::physics::PhysicsModel::from_json(text)?);
        }
        let m: NoiseModel = serde_json::from_str(text)
            .map_err(|e| Error::malformed(format!("noise model JSON: {}", e)))?;
        if m.format != NOISE_MODEL_FORMAT {
            return Err(Error::malformed(format!(
                "noise model format {:?} (expected {:?})",
                m.format, NOISE_MODEL_FORMAT
            )));
        }
        let mut out = NoiseModel::new(m.source, m.isos)?;
        out.camera = m.camera;
        Ok(out)
    }

    /// Read a noise model file (its path is kept in [`NoiseModel::file`]).
    pub fn from_file(path: &std::path::Path) -> Result<NoiseModel> {
        let text = crate::bounds::read_calibration_text(path)?;
        let mut m = NoiseModel::from_json(&text).map_err(|e| e.in_file(path))?;
        m.file = Some(path.display().to_string());
        Ok(m)
    }

    /// Serialize to pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The calibrated points with a negative S or O, as `ISO 100 position 0 (S 2e-5, O -1)`
    /// (empty when none). A variance cannot be negative: [`NoiseModel::at`] clamps them to
    /// 0, and the noise chain warns with this list (docs/noise.md, "Negative parameters").
    pub fn negative_points(&self) -> Vec<String> {
        let mut out = Vec::new();
        for p in &self.isos {
            for (pos, v) in p.positions.iter().enumerate() {
                if v[0] < 0.0 || v[1] < 0.0 {
                    out.push(format!(
                        "ISO {} position {pos} (S {}, O {})",
                        p.iso,
                        crate::bounds::short(v[0]),
                        crate::bounds::short(v[1])
                    ));
                }
            }
        }
        out
    }

    /// Lowest and highest calibrated ISO.
    pub fn iso_range(&self) -> (u32, u32) {
        let lo = self.isos.first().map(|p| p.iso).unwrap_or(0);
        let hi = self.isos.last().map(|p| p.iso).unwrap_or(0);
        (lo, hi)
    }

    /// Parameters at `iso` (see the module docs for the interpolation rule).
    pub fn at(&self, iso: u32) -> Result<Evaluated> {
        if iso == 0 {
            return Err(Error::invalid("ISO 0"));
        }
        let t = iso as f64;
        let (lo, hi) = self.iso_range();
        if let Some(p) = self.isos.iter().find(|p| p.iso == iso) {
            return Ok(Evaluated {
                params: NoiseParams {
                    positions: p.positions,
                }
                .clamped(),
                extrapolated: false,
            });
        }
        let mut out = [[0.0; 2]; 4];
        let extrapolated = iso < lo || iso > hi;
        if !extrapolated {
            let k = self.isos.partition_point(|p| p.iso < iso);
            let (a, b) = (&self.isos[k - 1], &self.isos[k]);
            let (ia, ib) = (a.iso as f64, b.iso as f64);
            let fs = (t - ia) / (ib - ia);
            let fo = (t * t - ia * ia) / (ib * ib - ia * ia);
            for (pos, o) in out.iter_mut().enumerate() {
                let (pa, pb) = (a.positions[pos], b.positions[pos]);
                *o = [pa[0] + fs * (pb[0] - pa[0]), pa[1] + fo * (pb[1] - pa[1])];
            }
        } else {
            for (pos, o) in out.iter_mut().enumerate() {
                // S = c * ISO, least squares through the origin.
                let (mut sxy, mut sxx) = (0.0, 0.0);
                for p in &self.isos {
                    let x = p.iso as f64;
                    sxy += x * p.positions[pos][0];
                    sxx += x * x;
                }
                let s = sxy / sxx * t;
                // O = a + b * ISO^2, ordinary least squares (a = 0 with one point).
                let n = self.isos.len() as f64;
                let o_val = if self.isos.len() == 1 {
                    let p = &self.isos[0];
                    let x2 = (p.iso as f64).powi(2);
                    p.positions[pos][1] / x2 * t * t
                } else {
                    let (mut sx, mut sy, mut sxx2, mut sxy2) = (0.0, 0.0, 0.0, 0.0);
                    for p in &self.isos {
                        let x = (p.iso as f64).powi(2);
                        let y = p.positions[pos][1];
                        sx += x;
                        sy += y;
                        sxx2 += x * x;
                        sxy2 += x * y;
                    }
                    let den = n * sxx2 - sx * sx;
                    let b = if den.abs() > 0.0 {
                        (n * sxy2 - sx * sy) / den
                    } else {
                        0.0
                    };
                    let a = (sy - b * sx) / n;
                    a + b * t * t
                };
                *o = [s, o_val];
            }
        }
        let params = NoiseParams { positions: out }.clamped();
        params.check(&format!("noise model at ISO {}", iso))?;
        Ok(Evaluated {
            params,
            extrapolated,
        })
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use crate::synth::dictionaries::embedded;

    #[test]
    fn dn_conversion_matches_spec_figures() {
        let m = embedded::noise_model();
        let e = m.at(1600).unwrap();
        assert!(!e.extrapolated);
        // O at ISO 1600 about 1.03e-5, at 3200 about 4.33e-5 (docs/synthesis.md, "7. Noise").
        let o1600 = e.params.positions[0][1];
        let o3200 = m.at(3200).unwrap().params.positions[0][1];
        assert!((o1600 - 1.03e-5).abs() < 0.01e-5, "{o1600}");
        assert!((o3200 - 4.33e-5).abs() < 0.01e-5, "{o3200}");
        // Position 0 S at 1600: beta1 / 959.
        let s = e.params.positions[0][0];
        assert!((s - 2.2435579560800636 / 959.0).abs() < 1e-12);
        // Back in DN: var(x) = beta1 * x + beta2 at x = 500.
        let y = (500.0 - 64.0) / 959.0;
        let var_dn = e.params.var_norm(0, y) * 959.0 * 959.0;
        let want = 2.2435579560800636 * 500.0 - 134.13813652456366;
        assert!((var_dn - want).abs() < 1e-9 * want.abs(), "{var_dn} {want}");
    }

    #[test]
    fn interpolation_rules() {
        let m = NoiseModel::new(
            "t",
            vec![
                IsoPoint {
                    iso: 100,
                    positions: [[1.0, 1.0]; 4],
                },
                IsoPoint {
                    iso: 200,
                    positions: [[2.0, 4.0]; 4],
                },
            ],
        )
        .unwrap();
        let e = m.at(150).unwrap();
        assert!(!e.extrapolated);
        // S linear in ISO: 1.5; O linear in ISO^2: 1 + (22500-10000)/(40000-10000)*3 = 2.25.
        assert!((e.params.positions[2][0] - 1.5).abs() < 1e-12);
        assert!((e.params.positions[2][1] - 2.25).abs() < 1e-12);
        // Extrapolation: S = c*ISO with c = (100*1+200*2)/(100^2+200^2) = 0.01;
        // O = a + b ISO^2 exact through both points: b = 1e-4, a = 0.
        let e = m.at(400).unwrap();
        assert!(e.extrapolated);
        assert!((e.params.positions[0][0] - 4.0).abs() < 1e-9);
        assert!((e.params.positions[0][1] - 16.0).abs() < 1e-9);
    }

    #[test]
    fn extreme_isos_finite_and_non_negative() {
        let m = embedded::noise_model();
        for iso in [1, 25, 50, 204800, 409600, u32::MAX] {
            let e = m.at(iso).unwrap();
            assert!(e.extrapolated);
            for p in e.params.positions {
                assert!(p[0].is_finite() && p[1].is_finite(), "{iso} {p:?}");
                assert!(p[0] >= 0.0 && p[1] >= 0.0, "{iso} {p:?}");
            }
        }
        assert!(m.at(0).is_err());
    }

    #[test]
    fn single_point_scaling() {
        let m = NoiseModel::from_dng_profile(&[(1e-4, 1e-6)], Bayer::RGGB, 100).unwrap();
        let e = m.at(400).unwrap();
        assert!(e.extrapolated);
        assert!((e.params.positions[3][0] - 4e-4).abs() < 1e-15);
        assert!((e.params.positions[3][1] - 16e-6).abs() < 1e-15);
    }

    #[test]
    fn dng_profile_per_plane_round_trip() {
        let prof = vec![(1.0, 2.0), (3.0, 4.0), (5.0, 6.0)];
        for b in Bayer::ALL {
            let p = NoiseParams::from_dng_profile(&prof, b).unwrap();
            assert_eq!(p.to_dng_profile(b), prof);
        }
        assert!(NoiseParams::from_dng_profile(&[(1.0, 1.0); 2], Bayer::RGGB).is_err());
        assert!(NoiseParams::from_dng_profile(&[(f64::NAN, 1.0)], Bayer::RGGB).is_err());
    }

    #[test]
    fn json_round_trip_and_refusals() {
        let m = embedded::noise_model();
        let j = m.to_json();
        assert!(j.contains(NOISE_MODEL_FORMAT));
        assert_eq!(NoiseModel::from_json(&j).unwrap(), m);
        assert!(NoiseModel::from_json("{}").is_err());
        let bad = j.replace(NOISE_MODEL_FORMAT, "other/1");
        assert!(NoiseModel::from_json(&bad).is_err());
    }

    #[test]
    fn var_never_negative_or_nan() {
        let p = NoiseParams::uniform(1.0, -5.0);
        assert_eq!(p.var_norm(0, 0.0), 0.0);
        assert_eq!(p.var_norm(0, f64::NAN), 0.0);
    }
}
