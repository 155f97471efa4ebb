//! Where a warp reads: a guaranteed bound on the source rows and columns that the bicubic
//! taps of a rectangle of destination pixels reach, before any pixel is resampled. The
//! warp's formulas ([`super::warp`]) are evaluated in interval arithmetic over tiles of the
//! rectangle (64 x 64 pixels at most), and the union of the tiles' source intervals,
//! widened by a margin far above the formulas' rounding, gives the window. A few hundred
//! flops per tile, so the banded warp ([`super::warp_window`]) can plan which source lines
//! every band needs, and when each can be dropped, before computing any.
//!
//! The bound holds for every coefficient set: a non-finite interval (NaN or infinite
//! coefficients, a reciprocal polynomial that may reach 0, magnitudes past 1e200) gives the
//! whole image. A property test checks it against the exact window ([`super::warp::plan`])
//! for random warps and rectangles.

use super::warp::{Model, Warp};
use super::StageRect;
use std::ops::Range;

/// Tile side (pixels) of the rectangle's interval evaluation.
const TILE: usize = 64;

/// A closed interval; NaN bounds mean "unknown" (the whole image).
#[derive(Debug, Clone, Copy)]
struct Iv {
    lo: f64,
    hi: f64,
}

const NAN: Iv = Iv {
    lo: f64::NAN,
    hi: f64::NAN,
};

impl Iv {
    fn pt(v: f64) -> Iv {
        Iv::of(v, v)
    }

    fn of(a: f64, b: f64) -> Iv {
        if a.is_nan() || b.is_nan() {
            NAN
        } else {
            Iv {
                lo: a.min(b),
                hi: a.max(b),
            }
        }
    }

    fn ok(self) -> bool {
        self.lo.is_finite() && self.hi.is_finite() && self.mag() < 1e200
    }

    fn mag(self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    fn add(self, o: Iv) -> Iv {
        Iv::of(self.lo + o.lo, self.hi + o.hi)
    }

    fn mul(self, o: Iv) -> Iv {
        let p = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        if p.iter().any(|v| v.is_nan()) {
            return NAN;
        }
        Iv {
            lo: p.iter().copied().fold(f64::INFINITY, f64::min),
            hi: p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    fn scale(self, k: f64) -> Iv {
        self.mul(Iv::pt(k))
    }

    fn sq(self) -> Iv {
        if self.lo.is_nan() || self.hi.is_nan() {
            NAN
        } else if self.lo >= 0.0 {
            Iv::of(self.lo * self.lo, self.hi * self.hi)
        } else if self.hi <= 0.0 {
            Iv::of(self.hi * self.hi, self.lo * self.lo)
        } else {
            Iv::of(0.0, (self.lo * self.lo).max(self.hi * self.hi))
        }
    }

    /// `f` of a non-decreasing function.
    fn map(self, f: impl Fn(f64) -> f64) -> Iv {
        Iv::of(f(self.lo), f(self.hi))
    }

    fn union(self, o: Iv) -> Iv {
        if self.lo.is_nan() || o.lo.is_nan() {
            NAN
        } else {
            Iv::of(self.lo.min(o.lo), self.hi.max(o.hi))
        }
    }
}

/// Horner's scheme over `k` (lowest power first) at `x`, as the warp evaluates it.
fn horner(k: &[f64], x: Iv) -> Iv {
    let Some((&last, rest)) = k.split_last() else {
        return Iv::pt(0.0);
    };
    rest.iter()
        .rev()
        .fold(Iv::pt(last), |acc, &c| Iv::pt(c).add(x.mul(acc)))
}

/// The sum of the coefficients' magnitudes (the Horner partial sums stay below it where
/// the variable is in [0, 1]).
fn weight(k: &[f64]) -> f64 {
    k.iter().map(|v| v.abs()).sum()
}

/// The radial ratio of `model` over `rr` (= `min(r^2, 1)`), and the magnitude that its
/// rounding scales with.
fn ratio(model: &Model, rr: Iv) -> (Iv, f64) {
    match model {
        Model::Rectilinear { kr, .. } => (horner(kr, rr), weight(kr)),
        Model::Rectilinear2 {
            kr,
            valid,
            reciprocal,
            ..
        } => {
            let (v0, v1) = (valid[0] * valid[0], valid[1] * valid[1]);
            let r = rr.map(|x| x.min(v1).max(v0)).map(f64::sqrt);
            let p = horner(kr, r);
            if !*reciprocal {
                return (p, weight(kr));
            }
            if !p.ok() || (p.lo <= 0.0 && p.hi >= 0.0) {
                return (NAN, 0.0);
            }
            let least = p.lo.abs().min(p.hi.abs());
            (Iv::of(1.0 / p.lo, 1.0 / p.hi), weight(kr) / (least * least))
        }
        Model::Fisheye { kr } => {
            // ratio = 1 below r^2 = 1e-12 (the warp's own cut, with a margin for the
            // rounding of r^2), else atan(r) poly(atan(r)^2) / r, atan(r) / r decreasing.
            const CUT: f64 = 1e-12;
            let one = (rr.lo * (1.0 - 1e-9) < CUT).then_some(Iv::pt(1.0));
            let rest = (rr.hi >= CUT).then(|| {
                let r = Iv::of(rr.lo.max(CUT), rr.hi).map(f64::sqrt);
                let t = r.map(f64::atan);
                let g = Iv::of(t.hi / r.hi, t.lo / r.lo);
                g.mul(horner(kr, t.sq()))
            });
            let iv = match (one, rest) {
                (Some(a), Some(b)) => a.union(b),
                (Some(a), None) => a,
                (None, Some(b)) => b,
                (None, None) => NAN,
            };
            (iv, weight(kr) + 1.0)
        }
    }
}

/// The source row and column intervals of plane `p` of `warp` over destination offsets
/// `dv` (row - centre) and `dh` (column - centre), widened by the rounding margin.
fn source(warp: &Warp, p: usize, dv: Iv, dh: Iv) -> (Iv, Iv) {
    let (nv, nh) = (dv.scale(warp.inv), dh.scale(warp.inv));
    let rr = nv.sq().add(nh.sq()).map(|x| x.min(1.0));
    let model = &warp.planes[p];
    let (ratio, k) = ratio(model, rr);
    let kt = match model {
        Model::Rectilinear { kt, .. } | Model::Rectilinear2 { kt, .. } => *kt,
        Model::Fisheye { .. } => [0.0, 0.0],
    };
    let (sv, sh, tmag) = if kt == [0.0, 0.0] {
        (
            Iv::pt(warp.cv).add(dv.mul(ratio)),
            Iv::pt(warp.ch).add(dh.mul(ratio)),
            0.0,
        )
    } else {
        let tv = rr
            .add(nv.sq().scale(2.0))
            .scale(kt[0])
            .add(nh.mul(nv).scale(2.0 * kt[1]));
        let th = rr
            .add(nh.sq().scale(2.0))
            .scale(kt[1])
            .add(nh.mul(nv).scale(2.0 * kt[0]));
        (
            Iv::pt(warp.cv).add(nv.mul(ratio).add(tv).scale(warp.norm)),
            Iv::pt(warp.ch).add(nh.mul(ratio).add(th).scale(warp.norm)),
            tv.mag() + th.mag() + 3.0 * (kt[0].abs() + kt[1].abs()),
        )
    };
    let scale = 1.0 + warp.cv.abs() + warp.ch.abs() + warp.norm * (1.0 + ratio.mag() + k + tmag);
    let eps = 1e-9 * (scale + sv.mag().max(sh.mag()));
    let widen = |v: Iv| Iv::of(v.lo - eps, v.hi + eps);
    (widen(sv), widen(sh))
}

/// The image lines `0..n` that the taps of source positions in `s` (stage coordinates,
/// `origin` = the stage position of line 0) read; all of them when `s` is not finite.
fn lines(s: Iv, origin: i64, n: usize) -> Range<usize> {
    if !s.ok() {
        return 0..n;
    }
    // As `warp::taps`: first tap floor(s) - 1 (floor clamped to +-1e15), four taps.
    let first = |v: f64| (v - origin as f64).floor().clamp(-1e15, 1e15) as i64;
    let clamp = |v: i64| v.clamp(0, n as i64 - 1) as usize;
    clamp(first(s.lo) - 1)..clamp(first(s.hi) + 2) + 1
}

/// The source rows and columns (image lines of a `w x h` image whose pixel (0, 0) sits at
/// stage position (`extent.t`, `extent.l`)) that the taps of `warp` read for the
/// destination pixels `rows x cols`: a superset of [`super::warp::plan`]'s window. Empty
/// ranges for an empty rectangle or image.
pub(crate) fn window(
    warp: &Warp,
    extent: StageRect,
    (w, h): (usize, usize),
    rows: Range<usize>,
    cols: Range<usize>,
) -> (Range<usize>, Range<usize>) {
    if rows.is_empty() || cols.is_empty() || w == 0 || h == 0 {
        return (0..0, 0..0);
    }
    let (mut sv, mut sh): (Option<Iv>, Option<Iv>) = (None, None);
    let edges = |r: &Range<usize>| {
        let end = r.end;
        (r.start..end)
            .step_by(TILE)
            .map(move |a| (a, (a + TILE).min(end) - 1))
    };
    let planes = warp.planes.len();
    let shared = warp.planes.windows(2).all(|p| p[0] == p[1]);
    for (r0, r1) in edges(&rows) {
        let dv = Iv::of(
            (extent.t + r0 as i64) as f64 - warp.cv,
            (extent.t + r1 as i64) as f64 - warp.cv,
        );
        for (c0, c1) in edges(&cols) {
            let dh = Iv::of(
                (extent.l + c0 as i64) as f64 - warp.ch,
                (extent.l + c1 as i64) as f64 - warp.ch,
            );
            for p in 0..if shared { 1 } else { planes } {
                let (a, b) = source(warp, p, dv, dh);
                sv = Some(sv.map_or(a, |v| v.union(a)));
                sh = Some(sh.map_or(b, |v| v.union(b)));
            }
        }
    }
    (
        lines(sv.unwrap_or(NAN), extent.t, h),
        lines(sh.unwrap_or(NAN), extent.l, w),
    )
}

#[cfg(test)]
mod tests {
    use super::super::warp::plan;
    use super::*;
    use proptest::prelude::*;

    fn contains(outer: &Range<usize>, inner: &Range<usize>) -> bool {
        inner.is_empty() || (outer.start <= inner.start && inner.end <= outer.end)
    }

    fn check(
        warp: &Warp,
        b: StageRect,
        (w, h): (usize, usize),
        rows: Range<usize>,
        cols: Range<usize>,
    ) {
        let exact = plan(warp, (w, h, 3), b, rows.clone(), cols.clone());
        let (br, bc) = window(warp, b, (w, h), rows.clone(), cols.clone());
        assert!(
            contains(&br, &exact.win_rows) && contains(&bc, &exact.win_cols),
            "rows {rows:?} cols {cols:?}: bound {br:?} x {bc:?}, exact {:?} x {:?}",
            exact.win_rows,
            exact.win_cols
        );
    }

    fn model(kind: u8, k: [f64; 4], kt: [f64; 2], valid: [f64; 2], recip: bool) -> Model {
        match kind % 3 {
            0 => Model::Rectilinear { kr: k, kt },
            1 => Model::Fisheye { kr: k },
            _ => {
                let mut kr = [0.0; 15];
                (kr[0], kr[1], kr[2], kr[7]) = (k[0], k[1], k[2], k[3]);
                Model::Rectilinear2 {
                    kr,
                    kt,
                    valid,
                    reciprocal: recip,
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]
        #[test]
        fn the_bound_holds_the_exact_window(
            kind in 0u8..3,
            k0 in 0.3f64..2.0,
            k in prop::array::uniform3(-0.6f64..0.6),
            kt in prop::array::uniform2(-0.05f64..0.05),
            valid in (0.0f64..0.6, 0.4f64..1.2),
            recip in any::<bool>(),
            per_plane in any::<bool>(),
            center in prop::array::uniform2(0.0f64..=1.0),
            (w, h) in (1usize..90, 1usize..90),
            (t, l) in (0i64..5, 0i64..5),
            rect in (0usize..90, 0usize..90, 1usize..40, 1usize..40),
        ) {
            let m = model(kind, [k0, k[0], k[1], k[2]], kt, [valid.0, valid.1], recip);
            let models = if per_plane {
                vec![m, model(kind, [k0 * 1.01, k[0], k[1], 0.0], kt, [valid.0, valid.1], recip), m]
            } else {
                vec![m]
            };
            let b = StageRect { t, l, b: t + h as i64, r: l + w as i64 };
            let warp = Warp::new(models, center, b, 3).unwrap();
            let (r0, c0) = (rect.0 % h, rect.1 % w);
            let rows = r0..(r0 + rect.2).min(h);
            let cols = c0..(c0 + rect.3).min(w);
            check(&warp, b, (w, h), rows, cols);
        }
    }

    #[test]
    fn the_bound_is_tight_for_a_usual_distortion_and_whole_for_non_finite_warps() {
        let (w, h) = (1200, 800);
        let b = StageRect::of_size(w, h);
        let warp = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, -0.02, 0.0, 0.0],
                kt: [0.0, 0.0],
            }],
            [0.5, 0.5],
            b,
            3,
        )
        .unwrap();
        for r0 in [0, 32, 384, 768] {
            let rows = r0..r0 + 32;
            check(&warp, b, (w, h), rows.clone(), 0..w);
            let exact = plan(&warp, (w, h, 3), b, rows.clone(), 0..w).win_rows;
            let (br, _) = window(&warp, b, (w, h), rows, 0..w);
            assert!(br.len() <= exact.len() + 4, "{br:?} vs {exact:?}");
        }
        let nan = Warp::new(
            vec![Model::Rectilinear {
                kr: [f64::NAN, 0.0, 0.0, 0.0],
                kt: [0.0, 0.0],
            }],
            [0.5, 0.5],
            b,
            3,
        )
        .unwrap();
        assert_eq!(window(&nan, b, (w, h), 10..20, 0..5), (0..h, 0..w));
        check(&nan, b, (w, h), 10..20, 0..5);
        // a reciprocal polynomial through 0: the whole image
        let mut kr = [0.0; 15];
        (kr[0], kr[2]) = (0.1, -1.0);
        let zero = Warp::new(
            vec![Model::Rectilinear2 {
                kr,
                kt: [0.0, 0.0],
                valid: [0.0, 1.0],
                reciprocal: true,
            }],
            [0.5, 0.5],
            b,
            3,
        )
        .unwrap();
        assert_eq!(window(&zero, b, (w, h), 390..410, 0..w), (0..h, 0..w));
        check(&zero, b, (w, h), 390..410, 0..w);
        // where it stays away from 0 it is finite (here: it flips the top rows to the bottom)
        assert_eq!(window(&zero, b, (w, h), 0..10, 0..w).0, h - 1..h);
        check(&zero, b, (w, h), 0..10, 0..w);
        assert_eq!(window(&warp, b, (w, h), 5..5, 0..w), (0..0, 0..0));
    }
}
