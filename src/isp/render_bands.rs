//! The banded render: the output geometry cut into bands (`place`: DefaultCrop and
//! orientation, each band asking for the active-area rectangle it shows), the plain path's
//! rectangle renderer (`banded`: normalize, white balance, demosaic, `post`), and the
//! band-wise consumer of the render (`bands_with`, behind
//! [`render_bands`](super::render::render_bands)) that `synth` and `render` write their
//! targets from: the bands executions of the pipeline. Files with opcodes take
//! `super::opcodes::banded`'s rectangle renderer through the same `place`.

use super::color::normalize_neutral;
use super::demosaic::{demosaic_rect, row_kernel, Post, RowDemosaic, RowKernel};
use super::opcodes::{self, banded::Tune};
use super::place::{place, BandBody};
use super::render_parts::{Bands, BAND};
use super::stages::Plan;
use crate::error::{Error, Result};
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::RawImage;

/// How [`banded`] makes a row: normalization, white balance by `neutral`, the row
/// demosaicer `kernel`, and `post` on every output row.
pub(crate) struct PlainRows<'a> {
    pub(crate) norm: Normalizer,
    pub(crate) neutral: [f64; 3],
    pub(crate) kernel: RowKernel,
    pub(crate) post: &'a Post,
}

/// The plain path's banded render (no opcodes): its rectangle renderer (normalize, white
/// balance, demosaic, `post`), placed by [`place`] in bands of `band` output rows.
pub(crate) fn banded<R>(
    img: &RawImage,
    rows: PlainRows,
    (crop, orient): (bool, bool),
    band: usize,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<R> {
    let PlainRows {
        norm,
        neutral,
        kernel,
        post,
    } = rows;
    let bayer = img.bayer()?;
    let n = normalize_neutral(neutral)?;
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
    place(&img.meta, (w, h), crop, orient, band, &rect, run)
}

/// [`render_bands`](super::render::render_bands) of a CFA image: `None` when the
/// demosaicer is not banded (Menon) or OpcodeList3 has a TrimBounds.
pub(crate) fn bands_with<T, S, F>(plan: &Plan, start: S, f: F) -> Result<Option<Bands<T>>>
where
    T: Send,
    S: FnOnce(usize, usize) -> Result<()>,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    let Some(kernel) = row_kernel(plan.method()) else {
        return Ok(None);
    };
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
    banded_any(plan, kernel, Tune::default(), run)
}

/// The banded render of `plan` with the row demosaicer `kernel` (the plan's), bands of
/// `tune.band` rows handed to `run` as [`place`] does: the opcode path
/// ([`opcodes::banded`]) when opcode lists apply (`None` when they cannot be banded: a
/// TrimBounds), else the plain one ([`banded`]).
pub(crate) fn banded_any<R>(
    plan: &Plan,
    kernel: RowKernel,
    tune: Tune,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<Option<R>> {
    plan.demosaic();
    let colour = plan.colour();
    let post = move |row: &mut [f32]| colour.row(row);
    let ends = plan.geometry();
    let n = plan.neutral()?;
    let norm = plan.normalizer()?;
    match plan.opcodes() {
        Some(p) => {
            let rows = opcodes::banded::RowRender {
                norm,
                neutral: n,
                kernel,
                post: &post,
            };
            opcodes::banded::render(plan.img, p, rows, ends, tune, run)
        }
        None => {
            let rows = PlainRows {
                norm,
                neutral: n,
                kernel,
                post: &post,
            };
            banded(plan.img, rows, ends, tune.band, run).map(Some)
        }
    }
}
