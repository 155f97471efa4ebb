//! CIE XYZ and xy chromaticities, the standard whites, Bradford chromatic adaptation, and the
//! matrices between XYZ and linear sRGB (Rec.709 primaries, D65 white).
//!
//! Two XYZ -> sRGB matrices exist, on purpose, and both are defined here only:
//! * [`xyz_to_srgb_matrix`] is derived from the primaries and [`D65_XY`] (3.2410, -1.5374,
//!   ...): the renders' colour conversion uses it.
//! * [`XYZ_TO_SRGB`] is the tabulated 7-digit matrix (3.2404542, ..., Lindbloom's, with the
//!   D65 white 0.31271, 0.32902): the DNG thumbnail's conversion, the default ColorMatrix1
//!   of a raw without colour metadata and of the synthetic metadata, and LibRaw's
//!   `color_matrix` (the Python package's `from_rawpy` undoes it with this one). They differ by up
//!   to 5.2e-4; each stays where its outputs were made with it.

use super::matrix3::{diag, inverse, mul, mul_vec, Mat3, IDENTITY};

/// Chromaticity of CIE D50 as the DNG SDK uses it (the PCS white).
pub const D50_XY: [f64; 2] = [0.3457, 0.3585];
/// Chromaticity of CIE D65 (sRGB / Rec.709 white).
pub const D65_XY: [f64; 2] = [0.3127, 0.3290];
/// Rec.709 / sRGB primaries (x, y): red, green, blue.
pub const REC709_PRIMARIES: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

/// XYZ (D65) -> linear sRGB, the tabulated 7-digit matrix (module docs), row-major.
pub const XYZ_TO_SRGB: [f64; 9] = [
    3.2404542, -1.5371385, -0.4985314, -0.9692660, 1.8760108, 0.0415560, 0.0556434, -0.2040259,
    1.0572252,
];

/// Linear sRGB -> XYZ (D65), the tabulated 7-digit matrix paired with [`XYZ_TO_SRGB`]
/// (Lindbloom's), row-major: the synthetic scene of the example generators
/// (examples/common/scene.rs), and so the committed fixtures made from it.
pub const SRGB_TO_XYZ_TABULATED: [f64; 9] = [
    0.4124564, 0.3575761, 0.1804375, 0.2126729, 0.7151522, 0.0721750, 0.0193339, 0.1191920,
    0.9503041,
];

/// Linear sRGB -> XYZ (D65) with the 4-digit values of IEC 61966-2-1 (as colour-science's
/// `sRGB_to_XYZ`): the CIELAB conversion of the colour-difference metric.
pub const SRGB_TO_XYZ: Mat3 = [
    [0.4124, 0.3576, 0.1805],
    [0.2126, 0.7152, 0.0722],
    [0.0193, 0.1192, 0.9505],
];

/// Bradford cone response matrix.
const BRADFORD: Mat3 = [
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
];

/// xy chromaticity to XYZ with Y = 1.
pub fn xy_to_xyz(xy: [f64; 2]) -> [f64; 3] {
    let y = xy[1].max(1e-12);
    [xy[0] / y, 1.0, (1.0 - xy[0] - xy[1]) / y]
}

/// XYZ to xy chromaticity (D50 for black or degenerate input, as the DNG SDK does).
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
    let inv = inverse(&BRADFORD).unwrap_or(IDENTITY);
    mul(&inv, &mul(&diag(gain), &BRADFORD))
}

/// RGB -> XYZ matrix of an RGB space from its primaries and white (Y of white = 1); `None`
/// when the primaries are collinear.
pub fn rgb_to_xyz_matrix(primaries: [[f64; 2]; 3], white: [f64; 2]) -> Option<Mat3> {
    let p = primaries.map(xy_to_xyz);
    let m = [
        [p[0][0], p[1][0], p[2][0]],
        [p[0][1], p[1][1], p[2][1]],
        [p[0][2], p[1][2], p[2][2]],
    ];
    let s = mul_vec(&inverse(&m).ok()?, xy_to_xyz(white));
    Some(mul(&m, &diag(s)))
}

/// XYZ (D65) -> linear sRGB, derived from [`REC709_PRIMARIES`] and [`D65_XY`].
pub fn xyz_to_srgb_matrix() -> Mat3 {
    rgb_to_xyz_matrix(REC709_PRIMARIES, D65_XY)
        .and_then(|m| inverse(&m).ok())
        .unwrap_or(IDENTITY)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::matrix3::from_row_major;
    use proptest::prelude::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
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
    fn srgb_matrices_match_iec() {
        let m = xyz_to_srgb_matrix();
        assert!(
            close(m[0][0], 3.2406, 1e-3) && close(m[0][1], -1.5372, 1e-3),
            "{m:?}"
        );
        assert!(
            close(m[1][1], 1.8758, 1e-3) && close(m[2][2], 1.0570, 1e-3),
            "{m:?}"
        );
        // The tabulated matrix is the same to 6e-4 (at most 5.2e-4, in [0][0]), and inverts
        // the IEC sRGB -> XYZ.
        let t = from_row_major(&XYZ_TO_SRGB).unwrap();
        for i in 0..9 {
            assert!(close(t[i / 3][i % 3], m[i / 3][i % 3], 6e-4), "{t:?} {m:?}");
        }
        let p = mul(&t, &SRGB_TO_XYZ);
        for i in 0..9 {
            let want = if i % 4 == 0 { 1.0 } else { 0.0 };
            assert!(close(p[i / 3][i % 3], want, 1e-3), "{p:?}");
        }
        // White (1, 1, 1) of sRGB is D65 with Y = 1.
        let w = mul_vec(
            &rgb_to_xyz_matrix(REC709_PRIMARIES, D65_XY).unwrap(),
            [1.0; 3],
        );
        let d65 = xy_to_xyz(D65_XY);
        assert!((0..3).all(|i| close(w[i], d65[i], 1e-12)), "{w:?}");
        assert!(rgb_to_xyz_matrix([[0.3, 0.3], [0.3, 0.3], [0.2, 0.2]], D65_XY).is_none());
    }

    #[test]
    fn degenerate_xyz_is_d50() {
        assert_eq!(xyz_to_xy([0.0; 3]), D50_XY);
        assert_eq!(xyz_to_xy([f64::NAN, 1.0, 1.0]), D50_XY);
    }

    proptest! {
        /// xy -> XYZ -> xy is the identity, and Bradford maps its source white to its target.
        #[test]
        fn chromaticity_round_trips(x in 0.05f64..0.7, y in 0.05f64..0.8) {
            prop_assume!(x + y < 0.99);
            let back = xyz_to_xy(xy_to_xyz([x, y]));
            prop_assert!(close(back[0], x, 1e-12) && close(back[1], y, 1e-12));
            let w = mul_vec(&bradford([x, y], D65_XY), xy_to_xyz([x, y]));
            let t = xy_to_xyz(D65_XY);
            prop_assert!((0..3).all(|i| close(w[i], t[i], 1e-9)), "{:?}", w);
        }
    }
}
