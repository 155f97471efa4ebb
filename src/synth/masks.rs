//! Light masks (docs/synthesis.md, "5. Relight"): separable Gaussians evaluated per row and per column.
//!
//! A light has a centre `(row, col)` in active-area pixel coordinates (pixel centres at
//! integer coordinates), per-axis sigmas and optionally a window `(h, w)`: a pixel is inside
//! the window when `|row - c_row| < h/2` and `|col - c_col| < w/2`. Inside, the mask is
//! `max(exp(-d_r^2 / 2 s_r^2) * exp(-d_c^2 / 2 s_c^2), floor)` (peak 1); outside it is
//! exactly 0, so a light is skipped on every row outside its window and every column
//! outside its column range. [`MaskEval`] picks how the product is computed: separable
//! (row factor times a precomputed f32 column factor: default), exact (one 2-D `exp` per
//! pixel in f64: the reference), truncated at `k` sigma (also zero beyond `k` sigma) or
//! release (the authors' sampled, max-normalized and bilinearly resized kernel:
//! [`release_resized`]).

use crate::choice::Name;
use crate::error::{Error, Result};
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
    /// The authors' released code: windowed lights are a sampled Gaussian kernel divided by
    /// its maximum and resized bilinearly to the window ([`release_resized`]); lights
    /// without a window are evaluated like `Separable`.
    Release,
}

impl MaskEval {
    /// The names `--mask-eval` takes (`truncated` with its radius, `truncated:K`): the
    /// synthesis table's choices, and what [`std::str::FromStr`] reads.
    pub const NAMES: &'static [Name] = &[
        Name::new(
            "separable",
            "Each light's row and column factors (f32): the fastest",
        ),
        Name::new("exact", "The 2-D exponential per pixel in f64 (reference)"),
        Name {
            param: Some("truncated:K"),
            ..Name::new("truncated", "As exact, masks zeroed beyond K sigmas")
        },
        Name::new("release", "The authors' sampled kernel resized bilinearly"),
    ];
    /// The value of each of [`MaskEval::NAMES`] (None: the name takes a parameter).
    const PLAIN: [Option<MaskEval>; 4] = [
        Some(MaskEval::Separable),
        Some(MaskEval::Exact),
        None,
        Some(MaskEval::Release),
    ];

    fn k(&self) -> Option<f64> {
        match self {
            MaskEval::Truncated { k } => Some(*k),
            _ => None,
        }
    }
}

impl std::str::FromStr for MaskEval {
    type Err = Error;
    /// `separable`, `exact`, `truncated:K` (K > 0 sigmas) or `release`.
    fn from_str(s: &str) -> Result<MaskEval> {
        let names = MaskEval::NAMES.iter().zip(MaskEval::PLAIN);
        let mut truncated = None;
        for (n, v) in names {
            match v {
                Some(v) if n.accepts(s) => return Ok(v),
                None if n.accepts(s) => truncated = s.split_once(':').map(|(_, k)| k),
                _ => {}
            }
        }
        match truncated.and_then(|k| k.parse::<f64>().ok()) {
            Some(k) if k > 0.0 && k.is_finite() => Ok(MaskEval::Truncated { k }),
            _ => Err(Error::invalid(format!(
                "{s:?} (use {})",
                crate::choice::list(MaskEval::NAMES, ", ", " or ")
            ))),
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
    /// Release kernel of a windowed light under [`MaskEval::Release`].
    release: Option<ReleaseKernel>,
    /// Column factors over `cols` in f64 (release kernel only).
    col64: Vec<f64>,
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
        let release = match (eval, light.window) {
            (MaskEval::Release, Some(win)) => {
                Some(ReleaseKernel::new(light.center, win, light.sigma))
            }
            _ => None,
        };
        let (rows, cols) = match &release {
            Some(k) => (clip_range(k.r0, k.h, height), clip_range(k.c0, k.w, width)),
            None => (rows, cols),
        };
        let cols = (cols.0.max(within.start), cols.1.min(within.end));
        let cols = if cols.1 > cols.0 { cols } else { (0, 0) };
        let (col_factor, col64) = match &release {
            Some(k) => (Vec::new(), (cols.0..cols.1).map(|c| k.col(c)).collect()),
            None => (
                (cols.0..cols.1)
                    .map(|c| gauss(c as f64 - light.center[1], light.sigma[1]) as f32)
                    .collect(),
                Vec::new(),
            ),
        };
        PreparedMask {
            rows,
            cols,
            col_factor,
            release,
            col64,
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
        fill_row(self, r, out);
    }

    /// Row `r`'s mask as its row factor and column factors, for a caller that computes
    /// each sample where it uses it: sample `i` is `g(cols[i])` with the expression of
    /// [`fill_row`](Self::fill_row), so the same bits. `None` for the exact evaluation
    /// (a full Gaussian per sample): fill a row instead.
    #[inline]
    pub(crate) fn row_view(&self, r: usize) -> Option<MaskRow<'_>> {
        if let Some(k) = &self.release {
            return Some(MaskRow::Release {
                rf: k.row(r),
                cols: &self.col64,
                floor: self.floor,
            });
        }
        match self.eval {
            MaskEval::Exact => None,
            _ => Some(MaskRow::Separable {
                rf: self.row_factor(r) as f32,
                cols: &self.col_factor,
                floor: self.floor as f32,
            }),
        }
    }

    /// [`PreparedMask::fill_row`]'s body.
    #[inline(always)]
    fn fill_row_body(&self, r: usize, out: &mut [f32]) {
        let floor = self.floor as f32;
        if let Some(k) = &self.release {
            // The release floors the f64 kernel, then stores the mask as f32.
            let rf = k.row(r);
            for (o, &cf) in out.iter_mut().zip(&self.col64) {
                *o = (rf * cf).max(self.floor) as f32;
            }
            return;
        }
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
        let i = c - self.cols.0;
        let sub = PreparedMask {
            cols: (c, c + 1),
            col_factor: self.col_factor.get(i).map(|&f| vec![f]).unwrap_or_default(),
            col64: self.col64.get(i).map(|&f| vec![f]).unwrap_or_default(),
            ..self.clone()
        };
        sub.fill_row(r, &mut v);
        v[0]
    }
}

/// One row of a separable mask ([`PreparedMask::row_view`]).
pub(crate) enum MaskRow<'a> {
    /// The release kernel: `(rf * cols[i]).max(floor) as f32`, in f64.
    Release {
        rf: f64,
        cols: &'a [f64],
        floor: f64,
    },
    /// The separable Gaussian: `(rf * cols[i]).max(floor)`, in f32.
    Separable {
        rf: f32,
        cols: &'a [f32],
        floor: f32,
    },
}

/// [`PreparedMask::fill_row`], compiled twice, the second time for AVX2, picked at run time
/// (the same operations per element, so the same bits).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn fill_row(mask: &PreparedMask, r: usize, out: &mut [f32]) {
    mask.fill_row_body(r, out);
}

/// `[start, end)` of `len` samples starting at `start` (possibly negative), cut to `[0, n)`.
fn clip_range(start: i64, len: usize, n: usize) -> (usize, usize) {
    let lo = start.clamp(0, n as i64);
    let hi = start.saturating_add(len as i64).clamp(0, n as i64);
    if hi <= lo {
        (0, 0)
    } else {
        (lo as usize, hi as usize)
    }
}

/// Largest window side (samples) the release kernel is built for; plans with larger windows
/// are cut to it (no real frame comes near).
const MAX_RELEASE_WINDOW: f64 = (1u64 << 31) as f64;

/// A windowed light as the authors' released code makes its mask (`gaussian_kernel` and
/// `translate_in_frame` of `utils/relight.py`): a `sz x sz` kernel, `sz = max(h, w)`,
/// sampled by `cv2.getGaussianKernel(sz, sigma)`, its outer product divided by its maximum,
/// resized to `h` rows and `w` columns by `cv2.resize` (INTER_LINEAR), floored at 1e-7 and
/// shifted so that its sample `[0][0]` lands on frame pixel `(r0, c0)`; 0 outside.
///
/// The kernel's sigma is the plan's sigma of the longer window axis (the plan's other sigma
/// is that one scaled by the window ratio, which is what the resize does). The window's
/// first row is the first integer inside the plan's window, `r0 = floor(c_row - h/2) + 1`:
/// for the release's integer location `ty`, a plan centre of `ty` (odd `h`) or `ty - 0.5`
/// (even `h`, where the resized kernel's peak lies) gives the release's `ty - h // 2`.
#[derive(Debug, Clone)]
struct ReleaseKernel {
    sz: usize,
    sigma: f64,
    r0: i64,
    c0: i64,
    h: usize,
    w: usize,
}

impl ReleaseKernel {
    fn new(center: [f64; 2], window: [f64; 2], sigma: [f64; 2]) -> ReleaseKernel {
        let side = |v: f64| {
            if v.is_nan() {
                1
            } else {
                v.round().clamp(1.0, MAX_RELEASE_WINDOW) as usize
            }
        };
        let (h, w) = (side(window[0]), side(window[1]));
        let first = |c: f64, n: usize| {
            let v = (c - n as f64 / 2.0).floor() + 1.0;
            if v.is_nan() {
                0
            } else {
                v.clamp(-MAX_RELEASE_WINDOW * 4.0, MAX_RELEASE_WINDOW * 4.0) as i64
            }
        };
        ReleaseKernel {
            sz: h.max(w),
            sigma: if h >= w { sigma[0] } else { sigma[1] },
            r0: first(center[0], h),
            c0: first(center[1], w),
            h,
            w,
        }
    }
    /// Row factor of frame row `r` (inside the window).
    fn row(&self, r: usize) -> f64 {
        let i = (r as i64 - self.r0).clamp(0, self.h as i64 - 1) as usize;
        release_resized(i, self.h, self.sz, self.sigma)
    }
    /// Column factor of frame column `c` (inside the window).
    fn col(&self, c: usize) -> f64 {
        let j = (c as i64 - self.c0).clamp(0, self.w as i64 - 1) as usize;
        release_resized(j, self.w, self.sz, self.sigma)
    }
}

/// Sample `i` of the release's 1-D Gaussian kernel of `sz` samples and `sigma`, divided by
/// the kernel's maximum, as `cv2.getGaussianKernel(sz, sigma) / max` gives it (OpenCV's
/// bit-exact kernel; its sum normalization cancels): `exp(-d^2 / (2 sigma^2))` with
/// `d = i - (sz - 1)/2`, and exactly 1 at the centre sample (odd `sz`) or the two centre
/// samples (even `sz`, `d = -1/2, 1/2`: OpenCV gives them the centre's value 1, not
/// `exp(-1 / (8 sigma^2))`). A `sigma` that is not positive gives 1 at the centre and 0
/// elsewhere.
pub fn release_kernel(i: usize, sz: usize, sigma: f64) -> f64 {
    let d = i as f64 - (sz as f64 - 1.0) / 2.0;
    if d.abs() <= 0.5 {
        return 1.0;
    }
    if sigma.is_nan() || sigma <= 0.0 {
        return 0.0;
    }
    let v = (-(d * d) / (2.0 * sigma * sigma)).exp();
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

/// Sample `j` of the release kernel ([`release_kernel`], `sz` samples) resized to `n`
/// samples the way `cv2.resize(..., INTER_LINEAR)` does on a float64 image (applied to
/// the separable outer product, it works axis by axis): source position
/// `f = (j + 0.5) * scale - 0.5` with `scale = 1 / (n / sz)`, `s = floor(f)`, weights
/// `1 - (f - s)` and `f - s` in f64; `s < 0` takes sample 0 and `s >= sz - 1` the last
/// sample. `n == sz` is the identity.
pub fn release_resized(j: usize, n: usize, sz: usize, sigma: f64) -> f64 {
    let sz = sz.max(1);
    let scale = 1.0 / (n.max(1) as f64 / sz as f64);
    let f = (j as f64 + 0.5) * scale - 0.5;
    let s = f.floor();
    let mut fx = f - s;
    let mut s = if s.is_finite() { s as i64 } else { 0 };
    if s < 0 {
        s = 0;
        fx = 0.0;
    }
    let last = sz as i64 - 1;
    if s >= last {
        return release_kernel(sz - 1, sz, sigma);
    }
    let s = s as usize;
    release_kernel(s, sz, sigma) * (1.0 - fx) + release_kernel(s + 1, sz, sigma) * fx
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

    /// `cv2.resize(k / k.max(), (w, h))` of `k = g.T * g`, `g = cv2.getGaussianKernel(max(h, w),
    /// sigma)`, floored at 1e-7: values printed by opencv-python-headless 5.0.0 (numpy
    /// 2.4) for (h, w, row, col, sigma, value) (the release's `gaussian_kernel`).
    const OPENCV: &[(usize, usize, usize, usize, f64, f64)] = &[
        (7, 12, 0, 0, 2.15, 0.0024402879003997623),
        (7, 12, 6, 11, 2.15, 0.0024402879003997636),
        (7, 12, 3, 6, 2.15, 1.0),
        (7, 12, 2, 6, 2.15, 0.7249738373615809),
        (7, 12, 4, 8, 2.15, 0.3687409866995592),
        (7, 12, 1, 10, 2.15, 0.031676004898253514),
        (7, 12, 3, 10, 2.15, 0.11187499191122484),
        (7, 12, 2, 2, 2.15, 0.19269237499629316),
        (12, 7, 5, 3, 2.15, 1.0),
        (12, 7, 7, 5, 2.15, 0.22197346073462254),
        (12, 7, 2, 6, 2.15, 0.01710061455604925),
        (12, 7, 6, 6, 2.15, 0.0643382913111057),
        (12, 7, 3, 5, 2.15, 0.14401126452350732),
        (300, 512, 150, 256, 10.870547945205479, 0.996652129896137),
        (300, 512, 135, 268, 10.870547945205479, 0.038808894189584275),
        (
            300,
            512,
            156,
            308,
            10.870547945205479,
            5.116625911767752e-06,
        ),
        (300, 512, 154, 262, 10.870547945205479, 0.6514014137740752),
        (300, 512, 129, 308, 10.870547945205479, 1e-07),
        (300, 512, 160, 256, 10.870547945205479, 0.2574341597282431),
        (513, 200, 256, 100, 8.806043956043956, 0.988195814730753),
        (513, 200, 255, 100, 8.806043956043956, 0.9818446707627703),
        (513, 200, 255, 98, 8.806043956043956, 0.9024917034514046),
        (513, 200, 209, 97, 8.806043956043956, 4.998630192164719e-07),
        (513, 200, 256, 92, 8.806043956043956, 0.09237593606842186),
        (333, 334, 168, 188, 10.37, 0.11428140810746094),
        (333, 334, 191, 191, 10.37, 0.0033165461181134176),
        (333, 334, 136, 156, 10.37, 0.008969023769530366),
        (1500, 2000, 0, 0, 300.35, 1.5536883228000477e-05),
        (1500, 2000, 750, 1000, 300.35, 0.9999979215322443),
        (1500, 2000, 1477, 711, 300.35, 0.003426013452652142),
        (1500, 2000, 868, 689, 300.35, 0.5103126150835575),
        (1500, 2000, 46, 62, 300.35, 5.840764235042259e-05),
        (64, 64, 28, 29, 2.0954545454545457, 0.12164901019934563),
    ];

    fn release_light(center: [f64; 2], h: f64, w: f64, sigma: f64) -> Light {
        let m = h.max(w);
        light(center, Some([h, w]), [sigma * h / m, sigma * w / m])
    }

    #[test]
    fn release_kernel_matches_opencv() {
        for &(h, w, i, j, sigma, want) in OPENCV {
            let sz = h.max(w);
            let v = (release_resized(i, h, sz, sigma) * release_resized(j, w, sz, sigma))
                .max(MASK_FLOOR);
            assert!(
                (v - want).abs() <= 1e-12 * want.max(1e-3),
                "{h}x{w} ({i},{j}): {v} vs {want}"
            );
            // through a prepared mask: kernel [0][0] at frame (10, 20), odd/even windows
            // placed by the plan's centre rule (peak at ty, or ty - 0.5 for even sides)
            let (ty, tx) = (10 + h / 2, 20 + w / 2);
            let cy = ty as f64 - if h % 2 == 0 { 0.5 } else { 0.0 };
            let cx = tx as f64 - if w % 2 == 0 { 0.5 } else { 0.0 };
            let l = release_light([cy, cx], h as f64, w as f64, sigma);
            let pm = PreparedMask::new(&l, w + 40, h + 20, MaskEval::Release);
            assert_eq!(pm.rows, (10, 10 + h));
            assert_eq!(pm.cols, (20, 20 + w));
            let got = pm.at(10 + i, 20 + j);
            let ulp = (want as f32 - got).abs() / f32::EPSILON / (want as f32).max(1e-30);
            assert!(
                ulp <= 1.0,
                "{h}x{w} ({i},{j}): f32 {got} vs {want} ({ulp} ulp)"
            );
            assert_eq!(pm.at(9, 20 + j), 0.0);
            assert_eq!(pm.at(10 + i, 20 + w), 0.0);
        }
    }

    #[test]
    fn release_resize_identity_and_ends() {
        // n == sz: the kernel itself; a kernel of one sample is 1
        for i in 0..9 {
            assert_eq!(release_resized(i, 9, 9, 1.7), release_kernel(i, 9, 1.7));
        }
        assert_eq!(release_kernel(4, 9, 1.7), 1.0);
        assert_eq!(release_kernel(4, 10, 1.7), 1.0);
        assert_eq!(release_kernel(5, 10, 1.7), 1.0);
        assert_eq!(release_resized(0, 1, 1, 0.0), 1.0);
        // sigma 0 or NaN: a delta at the centre; never NaN
        assert_eq!(release_kernel(3, 9, 0.0), 0.0);
        assert_eq!(release_kernel(3, 9, f64::NAN), 0.0);
        for n in 1..12 {
            for j in 0..n {
                let v = release_resized(j, n, 12, 2.0);
                assert!((0.0..=1.0).contains(&v), "{n} {j} {v}");
            }
        }
    }

    #[test]
    fn release_eval_is_sane_on_odd_plans() {
        // non-finite or huge geometry: no panic, values in [0, 1], zero outside the window
        for (c, win, sig) in [
            ([f64::NAN, 5.0], [10.0, 10.0], [2.0, 2.0]),
            ([5.0, 5.0], [f64::NAN, 1e300], [2.0, 2.0]),
            ([5.0, 5.0], [0.0, -3.0], [0.0, 0.0]),
            ([-1e18, 1e18], [4.0, 4.0], [1.0, 1.0]),
            ([5.0, 5.0], [7.0, 7.0], [f64::NAN, f64::INFINITY]),
        ] {
            let l = light(c, Some(win), sig);
            let pm = PreparedMask::new(&l, 16, 12, MaskEval::Release);
            for r in 0..12 {
                for k in 0..16 {
                    let v = pm.at(r, k);
                    assert!((0.0..=1.0).contains(&v), "{c:?} {win:?} {v}");
                }
            }
        }
        // without a window (paper lights) the release eval is the separable one
        let l = light([30.3, 41.7], None, [7.0, 9.5]);
        let a = PreparedMask::new(&l, 80, 90, MaskEval::Release);
        let b = PreparedMask::new(&l, 80, 90, MaskEval::Separable);
        for r in 0..80 {
            for k in 0..90 {
                assert_eq!(a.at(r, k), b.at(r, k));
            }
        }
    }

    #[test]
    fn release_kernel_is_close_to_the_analytic_mask_for_large_sigmas() {
        // a local light's kernel (sigma ~0.15 of the window) is well sampled: close to ours
        let (h, w) = (301.0, 451.0);
        let l = release_light([200.0, 300.0], h, w, opencv_sigma(451.0));
        let a = PreparedMask::new(&l, 600, 400, MaskEval::Release);
        let b = PreparedMask::new(&l, 600, 400, MaskEval::Exact);
        let mut worst = 0f32;
        for r in (0..400).step_by(3) {
            for k in (0..600).step_by(3) {
                worst = worst.max((a.at(r, k) - b.at(r, k)).abs());
            }
        }
        assert!(worst < 5e-3, "{worst}");
        assert!(worst > 0.0);
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
