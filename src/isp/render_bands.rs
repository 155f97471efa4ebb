//! The banded render: the output geometry cut into bands (`place`: DefaultCrop and
//! orientation, each band asking for the active-area rectangle it shows), the plain path's
//! rectangle renderer (`banded`: normalize, white balance, demosaic, `post`), and the
//! band-wise consumers of the render ([`render_linear_bands_sized`],
//! [`render_input_bands_sized`]) that `synth` and `render` write their targets from. Files
//! with opcodes take `super::opcodes::banded`'s rectangle renderer through the same
//! `place`.

use super::color::normalize_neutral;
use super::demosaic::{demosaic_rect, row_kernel, Post, RowDemosaic, RowKernel};
use super::opcodes;
use super::place::{place, BandBody};
use super::render_parts::{
    clip_row, color_matrix, matrix_row, resolve_neutral, Bands, RenderOptions, BAND,
};
use crate::error::{Error, Result};
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::RawImage;

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
        let cfa = RowDemosaic {
            width: w,
            height: h,
            bayer,
            kernel,
        };
        demosaic_rect(cfa, rows, cols, fill, post, emit);
        Ok(())
    };
    place(&img.meta, (w, h), crop, orient, BAND, &rect, run)
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
/// is some (`None` when its opcodes cannot be banded: a TrimBounds), else
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
        Some(p) => {
            let tune = opcodes::banded::Tune::default();
            let rows = opcodes::banded::RowRender {
                neutral: n,
                kernel,
                post,
            };
            opcodes::banded::render(img, p, rows, (crop, orient), tune, run)
        }
        None => banded(img, n, kernel, post, crop, orient, run).map(Some),
    }
}
