//! The planning of opcode work, before any pixel is touched: opcodes that change nothing are
//! dropped ([`noop_reason`]: an identity warp, gains or scales of 1, zero deltas, an identity
//! polynomial, an empty bad-pixel list, a bad-pixel list that repeats the one before it), and
//! the rest are costed ([`cost`]) against the budget of [`crate::limits::check_opcode_work`]
//! (docs/limits.md, "Opcode work").
//!
//! A dropped opcode leaves every sample bit for bit as it was, so dropping it changes no
//! output: stage values are pinned into `[0, range]` (never NaN, never -0) before and after
//! every opcode, and `min(x * 1, range)`, `x + 0` and `0 + 1 x` give `x` exactly there. The
//! one exception is the identity warp, which the whole-frame path resampled at source
//! positions `c + (d - c)` that float rounding may move by 1e-16 of a pixel; the Adobe DNG
//! SDK skips it too (`IsNOP`).

use super::area;
use crate::dng::opcodes::{AreaSpec, Opcode, OpcodeKind};
use crate::limits::{
    COST_BAD_PIXELS, COST_BAD_PIXELS_REPEAT, COST_GAIN, COST_POINTWISE, COST_TRIM, COST_WARP,
    COST_WARP_FISHEYE,
};

/// Why `kind` changes no sample (None: it may).
pub fn noop_reason(kind: &OpcodeKind) -> Option<&'static str> {
    match kind {
        OpcodeKind::WarpRectilinear { planes, .. }
            if planes
                .iter()
                .all(|p| p.kr == [1.0, 0.0, 0.0, 0.0] && p.kt == [0.0, 0.0]) =>
        {
            Some("identity warp (kr0 = 1, every other coefficient 0)")
        }
        OpcodeKind::WarpRectilinear2 { planes, .. }
            if planes.iter().all(|p| {
                p.kr[0] == 1.0 && p.kr[1..].iter().all(|&k| k == 0.0) && p.kt == [0.0, 0.0]
            }) =>
        {
            Some("identity warp (kr0 = 1, every other coefficient 0)")
        }
        OpcodeKind::FixVignetteRadial { k, .. } if k.iter().all(|&v| v == 0.0) => {
            Some("gain 1 everywhere (every coefficient 0)")
        }
        OpcodeKind::GainMap(g) if !g.gains.is_empty() && g.gains.iter().all(|&v| v == 1.0) => {
            Some("every gain is 1")
        }
        OpcodeKind::MapPolynomial { coefficients, .. }
            if coefficients.len() >= 2
                && coefficients[1] == 1.0
                && coefficients
                    .iter()
                    .enumerate()
                    .all(|(i, &c)| i == 1 || c == 0.0) =>
        {
            Some("identity polynomial (c1 = 1, every other coefficient 0)")
        }
        OpcodeKind::DeltaPerRow { deltas, .. } | OpcodeKind::DeltaPerColumn { deltas, .. }
            if deltas.iter().all(|&d| d == 0.0) =>
        {
            Some("every delta is 0")
        }
        OpcodeKind::ScalePerRow { scales, .. } | OpcodeKind::ScalePerColumn { scales, .. }
            if scales.iter().all(|&s| s == 1.0) =>
        {
            Some("every scale is 1")
        }
        OpcodeKind::FixBadPixelsList { points, rects, .. }
            if points.is_empty() && rects.is_empty() =>
        {
            Some("no bad pixel listed")
        }
        k => k
            .area()
            .filter(|a| a.planes == 0)
            .map(|_| "its area has no plane"),
    }
}

/// True when `op` repeats `prev` and applying it again changes nothing: a FixBadPixelsList
/// marks the same samples and reads the same good neighbours, so a second pass writes the
/// same means again.
pub fn repeats_idempotently(prev: Option<&Opcode>, op: &Opcode) -> bool {
    matches!(op.kind, OpcodeKind::FixBadPixelsList { .. })
        && prev.is_some_and(|p| p.kind == op.kind)
}

/// Pixels of a `w x h` stage image an area opcode touches.
fn area_pixels(a: &AreaSpec, w: usize, h: usize) -> u64 {
    let rows = (0..h).filter(|&r| area::row_step(a, r).is_some()).count() as u64;
    let cols = area::col_span(a, 0, w).map_or(0, |(first, end, pitch, _)| {
        ((end - first).div_ceil(pitch)) as u64
    });
    rows * cols
}

/// The pixel-passes of `op` on a `w x h` stage image; `repeat` when it repeats the
/// FixBadPixelsConstant before it (merged into one pass that revisits the pixels still bad).
pub fn cost(op: &OpcodeKind, (w, h): (usize, usize), repeat: bool) -> u64 {
    let px = (w as u64).saturating_mul(h as u64);
    match op {
        OpcodeKind::GainMap(g) => COST_GAIN.saturating_mul(area_pixels(&g.area, w, h)),
        k if k.area().is_some() => {
            COST_POINTWISE.saturating_mul(k.area().map_or(px, |a| area_pixels(a, w, h)))
        }
        OpcodeKind::FixVignetteRadial { .. } => COST_GAIN.saturating_mul(px),
        OpcodeKind::FixBadPixelsConstant { .. } if repeat => {
            COST_BAD_PIXELS_REPEAT.saturating_mul(px)
        }
        OpcodeKind::FixBadPixelsConstant { .. } => COST_BAD_PIXELS.saturating_mul(px),
        OpcodeKind::FixBadPixelsList { points, rects, .. } => {
            let listed: u64 = rects
                .iter()
                .map(|q| {
                    let rh = (q[2].min(h as u32)).saturating_sub(q[0]) as u64;
                    let rw = (q[3].min(w as u32)).saturating_sub(q[1]) as u64;
                    rh * rw
                })
                .fold(points.len() as u64, u64::saturating_add);
            COST_BAD_PIXELS
                .saturating_mul(px)
                .saturating_add(listed.min(px))
        }
        OpcodeKind::WarpRectilinear { .. } | OpcodeKind::WarpRectilinear2 { .. } => {
            COST_WARP.saturating_mul(px)
        }
        OpcodeKind::WarpFisheye { .. } => COST_WARP_FISHEYE.saturating_mul(px),
        OpcodeKind::TrimBounds { .. } => COST_TRIM.saturating_mul(px),
        _ => px,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dng::opcodes::{WarpPlane, WarpPlane2};

    fn area(bottom: u32, right: u32, pitch: u32) -> AreaSpec {
        AreaSpec {
            top: 0,
            left: 0,
            bottom,
            right,
            plane: 0,
            planes: 1,
            row_pitch: pitch,
            col_pitch: pitch,
        }
    }

    #[test]
    fn no_ops_are_recognised_and_others_are_not() {
        let warp = |kr0: f64, kt0: f64| OpcodeKind::WarpRectilinear {
            planes: vec![WarpPlane {
                kr: [kr0, 0.0, 0.0, 0.0],
                kt: [kt0, 0.0],
            }],
            center: [0.3, 0.6],
        };
        assert!(noop_reason(&warp(1.0, 0.0)).is_some());
        assert!(noop_reason(&warp(1.0, 0.001)).is_none());
        assert!(noop_reason(&warp(0.999, 0.0)).is_none());
        let mut kr = [0.0; 15];
        kr[0] = 1.0;
        let w2 = |kr| OpcodeKind::WarpRectilinear2 {
            planes: vec![WarpPlane2 {
                kr,
                kt: [0.0; 2],
                valid: [0.0, 1.0],
            }],
            center: [0.5, 0.5],
            reciprocal: true,
        };
        assert!(noop_reason(&w2(kr)).is_some());
        kr[14] = 1e-9;
        assert!(noop_reason(&w2(kr)).is_none());
        // a fisheye with kr0 = 1 bends the image (atan): never a no-op
        let fish = OpcodeKind::WarpFisheye {
            planes: vec![[1.0, 0.0, 0.0, 0.0]],
            center: [0.5, 0.5],
        };
        assert!(noop_reason(&fish).is_none());
        let poly = |c: &[f64]| OpcodeKind::MapPolynomial {
            area: area(4, 4, 1),
            coefficients: c.to_vec(),
        };
        assert!(noop_reason(&poly(&[0.0, 1.0, 0.0])).is_some());
        assert!(noop_reason(&poly(&[0.0, 1.0, 1e-12])).is_none());
        assert!(noop_reason(&poly(&[1.0])).is_none());
        let scale = |s| OpcodeKind::ScalePerColumn {
            area: area(4, 4, 1),
            scales: vec![1.0, s],
        };
        assert!(noop_reason(&scale(1.0)).is_some());
        assert!(noop_reason(&scale(1.5)).is_none());
        let delta = OpcodeKind::DeltaPerRow {
            area: area(4, 4, 1),
            deltas: vec![0.0; 4],
        };
        assert!(noop_reason(&delta).is_some());
        let empty = OpcodeKind::FixBadPixelsList {
            bayer_phase: 0,
            points: vec![],
            rects: vec![],
        };
        assert!(noop_reason(&empty).is_some());
        let constant = OpcodeKind::FixBadPixelsConstant {
            constant: 0,
            bayer_phase: 0,
        };
        assert!(noop_reason(&constant).is_none());
        let vig = OpcodeKind::FixVignetteRadial {
            k: [0.0; 5],
            center: [0.5, 0.5],
        };
        assert!(noop_reason(&vig).is_some());
    }

    #[test]
    fn costs_follow_the_area_and_the_kind() {
        let scale = OpcodeKind::ScalePerRow {
            area: area(10, 10, 2),
            scales: vec![2.0; 5],
        };
        // rows 0, 2, 4, 6, 8 x columns 0, 2, 4, 6, 8 of a 100 x 100 image
        assert_eq!(cost(&scale, (100, 100), false), 25);
        let whole = OpcodeKind::ScalePerRow {
            area: area(0, 0, 1),
            scales: vec![2.0],
        };
        assert_eq!(cost(&whole, (30, 20), false), 600);
        let warp = OpcodeKind::WarpRectilinear {
            planes: vec![WarpPlane {
                kr: [1.0, 0.1, 0.0, 0.0],
                kt: [0.0; 2],
            }],
            center: [0.5, 0.5],
        };
        assert_eq!(cost(&warp, (10, 10), false), 100 * COST_WARP);
        let c = OpcodeKind::FixBadPixelsConstant {
            constant: 0,
            bayer_phase: 0,
        };
        assert_eq!(cost(&c, (10, 10), false), 100 * COST_BAD_PIXELS);
        assert_eq!(cost(&c, (10, 10), true), 100 * COST_BAD_PIXELS_REPEAT);
    }
}
