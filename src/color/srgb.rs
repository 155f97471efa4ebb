//! The sRGB transfer curves of IEC 61966-2-1: the OETF (linear to display,
//! `12.92 x` up to x = 0.0031308, else `1.055 x^(1/2.4) - 0.055`) and its inverse (display to
//! linear, `v / 12.92` up to v = 0.04045, else `((v + 0.055) / 1.055)^2.4`), in `f32` (the
//! renders, metrics and report images) and `f64` (the DNG thumbnail), and the 8-bit encoding
//! of the report's images.
//!
//! Both precisions are generated from one definition, so each spells the same constants and
//! the same operation order its callers always used.

/// The linear value where the OETF's two pieces meet, 0.0031308 (a point tests probe).
pub const KNEE: f32 = 0.003_130_8;

/// Defines the OETF and its inverse for one float type (literals take the type).
macro_rules! srgb_curves {
    ($t:ty, $oetf:ident, $eotf:ident) => {
        /// sRGB OETF: a linear value to its display value (not clamped).
        #[inline]
        pub fn $oetf(x: $t) -> $t {
            if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            }
        }

        /// Inverse of the sRGB OETF: a display value to its linear value (not clamped).
        #[inline]
        pub fn $eotf(v: $t) -> $t {
            if v <= 0.040_45 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        }
    };
}

srgb_curves!(f32, oetf, eotf);
srgb_curves!(f64, oetf_f64, eotf_f64);

/// A linear value as an 8-bit sRGB code: clipped to [0, 1] (non-finite values give 0), the
/// OETF, rounded half up.
pub fn encode8(v: f32) -> u8 {
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.0
    };
    (oetf(v) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn known_points_and_the_knee() {
        assert_eq!(oetf(0.0), 0.0);
        assert!((oetf(1.0) - 1.0).abs() < 1e-6);
        assert!((oetf(0.18) - 0.4613561).abs() < 1e-5);
        assert!((oetf_f64(0.18) - 0.461356129).abs() < 1e-8);
        assert!((eotf_f64(0.5) - 0.214041140).abs() < 1e-8);
        // The two pieces meet at the knee (within the 4-digit constants' mismatch).
        let k = f64::from(KNEE);
        assert!((12.92 * k - (1.055 * k.powf(1.0 / 2.4) - 0.055)).abs() < 1e-7);
        assert!((oetf_f64(k) - 0.040_45).abs() < 1e-6);
        assert_eq!(encode8(0.0), 0);
        assert_eq!(encode8(1.0), 255);
        assert_eq!(encode8(f32::NAN), 0);
        assert_eq!(encode8(f32::INFINITY), 0);
        assert_eq!(encode8(0.2159), 128);
    }

    #[test]
    fn both_precisions_agree() {
        for i in 0..=1000 {
            let x = i as f32 / 1000.0;
            assert!((f64::from(oetf(x)) - oetf_f64(f64::from(x))).abs() < 1e-6);
            assert!((f64::from(eotf(x)) - eotf_f64(f64::from(x))).abs() < 1e-6);
        }
    }

    proptest! {
        /// The OETF is monotone on [0, 1] and the inverse undoes it.
        #[test]
        fn monotone_and_invertible(a in 0.0f64..=1.0, b in 0.0f64..=1.0) {
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            prop_assert!(oetf_f64(lo) <= oetf_f64(hi));
            prop_assert!(eotf_f64(lo) <= eotf_f64(hi));
            prop_assert!((eotf_f64(oetf_f64(a)) - a).abs() < 1e-12);
            prop_assert!((oetf_f64(eotf_f64(a)) - a).abs() < 1e-12);
            let x = a as f32;
            prop_assert!((eotf(oetf(x)) - x).abs() < 1e-5);
            prop_assert!(oetf(lo as f32) <= oetf(hi as f32));
        }
    }
}
