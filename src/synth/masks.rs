//! Light masks (SYNTHESIS.md 5): separable Gaussians evaluated per row and per column.
//!
//! A light has a centre `(row, col)` in active-area pixel coordinates (pixel centres at
//! integer coordinates), per-axis sigmas and optionally a window `(h, w)`: a pixel is inside
//! the window when `|row - c_row| < h/2` and `|col - c_col| < w/2`. Inside, the mask is
//! `max(exp(-d_r^2 / 2 s_r^2) * exp(-d_c^2 / 2 s_c^2), floor)` (peak 1); outside it is
//! exactly 0, so a light is skipped on every row outside its window and every column
//! outside its column range. [`MaskEval`] picks how the product is computed: separable
//! (row factor times a precomputed f32 column factor: default), exact (one 2-D `exp` per
//! pixel in f64: the reference) or truncated at `k` sigma (also zero beyond `k` sigma).

use serde::{Deserialize, Serialize};

/// Floor of release-style masks inside their window.
pub const MASK_FLOOR: f64 = 1e-7;

/// Kind of light.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LightKind {
    /// Mask 1 everywhere.
    Ambient,
    /// A local Gaussian light (weighted mean).
    Local,
    /// A saturated bulb added on top (released code).
    Bulb,
}

/// One sampled light: everything needed to evaluate it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Kind.
    pub kind: LightKind,
    /// Illuminant `(r/g, 1, b/g)`.
    pub illuminant: [f64; 3],
    /// Gain on the relit image (release: ambient 0.05, local 1; bulbs: g ~ U(50, 100)).
    pub gain: f64,
    /// Weight of the mask in the weighted mean (paper formula; 1 in the release formula).
    pub weight: f64,
    /// Centre `[row, col]` in active-area pixels.
    pub center: [f64; 2],
    /// Window `[h, w]` in pixels; `None` = unbounded.
    pub window: Option<[f64; 2]>,
    /// Sigma `[rows, cols]` in pixels.
    pub sigma: [f64; 2],
    /// Floor of the mask inside its window ([`MASK_FLOOR`] or 0).
    pub floor: f64,
}

/// How masks are evaluated (an accuracy/speed knob; see docs/benchmarks.md).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "eval")]
pub enum MaskEval {
    /// Row factor x precomputed column factor (f32): default.
    #[default]
    Separable,
    /// One `exp` of the 2-D quadratic form per pixel, f64 (reference).
    Exact,
    /// Separable, and exactly 0 beyond `k` sigma on either axis.
    Truncated {
        /// Truncation radius in sigmas.
        k: f64,
    },
}

impl MaskEval {
    fn k(&self) -> Option<f64> {
        match self {
            MaskEval::Truncated { k } => Some(*k),
            _ => None,
        }
    }
}

/// Index range `[start, end)` of an axis of length `len` where a light can be non-zero.
pub fn axis_range(
    center: f64,
    window: Option<f64>,
    sigma: f64,
    len: usize,
    eval: MaskEval,
) -> (usize, usize) {
    let (mut lo, mut hi) = (0i64, len as i64);
    if let Some(h) = window {
        // |i - c| < h/2  <=>  c - h/2 < i < c + h/2
        let a = center - h / 2.0;
        let b = center + h / 2.0;
        lo = lo.max((a.floor() as i64).saturating_add(1));
        hi = hi.min(b.ceil() as i64);
    }
    if let Some(k) = eval.k() {
        let a = center - k * sigma;
        let b = center + k * sigma;
        lo = lo.max(a.ceil() as i64);
        hi = hi.min((b.floor() as i64).saturating_add(1));
    }
    if hi <= lo {
        return (0, 0);
    }
    (lo.max(0) as usize, hi.max(0) as usize)
}

/// `exp(-d^2 / (2 sigma^2))` (1 at d = 0 even for sigma 0).
#[inline]
pub fn gauss(d: f64, sigma: f64) -> f64 {
    if d == 0.0 {
        return 1.0;
    }
    if sigma.is_nan() || sigma <= 0.0 {
        return 0.0;
    }
    (-(d * d) / (2.0 * sigma * sigma)).exp()
}

/// A light prepared for one image: its row/column ranges and column factors.
#[derive(Debug, Clone)]
pub struct PreparedMask {
    /// Rows `[start, end)` where the light is non-zero.
    pub rows: (usize, usize),
    /// Columns `[start, end)` where the light is non-zero.
    pub cols: (usize, usize),
    /// Column factors over `cols` (separable evaluation).
    pub col_factor: Vec<f32>,
    center: [f64; 2],
    sigma: [f64; 2],
    floor: f64,
    eval: MaskEval,
}

impl PreparedMask {
    /// Prepare `light` for an active area of `width x height`.
    pub fn new(light: &Light, width: usize, height: usize, eval: MaskEval) -> PreparedMask {
        PreparedMask::new_in(light, width, height, eval, 0..width)
    }

    /// [`PreparedMask::new`] restricted to the active-area columns `within` (for a crop):
    /// the column range is cut to it and only its column factors are computed (each the
    /// same value as in the whole-width mask).
    pub fn new_in(
        light: &Light,
        width: usize,
        height: usize,
        eval: MaskEval,
        within: std::ops::Range<usize>,
    ) -> PreparedMask {
        let rows = axis_range(
            light.center[0],
            light.window.map(|w| w[0]),
            light.sigma[0],
            height,
            eval,
        );
        let cols = axis_range(
            light.center[1],
            light.window.map(|w| w[1]),
            light.sigma[1],
            width,
            eval,
        );
        let cols = (cols.0.max(within.start), cols.1.min(within.end));
        let cols = if cols.1 > cols.0 { cols } else { (0, 0) };
        let col_factor = (cols.0..cols.1)
            .map(|c| gauss(c as f64 - light.center[1], light.sigma[1]) as f32)
            .collect();
        PreparedMask {
            rows,
            cols,
            col_factor,
            center: light.center,
            sigma: light.sigma,
            floor: light.floor,
            eval,
        }
    }
    /// True when the light is non-zero somewhere on row `r`.
    #[inline]
    pub fn on_row(&self, r: usize) -> bool {
        r >= self.rows.0 && r < self.rows.1 && self.cols.1 > self.cols.0
    }
    /// Row factor of row `r`.
    #[inline]
    pub fn row_factor(&self, r: usize) -> f64 {
        gauss(r as f64 - self.center[0], self.sigma[0])
    }
    /// Fill `out[i]` with the mask at columns `cols.0 + i` of row `r` (which must be on_row).
    pub fn fill_row(&self, r: usize, out: &mut [f32]) {
        let floor = self.floor as f32;
        match self.eval {
            MaskEval::Exact => {
                let dr = r as f64 - self.center[0];
                let qr = if dr == 0.0 {
                    0.0
                } else {
                    dr * dr / (2.0 * self.sigma[0] * self.sigma[0])
                };
                for (i, o) in out.iter_mut().enumerate() {
                    let dc = (self.cols.0 + i) as f64 - self.center[1];
                    let qc = if dc == 0.0 {
                        0.0
                    } else {
                        dc * dc / (2.0 * self.sigma[1] * self.sigma[1])
                    };
                    let q = qr + qc;
                    let m = if q.is_finite() { (-q).exp() } else { 0.0 };
                    *o = m.max(self.floor) as f32;
                }
            }
            _ => {
                let rf = self.row_factor(r) as f32;
                for (o, &cf) in out.iter_mut().zip(&self.col_factor) {
                    *o = (rf * cf).max(floor);
                }
            }
        }
    }
    /// The mask at (r, c) (0 outside the ranges), computed like [`fill_row`](Self::fill_row).
    pub fn at(&self, r: usize, c: usize) -> f32 {
        if !self.on_row(r) || c < self.cols.0 || c >= self.cols.1 {
            return 0.0;
        }
        let mut v = [0.0f32; 1];
        let sub = PreparedMask {
            cols: (c, c + 1),
            col_factor: vec![self.col_factor[c - self.cols.0]],
            ..self.clone()
        };
        sub.fill_row(r, &mut v);
        v[0]
    }
}

/// Sigma of a release-style local light for a window of `h x w`: OpenCV's
/// `0.3 * ((k - 1) / 2 - 1) + 0.8` with `k = max(h, w)`, scaled per axis by `h/k`, `w/k`.
pub fn release_sigma(h: f64, w: f64) -> [f64; 2] {
    let k = h.max(w);
    let s = opencv_sigma(k);
    [s * h / k, s * w / k]
}

/// OpenCV's default sigma of a Gaussian kernel of size `k`: `0.3 * ((k - 1) / 2 - 1) + 0.8`
/// (at least 0.35 for k >= 0).
pub fn opencv_sigma(k: f64) -> f64 {
    0.3 * ((k - 1.0) / 2.0 - 1.0) + 0.8
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    fn light(center: [f64; 2], window: Option<[f64; 2]>, sigma: [f64; 2]) -> Light {
        Light {
            kind: LightKind::Local,
            illuminant: [1.0; 3],
            gain: 1.0,
            weight: 1.0,
            center,
            window,
            sigma,
            floor: MASK_FLOOR,
        }
    }

    #[test]
    fn window_ranges_by_hand() {
        // centre 5, window 4: |i - 5| < 2 -> i in {4, 5, 6}
        assert_eq!(
            axis_range(5.0, Some(4.0), 1.0, 100, MaskEval::Separable),
            (4, 7)
        );
        // clipped at the image edge
        assert_eq!(
            axis_range(1.0, Some(10.0), 1.0, 3, MaskEval::Separable),
            (0, 3)
        );
        assert_eq!(axis_range(5.0, None, 1.0, 8, MaskEval::Separable), (0, 8));
        // truncated at 1.5 sigma = 3 px: i in [2, 8]
        assert_eq!(
            axis_range(5.0, None, 2.0, 100, MaskEval::Truncated { k: 1.5 }),
            (2, 9)
        );
        // outside the image
        assert_eq!(
            axis_range(-10.0, Some(4.0), 1.0, 100, MaskEval::Separable),
            (0, 0)
        );
    }

    #[test]
    fn values_by_hand_and_floor_and_zero_outside() {
        let l = light([2.0, 3.0], Some([4.0, 4.0]), [1.0, 2.0]);
        let m = PreparedMask::new(&l, 10, 10, MaskEval::Separable);
        assert_eq!(m.rows, (1, 4));
        assert_eq!(m.cols, (2, 5));
        assert_eq!(m.at(2, 3), 1.0);
        let want = (-0.5f64).exp() * (-1.0f64 / 8.0).exp();
        assert!((m.at(1, 4) as f64 - want).abs() < 1e-7);
        assert_eq!(m.at(0, 3), 0.0);
        assert_eq!(m.at(2, 5), 0.0);
        // far inside a huge window with a tiny sigma: floored, not zero
        let l = light([0.0, 0.0], Some([100.0, 100.0]), [0.5, 0.5]);
        let m = PreparedMask::new(&l, 60, 60, MaskEval::Separable);
        assert_eq!(m.at(40, 40), MASK_FLOOR as f32);
        let e = PreparedMask::new(&l, 60, 60, MaskEval::Exact);
        assert_eq!(e.at(40, 40), MASK_FLOOR as f32);
    }

    #[test]
    fn exact_and_separable_agree() {
        let l = light([30.3, 41.7], Some([50.0, 70.0]), [7.0, 9.5]);
        let s = PreparedMask::new(&l, 80, 90, MaskEval::Separable);
        let e = PreparedMask::new(&l, 80, 90, MaskEval::Exact);
        for r in 0..80 {
            for c in 0..90 {
                assert!((s.at(r, c) - e.at(r, c)).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn release_sigma_formula() {
        let s = release_sigma(101.0, 51.0);
        assert!((s[0] - (0.3 * 49.0 + 0.8)).abs() < 1e-12);
        assert!((s[1] - (0.3 * 49.0 + 0.8) * 51.0 / 101.0).abs() < 1e-12);
        let s = release_sigma(1.0, 1.0);
        assert!(s[0] > 0.0 && s[1] > 0.0);
    }
}
