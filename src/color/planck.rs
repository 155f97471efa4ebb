//! The Planckian locus, correlated colour temperature (CCT) and distance from the locus
//! (Duv) of a CIE 1931 xy chromaticity, for judging and plotting light colours.
//!
//! * The locus in CIE 1960 (u, v) is Krystek's rational approximation ("An algorithm to
//!   calculate correlated colour temperature", Color Research & Application 10(1), 1985),
//!   published for 1,000 K to 15,000 K; it agrees with colour-science's Ohno 2013 within
//!   0.5 mired and 2e-4 in Duv (validator test `synth_lamps::cie_table_matches_colour_science`).
//! * CCT is the temperature of the nearest locus point in (u, v) (the CIE definition, as
//!   Ohno's 2013 method computes it), found by a grid search in mired followed by golden
//!   section refinement; Duv is the signed distance to that point, positive above the locus
//!   (towards green), negative below (towards magenta).
//!
//! [`super::cct::xy_to_cct`] (Robertson's lines, as the DNG SDK uses them) stays the one
//! that picks colour matrices; this module measures.

use crate::error::{Error, Result};

/// Temperature range of the locus approximation, kelvin.
pub const CCT_RANGE: (f64, f64) = (1000.0, 15000.0);

/// CIE 1960 (u, v) of the Planckian radiator at `t` kelvin (Krystek 1985), `t` clamped to
/// [`CCT_RANGE`].
pub fn planck_uv(t: f64) -> [f64; 2] {
    let t = t.clamp(CCT_RANGE.0, CCT_RANGE.1);
    let u = (0.860117757 + 1.54118254e-4 * t + 1.28641212e-7 * t * t)
        / (1.0 + 8.42420235e-4 * t + 7.08145163e-7 * t * t);
    let v = (0.317398726 + 4.22806245e-5 * t + 4.20481691e-8 * t * t)
        / (1.0 - 2.89741816e-5 * t + 1.61456053e-7 * t * t);
    [u, v]
}

/// CIE 1931 xy of the Planckian radiator at `t` kelvin.
pub fn planck_xy(t: f64) -> [f64; 2] {
    uv_to_xy(planck_uv(t))
}

/// CIE 1931 xy to CIE 1960 (u, v); `None` for a degenerate or non-finite xy.
pub fn xy_to_uv(xy: [f64; 2]) -> Option<[f64; 2]> {
    let d = -2.0 * xy[0] + 12.0 * xy[1] + 3.0;
    let uv = [4.0 * xy[0] / d, 6.0 * xy[1] / d];
    (d.abs() > 1e-12 && uv.iter().all(|v| v.is_finite())).then_some(uv)
}

/// CIE 1960 (u, v) to CIE 1931 xy.
pub fn uv_to_xy(uv: [f64; 2]) -> [f64; 2] {
    let d = 2.0 * uv[0] - 8.0 * uv[1] + 4.0;
    [3.0 * uv[0] / d, 2.0 * uv[1] / d]
}

fn dist2(uv: [f64; 2], mired: f64) -> f64 {
    let p = planck_uv(1e6 / mired);
    (uv[0] - p[0]).powi(2) + (uv[1] - p[1]).powi(2)
}

/// Correlated colour temperature (kelvin) and Duv of an xy chromaticity (module docs).
/// Errors on a non-finite or degenerate xy, and for colours whose nearest locus point lies
/// at an end of [`CCT_RANGE`] (no meaningful CCT: far from any white).
pub fn cct_duv(xy: [f64; 2]) -> Result<(f64, f64)> {
    let uv = xy_to_uv(xy)
        .filter(|_| xy.iter().all(|v| v.is_finite()))
        .ok_or_else(|| Error::invalid(format!("chromaticity {xy:?} has no CCT")))?;
    let (lo, hi) = (1e6 / CCT_RANGE.1, 1e6 / CCT_RANGE.0);
    const STEPS: usize = 400;
    let step = (hi - lo) / STEPS as f64;
    let best = (0..=STEPS)
        .map(|i| lo + step * i as f64)
        .min_by(|a, b| dist2(uv, *a).total_cmp(&dist2(uv, *b)))
        .unwrap_or(lo);
    if best <= lo || best >= hi {
        return Err(Error::invalid(format!(
            "chromaticity [{:.4}, {:.4}] is outside the Planckian locus range {:.0}..{:.0} K",
            xy[0], xy[1], CCT_RANGE.0, CCT_RANGE.1
        )));
    }
    // Golden section on [best - step, best + step] (the distance is unimodal there).
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (best - step, best + step);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    for _ in 0..80 {
        if dist2(uv, c) < dist2(uv, d) {
            b = d;
        } else {
            a = c;
        }
        c = b - g * (b - a);
        d = a + g * (b - a);
    }
    let mired = 0.5 * (a + b);
    let p = planck_uv(1e6 / mired);
    let dist = dist2(uv, mired).sqrt();
    let duv = if uv[1] >= p[1] { dist } else { -dist };
    Ok((1e6 / mired, duv))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locus_points_have_zero_duv_and_their_own_cct() {
        for t in [1200.0, 1900.0, 2856.0, 4000.0, 6504.0, 10000.0, 14000.0] {
            let (cct, duv) = cct_duv(planck_xy(t)).unwrap();
            assert!((cct - t).abs() < 1e-4 * t, "{t}: {cct}");
            assert!(duv.abs() < 1e-9, "{t}: {duv}");
        }
    }

    #[test]
    fn known_whites() {
        // Illuminant A (2856 K Planckian), D65 (Duv +0.0032), FL4.
        let (t, d) = cct_duv([0.44758, 0.40745]).unwrap();
        assert!((t - 2856.0).abs() < 3.0 && d.abs() < 2e-4, "{t} {d}");
        let (t, d) = cct_duv([0.3127, 0.3290]).unwrap();
        assert!(
            (t - 6504.0).abs() < 10.0 && (d - 0.0032).abs() < 2e-4,
            "{t} {d}"
        );
        // Off the locus towards green: positive; towards magenta: negative.
        let above = uv_to_xy([planck_uv(3000.0)[0], planck_uv(3000.0)[1] + 0.02]);
        let below = uv_to_xy([planck_uv(3000.0)[0], planck_uv(3000.0)[1] - 0.02]);
        assert!(cct_duv(above).unwrap().1 > 0.015);
        assert!(cct_duv(below).unwrap().1 < -0.015);
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        assert!(cct_duv([f64::NAN, 0.3]).is_err());
        assert!(cct_duv([0.7, 0.3]).is_err()); // past 1000 K
        assert!(cct_duv([0.0, 0.0]).is_err()); // far from any white
        assert!(xy_to_uv([1.5, 0.0]).is_none());
        let uv = xy_to_uv([0.31, 0.33]).unwrap();
        let xy = uv_to_xy(uv);
        assert!((xy[0] - 0.31).abs() < 1e-15 && (xy[1] - 0.33).abs() < 1e-15);
    }
}
