//! Camera colour to XYZ and linear sRGB, per DNG specification 1.6 chapter 6 ("Mapping
//! Camera Color Space to CIE XYZ Space").
//!
//! * Matrices for an illuminant: ColorMatrix1/2, CameraCalibration1/2 and ForwardMatrix1/2
//!   are interpolated linearly in inverse correlated colour temperature between the
//!   CalibrationIlluminant1/2 temperatures (taken from the EXIF LightSource codes of the
//!   tags); outside that range the nearest set is used, and a single set is used as is.
//! * `XYZtoCamera = AB * CC * CM` (AnalogBalance, CameraCalibration, ColorMatrix).
//! * The white point is found from the camera neutral by the spec's iteration: guess D50,
//!   compute its CCT, interpolate the matrices, map the neutral to xy, repeat to convergence.
//! * With ForwardMatrix: `CameraToXYZ_D50 = FM * D * Inverse(AB * CC)` with
//!   `D = Inverse(Diagonal(Inverse(AB * CC) * neutral))`; without it:
//!   `CameraToXYZ_D50 = CA * Inverse(XYZtoCamera)` with CA the linear Bradford adaptation
//!   from the white point to D50.
//! * Then Bradford D50 -> D65 and XYZ -> linear sRGB (Rec.709 primaries, D65 white), scaled
//!   so that a white-balanced (1, 1, 1) maps to Y = 1 (the DNG SDK's normalization of the
//!   neutral to the PCS white).
//!
//! The temperature from xy uses Robertson's 1968 isotemperature lines, as the DNG SDK does
//! ([`crate::color::cct`]); the matrix and XYZ maths is [`crate::color`]'s.

use crate::color::cct::{light_source_temperature, xy_to_cct};
use crate::color::matrix3::{self, diag, mul, mul_vec, Mat3, NotInvertible, IDENTITY};
use crate::color::xyz::{bradford, xy_to_xyz, xyz_to_srgb_matrix, xyz_to_xy, D50_XY, D65_XY};
use crate::error::{Error, Result};
use crate::raw::meta::ColorInfo;

/// Inverse of a colour matrix, or an error naming it singular or ill-conditioned.
fn invert(m: &Mat3) -> Result<Mat3> {
    matrix3::inverse(m).map_err(|e| match e {
        NotInvertible::Singular => Error::malformed(format!("colour matrix {m:?} is singular")),
        // Not singular (e.g. diag(2^31, 1, 2^-31) has determinant 1): ill-conditioned. Files
        // are refused earlier by its condition number (crate::dng::check).
        NotInvertible::IllConditioned {
            relative_determinant,
        } => Error::malformed(format!(
            "colour matrix {m:?} is ill-conditioned (determinant {} relative to its largest \
             entry cubed)",
            crate::bounds::short(relative_determinant)
        )),
    })
}

/// The per-illuminant matrices after interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct IlluminantMatrices {
    /// Interpolated ColorMatrix (XYZ -> reference camera).
    pub color_matrix: Mat3,
    /// Interpolated CameraCalibration (identity when absent).
    pub camera_calibration: Mat3,
    /// Interpolated ForwardMatrix, when the file has one.
    pub forward_matrix: Option<Mat3>,
    /// Weight of set 1 (1 = only set 1, 0 = only set 2).
    pub weight1: f64,
}

fn mat_from(v: &[f64], name: &str) -> Result<Mat3> {
    match matrix3::from_row_major(v) {
        Some(m) if v.iter().all(|x| x.is_finite()) => Ok(m),
        _ => Err(Error::malformed(format!(
            "{name} has {} values (a three-colour camera needs 9 finite values)",
            v.len()
        ))),
    }
}

fn lerp(a: &Mat3, b: &Mat3, w: f64) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = w * a[i][j] + (1.0 - w) * b[i][j];
        }
    }
    m
}

/// Camera colour description from a DNG's colour tags.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraColor {
    cm1: Mat3,
    cm2: Option<Mat3>,
    cc1: Mat3,
    cc2: Mat3,
    fm1: Option<Mat3>,
    fm2: Option<Mat3>,
    ab: Mat3,
    /// Temperatures of illuminants 1 and 2 (None: unknown or single set).
    pub temps: Option<(f64, f64)>,
}

impl CameraColor {
    /// Parse the colour tags; errors when ColorMatrix1 is missing or a matrix is malformed.
    pub fn new(c: &ColorInfo) -> Result<CameraColor> {
        let cm1 = c
            .color_matrix1
            .as_deref()
            .ok_or_else(|| {
                Error::unsupported("no ColorMatrix1: camera colour cannot be mapped to XYZ")
            })
            .and_then(|v| mat_from(v, "ColorMatrix1"))?;
        let cm2 = c
            .color_matrix2
            .as_deref()
            .map(|v| mat_from(v, "ColorMatrix2"))
            .transpose()?;
        let opt = |v: &Option<Vec<f64>>, n: &str| v.as_deref().map(|v| mat_from(v, n)).transpose();
        let cc1 = opt(&c.camera_calibration1, "CameraCalibration1")?.unwrap_or(IDENTITY);
        let cc2 = opt(&c.camera_calibration2, "CameraCalibration2")?.unwrap_or(cc1);
        let fm1 = opt(&c.forward_matrix1, "ForwardMatrix1")?;
        let fm2 = opt(&c.forward_matrix2, "ForwardMatrix2")?;
        let ab = match &c.analog_balance {
            Some(v) if v.len() == 3 && v.iter().all(|x| x.is_finite() && *x > 0.0) => {
                diag([v[0], v[1], v[2]])
            }
            Some(v) => {
                return Err(Error::malformed(format!(
                    "AnalogBalance {v:?} is not three positive numbers"
                )))
            }
            None => IDENTITY,
        };
        let temps = match (cm2, c.calibration_illuminant1, c.calibration_illuminant2) {
            (Some(_), Some(i1), Some(i2)) => {
                match (light_source_temperature(i1), light_source_temperature(i2)) {
                    (Some(t1), Some(t2)) if t1 != t2 => Some((t1, t2)),
                    _ => None,
                }
            }
            _ => None,
        };
        Ok(CameraColor {
            cm1,
            cm2,
            cc1,
            cc2,
            fm1,
            fm2,
            ab,
            temps,
        })
    }

    /// Matrices interpolated for a white of temperature `cct` kelvin.
    pub fn matrices_at(&self, cct: f64) -> IlluminantMatrices {
        let w = match self.temps {
            None => 1.0,
            Some((t1, t2)) => {
                // weight of set 1, linear in 1/T, clamped (nearest set outside the range)
                let g = (1.0 / cct - 1.0 / t2) / (1.0 / t1 - 1.0 / t2);
                if g.is_finite() {
                    g.clamp(0.0, 1.0)
                } else {
                    1.0
                }
            }
        };
        let cm2 = self.cm2.unwrap_or(self.cm1);
        let forward_matrix = match (self.fm1, self.fm2) {
            (Some(a), Some(b)) if self.temps.is_some() => Some(lerp(&a, &b, w)),
            (Some(a), _) => Some(a),
            (None, Some(b)) => Some(b),
            (None, None) => None,
        };
        IlluminantMatrices {
            color_matrix: lerp(&self.cm1, &cm2, w),
            camera_calibration: lerp(&self.cc1, &self.cc2, w),
            forward_matrix,
            weight1: w,
        }
    }

    /// `AB * CC * CM` for a white of temperature `cct`.
    pub fn xyz_to_camera(&self, cct: f64) -> Mat3 {
        let m = self.matrices_at(cct);
        mul(&self.ab, &mul(&m.camera_calibration, &m.color_matrix))
    }

    /// White xy of a camera neutral by the spec's iteration (at most 30 passes; the mean
    /// of the last two estimates when it oscillates).
    pub fn neutral_to_xy(&self, neutral: [f64; 3]) -> Result<[f64; 2]> {
        let mut last = D50_XY;
        for pass in 0..30 {
            let m = invert(&self.xyz_to_camera(xy_to_cct(last)))?;
            let mut next = xyz_to_xy(mul_vec(&m, neutral));
            if (next[0] - last[0]).abs() + (next[1] - last[1]).abs() < 1e-7 {
                return Ok(next);
            }
            if pass == 29 {
                next = [(last[0] + next[0]) * 0.5, (last[1] + next[1]) * 0.5];
            }
            last = next;
        }
        Ok(last)
    }

    /// Camera response (not normalized) to a white of chromaticity `xy` with Y = 1:
    /// `XYZtoCamera(CCT(xy)) * XYZ(xy)` (DNG spec chapter 6, "Translating White Balance xy
    /// Coordinates to Camera Neutral Coordinates": the matrices for a known white are
    /// interpolated at its own CCT, no iteration needed).
    pub fn xy_to_camera(&self, xy: [f64; 2]) -> [f64; 3] {
        mul_vec(&self.xyz_to_camera(xy_to_cct(xy)), xy_to_xyz(xy))
    }

    /// Camera neutral (green = 1) of a white chromaticity (for AsShotWhiteXY).
    pub fn xy_to_neutral(&self, xy: [f64; 2]) -> Result<[f64; 3]> {
        normalize_neutral(self.xy_to_camera(xy))
    }

    /// Camera (not white-balanced) -> XYZ D50 for the given neutral, per chapter 6.
    pub fn camera_to_xyz_d50(&self, neutral: [f64; 3]) -> Result<Mat3> {
        let white = self.neutral_to_xy(neutral)?;
        let cct = xy_to_cct(white);
        let m = self.matrices_at(cct);
        let abcc = mul(&self.ab, &m.camera_calibration);
        match m.forward_matrix {
            Some(fm) => {
                let abcc_inv = invert(&abcc)?;
                let r = mul_vec(&abcc_inv, neutral);
                if r.iter().any(|v| v.is_nan() || *v <= 0.0 || !v.is_finite()) {
                    return Err(Error::malformed(format!(
                        "reference neutral {r:?} is not positive"
                    )));
                }
                let d = diag([1.0 / r[0], 1.0 / r[1], 1.0 / r[2]]);
                Ok(mul(&fm, &mul(&d, &abcc_inv)))
            }
            None => {
                let cam_to_xyz = invert(&mul(&abcc, &m.color_matrix))?;
                Ok(mul(&bradford(white, D50_XY), &cam_to_xyz))
            }
        }
    }

    /// White-balanced camera RGB (camera / neutral) -> linear sRGB (D65), normalized so
    /// that (1, 1, 1) maps to Y = 1.
    pub fn wb_camera_to_srgb(&self, neutral: [f64; 3]) -> Result<Mat3> {
        let to_d65 = mul(&bradford(D50_XY, D65_XY), &self.camera_to_xyz_d50(neutral)?);
        let to_xyz = mul(&to_d65, &diag(neutral));
        let y = mul_vec(&to_xyz, [1.0, 1.0, 1.0])[1];
        if y.is_nan() || y <= 0.0 || !y.is_finite() {
            return Err(Error::malformed(
                "colour matrices map the neutral to a non-positive luminance",
            ));
        }
        let m = mul(&xyz_to_srgb_matrix(), &to_xyz);
        Ok(m.map(|row| row.map(|v| v / y)))
    }
}

/// Normalize a neutral to green = 1; error unless all three are positive and finite.
pub fn normalize_neutral(n: [f64; 3]) -> Result<[f64; 3]> {
    if n.iter().any(|v| !v.is_finite() || *v <= 0.0) {
        return Err(Error::invalid(format!(
            "neutral {n:?} must be three positive finite numbers"
        )));
    }
    Ok([n[0] / n[1], 1.0, n[2] / n[1]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::xyz::{rgb_to_xyz_matrix, REC709_PRIMARIES};

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    fn srgb_camera(illum: u16) -> ColorInfo {
        // XYZ -> camera = XYZ->sRGB (the camera *is* sRGB under D65).
        let m = xyz_to_srgb_matrix();
        ColorInfo {
            color_matrix1: Some(m.iter().flatten().cloned().collect()),
            calibration_illuminant1: Some(illum),
            ..ColorInfo::default()
        }
    }

    #[test]
    fn srgb_camera_under_d65_is_identity() {
        let cc = CameraColor::new(&srgb_camera(21)).unwrap();
        // neutral of D65 in this camera is (1,1,1)
        let n = cc.xy_to_neutral(D65_XY).unwrap();
        for v in n {
            assert!(close(v, 1.0, 1e-9), "{n:?}");
        }
        let xy = cc.neutral_to_xy([1.0, 1.0, 1.0]).unwrap();
        assert!(close(xy[0], D65_XY[0], 1e-7) && close(xy[1], D65_XY[1], 1e-7));
        let m = cc.wb_camera_to_srgb([1.0, 1.0, 1.0]).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!(close(m[i][j], want, 1e-9), "{m:?}");
            }
        }
    }

    #[test]
    fn white_balanced_white_maps_to_white() {
        let cc = CameraColor::new(&srgb_camera(21)).unwrap();
        let m = cc.wb_camera_to_srgb([0.5, 1.0, 0.8]).unwrap();
        let w = mul_vec(&m, [1.0, 1.0, 1.0]);
        for v in w {
            assert!(close(v, 1.0, 1e-9), "{w:?}");
        }
    }

    #[test]
    fn interpolation_in_inverse_cct_with_clamping() {
        let mut ci = srgb_camera(17); // A = 2850 K
        let m2: Vec<f64> = (0..9).map(|i| if i % 4 == 0 { 2.0 } else { 0.0 }).collect();
        ci.color_matrix2 = Some(m2);
        ci.calibration_illuminant2 = Some(21); // 6500 K
        let cc = CameraColor::new(&ci).unwrap();
        assert_eq!(cc.temps, Some((2850.0, 6500.0)));
        assert_eq!(cc.matrices_at(2000.0).weight1, 1.0);
        assert_eq!(cc.matrices_at(9000.0).weight1, 0.0);
        let t = 4000.0;
        let want = (1.0 / t - 1.0 / 6500.0) / (1.0 / 2850.0 - 1.0 / 6500.0);
        assert!(close(cc.matrices_at(t).weight1, want, 1e-12));
        // order of the two illuminants does not matter
        let mut swapped = ci.clone();
        std::mem::swap(&mut swapped.color_matrix1, &mut swapped.color_matrix2);
        std::mem::swap(
            &mut swapped.calibration_illuminant1,
            &mut swapped.calibration_illuminant2,
        );
        let cs = CameraColor::new(&swapped).unwrap();
        let a = cc.xyz_to_camera(t);
        let b = cs.xyz_to_camera(t);
        for i in 0..3 {
            for j in 0..3 {
                assert!(close(a[i][j], b[i][j], 1e-12));
            }
        }
        // unknown illuminant code: single matrix
        let mut unk = ci.clone();
        unk.calibration_illuminant2 = Some(255);
        assert_eq!(CameraColor::new(&unk).unwrap().matrices_at(t).weight1, 1.0);
    }

    #[test]
    fn forward_matrix_path_maps_white_to_d50() {
        let mut ci = srgb_camera(21);
        // A forward matrix mapping (1,1,1) to D50: sRGB->XYZ adapted to D50.
        let fm = mul(
            &bradford(D65_XY, D50_XY),
            &rgb_to_xyz_matrix(REC709_PRIMARIES, D65_XY).unwrap(),
        );
        ci.forward_matrix1 = Some(fm.iter().flatten().cloned().collect());
        let cc = CameraColor::new(&ci).unwrap();
        let n = [0.6, 1.0, 0.7];
        let m = cc.camera_to_xyz_d50(n).unwrap();
        let w = mul_vec(&m, n);
        let d50 = xy_to_xyz(D50_XY);
        for i in 0..3 {
            assert!(close(w[i], d50[i], 1e-9), "{w:?}");
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(CameraColor::new(&ColorInfo::default()).is_err());
        let mut ci = srgb_camera(21);
        ci.color_matrix1 = Some(vec![1.0; 9]);
        let cc = CameraColor::new(&ci).unwrap();
        assert!(cc.wb_camera_to_srgb([1.0, 1.0, 1.0]).is_err());
        assert!(normalize_neutral([0.0, 1.0, 1.0]).is_err());
        assert!(normalize_neutral([f64::NAN, 1.0, 1.0]).is_err());
        assert_eq!(normalize_neutral([1.0, 2.477, 1.462]).unwrap()[1], 1.0);
    }
}
