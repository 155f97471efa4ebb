//! The day neutral (docs/synthesis.md, "2. Remove the day illuminant"): AsShotNeutral, or AsShotWhiteXY converted through the
//! colour matrices, or the user's `--day-neutral`; normalized so that green = 1 and
//! refused when a component is tiny, zero, negative or not finite.
//!
//! Why green = 1: AsShotNeutral is a direction, "the selected white balance in linear
//! reference space values" (DNG 1.6, AsShotNeutral); its scale carries no meaning (raw
//! tools divide by it and renormalize; many cameras store green = 1, others do not), so
//! dividing by the vector as stored would also dim or brighten the image by its arbitrary
//! green component. The authors' release does divide by the stored vector
//! ([`day_neutral_as_stored`], `SynthOptions::compat.neutral_as_stored`): a file storing
//! "1 2.477 1.462" comes out 2.477 times darker there.
//!
//! AsShotWhiteXY conversion: `neutral = AnalogBalance * CameraCalibration * ColorMatrix * XYZ(x, y)`
//! with ColorMatrix1/2 interpolated linearly in inverse correlated colour temperature (DNG
//! chapter 6); the white's CCT comes from McCamy's formula (no iteration is needed because
//! the white is given in xy).

use crate::color::matrix3::{from_row_major, mul_vec, Mat3};
use crate::error::{Error, Result};
use crate::raw::meta::RawMeta;

/// Smallest accepted neutral component (relative to green): the one table's bound.
pub const MIN_NEUTRAL: f64 = 1.0 / crate::bounds::MAX_NEUTRAL_RATIO;

/// [`check_neutral`] for a day (camera) neutral, which also may not exceed
/// [`crate::bounds::MAX_NEUTRAL_RATIO`] times green.
pub fn check_day_neutral(n: [f64; 3], what: &str) -> Result<[f64; 3]> {
    let out = check_neutral(n, what)?;
    crate::bounds::ratios(what, &out, crate::bounds::MAX_NEUTRAL_RATIO)?;
    Ok(out)
}

/// Normalize a neutral to green = 1 and check it.
pub fn check_neutral(n: [f64; 3], what: &str) -> Result<[f64; 3]> {
    if n.iter().any(|v| !v.is_finite()) || n[1] <= 0.0 {
        return Err(Error::invalid(format!(
            "{} {:?} has a non-finite or non-positive green component",
            what, n
        )));
    }
    let out = [n[0] / n[1], 1.0, n[2] / n[1]];
    if out
        .iter()
        .any(|&v| v.is_nan() || v < MIN_NEUTRAL || !v.is_finite())
    {
        return Err(Error::invalid(format!(
            "{} {:?} has a tiny, zero or negative component (each must be >= {} of green)",
            what, n, MIN_NEUTRAL
        )));
    }
    Ok(out)
}

/// CCT of an EXIF LightSource code (None when unknown).
pub fn illuminant_cct(code: u16) -> Option<f64> {
    Some(match code {
        1 | 4 | 9 => 5500.0,
        2 | 14 => 4150.0,
        3 | 17 => 2856.0,
        10 => 6500.0,
        11 => 7500.0,
        12 => 6430.0,
        13 => 5000.0,
        15 => 3450.0,
        16 => 2940.0,
        18 => 4874.0,
        19 => 6774.0,
        20 => 5503.0,
        21 => 6504.0,
        22 => 7504.0,
        23 => 5003.0,
        24 => 3200.0,
        _ => return None,
    })
}

/// Camera neutral of a white given as CIE xy, through the metadata's colour matrices.
pub fn neutral_from_white_xy(meta: &RawMeta, xy: [f64; 2]) -> Result<[f64; 3]> {
    let (x, y) = (xy[0], xy[1]);
    if y.is_nan() || y <= 0.0 || !x.is_finite() {
        return Err(Error::invalid(format!(
            "AsShotWhiteXY {:?} is not a valid white",
            xy
        )));
    }
    let xyz = [x / y, 1.0, (1.0 - x - y) / y];
    let c = &meta.color;
    let m1 = c.color_matrix1.as_deref().and_then(from_row_major);
    let m2 = c.color_matrix2.as_deref().and_then(from_row_major);
    let cc1 = c.camera_calibration1.as_deref().and_then(from_row_major);
    let cc2 = c.camera_calibration2.as_deref().and_then(from_row_major);
    let n = (x - 0.3320) / (0.1858 - y);
    let cct = 449.0 * n.powi(3) + 3525.0 * n.powi(2) + 6823.3 * n + 5520.33;
    let t1 = c.calibration_illuminant1.and_then(illuminant_cct);
    let t2 = c.calibration_illuminant2.and_then(illuminant_cct);
    // Weight of matrix 1, linear in 1/CCT between the two calibration CCTs.
    let w1 = match (m1.is_some(), m2.is_some(), t1, t2) {
        (true, true, Some(a), Some(b)) if a != b && cct.is_finite() && cct > 0.0 => {
            let (ia, ib, ic) = (1.0 / a, 1.0 / b, 1.0 / cct);
            ((ic - ib) / (ia - ib)).clamp(0.0, 1.0)
        }
        (true, _, _, _) => 1.0,
        (false, true, _, _) => 0.0,
        _ => {
            return Err(Error::unsupported(
                "AsShotWhiteXY without a ColorMatrix cannot give a camera neutral (pass --day-neutral r,g,b)",
            ))
        }
    };
    let apply = |m: Option<Mat3>, cc: Option<Mat3>| -> [f64; 3] {
        match m {
            Some(m) => {
                let v = mul_vec(&m, xyz);
                match cc {
                    Some(cc) => mul_vec(&cc, v),
                    None => v,
                }
            }
            None => [0.0; 3],
        }
    };
    let a = apply(m1, cc1);
    let b = apply(m2, cc2);
    let mut v = [0.0; 3];
    for i in 0..3 {
        v[i] = w1 * a[i] + (1.0 - w1) * b[i];
    }
    if let Some(ab) = c.analog_balance.as_deref().filter(|ab| ab.len() == 3) {
        for i in 0..3 {
            v[i] *= ab[i];
        }
    }
    check_day_neutral(v, "camera neutral from AsShotWhiteXY")
}

/// The day neutral and a word on where it came from.
pub fn day_neutral(meta: &RawMeta, user: Option<[f64; 3]>) -> Result<([f64; 3], String)> {
    if let Some(n) = user {
        return Ok((
            check_day_neutral(n, "--day-neutral")?,
            "--day-neutral".into(),
        ));
    }
    if let Some(n) = meta.as_shot_neutral {
        return Ok((
            check_day_neutral(n, "AsShotNeutral")?,
            "AsShotNeutral".into(),
        ));
    }
    if let Some(xy) = meta.as_shot_white_xy {
        return Ok((
            neutral_from_white_xy(meta, xy)?,
            "AsShotWhiteXY through ColorMatrix".into(),
        ));
    }
    Err(Error::unsupported(
        "no AsShotNeutral or AsShotWhiteXY: the day illuminant is unknown (pass --day-neutral r,g,b)",
    ))
}

/// Components of a day neutral divided by as stored must lie in `[1e-12, 1e12]` (their
/// reciprocals then stay finite and far from 0).
pub const AS_STORED_RANGE: [f64; 2] = [1e-12, 1e12];

/// The day neutral as the release uses it: AsShotNeutral as stored, or `--day-neutral` as
/// given, without normalizing to green = 1 (checked like [`check_neutral`], and each
/// component within [`AS_STORED_RANGE`]). AsShotWhiteXY has no stored scale: it gives the
/// same (green = 1) neutral as [`day_neutral`].
pub fn day_neutral_as_stored(meta: &RawMeta, user: Option<[f64; 3]>) -> Result<([f64; 3], String)> {
    // The reader normalizes AsShotNeutral to green = 1; the entry as the file stored it
    // (`RawMeta::stored`) gives the release's reading.
    let stored = meta
        .stored_value(crate::tiff::tags::AS_SHOT_NEUTRAL)
        .and_then(|v| v.to_f64_vec())
        .and_then(|v| <[f64; 3]>::try_from(v.as_slice()).ok());
    let (n, what) = match (user, stored.or(meta.as_shot_neutral)) {
        (Some(n), _) => (n, "--day-neutral"),
        (None, Some(n)) => (n, "AsShotNeutral"),
        (None, None) => return day_neutral(meta, None),
    };
    check_neutral(n, what)?;
    if n.iter()
        .any(|&v| !(AS_STORED_RANGE[0]..=AS_STORED_RANGE[1]).contains(&v))
    {
        return Err(Error::invalid(format!(
            "{} {:?}: to divide by it as stored, each component must lie in [{}, {}]",
            what, n, AS_STORED_RANGE[0], AS_STORED_RANGE[1]
        )));
    }
    Ok((
        n,
        format!("{} as stored (not normalized; release compatibility)", what),
    ))
}

/// The day neutral `opts` asks for: [`day_neutral_as_stored`] with
/// `compat.neutral_as_stored`, else [`day_neutral`].
pub fn day_neutral_for(meta: &RawMeta, opts: &super::SynthOptions) -> Result<([f64; 3], String)> {
    if opts.compat.neutral_as_stored {
        day_neutral_as_stored(meta, opts.day_neutral)
    } else {
        day_neutral(meta, opts.day_neutral)
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use crate::raw::Bayer;

    #[test]
    fn tiny_or_zero_components_are_errors() {
        assert!(check_neutral([0.0, 1.0, 0.5], "n").is_err());
        assert!(check_neutral([1e-9, 1.0, 0.5], "n").is_err());
        assert!(check_neutral([0.5, 0.0, 0.5], "n").is_err());
        assert!(check_neutral([0.5, 1.0, f64::NAN], "n").is_err());
        assert!(check_neutral([-0.5, 1.0, 0.5], "n").is_err());
        assert_eq!(check_neutral([1.0, 2.477, 1.462], "n").unwrap()[1], 1.0);
    }

    #[test]
    fn as_stored_keeps_the_scale_and_checks() {
        let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        m.as_shot_neutral = Some([1.0, 2.477, 1.462]);
        let (n, src) = day_neutral_as_stored(&m, None).unwrap();
        assert_eq!(n, [1.0, 2.477, 1.462]);
        assert!(src.contains("as stored"), "{src}");
        // the default reading divides by green
        let (d, _) = day_neutral(&m, None).unwrap();
        assert_eq!(d, [1.0 / 2.477, 1.0, 1.462 / 2.477]);
        // the user's neutral as given
        assert_eq!(
            day_neutral_as_stored(&m, Some([0.5, 0.25, 0.75]))
                .unwrap()
                .0,
            [0.5, 0.25, 0.75]
        );
        // refused: bad components, and scales whose reciprocal would overflow or vanish
        for bad in [
            [0.0, 1.0, 1.0],
            [f64::NAN, 1.0, 1.0],
            [1e-300, 1e-300, 1e-300],
            [1e300, 1e300, 1e300],
            [-1.0, -1.0, -1.0],
        ] {
            m.as_shot_neutral = Some(bad);
            assert!(day_neutral_as_stored(&m, None).is_err(), "{bad:?}");
        }
        // no stored vector: AsShotWhiteXY has no scale and gives the normalized neutral
        m.as_shot_neutral = None;
        m.as_shot_white_xy = Some([0.3127, 0.3290]);
        let (w, _) = day_neutral_as_stored(&m, None).unwrap();
        assert_eq!(w, day_neutral(&m, None).unwrap().0);
    }

    #[test]
    fn white_xy_of_d65_on_srgb_camera_is_unit() {
        // new_bayer's ColorMatrix1 is XYZ(D65) -> linear sRGB: D65 white -> (1, 1, 1).
        let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        m.as_shot_neutral = None;
        m.as_shot_white_xy = Some([0.3127, 0.3290]);
        let (n, src) = day_neutral(&m, None).unwrap();
        assert!(src.contains("WhiteXY"));
        for v in n {
            assert!((v - 1.0).abs() < 2e-3, "{n:?}");
        }
        m.as_shot_white_xy = None;
        assert!(day_neutral(&m, None)
            .unwrap_err()
            .to_string()
            .contains("--day-neutral"));
        assert_eq!(
            day_neutral(&m, Some([2.0, 4.0, 1.0])).unwrap().0,
            [0.5, 1.0, 0.25]
        );
    }
}
