//! WarpRectilinear (opcode 1) and WarpFisheye (opcode 2) on the stage-3 image (OpcodeList3),
//! as the Adobe DNG SDK's `dng_filter_warp`:
//! * the optical centre is `(l + cx (r - l), t + cy (b - t))` of the image extent, in pixel
//!   coordinates where pixel (row, col) sits at (row, col);
//! * the normalising radius is the largest distance from the centre to a corner of the
//!   extent (`MaxDistancePointToRect`), so `r = 1` at the farthest corner;
//! * each destination (corrected) pixel `d` maps to the source (uncorrected) position
//!   `s = c + R (n ratio + tan)` with `n = (d - c) / R`, `r^2 = min(|n|^2, 1)`,
//!   rectilinear `ratio = kr0 + kr1 r^2 + kr2 r^4 + kr3 r^6`,
//!   `tan_v = kt0 (r^2 + 2 n_v^2) + 2 kt1 n_h n_v`, `tan_h = kt1 (r^2 + 2 n_h^2) + 2 kt0 n_h n_v`;
//!   fisheye `ratio = f(r) / r` with `f(r) = t (kr0 + kr1 t^2 + kr2 t^4 + kr3 t^6)`,
//!   `t = atan(r)` (no tangential terms);
//! * the source is resampled with the SDK's separable bicubic kernel (A = -0.75, 4x4 taps,
//!   weights normalised to sum 1; the SDK quantises the fraction to 1/32 of a pixel, day2night
//!   does not), edges repeated, and the result pinned into [0, 1].
//!
//! WarpRectilinear2 (opcode 14, DNG 1.6) is the rectilinear model with `ratio` a polynomial
//! of degree 14 in `r` (not `r^2`): `ratio = kr0 + kr1 r + ... + kr14 r^14`, with `r^2`
//! first pinned into the plane's valid range `[min^2, max^2]` (after the clamp to 1), and
//! `1 / ratio` when its reciprocal flag is set; the tangential terms are those of
//! WarpRectilinear (with the unpinned `r^2`). (Adobe DNG SDK 1.6 `dng_warp_params_radial`.)
//!
//! One set of coefficients applies to every plane; one per plane when the opcode has as
//! many as the image. Square pixels (PixelAspectRatio 1).
//!
//! [`apply_rows`] warps a band of output rows reading only the rows of the source its taps
//! reach (its source window, from the source positions of the band's pixels); [`apply`]
//! warps the whole image. Both resample every pixel with the same expressions.

use super::StageRect;
use crate::dng::opcodes::OpcodeKind;
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::ops::Range;

/// The radial model of a warp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Model {
    /// Rectilinear: radial kr0..kr3 and tangential kt0, kt1.
    Rectilinear {
        /// kr0..kr3.
        kr: [f64; 4],
        /// kt0, kt1.
        kt: [f64; 2],
    },
    /// Fisheye: kr0..kr3 of `atan(r)`.
    Fisheye {
        /// kr0..kr3.
        kr: [f64; 4],
    },
    /// WarpRectilinear2: radial kr0..kr14 in `r`, tangential kt0, kt1, the valid radius
    /// range, and whether the ratio is the polynomial's reciprocal.
    Rectilinear2 {
        /// kr0..kr14.
        kr: [f64; 15],
        /// kt0, kt1.
        kt: [f64; 2],
        /// Minimum and maximum valid radius.
        valid: [f64; 2],
        /// `ratio = 1 / sum`.
        reciprocal: bool,
    },
}

/// The radial ratio of WarpRectilinear2 at `rr` (= `min(r^2, 1)`).
fn ratio2(kr: &[f64; 15], valid: [f64; 2], reciprocal: bool, rr: f64) -> f64 {
    let r2 = rr.min(valid[1] * valid[1]).max(valid[0] * valid[0]);
    let r = r2.sqrt();
    let mut poly = kr[14];
    for &k in kr[..14].iter().rev() {
        poly = poly * r + k;
    }
    if reciprocal {
        1.0 / poly
    } else {
        poly
    }
}

/// A warp ready to map destination pixels to source positions.
#[derive(Debug, Clone)]
pub struct Warp {
    pub(super) planes: Vec<Model>,
    pub(super) cv: f64,
    pub(super) ch: f64,
    pub(super) norm: f64,
    pub(super) inv: f64,
}

fn poly(k: &[f64; 4], x2: f64) -> f64 {
    k[0] + x2 * (k[1] + x2 * (k[2] + x2 * k[3]))
}

impl Warp {
    /// A warp with `models` (one, or one per plane) about the relative centre (x, y) of an
    /// image of `extent` with `planes` planes. Errors when the number of coefficient sets
    /// is neither 1 nor `planes` (the SDK refuses such a file too).
    pub fn new(models: Vec<Model>, center: [f64; 2], b: StageRect, planes: usize) -> Result<Warp> {
        if models.is_empty() || (models.len() != 1 && models.len() != planes) {
            return Err(Error::malformed(format!(
                "OpcodeList3: a warp with {} coefficient sets for a {planes}-plane image",
                models.len()
            )));
        }
        if !center.iter().all(|c| (0.0..=1.0).contains(c)) {
            return Err(Error::malformed(format!(
                "OpcodeList3: warp optical centre {center:?} outside [0, 1]"
            )));
        }
        let cv = b.t as f64 + b.h() as f64 * center[1];
        let ch = b.l as f64 + b.w() as f64 * center[0];
        let norm = [(b.t, b.l), (b.t, b.r), (b.b, b.l), (b.b, b.r)]
            .iter()
            .map(|&(y, x)| (y as f64 - cv).hypot(x as f64 - ch))
            .fold(0.0f64, f64::max);
        let planes = (0..planes)
            .map(|p| models[if models.len() == 1 { 0 } else { p }])
            .collect();
        Ok(Warp {
            planes,
            cv,
            ch,
            norm,
            inv: if norm > 0.0 { 1.0 / norm } else { 0.0 },
        })
    }

    /// The source (uncorrected) position (row, col) of destination pixel (row, col) in plane
    /// `p`.
    pub fn source(&self, p: usize, row: f64, col: f64) -> (f64, f64) {
        let (dv, dh) = (row - self.cv, col - self.ch);
        let (nv, nh) = (dv * self.inv, dh * self.inv);
        let rr = (nv * nv + nh * nh).min(1.0);
        let (ratio, kt) = match self.planes[p] {
            Model::Rectilinear { kr, kt } => (poly(&kr, rr), kt),
            Model::Rectilinear2 {
                kr,
                kt,
                valid,
                reciprocal,
            } => (ratio2(&kr, valid, reciprocal, rr), kt),
            Model::Fisheye { kr } => {
                let ratio = if rr < 1e-12 {
                    1.0
                } else {
                    let r = rr.sqrt();
                    let t = r.atan();
                    t * poly(&kr, t * t) / r
                };
                return (self.cv + dv * ratio, self.ch + dh * ratio);
            }
        };
        if kt == [0.0, 0.0] {
            (self.cv + dv * ratio, self.ch + dh * ratio)
        } else {
            let tv = kt[0] * (rr + 2.0 * nv * nv) + 2.0 * kt[1] * nh * nv;
            let th = kt[1] * (rr + 2.0 * nh * nh) + 2.0 * kt[0] * nh * nv;
            (
                self.cv + self.norm * (nv * ratio + tv),
                self.ch + self.norm * (nh * ratio + th),
            )
        }
    }

    /// The warp of opcode `kind` (WarpRectilinear, WarpRectilinear2 or WarpFisheye) on an
    /// image of `b` with `planes` planes; `None` for other kinds.
    pub fn of_opcode(kind: &OpcodeKind, b: StageRect, planes: usize) -> Option<Result<Warp>> {
        let (models, center): (Vec<Model>, [f64; 2]) = match kind {
            OpcodeKind::WarpRectilinear { planes, center } => (
                planes
                    .iter()
                    .map(|p| Model::Rectilinear { kr: p.kr, kt: p.kt })
                    .collect(),
                *center,
            ),
            OpcodeKind::WarpRectilinear2 {
                planes,
                center,
                reciprocal,
            } => (
                planes
                    .iter()
                    .map(|p| Model::Rectilinear2 {
                        kr: p.kr,
                        kt: p.kt,
                        valid: p.valid,
                        reciprocal: *reciprocal,
                    })
                    .collect(),
                *center,
            ),
            OpcodeKind::WarpFisheye { planes, center } => (
                planes.iter().map(|&kr| Model::Fisheye { kr }).collect(),
                *center,
            ),
            _ => return None,
        };
        Some(Warp::new(models, center, b, planes))
    }

    /// True when every plane has the same model (one source position per pixel).
    fn shared(&self) -> bool {
        self.planes.windows(2).all(|p| p[0] == p[1])
    }
}

/// The SDK's bicubic kernel (A = -0.75).
fn cubic(x: f64) -> f64 {
    const A: f64 = -0.75;
    let x = x.abs();
    if x >= 2.0 {
        0.0
    } else if x >= 1.0 {
        ((A * x - 5.0 * A) * x + 8.0 * A) * x - 4.0 * A
    } else {
        ((A + 2.0) * x - (A + 3.0)) * x * x + 1.0
    }
}

/// The four normalised tap weights and the first tap index of position `s`.
fn taps(s: f64) -> (i64, [f64; 4]) {
    let f = s.floor();
    let i = if f.is_finite() {
        f.clamp(-1e15, 1e15) as i64
    } else {
        0
    };
    let fr = if f.is_finite() { s - f } else { 0.0 };
    let mut w = [0.0; 4];
    for (k, wk) in w.iter_mut().enumerate() {
        *wk = cubic(k as f64 - 1.0 - fr);
    }
    let t: f64 = w.iter().sum();
    if t != 0.0 {
        w.iter_mut().for_each(|v| *v /= t);
    }
    (i - 1, w)
}

/// The tap origins and weights (rows, columns) of source position (`sv`, `sh`) in an image
/// whose pixel (0, 0) sits at stage position (`extent.t`, `extent.l`).
type Taps = ((i64, [f64; 4]), (i64, [f64; 4]));

#[inline]
fn taps_of((sv, sh): (f64, f64), extent: StageRect) -> Taps {
    (taps(sv - extent.t as f64), taps(sh - extent.l as f64))
}

#[inline]
fn clampi(v: i64, n: usize) -> usize {
    v.clamp(0, n as i64 - 1) as usize
}

/// The resample of plane `p` at `taps` from the image rows that `row(yy)` gives (each
/// `w * planes` samples), edges repeated, pinned into [0, 1].
#[inline]
fn resample<'a>(
    ((y0, wy), (x0, wx)): Taps,
    p: usize,
    (w, h, planes): (usize, usize, usize),
    row: impl Fn(usize) -> &'a [f32],
) -> f32 {
    let mut total = 0.0f64;
    for (i, wyi) in wy.iter().enumerate() {
        let srow = row(clampi(y0 + i as i64, h));
        let mut acc = 0.0f64;
        for (j, wxj) in wx.iter().enumerate() {
            let xx = clampi(x0 + j as i64, w);
            acc += wxj * srow[xx * planes + p] as f64;
        }
        total += wyi * acc;
    }
    super::pin(total as f32, 1.0)
}

/// Warp a stage-3 image (`w x h` pixels of `planes` interleaved samples in [0, 1], pixel
/// (0, 0) at stage position (`extent.t`, `extent.l`)): every output pixel is the bicubic
/// resample of `data` at its source position.
pub fn apply(
    warp: &Warp,
    data: &[f32],
    w: usize,
    h: usize,
    planes: usize,
    extent: StageRect,
) -> Vec<f32> {
    let mut out = vec![0.0f32; data.len()];
    if w == 0 || h == 0 || planes == 0 {
        return out;
    }
    let shared = warp.shared();
    let dims = (w, h, planes);
    let row = |yy: usize| &data[yy * w * planes..];
    out.par_chunks_mut(w * planes)
        .enumerate()
        .for_each(|(y, orow)| {
            let r = (extent.t + y as i64) as f64;
            for x in 0..w {
                let c = (extent.l + x as i64) as f64;
                let mut t = taps_of(warp.source(0, r, c), extent);
                for p in 0..planes {
                    if p > 0 && !shared {
                        t = taps_of(warp.source(p, r, c), extent);
                    }
                    orow[x * planes + p] = resample(t, p, dims, row);
                }
            }
        });
    out
}

/// The source positions of a rectangle of destination pixels and the window of the
/// source their bicubic taps read ([`plan`]).
pub(crate) struct Plan {
    /// Destination rows and columns (image coordinates, 0 = `extent.t` / `extent.l`).
    rows: Range<usize>,
    cols: Range<usize>,
    /// Source positions, `per` per pixel (1 when the planes share the model).
    pos: Vec<(f64, f64)>,
    per: usize,
    /// The source rows and columns the taps read (clamped to the image).
    pub(crate) win_rows: Range<usize>,
    pub(crate) win_cols: Range<usize>,
}

/// Pass 1 of a windowed warp of a `w x h` image of `planes` samples per pixel: the source
/// position of every pixel of the destination rectangle `rows x cols`, and the rows and
/// columns of the source their taps reach (empty for an empty image or rectangle).
pub(crate) fn plan(
    warp: &Warp,
    (w, h, planes): (usize, usize, usize),
    extent: StageRect,
    rows: Range<usize>,
    cols: Range<usize>,
) -> Plan {
    let per = if warp.shared() { 1 } else { planes.max(1) };
    let mut pos = Vec::with_capacity(rows.len() * cols.len() * per);
    let (mut lo, mut hi) = (i64::MAX, i64::MIN);
    let (mut left, mut right) = (i64::MAX, i64::MIN);
    if w > 0 && h > 0 && planes > 0 {
        for y in rows.clone() {
            let r = (extent.t + y as i64) as f64;
            for x in cols.clone() {
                let c = (extent.l + x as i64) as f64;
                for p in 0..per {
                    let s = warp.source(p, r, c);
                    let ((y0, _), (x0, _)) = taps_of(s, extent);
                    lo = lo.min(y0);
                    hi = hi.max(y0 + 3);
                    left = left.min(x0);
                    right = right.max(x0 + 3);
                    pos.push(s);
                }
            }
        }
    }
    let (win_rows, win_cols) = if pos.is_empty() {
        (0..0, 0..0)
    } else {
        (
            clampi(lo, h)..clampi(hi, h) + 1,
            clampi(left, w)..clampi(right, w) + 1,
        )
    };
    Plan {
        rows,
        cols,
        pos,
        per,
        win_rows,
        win_cols,
    }
}

/// The source image a [`Plan`] reads, over (at least) its window.
pub(crate) enum Src<'a> {
    /// Whole rows: `rows[yy - first]` is image row `yy` (`w * planes` samples).
    Rows {
        /// Image row of `rows[0]`.
        first: usize,
        /// The rows.
        rows: Vec<&'a [f32]>,
    },
    /// Whole columns, stored transposed: `cols[xx - first]` is image column `xx` (`h *
    /// planes` samples, row by row).
    Cols {
        /// Image column of `cols[0]`.
        first: usize,
        /// The columns.
        cols: Vec<&'a [f32]>,
    },
}

/// The resample of plane `p` at `taps` from the image columns that `col(xx)` gives (each
/// `h * planes` samples, transposed storage): the same sums in the same order as
/// [`resample`].
#[inline]
fn resample_cols<'a>(
    ((y0, wy), (x0, wx)): Taps,
    p: usize,
    (w, h, planes): (usize, usize, usize),
    col: impl Fn(usize) -> &'a [f32],
) -> f32 {
    let cs: [&[f32]; 4] = std::array::from_fn(|j| col(clampi(x0 + j as i64, w)));
    let mut total = 0.0f64;
    for (i, wyi) in wy.iter().enumerate() {
        let yy = clampi(y0 + i as i64, h) * planes + p;
        let mut acc = 0.0f64;
        for (wxj, c) in wx.iter().zip(&cs) {
            acc += wxj * c[yy] as f64;
        }
        total += wyi * acc;
    }
    super::pin(total as f32, 1.0)
}

/// Pass 2: the destination rectangle of `plan` resampled from `src` into `out` (row by
/// row, `cols.len() * planes` samples per row), equal bit for bit to [`apply`]'s pixels.
pub(crate) fn resample_plan(
    plan: &Plan,
    (w, h, planes): (usize, usize, usize),
    extent: StageRect,
    src: &Src,
    out: &mut [f32],
) {
    let rw = plan.cols.len();
    if plan.pos.is_empty() || rw == 0 {
        return;
    }
    let (shared, per) = (plan.per == 1, plan.per);
    let dims = (w, h, planes);
    for (k, orow) in out
        .chunks_exact_mut(rw * planes)
        .take(plan.rows.len())
        .enumerate()
    {
        for x in 0..rw {
            let at = (k * rw + x) * per;
            let mut t = taps_of(plan.pos[at], extent);
            for p in 0..planes {
                if p > 0 && !shared {
                    t = taps_of(plan.pos[at + p], extent);
                }
                orow[x * planes + p] = match src {
                    Src::Rows { first, rows } => resample(t, p, dims, |yy| rows[yy - first]),
                    Src::Cols { first, cols } => resample_cols(t, p, dims, |xx| cols[xx - first]),
                };
            }
        }
    }
}

/// Output rows `rows` (image rows, 0 = `extent.t`) of the warp of a `w x h` image of
/// `planes` samples per pixel, reading only the source rows the taps reach: `source(y0,
/// y1)` is asked once for image rows `[y0, y1)` (the window, from the source positions of
/// these rows' pixels) and returns them (`(y1 - y0) * w * planes` samples). `out` receives
/// the rows (`rows.len() * w * planes` samples), equal bit for bit to those of [`apply`].
pub fn apply_rows<'s>(
    warp: &Warp,
    (w, h, planes): (usize, usize, usize),
    extent: StageRect,
    rows: Range<usize>,
    source: impl FnOnce(usize, usize) -> Result<std::borrow::Cow<'s, [f32]>>,
    out: &mut [f32],
) -> Result<()> {
    if w == 0 || h == 0 || planes == 0 || rows.is_empty() {
        return Ok(());
    }
    let dims = (w, h, planes);
    let plan = plan(warp, dims, extent, rows, 0..w);
    let (y0, y1) = (plan.win_rows.start, plan.win_rows.end);
    let src = source(y0, y1)?;
    if src.len() != (y1 - y0) * w * planes {
        return Err(Error::invalid("warp source window of the wrong size"));
    }
    let src = Src::Rows {
        first: y0,
        rows: src.chunks_exact(w * planes).collect(),
    };
    resample_plan(&plan, dims, extent, &src, out);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_warp_keeps_the_image() {
        let (w, h) = (7, 5);
        let data: Vec<f32> = (0..w * h * 3).map(|i| (i % 11) as f32 / 11.0).collect();
        let warp = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, 0.0, 0.0, 0.0],
                kt: [0.0, 0.0],
            }],
            [0.5, 0.5],
            StageRect::of_size(w, h),
            3,
        )
        .unwrap();
        let out = apply(&warp, &data, w, h, 3, StageRect::of_size(w, h));
        for (a, b) in out.iter().zip(&data) {
            assert!((a - b).abs() < 1e-6);
        }
    }

    #[test]
    fn radial_source_positions_follow_the_formula() {
        let b = StageRect::of_size(200, 100);
        let warp = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, 0.1, 0.0, 0.0],
                kt: [0.0, 0.0],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        // centre (50, 100), R = hypot(50, 100)
        let r = 50f64.hypot(100.0);
        let (sv, sh) = warp.source(0, 10.0, 180.0);
        let (nv, nh) = ((10.0 - 50.0) / r, (180.0 - 100.0) / r);
        let ratio = 1.0 + 0.1 * (nv * nv + nh * nh);
        assert!((sv - (50.0 + (10.0 - 50.0) * ratio)).abs() < 1e-9);
        assert!((sh - (100.0 + 80.0 * ratio)).abs() < 1e-9);
        // tangential terms
        let t = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, 0.0, 0.0, 0.0],
                kt: [0.01, 0.02],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        let (sv, sh) = t.source(0, 10.0, 180.0);
        let rr = nv * nv + nh * nh;
        let tv = 0.01 * (rr + 2.0 * nv * nv) + 2.0 * 0.02 * nh * nv;
        let th = 0.02 * (rr + 2.0 * nh * nh) + 2.0 * 0.01 * nh * nv;
        assert!((sv - (50.0 + r * (nv + tv))).abs() < 1e-9);
        assert!((sh - (100.0 + r * (nh + th))).abs() < 1e-9);
    }

    #[test]
    fn rectilinear2_follows_the_dng_1_6_formula() {
        let b = StageRect::of_size(200, 100);
        let r = 50f64.hypot(100.0);
        let (nv, nh) = ((10.0 - 50.0) / r, (180.0 - 100.0) / r);
        let rr = nv * nv + nh * nh;
        let mut kr = [0.0; 15];
        kr[0] = 1.0;
        kr[1] = 0.05; // odd powers of r exist in this model
        kr[2] = -0.1;
        let m = |kt, valid, reciprocal| {
            Warp::new(
                vec![Model::Rectilinear2 {
                    kr,
                    kt,
                    valid,
                    reciprocal,
                }],
                [0.5, 0.5],
                b,
                1,
            )
            .unwrap()
        };
        let (sv, sh) = m([0.0; 2], [0.0, 1.0], false).source(0, 10.0, 180.0);
        let ratio = 1.0 + 0.05 * rr.sqrt() - 0.1 * rr;
        assert!((sv - (50.0 - 40.0 * ratio)).abs() < 1e-9);
        assert!((sh - (100.0 + 80.0 * ratio)).abs() < 1e-9);
        // reciprocal
        let (sv, _) = m([0.0; 2], [0.0, 1.0], true).source(0, 10.0, 180.0);
        assert!((sv - (50.0 - 40.0 / ratio)).abs() < 1e-9);
        // the radius is pinned into the valid range [0.2, 0.5]
        let (sv, _) = m([0.0; 2], [0.2, 0.5], false).source(0, 10.0, 180.0);
        let pinned = 1.0 + 0.05 * 0.5 - 0.1 * 0.25;
        assert!((sv - (50.0 - 40.0 * pinned)).abs() < 1e-9);
        // tangential terms as WarpRectilinear's, with the unpinned r^2
        let (sv, sh) = m([0.01, 0.02], [0.2, 0.5], false).source(0, 10.0, 180.0);
        let tv = 0.01 * (rr + 2.0 * nv * nv) + 2.0 * 0.02 * nh * nv;
        let th = 0.02 * (rr + 2.0 * nh * nh) + 2.0 * 0.01 * nh * nv;
        assert!((sv - (50.0 + r * (nv * pinned + tv))).abs() < 1e-9);
        assert!((sh - (100.0 + r * (nh * pinned + th))).abs() < 1e-9);
        // WarpRectilinear's coefficients in the even terms give WarpRectilinear's positions
        let mut even = [0.0; 15];
        (even[0], even[2], even[4], even[6]) = (1.0, 0.1, -0.02, 0.003);
        let w1 = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, 0.1, -0.02, 0.003],
                kt: [0.001, 0.0],
            }],
            [0.3, 0.6],
            b,
            1,
        )
        .unwrap();
        let w2 = Warp::new(
            vec![Model::Rectilinear2 {
                kr: even,
                kt: [0.001, 0.0],
                valid: [0.0, 1.0],
                reciprocal: false,
            }],
            [0.3, 0.6],
            b,
            1,
        )
        .unwrap();
        for (y, x) in [(0.0, 0.0), (33.0, 150.0), (99.0, 199.0)] {
            let (a, c) = (w1.source(0, y, x), w2.source(0, y, x));
            assert!((a.0 - c.0).abs() < 1e-9 && (a.1 - c.1).abs() < 1e-9);
        }
    }

    #[test]
    fn rows_read_only_their_window_and_equal_the_whole_warp() {
        let (w, h) = (37, 53);
        let data: Vec<f32> = (0..w * h * 3)
            .map(|i| ((i * 7919) % 1000) as f32 / 999.0)
            .collect();
        let b = StageRect {
            t: 4,
            l: 2,
            b: 4 + h as i64,
            r: 2 + w as i64,
        };
        let models = [
            vec![Model::Rectilinear {
                kr: [1.0, -0.2, 0.05, 0.0],
                kt: [0.002, -0.001],
            }],
            vec![
                Model::Fisheye {
                    kr: [1.0, 0.1, 0.0, 0.0],
                },
                Model::Fisheye {
                    kr: [1.02, 0.1, 0.0, 0.0],
                },
                Model::Fisheye {
                    kr: [0.98, 0.1, 0.0, 0.0],
                },
            ],
        ];
        for m in models {
            let warp = Warp::new(m, [0.4, 0.7], b, 3).unwrap();
            let whole = apply(&warp, &data, w, h, 3, b);
            for band in [1, 5, 16, 53] {
                let mut got = vec![0.0f32; data.len()];
                let mut widest = 0;
                for (k, out) in got.chunks_mut(band * w * 3).enumerate() {
                    let rows = k * band..(k * band + band).min(h);
                    apply_rows(
                        &warp,
                        (w, h, 3),
                        b,
                        rows,
                        |y0, y1| {
                            widest = widest.max(y1 - y0);
                            Ok(std::borrow::Cow::Borrowed(&data[y0 * w * 3..y1 * w * 3]))
                        },
                        out,
                    )
                    .unwrap();
                }
                assert_eq!(got, whole, "band {band}");
                if band == 1 {
                    assert!(widest < h, "a one-row band read {widest} of {h} rows");
                }
            }
        }
    }

    #[test]
    fn fisheye_and_bad_inputs() {
        let b = StageRect::of_size(10, 10);
        let f = Warp::new(
            vec![Model::Fisheye {
                kr: [1.0, 0.0, 0.0, 0.0],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        let (sv, _) = f.source(0, 5.0, 5.0);
        assert_eq!(sv, 5.0);
        let (sv, _) = f.source(0, 0.0, 5.0);
        let r = 5.0 / 50f64.sqrt();
        assert!((sv - (5.0 - 5.0 * r.atan() / r)).abs() < 1e-9);
        let two = vec![Model::Fisheye { kr: [1.0; 4] }; 2];
        assert!(Warp::new(two, [0.5, 0.5], b, 3).is_err());
        assert!(Warp::new(vec![Model::Fisheye { kr: [1.0; 4] }], [1.5, 0.5], b, 3).is_err());
        // NaN coefficients: output pinned, no NaN
        let n = Warp::new(
            vec![Model::Rectilinear {
                kr: [f64::NAN; 4],
                kt: [0.0; 2],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        let out = apply(&n, &[0.5; 100], 10, 10, 1, b);
        assert!(out.iter().all(|v| v.is_finite()));
        // a 1x1 image
        let out = apply(&f, &[0.25], 1, 1, 1, StageRect::of_size(1, 1));
        assert_eq!(out, vec![0.25]);
    }
}
