//! GainMap (opcode 9): a grid of gains, bilinearly interpolated, multiplied into the area
//! (lens shading). As the Adobe DNG SDK (`dng_gain_map_interpolator`): the position of
//! pixel (r, c) relative to the stage image `extent` is `v = (r + 0.5 - t) / H`,
//! `h = (c + 0.5 - l) / W` (pixel centres); its map coordinates are
//! `(v - origin_v) / spacing_v` and `(h - origin_h) / spacing_h`, clamped to the first and
//! last map point (edges repeat); the gain is the bilinear mix of the four points around;
//! the sample becomes `min(x * gain, range)` (pinned at 0). A map of one point in a
//! direction has spacing 1 and origin 0 there (the SDK's rule). Map plane
//! `min(plane, map_planes - 1)`: one map plane serves every plane.
//!
//! The gain is computed from each pixel's own coordinates (the SDK steps it along the row;
//! the difference is float rounding), so any rectangle of the image gives the same samples
//! as the whole image.

use super::area::{col_span, plane_range, row_step};
use super::{pin, StageRect};
use crate::dng::opcodes::GainMap;

/// A gain map ready for rows.
#[derive(Debug, Clone)]
pub struct Prepared<'a> {
    map: &'a GainMap,
    pv: usize,
    ph: usize,
    planes: usize,
    spacing: [f64; 2],
    origin: [f64; 2],
    extent: StageRect,
    valid: bool,
}

/// Index and fraction of map coordinate `f` on a grid of `n` points (clamped at the ends).
#[inline]
fn locate(f: f64, n: usize) -> (usize, usize, f32) {
    if f.is_nan() || f <= 0.0 || n <= 1 {
        return (0, 0, 0.0);
    }
    let last = n - 1;
    if f >= last as f64 {
        return (last, last, 0.0);
    }
    let i = f as usize;
    (i, i + 1, (f - i as f64) as f32)
}

impl<'a> Prepared<'a> {
    /// Prepare `map` for an image of `extent`.
    pub fn new(map: &'a GainMap, extent: StageRect) -> Prepared<'a> {
        let (pv, ph) = (map.points_v as usize, map.points_h as usize);
        let planes = map.map_planes as usize;
        let (sv, ov) = if pv == 1 {
            (1.0, 0.0)
        } else {
            (map.spacing_v, map.origin_v)
        };
        let (sh, oh) = if ph == 1 {
            (1.0, 0.0)
        } else {
            (map.spacing_h, map.origin_h)
        };
        let need = pv.checked_mul(ph).and_then(|n| n.checked_mul(planes));
        let valid = pv >= 1
            && ph >= 1
            && planes >= 1
            && need.is_some_and(|n| map.gains.len() >= n)
            && sv > 0.0
            && sh > 0.0
            && sv.is_finite()
            && sh.is_finite()
            && ov.is_finite()
            && oh.is_finite()
            && extent.h() > 0
            && extent.w() > 0;
        Prepared {
            map,
            pv,
            ph,
            planes,
            spacing: [sv, sh],
            origin: [ov, oh],
            extent,
            valid,
        }
    }

    #[inline]
    fn entry(&self, i: usize, j: usize, p: usize) -> f32 {
        self.map.gains[(i * self.ph + j) * self.planes + p]
    }

    /// The gain at stage pixel (r, c) of map plane `mp`.
    pub fn gain(&self, r: usize, c: usize, mp: usize) -> f32 {
        let (i0, i1, fr) = self.map_row(r);
        self.gain_in_row(i0, i1, fr, c, mp)
    }

    #[inline]
    fn gain_in_row(&self, i0: usize, i1: usize, fr: f32, c: usize, mp: usize) -> f32 {
        let fh = ((c as f64 + 0.5 - self.extent.l as f64) / self.extent.w() as f64
            - self.origin[1])
            / self.spacing[1];
        let (j0, j1, fc) = locate(fh, self.ph);
        let col = |j| self.entry(i0, j, mp) * (1.0 - fr) + self.entry(i1, j, mp) * fr;
        let a = col(j0);
        a + (col(j1) - a) * fc
    }

    #[inline]
    fn map_row(&self, r: usize) -> (usize, usize, f32) {
        let fv = ((r as f64 + 0.5 - self.extent.t as f64) / self.extent.h() as f64
            - self.origin[0])
            / self.spacing[0];
        locate(fv, self.pv)
    }

    /// Apply to one row (stage row `r`, first pixel at stage column `left`, `planes`
    /// interleaved samples per pixel, values in `[0, range]`).
    pub fn row(&self, r: usize, left: usize, planes: usize, range: f32, row: &mut [f32]) {
        let area = &self.map.area;
        if !self.valid || row_step(area, r).is_none() {
            return;
        }
        let width = row.len() / planes.max(1);
        let Some((first, end, pitch, _)) = col_span(area, left, width) else {
            return;
        };
        let pr = plane_range(area, planes);
        let (i0, i1, fr) = self.map_row(r);
        for c in (first..end).step_by(pitch) {
            let base = (c - left) * planes;
            let (mut last, mut g) = (usize::MAX, 0.0f32);
            for p in pr.clone() {
                let mp = p.min(self.planes - 1);
                if mp != last {
                    g = self.gain_in_row(i0, i1, fr, c, mp);
                    last = mp;
                }
                row[base + p] = pin(row[base + p] * g, range);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dng::opcodes::AreaSpec;

    fn map(pv: u32, ph: u32, planes: u32, gains: Vec<f32>) -> GainMap {
        GainMap {
            area: AreaSpec {
                top: 0,
                left: 0,
                bottom: 100,
                right: 100,
                plane: 0,
                planes: 3,
                row_pitch: 1,
                col_pitch: 1,
            },
            points_v: pv,
            points_h: ph,
            spacing_v: 1.0 / (pv.max(2) - 1) as f64,
            spacing_h: 1.0 / (ph.max(2) - 1) as f64,
            origin_v: 0.0,
            origin_h: 0.0,
            map_planes: planes,
            gains,
        }
    }

    #[test]
    fn bilinear_between_points_and_clamped_outside() {
        // 2x2 map over a 10x10 image: gains 1 (top-left), 2, 3, 4 (bottom-right)
        let m = map(2, 2, 1, vec![1.0, 2.0, 3.0, 4.0]);
        let b = StageRect::of_size(10, 10);
        let p = Prepared::new(&m, b);
        // pixel (r, c): v = (r + 0.5) / 10 in [0.05, 0.95]
        let want = |r: usize, c: usize| {
            let v = (r as f32 + 0.5) / 10.0;
            let h = (c as f32 + 0.5) / 10.0;
            let top = 1.0 + h;
            let bot = 3.0 + h;
            top + (bot - top) * v
        };
        for (r, c) in [(0, 0), (9, 9), (4, 7), (2, 0)] {
            assert!((p.gain(r, c, 0) - want(r, c)).abs() < 1e-5, "({r},{c})");
        }
        // origin past the image: clamped to the first point
        let mut m2 = m.clone();
        m2.origin_v = 2.0;
        m2.origin_h = 2.0;
        let p2 = Prepared::new(&m2, b);
        assert_eq!(p2.gain(9, 9, 0), 1.0);
        m2.origin_v = -5.0;
        m2.origin_h = -5.0;
        assert_eq!(Prepared::new(&m2, b).gain(0, 0, 0), 4.0);
    }

    #[test]
    fn one_point_map_and_per_plane_maps_and_pinning() {
        let m = map(1, 1, 1, vec![2.5]);
        let p = Prepared::new(&m, StageRect::of_size(4, 3));
        let mut row = vec![0.1, 0.2, 0.3, 0.5, 0.6, 0.7];
        p.row(1, 0, 3, 1.0, &mut row);
        let want = [0.25, 0.5, 0.75, 1.0, 1.0, 1.0];
        for (a, b) in row.iter().zip(want) {
            assert!((a - b).abs() < 1e-6);
        }
        // three map planes: plane p takes its own gains; zero gains give 0, never NaN
        let m = map(1, 1, 3, vec![0.0, 1.0, 2.0]);
        let p = Prepared::new(&m, StageRect::of_size(4, 3));
        let mut row = vec![0.4; 6];
        p.row(0, 2, 3, 1.0, &mut row);
        assert_eq!(row, vec![0.0, 0.4, 0.8, 0.0, 0.4, 0.8]);
        // a map without enough gains is not applied (no panic)
        let bad = map(2, 2, 1, vec![1.0]);
        let mut row = vec![0.4; 3];
        Prepared::new(&bad, StageRect::of_size(4, 3)).row(0, 0, 1, 1.0, &mut row);
        assert_eq!(row, vec![0.4; 3]);
    }

    #[test]
    fn bounds_offset_moves_the_map() {
        // stage image extent starting at (2, 2): pixel (2, 2) is the image's first pixel
        let m = map(2, 2, 1, vec![1.0, 2.0, 3.0, 4.0]);
        let b = StageRect {
            t: 2,
            l: 2,
            b: 12,
            r: 12,
        };
        let a = Prepared::new(&m, b).gain(2, 2, 0);
        let z = Prepared::new(&m, StageRect::of_size(10, 10)).gain(0, 0, 0);
        assert_eq!(a, z);
    }
}
