//! The banded render: the output geometry cut into bands ([`place`]: DefaultCrop and
//! orientation, each band asking for the active-area rectangle it shows), the plain path's
//! rectangle renderer ([`banded`]: normalize, white balance, demosaic, `post`), and the
//! band-wise consumers of the render ([`render_linear_bands_sized`],
//! [`render_input_bands_sized`]) that `synth` and `render` write their targets from. Files
//! with opcodes take [`super::opcodes::banded`]'s rectangle renderer through the same
//! [`place`].

use super::color::normalize_neutral;
use super::demosaic::{demosaic_rect, row_kernel, Post, RowKernel};
use super::opcodes;
use super::render::{
    clip_row, color_matrix, default_crop, matrix_row, resolve_neutral, RenderOptions, BAND,
};
use super::RgbImage;
use crate::error::{Error, Result};
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::meta::RawMeta;
use crate::raw::RawImage;
use rayon::prelude::*;

/// The `run` of [`place`] that keeps the whole image: every band rendered in parallel into
/// its place in the output.
pub(crate) fn collect_bands(ow: usize, oh: usize, body: &BandBody) -> Result<RgbImage> {
    collect_bands_of(BAND)(ow, oh, body)
}

/// [`collect_bands`] for bands of `band` rows (the `band` given to [`place`]).
pub(crate) fn collect_bands_of(
    band: usize,
) -> impl Fn(usize, usize, &BandBody) -> Result<RgbImage> {
    move |ow, oh, body| {
        let mut out = RgbImage::try_new(ow, oh)?;
        if ow > 0 {
            out.data
                .par_chunks_mut(3 * ow * band)
                .enumerate()
                .try_for_each(|(bi, rows)| body(bi, rows))?;
        }
        Ok(out)
    }
}

/// Renders the active-area rectangle `rows x cols` of a render, calling `emit(i, rgb)` for
/// each of its rows in order (`3 * cols.len()` samples, the caller's `post` applied). Must
/// not wait for other rayon work (it runs inside [`super::bands::in_order`]).
pub(crate) type RectFn<'a> = dyn Fn(
        std::ops::Range<usize>,
        std::ops::Range<usize>,
        &mut dyn FnMut(usize, &mut [f32]),
    ) -> Result<()>
    + Sync
    + 'a;

/// `body(bi, band)`: renders output rows `[bi * B, bi * B + band.len() / (3 * ow))` into
/// `band` (interleaved RGB, `ow` pixels per row), `B` the band height given to [`place`]
/// ([`BAND`] but in tests).
pub(crate) type BandBody<'a> = dyn Fn(usize, &mut [f32]) -> Result<()> + Sync + 'a;

/// The set-up of the whole render (`render::render_banded`): the plain path's rectangle
/// renderer (normalize, white balance, demosaic, `post`), placed by [`place`].
pub(crate) fn banded<R>(
    img: &RawImage,
    neutral: [f64; 3],
    kernel: RowKernel,
    post: &Post,
    crop: bool,
    orient: bool,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<R> {
    let bayer = img.bayer()?;
    let n = normalize_neutral(neutral)?;
    let norm = Normalizer::new(img)?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let stride = img.width;
    if w == 0 || h == 0 || (top + h - 1) * stride + left + w > img.data.len() {
        return Err(Error::invalid(
            "the active area is empty or outside the pixel buffer",
        ));
    }
    let inv = [1.0 / n[0], 1.0, 1.0 / n[2]];
    let data = &img.data;
    // CFA sample (r, cs[k]) into out[k]: normalized, white-balanced, clipped. Wide bands
    // take the black levels of the whole row from `Normalizer::black_row` (bit-identical
    // to `black_at`, without two integer divisions per sample); narrow ones (orientations
    // 5-8) ask per sample.
    let site = |x: u16, r: usize, c: usize, black: f64| -> f32 {
        let y = norm.normalize_with_black(x, black) * inv[bayer.color_at(r, c) as usize];
        y.clamp(0.0, 1.0) as f32
    };
    // With a 2x2-periodic black level every stored value up to white is tabulated per
    // 2x2 position (same expression, same bits).
    let table = SiteTable::new(&norm, |r, c, x| site(x, r, c, norm.black_at(r, c)));
    let fill = |blacks: &mut Vec<f64>, r: usize, cs: &[usize], out: &mut [f32]| {
        let src = &data[(r + top) * stride + left..][..w];
        if let Some(t) = &table {
            let (t0, t1) = t.row(r);
            for (o, &c) in out.iter_mut().zip(cs) {
                let x = src[c];
                let tab = if c & 1 == 0 { t0 } else { t1 };
                *o = match tab.get(x as usize) {
                    Some(&v) => v,
                    None => site(x, r, c, norm.black_at(r, c)),
                };
            }
        } else if 2 * cs.len() >= w {
            blacks.resize(w, 0.0);
            norm.black_row(r, blacks);
            for (o, &c) in out.iter_mut().zip(cs) {
                let y = norm.normalize_with_black(src[c], blacks[c])
                    * inv[bayer.color_at(r, c) as usize];
                *o = y.clamp(0.0, 1.0) as f32;
            }
        } else {
            for (o, &c) in out.iter_mut().zip(cs) {
                let y = norm.normalize(src[c], r, c) * inv[bayer.color_at(r, c) as usize];
                *o = y.clamp(0.0, 1.0) as f32;
            }
        }
    };
    let rect = |rows: std::ops::Range<usize>,
                cols: std::ops::Range<usize>,
                emit: &mut dyn FnMut(usize, &mut [f32])| {
        let mut blacks = Vec::new();
        let fill = |r: usize, cs: &[usize], out: &mut [f32]| fill(&mut blacks, r, cs, out);
        demosaic_rect(w, h, bayer, kernel, rows, cols, fill, post, emit);
        Ok(())
    };
    place(&img.meta, (w, h), crop, orient, BAND, &rect, run)
}

/// The output geometry of a banded render of an active area of `w x h`: DefaultCrop (if
/// `crop`) and orientation (if `orient`) of `meta`. Calls `run(ow, oh, body)`, where
/// `body(bi, band)` renders output band `bi` by asking `rect` for the active-area rectangle
/// it shows (the same crop rows for Orientation 1-4, in reverse order for 3 and 4; crop
/// columns for 5-8) and copying each row to its final place (mirrored or transposed as the
/// orientation asks).
pub(crate) fn place<R>(
    meta: &RawMeta,
    (w, h): (usize, usize),
    crop: bool,
    orient: bool,
    band_rows: usize,
    rect: &RectFn,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<R> {
    let (x0, y0, cw, ch) = if crop {
        default_crop(meta, w, h)
    } else {
        (0, 0, w, h)
    };
    let o = if orient && (2..=8).contains(&meta.orientation) {
        meta.orientation
    } else {
        1
    };
    let swap = o >= 5;
    let (ow, oh) = if swap { (ch, cw) } else { (cw, ch) };
    let body = |bi: usize, band: &mut [f32]| -> Result<()> {
        let a0 = bi * band_rows;
        let b0 = a0 + band.len() / (3 * ow).max(1);
        if !swap {
            // Output rows [a0, b0) are crop rows [s0, s1), in reverse order for 3 and 4,
            // mirrored left-right for 2 and 3.
            let (s0, s1) = if o <= 2 { (a0, b0) } else { (ch - b0, ch - a0) };
            let flip = o == 2 || o == 3;
            rect(y0 + s0..y0 + s1, x0..x0 + cw, &mut |i, rgb| {
                let yc = s0 + i;
                let yo = if o <= 2 { yc } else { ch - 1 - yc };
                let dst = &mut band[3 * ow * (yo - a0)..][..3 * ow];
                if flip {
                    for (d, p) in dst.chunks_exact_mut(3).zip(rgb.chunks_exact(3).rev()) {
                        d.copy_from_slice(p);
                    }
                } else {
                    dst.copy_from_slice(rgb);
                }
            })
        } else {
            // Output rows [a0, b0) are crop columns [s0, s1) (reversed for 7 and 8);
            // crop row y becomes output column y (5, 8) or ch - 1 - y (6, 7).
            let (s0, s1) = if o <= 6 { (a0, b0) } else { (cw - b0, cw - a0) };
            rect(y0..y0 + ch, x0 + s0..x0 + s1, &mut |y, rgb| {
                let xo = if o == 5 || o == 8 { y } else { ch - 1 - y };
                for (k, p) in rgb.chunks_exact(3).enumerate() {
                    let x = s0 + k;
                    let yo = if o <= 6 { x } else { cw - 1 - x };
                    let d = 3 * ((yo - a0) * ow + xo);
                    band[d..d + 3].copy_from_slice(p);
                }
            })
        }
    };
    run(ow, oh, &body)
}

/// Band-wise consumer of [`render_linear`](super::render::render_linear): the render is
/// made band by band ([`BAND`] output rows each, in parallel, into a per-thread buffer) and
/// `f(first_row, width, rows)` is called on each band (`rows` is interleaved linear RGB,
/// `width` pixels per row); the results come back in band order with the output size
/// ([`Bands`]). The rows are exactly those of
/// [`render_linear`](super::render::render_linear)'s image (same code), so consumers that
/// encode them (EXR blocks, 8-bit PNG samples) write the same bytes as from the whole
/// image, without holding it. `None` when the demosaicer is not banded (Menon): use
/// [`render_linear`](super::render::render_linear). See [`render_linear_bands_sized`] for
/// the order in which bands are made.
pub fn render_linear_bands<T, F>(
    img: &RawImage,
    opts: &RenderOptions,
    f: F,
) -> Result<Option<Bands<T>>>
where
    T: Send,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    render_linear_bands_sized(img, opts, |_, _| Ok(()), f)
}

/// [`render_linear_bands`] that first calls `start(width, height)` with the output size,
/// once, before any band (not at all when it returns `None`), e.g. to open a file that `f`
/// writes the bands into.
///
/// Bands are made nearly in order: each thread takes the lowest band not yet taken, and no
/// band is started more than 2 x threads + 1 bands beyond the lowest unfinished one, so a
/// consumer that writes the bands in order (holding those that come early) holds a few
/// bands at most. `f` must not wait for other rayon work (no parallel iterator or `join`
/// inside): other threads may be waiting for its band.
pub fn render_linear_bands_sized<T, S, F>(
    img: &RawImage,
    opts: &RenderOptions,
    start: S,
    f: F,
) -> Result<Option<Bands<T>>>
where
    T: Send,
    S: FnOnce(usize, usize) -> Result<()>,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    if img.meta.linear_raw.is_some() {
        return super::render_linear_raw::render_linear_bands(img, opts, start, f);
    }
    bands_with(img, opts, false, start, f)
}

/// [`render_linear_bands_sized`] of the network input
/// ([`render_input_opts`](super::render::render_input_opts): camera RGB clipped to [0, 1],
/// no colour matrix); `None` also for a LinearRaw image (render it whole).
pub fn render_input_bands_sized<T, S, F>(
    img: &RawImage,
    opts: &RenderOptions,
    start: S,
    f: F,
) -> Result<Option<Bands<T>>>
where
    T: Send,
    S: FnOnce(usize, usize) -> Result<()>,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    if img.meta.linear_raw.is_some() {
        return Ok(None);
    }
    bands_with(img, opts, true, start, f)
}

fn bands_with<T, S, F>(
    img: &RawImage,
    opts: &RenderOptions,
    camera: bool,
    start: S,
    f: F,
) -> Result<Option<Bands<T>>>
where
    T: Send,
    S: FnOnce(usize, usize) -> Result<()>,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    let Some(kernel) = row_kernel(opts.demosaic) else {
        return Ok(None);
    };
    let p = opcodes::active_image(img, opts.opcodes)?;
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let matrix = move |row: &mut [f32]| matrix_row(row, &mf);
    let post: &Post = if camera { &clip_row } else { &matrix };
    let run = |ow: usize, oh: usize, body: &BandBody| {
        start(ow, oh)?;
        let nb = oh.div_ceil(BAND);
        let bands = super::bands::in_order(nb, |bi, scratch: &mut Vec<f32>| {
            let rows = BAND.min(oh - bi * BAND);
            scratch.clear();
            scratch.resize(3 * ow * rows, 0.0);
            body(bi, scratch)?;
            f(bi * BAND, ow, scratch)
        })?;
        Ok(Bands {
            width: ow,
            height: oh,
            bands,
        })
    };
    banded_any(
        img,
        p.as_ref(),
        n,
        kernel,
        post,
        (opts.crop, opts.orient),
        run,
    )
}

/// The banded render of `img` with `post`: the opcode path ([`opcodes::banded`]) when `p`
/// is some (`None` when its opcodes cannot be banded: several warps, a TrimBounds), else
/// the plain one.
pub(crate) fn banded_any<R>(
    img: &RawImage,
    p: Option<&opcodes::Prepared>,
    n: [f64; 3],
    kernel: RowKernel,
    post: &Post,
    (crop, orient): (bool, bool),
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<Option<R>> {
    match p {
        Some(p) => opcodes::banded::render(img, p, n, kernel, post, (crop, orient), BAND, run),
        None => banded(img, n, kernel, post, crop, orient, run).map(Some),
    }
}

/// What [`render_linear_bands`] returns: the output size and one result per band, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Bands<T> {
    /// Output width.
    pub width: usize,
    /// Output height.
    pub height: usize,
    /// The consumer's result for each band of [`BAND`] rows, top to bottom.
    pub bands: Vec<T>,
}
