//! Frame k's clean raw from the clean night raw (docs/synthesis.md, "Bursts"):
//!
//! 1. the clean raw, normalized and white-balanced by the night neutral, is demosaiced with
//!    Malvar-He-Cutler (`isp::demosaic`), which keeps every measured sample: the demosaiced
//!    image's channel c at a site of colour c is that site's sample;
//! 2. each frame-k site (x, y) reads the frame-00 position `A^-1 (x, y)` of its own colour's
//!    channel through the interpolant ([`Interp`]); taps outside the image read the nearest
//!    edge sample (the edge is repeated), and [`super::motion::FrameTransform::valid`] is the
//!    rectangle of sites none of whose taps is outside;
//! 3. the value is un-white-balanced, clipped to the clean pass's range and denormalized as
//!    the clean pass denormalizes (docs/synthesis.md, "6. Denormalize").
//!
//! The image is processed in tiles of [`TILE`] x [`TILE`] frame-k sites: each tile
//! demosaics only the source window its taps read (plus the demosaicer's 2-sample
//! neighbourhood, read from the clean raw and mirrored at the image edges exactly as a
//! whole-image demosaic does), so a site's value does not depend on the tiling, on the rows
//! it was asked for with, or on the thread count, and no demosaiced frame is ever held.

use super::interp::Interp;
use super::motion::apply;
use crate::isp::demosaic::{demosaic_rect, mhc_row_kernel, RowDemosaic, RowKernel};
use crate::normalize::Normalizer;
use crate::raw::Bayer;
use std::ops::Range;

/// Frame-k sites per tile side.
pub const TILE: usize = 128;

/// The clean night raw (or a rectangle of it) that a warp reads.
#[derive(Debug, Clone)]
pub struct CleanSource<'a> {
    /// Samples, row-major.
    pub data: &'a [u16],
    /// Samples per row of `data`.
    pub stride: usize,
    /// Index in `data` of active-area sample (`rows.start`, `cols.start`).
    pub offset: usize,
    /// Active-area rows held.
    pub rows: Range<usize>,
    /// Active-area columns held.
    pub cols: Range<usize>,
}

/// What the warp of one frame needs.
pub struct Warper<'a> {
    src: CleanSource<'a>,
    norm: &'a Normalizer,
    bayer: Bayer,
    neutral: [f64; 3],
    active: (usize, usize),
    inv: [[f64; 3]; 2],
    interp: Interp,
    kernel: RowKernel,
    lo: f64,
    truncate: bool,
}

/// The levels and colours a warp works with.
pub struct WarpLevels<'a> {
    /// The clean raw's normalizer (linear values).
    pub norm: &'a Normalizer,
    /// The CFA pattern of the active area.
    pub bayer: Bayer,
    /// The night neutral (white balance of the demosaic).
    pub neutral: [f64; 3],
    /// Active-area width and height.
    pub active: (usize, usize),
    /// Keep normalized values below 0 (the plan's `keep_negative`).
    pub keep_negative: bool,
    /// Truncate instead of rounding when denormalizing (the plan's `truncate`).
    pub truncate: bool,
}

impl<'a> Warper<'a> {
    /// The warp of a frame whose inverse affine (frame-k to frame-00 coordinates) is `inv`.
    pub fn new(
        src: CleanSource<'a>,
        levels: &WarpLevels<'a>,
        inv: [[f64; 3]; 2],
        interp: Interp,
    ) -> Warper<'a> {
        Warper {
            src,
            norm: levels.norm,
            bayer: levels.bayer,
            neutral: levels.neutral,
            active: levels.active,
            inv,
            interp,
            // MHC: a single pass with a 2-sample neighbourhood that keeps measured samples
            kernel: mhc_row_kernel(),
            lo: if levels.keep_negative {
                f64::NEG_INFINITY
            } else {
                0.0
            },
            truncate: levels.truncate,
        }
    }

    /// The active-area rectangle of the clean raw the sites `rows` x `cols` of the frame
    /// read: their taps' bounding box, clamped to the image, grown by `margin` (clamped).
    pub fn source_window(
        inv: &[[f64; 3]; 2],
        interp: Interp,
        active: (usize, usize),
        (rows, cols): (&Range<usize>, &Range<usize>),
        margin: usize,
    ) -> (Range<usize>, Range<usize>) {
        let (aw, ah) = active;
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for y in [rows.start, rows.end - 1] {
            for x in [cols.start, cols.end - 1] {
                let (sx, sy) = apply(inv, x as f64, y as f64);
                x0 = x0.min(sx);
                x1 = x1.max(sx);
                y0 = y0.min(sy);
                y1 = y1.max(sy);
            }
        }
        let r = interp.radius() as f64;
        let span = |lo: f64, hi: f64, n: usize| {
            let top = (n - 1) as f64;
            let a = (lo.clamp(-1e9, 1e9).floor() - r + 1.0).clamp(0.0, top) as usize;
            let b = (hi.clamp(-1e9, 1e9).floor() + r).clamp(0.0, top) as usize;
            a.saturating_sub(margin)..(b + margin).min(n - 1) + 1
        };
        (span(y0, y1, ah), span(x0, x1, aw))
    }

    /// Frame-k clean samples of active-area rows `rows` x columns `cols` into `out`: row
    /// `rows.start + i` goes to `out[i * stride + left..][..cols.len()]`.
    pub fn fill(
        &self,
        rows: Range<usize>,
        cols: Range<usize>,
        out: &mut [u16],
        (stride, left): (usize, usize),
    ) {
        if rows.is_empty() || cols.is_empty() {
            return;
        }
        let mut buf = Vec::new();
        let mut ty = rows.start;
        while ty < rows.end {
            let ty1 = (ty + TILE).min(rows.end);
            let mut tx = cols.start;
            while tx < cols.end {
                let tx1 = (tx + TILE).min(cols.end);
                let o = (ty - rows.start) * stride + left + (tx - cols.start);
                self.tile(ty..ty1, tx..tx1, &mut out[o..], stride, &mut buf);
                tx = tx1;
            }
            ty = ty1;
        }
    }

    /// One tile: demosaic its source window into `buf`, then interpolate every site.
    fn tile(
        &self,
        rows: Range<usize>,
        cols: Range<usize>,
        out: &mut [u16],
        stride: usize,
        buf: &mut Vec<f32>,
    ) {
        let (aw, ah) = self.active;
        let (wr, wc) = Self::source_window(&self.inv, self.interp, self.active, (&rows, &cols), 0);
        let ww = wc.len();
        buf.clear();
        buf.resize(3 * ww * wr.len(), 0.0);
        let src = &self.src;
        let (norm, bayer, n) = (self.norm, self.bayer, self.neutral);
        let fill = |r: usize, cs: &[usize], o: &mut [f32]| {
            let base = src.offset + (r - src.rows.start) * src.stride;
            for (v, &c) in o.iter_mut().zip(cs) {
                let x = src.data[base + (c - src.cols.start)];
                let y = norm.normalize(x, r, c) / n[bayer.color_at(r, c) as usize];
                *v = y as f32;
            }
        };
        let emit = |i: usize, rgb: &mut [f32]| {
            buf[3 * ww * i..3 * ww * (i + 1)].copy_from_slice(rgb);
        };
        let cfa = RowDemosaic {
            width: aw,
            height: ah,
            bayer,
            kernel: self.kernel,
        };
        demosaic_rect(cfa, wr.clone(), wc.clone(), fill, &|_| {}, emit);
        let r = self.interp.radius();
        let taps = 2 * r;
        let (mut wx, mut wy) = ([0.0f64; 6], [0.0f64; 6]);
        let (mut ix, mut iy) = ([0usize; 6], [0usize; 6]);
        // tap offsets, clamped to the image, relative to the window
        let place = |s: f64, n: usize, w0: usize, idx: &mut [usize; 6], wts: &mut [f64; 6]| {
            let s = s.clamp(-1e9, 1e9);
            let fl = s.floor();
            self.interp.weights(s - fl, wts);
            let i0 = fl as i64 - r as i64 + 1;
            for (j, v) in idx.iter_mut().take(taps).enumerate() {
                *v = (i0 + j as i64).clamp(0, n as i64 - 1) as usize - w0;
            }
        };
        for (i, y) in rows.clone().enumerate() {
            let line = &mut out[i * stride..][..cols.len()];
            for (o, x) in line.iter_mut().zip(cols.clone()) {
                let (sx, sy) = apply(&self.inv, x as f64, y as f64);
                place(sx, aw, wc.start, &mut ix, &mut wx);
                place(sy, ah, wr.start, &mut iy, &mut wy);
                let c = bayer.color_at(y, x) as usize;
                let mut v = 0.0f64;
                for j in 0..taps {
                    let row = &buf[3 * ww * iy[j]..];
                    let mut h = 0.0f64;
                    for k in 0..taps {
                        h += wx[k] * row[3 * ix[k] + c] as f64;
                    }
                    v += wy[j] * h;
                }
                let yn = (v * n[c]).clamp(self.lo, 1.0);
                *o = norm.denormalize_with_black(yn, norm.black_at(y, x), self.truncate);
            }
        }
    }
}
