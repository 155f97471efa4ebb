//! The release's colour stages: its camera -> XYZ matrix (ColorMatrix1/2 with rows
//! normalized to sum 1, mixed by a CCT found from the neutral between a 6500 K and a 2500 K
//! end, inverted) and its XYZ -> sRGB step (the tabulated matrix with rows normalized to sum
//! 1), each clipped to [0, 1], in float64.
//!
//! Three habits of the release are kept because its renders depend on them: ColorMatrix2 is
//! divided by the row sums of the already normalized ColorMatrix1 (so it stays as stored);
//! a missing ColorMatrix is all ones; the CCT search mixes the matrices without clamping,
//! the final mix clamps the weight of the 6500 K end to [0, 1].

use super::meta::ReleaseMeta;
use crate::color::cct::release_xyz_to_cct;
use crate::color::matrix3::{determinant, inverse_with_determinant, Mat3};
use crate::color::xyz::XYZ_TO_SRGB;
use crate::error::{Error, Result};

/// The release's two matrix temperatures (kelvin): ColorMatrix1's and ColorMatrix2's, as it
/// assumes them whatever CalibrationIlluminant1/2 say.
const CCT1: f64 = 6500.0;
const CCT2: f64 = 2500.0;

/// The most CCT refinements before the search is called non-converging (the release would
/// loop for ever).
const MAX_ROUNDS: usize = 1000;

fn rows(v: &[f64; 9]) -> Mat3 {
    [[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]]
}

fn row_sums(m: &Mat3) -> [f64; 3] {
    m.map(|r| r[0] + r[1] + r[2])
}

fn divide_rows(m: &Mat3, s: [f64; 3]) -> Mat3 {
    let mut o = *m;
    for (row, d) in o.iter_mut().zip(s) {
        for v in row.iter_mut() {
            *v /= d;
        }
    }
    o
}

/// `m * v` with each row's products summed left to right.
fn apply(m: &Mat3, v: [f64; 3]) -> [f64; 3] {
    m.map(|r| r[0] * v[0] + r[1] * v[1] + r[2] * v[2])
}

fn invert(m: &Mat3, what: &str) -> Result<Mat3> {
    let det = determinant(m);
    if det == 0.0 || !det.is_finite() {
        return Err(Error::invalid(format!(
            "--isp release: the {what} matrix {m:?} is singular"
        )));
    }
    Ok(inverse_with_determinant(m, det))
}

/// `g * m1 + h * m2` with g the weight of the 6500 K end at temperature `t`; clamped to
/// [0, 1] when `clamp`.
fn mix(m1: &Mat3, m2: &Mat3, t: f64, clamp: bool) -> Mat3 {
    let (inv1, inv2) = (1.0 / CCT1, 1.0 / CCT2);
    let mut g = (1.0 / t - inv2) / (inv1 - inv2);
    let mut h = 1.0 - g;
    if clamp {
        g = g.max(0.0);
        h = h.clamp(0.0, 1.0);
    }
    let mut o = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            o[i][j] = g * m1[i][j] + h * m2[i][j];
        }
    }
    o
}

/// The release's CCT of `neutral` for these matrices: from XYZ (0.3, 0.3, 0.3), alternately
/// the CCT of the current XYZ and the XYZ of the neutral through the matrices mixed at it,
/// until the XYZ moves by at most 1e-4.
pub fn neutral_cct(neutral: [f64; 3], m1: &Mat3, m2: &Mat3) -> Result<f64> {
    let mut p = [0.3; 3];
    let mut loss = 1e10;
    let mut cct = CCT1;
    let mut rounds = 0;
    while loss > 1e-4 {
        rounds += 1;
        if rounds > MAX_ROUNDS {
            return Err(Error::invalid(format!(
                "--isp release: the release's CCT search for neutral {neutral:?} does not \
                 converge in {MAX_ROUNDS} rounds"
            )));
        }
        cct = release_xyz_to_cct(p).unwrap_or(-1.0);
        let xyz = apply(&invert(&mix(m1, m2, cct, false), "mixed colour")?, neutral);
        let d = [xyz[0] - p[0], xyz[1] - p[1], xyz[2] - p[2]];
        loss = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        p = xyz;
    }
    Ok(cct)
}

/// The release's camera -> XYZ matrix for `meta` (its neutral and colour matrices), with
/// the CCT that chose it.
pub fn camera_to_xyz(meta: &ReleaseMeta) -> Result<(Mat3, f64)> {
    let m1 = rows(&meta.cm1);
    let m1 = divide_rows(&m1, row_sums(&m1));
    let m2 = divide_rows(&rows(&meta.cm2), row_sums(&m1));
    let cct = neutral_cct(meta.neutral, &m1, &m2)?;
    let mixed = mix(&m1, &m2, cct, true);
    let mixed = divide_rows(&mixed, row_sums(&mixed));
    Ok((invert(&mixed, "XYZ -> camera")?, cct))
}

/// The release's XYZ -> sRGB matrix: [`XYZ_TO_SRGB`] with each row divided by its sum.
pub fn xyz_to_srgb() -> Mat3 {
    let m = rows(&XYZ_TO_SRGB);
    divide_rows(&m, row_sums(&m))
}

/// Camera RGB -> XYZ -> sRGB of one pixel, each step clipped to [0, 1].
#[inline]
pub fn to_srgb(cam_to_xyz: &Mat3, xyz_to_srgb: &Mat3, rgb: [f64; 3]) -> [f64; 3] {
    let xyz = apply(cam_to_xyz, rgb).map(|v| v.clamp(0.0, 1.0));
    apply(xyz_to_srgb, xyz).map(|v| v.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::isp::release::meta::{Black, ReleaseMeta};

    fn meta(cm1: [f64; 9], cm2: [f64; 9], neutral: [f64; 3]) -> ReleaseMeta {
        ReleaseMeta {
            black: Black::Scalar(0.0),
            white: 1.0,
            cfa: [0, 1, 1, 2],
            neutral,
            cm1,
            cm2,
            orientation: 1,
            second_crop: None,
        }
    }

    const EYE: [f64; 9] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

    #[test]
    fn srgb_rows_sum_to_one() {
        for row in xyz_to_srgb() {
            assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        }
    }

    /// Identity matrices and a flat neutral: XYZ (1, 1, 1), illuminant E (about 5455 K), and
    /// the identity back whatever the mix.
    #[test]
    fn identity_camera() {
        let (m, cct) = camera_to_xyz(&meta(EYE, EYE, [1.0; 3])).unwrap();
        assert!((cct - 5455.0).abs() < 10.0, "{cct}");
        for (i, row) in m.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                assert!((v - f64::from(u8::from(i == j))).abs() < 1e-12);
            }
        }
        let px = to_srgb(&m, &xyz_to_srgb(), [2.0, -1.0, 0.5]);
        assert!(px.iter().all(|v| (0.0..=1.0).contains(v)));
    }

    /// The release's missing ColorMatrix2 (all ones) mixes in only below 6500 K: a neutral
    /// that the search puts at a low CCT gives another matrix than ColorMatrix1 alone.
    #[test]
    fn missing_second_matrix_mixes_in_at_low_cct() {
        let cm1 = [
            0.4716, 0.0603, -0.083, -0.7798, 1.5474, 0.248, -0.1496, 0.1937, 0.6651,
        ];
        let ones = [1.0; 9];
        let (_, daylight) = camera_to_xyz(&meta(cm1, ones, [0.39, 1.0, 0.72])).unwrap();
        let (warm, t) = camera_to_xyz(&meta(cm1, ones, [0.8, 1.0, 0.3])).unwrap();
        let (alone, _) = camera_to_xyz(&meta(cm1, cm1, [0.8, 1.0, 0.3])).unwrap();
        assert!(t < daylight, "{t} vs {daylight}");
        assert!((warm[0][0] - alone[0][0]).abs() > 1e-3);
    }
}
