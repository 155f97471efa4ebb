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
//! The temperature from xy uses Robertson's 1968 isotemperature lines, as the DNG SDK does.

use crate::error::{Error, Result};
use crate::raw::meta::ColorInfo;

/// A 3x3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

/// Chromaticity of CIE D50 as the DNG SDK uses it (the PCS white).
pub const D50_XY: [f64; 2] = [0.3457, 0.3585];
/// Chromaticity of CIE D65 (sRGB / Rec.709 white).
pub const D65_XY: [f64; 2] = [0.3127, 0.3290];
/// Rec.709 / sRGB primaries (x, y): red, green, blue.
pub const REC709_PRIMARIES: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

/// Bradford cone response matrix.
const BRADFORD: Mat3 = [
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
];

/// Identity.
pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Matrix product.
pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// Matrix times vector.
pub fn mul_vec(a: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}

/// Diagonal matrix.
pub fn diag(v: [f64; 3]) -> Mat3 {
    [[v[0], 0.0, 0.0], [0.0, v[1], 0.0], [0.0, 0.0, v[2]]]
}

/// Inverse, or an error when (nearly) singular or not finite.
pub fn invert(m: &Mat3) -> Result<Mat3> {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    if !det.is_finite() || scale == 0.0 || det == 0.0 {
        return Err(Error::malformed(format!("colour matrix {m:?} is singular")));
    }
    if det.abs() < 1e-12 * scale.powi(3) {
        // Not singular (e.g. diag(2^31, 1, 2^-31) has determinant 1): ill-conditioned. Files
        // are refused earlier by its condition number (crate::dng::check).
        return Err(Error::malformed(format!(
            "colour matrix {m:?} is ill-conditioned (determinant {} relative to its largest \
             entry cubed)",
            crate::bounds::short(det / scale.powi(3))
        )));
    }
    let inv = 1.0 / det;
    Ok([
        [
            (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * inv,
            (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv,
            (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv,
        ],
        [
            (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * inv,
            (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv,
            (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv,
        ],
        [
            (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * inv,
            (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv,
            (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv,
        ],
    ])
}

/// xy chromaticity to XYZ with Y = 1.
pub fn xy_to_xyz(xy: [f64; 2]) -> [f64; 3] {
    let y = xy[1].max(1e-12);
    [xy[0] / y, 1.0, (1.0 - xy[0] - xy[1]) / y]
}

/// XYZ to xy chromaticity (D50 for black or degenerate input, as the SDK does).
pub fn xyz_to_xy(v: [f64; 3]) -> [f64; 2] {
    let s = v[0] + v[1] + v[2];
    if s > 0.0 && s.is_finite() {
        [v[0] / s, v[1] / s]
    } else {
        D50_XY
    }
}

/// Linear Bradford adaptation matrix from white `src` to white `dst` (xy).
pub fn bradford(src: [f64; 2], dst: [f64; 2]) -> Mat3 {
    let s = mul_vec(&BRADFORD, xy_to_xyz(src));
    let d = mul_vec(&BRADFORD, xy_to_xyz(dst));
    let gain = [d[0] / s[0], d[1] / s[1], d[2] / s[2]];
    // BRADFORD is well conditioned: its inverse always exists.
    let inv = invert(&BRADFORD).unwrap_or(IDENTITY);
    mul(&inv, &mul(&diag(gain), &BRADFORD))
}

/// RGB -> XYZ matrix of an RGB space from its primaries and white (Y of white = 1).
pub fn rgb_to_xyz_matrix(primaries: [[f64; 2]; 3], white: [f64; 2]) -> Result<Mat3> {
    let p = primaries.map(xy_to_xyz);
    let m = [
        [p[0][0], p[1][0], p[2][0]],
        [p[0][1], p[1][1], p[2][1]],
        [p[0][2], p[1][2], p[2][2]],
    ];
    let s = mul_vec(&invert(&m)?, xy_to_xyz(white));
    Ok(mul(&m, &diag(s)))
}

/// XYZ (D65) -> linear sRGB.
pub fn xyz_to_srgb_matrix() -> Mat3 {
    rgb_to_xyz_matrix(REC709_PRIMARIES, D65_XY)
        .and_then(|m| invert(&m))
        .unwrap_or(IDENTITY)
}

/// Correlated colour temperature (kelvin) of an EXIF LightSource code, as the DNG SDK
/// assigns them; `None` for unknown/other codes.
pub fn light_source_temperature(code: u16) -> Option<f64> {
    Some(match code {
        17 | 3 => 2850.0,              // Standard light A, Tungsten
        24 => 3200.0,                  // ISO studio tungsten
        23 => 5000.0,                  // D50
        20 | 1 | 9 | 4 | 18 => 5500.0, // D55, Daylight, Fine weather, Flash, Standard B
        21 | 19 | 10 => 6500.0,        // D65, Standard C, Cloudy
        22 | 11 => 7500.0,             // D75, Shade
        12 => 6430.0,                  // Daylight fluorescent (D 5700-7100K)
        13 => 5000.0,                  // Day white fluorescent (N 4600-5500K)
        14 | 2 => 4150.0,              // Cool white fluorescent (W 3800-4500K), Fluorescent
        15 => 3450.0,                  // White fluorescent (WW 3250-3800K)
        16 => 2940.0,                  // Warm white fluorescent (L 2600-3250K)
        _ => return None,
    })
}

/// Robertson (1968) isotemperature lines: (mired, u, v, slope), CIE 1960 UCS.
const ROBERTSON: [[f64; 4]; 31] = [
    [0.0, 0.18006, 0.26352, -0.24341],
    [10.0, 0.18066, 0.26589, -0.25479],
    [20.0, 0.18133, 0.26846, -0.26876],
    [30.0, 0.18208, 0.27119, -0.28539],
    [40.0, 0.18293, 0.27407, -0.30470],
    [50.0, 0.18388, 0.27709, -0.32675],
    [60.0, 0.18494, 0.28021, -0.35156],
    [70.0, 0.18611, 0.28342, -0.37915],
    [80.0, 0.18740, 0.28668, -0.40955],
    [90.0, 0.18880, 0.28997, -0.44278],
    [100.0, 0.19032, 0.29326, -0.47888],
    [125.0, 0.19462, 0.30141, -0.58204],
    [150.0, 0.19962, 0.30921, -0.70471],
    [175.0, 0.20525, 0.31647, -0.84901],
    [200.0, 0.21142, 0.32312, -1.0182],
    [225.0, 0.21807, 0.32909, -1.2168],
    [250.0, 0.22511, 0.33439, -1.4512],
    [275.0, 0.23247, 0.33904, -1.7298],
    [300.0, 0.24010, 0.34308, -2.0637],
    [325.0, 0.24792, 0.34655, -2.4681],
    [350.0, 0.25591, 0.34951, -2.9641],
    [375.0, 0.26400, 0.35200, -3.5814],
    [400.0, 0.27218, 0.35407, -4.3633],
    [425.0, 0.28039, 0.35577, -5.3762],
    [450.0, 0.28863, 0.35714, -6.7262],
    [475.0, 0.29685, 0.35823, -8.5955],
    [500.0, 0.30505, 0.35907, -11.324],
    [525.0, 0.31320, 0.35968, -15.628],
    [550.0, 0.32129, 0.36011, -23.325],
    [575.0, 0.32931, 0.36038, -40.770],
    [600.0, 0.33724, 0.36051, -116.45],
];

/// Correlated colour temperature of an xy chromaticity (Robertson's method, as in the DNG
/// SDK's `dng_temperature`), clamped to [1e6 / 600, 1e9] kelvin.
pub fn xy_to_cct(xy: [f64; 2]) -> f64 {
    let den = 1.5 - xy[0] + 6.0 * xy[1];
    let (u, v) = (2.0 * xy[0] / den, 3.0 * xy[1] / den);
    let (mut last_dt, mut last_du, mut last_dv) = (0.0, 0.0, 0.0);
    for index in 1..ROBERTSON.len() {
        let [_, tu, tv, slope] = ROBERTSON[index];
        let len = (1.0 + slope * slope).sqrt();
        let (du, dv) = (1.0 / len, slope / len);
        let dt = -(u - tu) * dv + (v - tv) * du;
        if dt <= 0.0 || index == ROBERTSON.len() - 1 {
            let dt = -dt.min(0.0);
            let f = if index == 1 { 0.0 } else { dt / (last_dt + dt) };
            let mired = ROBERTSON[index - 1][0] * f + ROBERTSON[index][0] * (1.0 - f);
            let _ = (last_du, last_dv);
            return 1.0e6 / mired.max(1e-3);
        }
        (last_dt, last_du, last_dv) = (dt, du, dv);
    }
    5000.0
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
    if v.len() != 9 || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::malformed(format!(
            "{name} has {} values (a three-colour camera needs 9 finite values)",
            v.len()
        )));
    }
    Ok([[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]])
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

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn cct_of_standard_whites() {
        // D65 ~ 6504 K, D50 ~ 5003 K, illuminant A (0.44757, 0.40745) ~ 2856 K.
        assert!(
            close(xy_to_cct(D65_XY), 6504.0, 5.0),
            "{}",
            xy_to_cct(D65_XY)
        );
        assert!(
            close(xy_to_cct(D50_XY), 5003.0, 5.0),
            "{}",
            xy_to_cct(D50_XY)
        );
        assert!(close(xy_to_cct([0.44757, 0.40745]), 2856.0, 5.0));
        assert!(xy_to_cct([0.25, 0.25]).is_finite());
        assert!(xy_to_cct([0.6, 0.35]).is_finite());
    }

    #[test]
    fn bradford_known_values() {
        // Lindbloom's Bradford D50 -> D65 (with his whites; ours differ in the 4th digit).
        let m = bradford(D50_XY, D65_XY);
        assert!(close(m[0][0], 0.9555766, 2e-3), "{m:?}");
        assert!(close(m[1][1], 1.0099416, 2e-3), "{m:?}");
        assert!(close(m[2][2], 1.3299098, 2e-3), "{m:?}");
        let w = mul_vec(&m, xy_to_xyz(D50_XY));
        let t = xy_to_xyz(D65_XY);
        for i in 0..3 {
            assert!(close(w[i], t[i], 1e-9));
        }
    }

    #[test]
    fn srgb_matrix_matches_iec() {
        let m = xyz_to_srgb_matrix();
        assert!(
            close(m[0][0], 3.2406, 1e-3) && close(m[0][1], -1.5372, 1e-3),
            "{m:?}"
        );
        assert!(
            close(m[1][1], 1.8758, 1e-3) && close(m[2][2], 1.0570, 1e-3),
            "{m:?}"
        );
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
