//! The opcode render band by band: each band of the output asks for the active-area
//! rectangle it shows ([`crate::isp::place::place`]), and that rectangle alone is computed
//! through the stages of [`super::pipeline`] with the same expressions, so the result equals
//! the whole-frame render ([`super::pipeline::render_frame`]) bit for bit, for any band
//! height and thread count:
//!
//! * OpcodeList1 runs on the stored rectangle the band needs, grown by the reach of the
//!   list's bad-pixel fixes ([`super::bad_pixels::REACH`] rows and columns each, clipped at
//!   the stored image's edges, where the whole-frame pass stops too), then rounds to 16
//!   bits; OpcodeList2 likewise on the normalized rectangle (the demosaicer's 2-sample
//!   margin plus its own fixes' reach). A run of repeated FixBadPixelsConstant (whose reach
//!   grows with each pass that repairs something) makes its list run once on the whole
//!   stage image instead, kept for every band.
//! * The rectangle is demosaiced ([`crate::isp::demosaic::demosaic_rect`]), the neutral
//!   multiplied back in and OpcodeList3's in-place opcodes applied to it, the neutral divided
//!   out, the caller's `post` applied.
//! * The warps of OpcodeList3 (with in-place opcodes before, between and after them) read
//!   the image before them through a rolling window of strips ([`super::warp_window`]):
//!   strips of rows (orientations 1-4), or of columns for the turning orientations 5-8,
//!   whose bands are columns of the image, made on demand and dropped once no later band
//!   reaches them; a pathological warp (or more than [`super::warp_window::MAX_WARPS`]) takes
//!   the whole-image path. A TrimBounds is not banded ([`render`] returns `None`; the
//!   whole-frame path runs).
//!
//! No whole stored copy, no whole normalized plane and no whole image before a warp exist
//! unless a list runs whole or a warp takes the whole-image path.

use super::bad_pixels::REACH;
use super::pipeline::{checked_active, moves_pixels, stage1};
use super::warp::Warp;
use super::warp_window::{Axis, Chain, Strips, WindowStats};
use super::{apply_region, apply_region_seq, pin, Prepared, Region, StageRect};
use crate::dng::opcodes::{ListId, Opcode, OpcodeKind};
use crate::error::{Error, Result};
use crate::isp::color::normalize_neutral;
use crate::isp::demosaic::{demosaic_rect, Post, RowDemosaic, RowKernel, PAD};
use crate::isp::place::{place, BandBody, Placement, RectFn};
use crate::isp::pre_demosaic::CfaSites;
use crate::limits::try_filled;
use crate::raw::{Bayer, RawImage};
use rayon::prelude::*;
use std::borrow::Cow;
use std::ops::Range;

/// Rows (and columns) of margin a list's opcodes need around a rectangle for its samples to
/// equal the whole stage image's: the bad-pixel fixes' reach, added up. `None` when the list
/// must run on the whole stage: a run of repeated FixBadPixelsConstant.
pub(crate) fn reach(ops: &[Opcode]) -> Option<usize> {
    let mut total = 0usize;
    for (i, op) in ops.iter().enumerate() {
        match op.kind {
            OpcodeKind::FixBadPixelsConstant { .. } => {
                if i > 0 && ops[i - 1].kind == op.kind {
                    return None;
                }
                total += REACH;
            }
            OpcodeKind::FixBadPixelsList { .. } => total += REACH,
            _ => {}
        }
    }
    Some(total)
}

/// A rectangle of a stage image held in memory (one sample per pixel).
#[derive(Clone)]
struct Grid<T> {
    data: Vec<T>,
    top: usize,
    left: usize,
    width: usize,
}

impl<T: Copy> Grid<T> {
    #[inline]
    fn get(&self, r: usize, c: usize) -> T {
        self.data[(r - self.top) * self.width + (c - self.left)]
    }
}

/// `range` grown by `by` on both sides, clipped to `0..n`.
fn grown(range: &Range<usize>, by: usize, n: usize) -> Range<usize> {
    range.start.saturating_sub(by)..range.end.saturating_add(by).min(n)
}

/// The frame the bands are cut from: the image, its opcodes and the stages run whole.
struct Frame<'a> {
    img: &'a RawImage,
    p: &'a Prepared,
    sites: &'a CfaSites,
    bayer: Bayer,
    kernel: RowKernel,
    /// Active area size and origin in the stored image.
    aw: usize,
    ah: usize,
    top: usize,
    left: usize,
    reach1: Option<usize>,
    reach2: Option<usize>,
    /// Stage 1 of the whole stored image, when OpcodeList1 runs whole.
    s1_whole: Option<Vec<u16>>,
    /// Stage 2 of the whole active area, when OpcodeList2 runs whole.
    s2_whole: Option<Grid<f32>>,
    /// The neutral (multiplied in for OpcodeList3) and its inverse (divided out after).
    nf: [f32; 3],
    inv_n: [f32; 3],
}

impl<'a> Frame<'a> {
    fn new(
        img: &'a RawImage,
        p: &'a Prepared,
        sites: &'a CfaSites,
        n: [f64; 3],
        kernel: RowKernel,
    ) -> Result<Self> {
        let bayer = img.bayer()?;
        let (aw, ah, top, left) = checked_active(img)?;
        let (l1, l2) = (p.list(ListId::List1), p.list(ListId::List2));
        let (sw, sh) = (img.width, img.height);
        // A list whose margin would cover most of the image anyway runs once, whole.
        let reach1 = reach(l1).filter(|&r| 4 * r < sh);
        let reach2 = reach(l2).filter(|&r| 4 * r < ah);
        let s1_whole = (!l1.is_empty() && reach1.is_none())
            .then(|| stage1(l1, &img.data, (0, 0, sw, sh), (sw, sh)));
        let mut f = Frame {
            img,
            p,
            sites,
            bayer,
            kernel,
            aw,
            ah,
            top,
            left,
            reach1,
            reach2,
            s1_whole,
            s2_whole: None,
            nf: n.map(|v| v as f32),
            inv_n: n.map(|v| (1.0 / v) as f32),
        };
        if !l2.is_empty() && reach2.is_none() {
            f.s2_whole = Some(f.stage2_of(0..ah, 0..aw, true)?);
        }
        Ok(f)
    }

    /// The stage-1 samples of the stored rectangle `rows x cols` (and its list's margin).
    fn stage1_window(&self, rows: Range<usize>, cols: Range<usize>) -> Result<Grid<u16>> {
        let img = self.img;
        let (sw, sh) = (img.width, img.height);
        let r = self.reach1.unwrap_or(0);
        let (gr, gc) = (grown(&rows, r, sh), grown(&cols, r, sw));
        let (gw, gh) = (gc.len(), gr.len());
        let mut f = try_filled(0.0f32, gw * gh, "a window of the stored image")?;
        for (i, row) in f.chunks_exact_mut(gw.max(1)).enumerate() {
            let src = &img.data[(gr.start + i) * sw + gc.start..][..gw];
            for (o, &x) in row.iter_mut().zip(src) {
                *o = x as f32;
            }
        }
        let mut reg = Region {
            data: &mut f,
            top: gr.start,
            left: gc.start,
            width: gw,
            height: gh,
            planes: 1,
            extent: StageRect::of_size(sw, sh),
            range: 65535.0,
        };
        apply_region_seq(self.p.list(ListId::List1), &mut reg);
        Ok(Grid {
            data: f.iter().map(|&v| pin(v, 65535.0).round() as u16).collect(),
            top: gr.start,
            left: gc.start,
            width: gw,
        })
    }

    /// The stage-2 samples (normalized, pinned, OpcodeList2 applied) of the active-area
    /// rectangle `rows x cols` grown by the list's margin; `par`: in parallel over rows.
    fn stage2_of(&self, rows: Range<usize>, cols: Range<usize>, par: bool) -> Result<Grid<f32>> {
        let r = self.reach2.unwrap_or(self.aw.max(self.ah));
        let (gr, gc) = (grown(&rows, r, self.ah), grown(&cols, r, self.aw));
        let (gw, gh) = (gc.len(), gr.len());
        let (top, left) = (self.top, self.left);
        let l1 = self.p.list(ListId::List1);
        let window;
        // Stage-1 samples: stored values, the whole stage 1, or a window of it.
        let (s1, s1_top, s1_left, s1_w): (&[u16], usize, usize, usize) =
            match (&self.s1_whole, l1.is_empty()) {
                (_, true) => (&self.img.data, 0, 0, self.img.width),
                (Some(w), false) => (w, 0, 0, self.img.width),
                (None, false) => {
                    window = self.stage1_window(
                        gr.start + top..gr.end + top,
                        gc.start + left..gc.end + left,
                    )?;
                    (&window.data, window.top, window.left, window.width)
                }
            };
        let mut data = try_filled(0.0f32, gw * gh, "a normalized CFA window")?;
        let sites = self.sites;
        let fill = |i: usize, row: &mut [f32]| {
            let r = gr.start + i;
            let src = &s1[(r + top - s1_top) * s1_w + (gc.start + left - s1_left)..][..gw];
            for (k, (o, &x)) in row.iter_mut().zip(src).enumerate() {
                *o = sites.stage2(x, r, gc.start + k);
            }
        };
        if par {
            data.par_chunks_mut(gw.max(1))
                .enumerate()
                .for_each(|(i, row)| fill(i, row));
        } else {
            data.chunks_mut(gw.max(1))
                .enumerate()
                .for_each(|(i, row)| fill(i, row));
        }
        let mut reg = Region {
            data: &mut data,
            top: gr.start,
            left: gc.start,
            width: gw,
            height: gh,
            planes: 1,
            extent: StageRect::of_size(self.aw, self.ah),
            range: 1.0,
        };
        let l2 = self.p.list(ListId::List2);
        if par {
            apply_region(l2, &mut reg);
        } else {
            apply_region_seq(l2, &mut reg);
        }
        Ok(Grid {
            data,
            top: gr.start,
            left: gc.start,
            width: gw,
        })
    }

    /// The camera RGB of the active-area rectangle `rows x cols` before OpcodeList3's
    /// pixel-moving opcodes: demosaiced, the neutral multiplied back in and the in-place
    /// opcodes `pre` applied (none of this when OpcodeList3 is empty, as the whole-frame
    /// path).
    fn pre3(&self, rows: Range<usize>, cols: Range<usize>, pre: &[Opcode]) -> Result<Vec<f32>> {
        let (rw, rh) = (cols.len(), rows.len());
        let s2 = match &self.s2_whole {
            Some(w) => Cow::Borrowed(w),
            None => Cow::Owned(self.stage2_of(
                grown(&rows, PAD, self.ah),
                grown(&cols, PAD, self.aw),
                false,
            )?),
        };
        let mut out = try_filled(0.0f32, 3 * rw * rh, "a band of the render")?;
        let (bayer, sites) = (self.bayer, self.sites);
        let site = |r: usize, c: usize| -> f32 { sites.balanced(s2.get(r, c), r, c) };
        let cfa = RowDemosaic {
            width: self.aw,
            height: self.ah,
            bayer,
            kernel: self.kernel,
        };
        demosaic_rect(
            cfa,
            rows.clone(),
            cols.clone(),
            |r, cs, o| {
                for (v, &c) in o.iter_mut().zip(cs) {
                    *v = site(r, c);
                }
            },
            &|_| {},
            |i, px| out[3 * rw * i..][..3 * rw].copy_from_slice(px),
        );
        if self.p.list(ListId::List3).is_empty() {
            return Ok(out);
        }
        let nf = self.nf;
        for px in out.chunks_exact_mut(3) {
            for k in 0..3 {
                px[k] = pin(px[k] * nf[k], 1.0);
            }
        }
        self.list3_in_place(pre, &mut out, rows.start, cols.start, rw);
        Ok(out)
    }

    fn list3_in_place(&self, ops: &[Opcode], data: &mut [f32], top: usize, left: usize, w: usize) {
        if ops.is_empty() || w == 0 {
            return;
        }
        let height = data.len() / (3 * w);
        let mut reg = Region {
            data,
            top,
            left,
            width: w,
            height,
            planes: 3,
            extent: StageRect::of_size(self.aw, self.ah),
            range: 1.0,
        };
        apply_region_seq(ops, &mut reg);
    }

    /// The white balance divided out again (when OpcodeList3 ran), `post`, and the rows
    /// handed to `emit`.
    fn finish(
        &self,
        mut rgb: Vec<f32>,
        w: usize,
        post: &Post,
        emit: &mut dyn FnMut(usize, &mut [f32]),
    ) {
        let list3 = !self.p.list(ListId::List3).is_empty();
        let inv = self.inv_n;
        for (i, row) in rgb.chunks_exact_mut(3 * w.max(1)).enumerate() {
            if list3 {
                for px in row.chunks_exact_mut(3) {
                    for k in 0..3 {
                        px[k] *= inv[k];
                    }
                }
            }
            post(row);
            emit(i, row);
        }
    }
}

/// How [`render`] makes a row: the pre-demosaic step `sites` (normalization, the sample
/// stages), the neutral OpcodeList3 takes out and puts back, the row demosaicer `kernel`,
/// and `post` on every output row.
pub(crate) struct RowRender<'a> {
    /// The normalization and sample stages of the stage-1 samples.
    pub(crate) sites: &'a CfaSites,
    /// The neutral (normalized to green = 1).
    pub(crate) neutral: [f64; 3],
    /// The row demosaicer.
    pub(crate) kernel: RowKernel,
    /// Applied to every output row (e.g. the colour matrix).
    pub(crate) post: &'a Post,
}

/// How [`render`] cuts the work (tests vary it; the renders use [`Tune::default`]).
#[derive(Debug)]
pub(crate) struct Tune<'s> {
    /// Output rows per band, and lines per strip of the image before a warp.
    pub(crate) band: usize,
    /// Lines a warp's window may hold before the whole-image path runs (default
    /// [`warp_window::limit`]).
    pub(crate) limit: Option<usize>,
    /// Receives what the warp window did.
    pub(crate) stats: Option<&'s mut WindowStats>,
}

impl Default for Tune<'_> {
    fn default() -> Self {
        Tune {
            band: crate::isp::render_parts::BAND,
            limit: None,
            stats: None,
        }
    }
}

/// The banded render of `img` with the opcodes `p` (rows made as `rows` says, DefaultCrop
/// and orientation if asked), handed
/// to `run` as [`place`] does; `None` (and `run` not called) when OpcodeList3 has a
/// TrimBounds. The warps of OpcodeList3 read the image before them through a rolling
/// window of strips ([`warp_window::Chain`]).
pub(crate) fn render<R>(
    img: &RawImage,
    p: &Prepared,
    rows: RowRender,
    (crop, orient): (bool, bool),
    tune: Tune,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<Option<R>> {
    let l3 = p.list(ListId::List3);
    if l3
        .iter()
        .any(|o| matches!(o.kind, OpcodeKind::TrimBounds { .. }))
    {
        return Ok(None);
    }
    let at: Vec<usize> = (0..l3.len())
        .filter(|&i| moves_pixels(&l3[i].kind))
        .collect();
    let RowRender {
        sites,
        neutral,
        kernel,
        post,
    } = rows;
    let n = normalize_neutral(neutral)?;
    let f = Frame::new(img, p, sites, n, kernel)?;
    let dims = (f.aw, f.ah);
    let band = tune.band.max(1);
    let Some(&first) = at.first() else {
        let rect =
            |rows: Range<usize>, cols: Range<usize>, emit: &mut dyn FnMut(usize, &mut [f32])| {
                let w = cols.len();
                let rgb = f.pre3(rows, cols, l3)?;
                f.finish(rgb, w, post, emit);
                Ok(())
            };
        return place(&img.meta, dims, crop, orient, band, &rect, run).map(Some);
    };
    let extent = StageRect::of_size(f.aw, f.ah);
    let warps = at
        .iter()
        .map(|&i| {
            Warp::of_opcode(&l3[i].kind, extent, 3)
                .unwrap_or_else(|| Err(Error::invalid("OpcodeList3: not a warp")))
        })
        .collect::<Result<Vec<_>>>()?;
    // The in-place opcodes after warp j: up to the next warp.
    let afters: Vec<&[Opcode]> = at
        .iter()
        .enumerate()
        .map(|(j, &i)| &l3[i + 1..at.get(j + 1).copied().unwrap_or(l3.len())])
        .collect();
    let pre_ops = &l3[..first];
    let pre = |rows: Range<usize>, cols: Range<usize>| f.pre3(rows, cols, pre_ops);
    let after = |j: usize, data: &mut [f32], rows: Range<usize>, cols: Range<usize>| {
        f.list3_in_place(afters[j], data, rows.start, cols.start, cols.len())
    };
    let g = Placement::new(&img.meta, dims, crop, orient, band);
    let axis = if g.turned() { Axis::Cols } else { Axis::Rows };
    let finals: Vec<_> = (0..g.bands()).map(|bi| g.rect(bi)).collect();
    let strips = Strips {
        axis,
        dims,
        lines: band,
        extent,
    };
    let chain = Chain::new(strips, warps, &pre, &after, &finals, tune.limit)?;
    let rect = |rows: Range<usize>, cols: Range<usize>, emit: &mut dyn FnMut(usize, &mut [f32])| {
        let w = cols.len();
        let rgb = chain.render(rows, cols)?;
        f.finish(rgb, w, post, emit);
        Ok(())
    };
    let rect: &RectFn = &rect;
    let out = place(&img.meta, dims, crop, orient, band, rect, run)?;
    if let Some(s) = tune.stats {
        *s = chain.stats();
    }
    Ok(Some(out))
}
