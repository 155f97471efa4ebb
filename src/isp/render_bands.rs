//! The banded render: the output geometry cut into bands (`place`: DefaultCrop and
//! orientation, each band asking for the active-area rectangle it shows), the plain path's
//! rectangle renderer (`banded`: the pre-demosaic step, demosaic, `post`), and the
//! band-wise consumer of the render (the walk `Consumer`, behind
//! [`render_bands`](super::render::render_bands)) that `synth` and `render` write their
//! targets from: the bands executions of the pipeline. Files with opcodes take
//! `super::opcodes::banded`'s rectangle renderer through the same `place`.

use super::demosaic::{demosaic_rect, row_kernel, Post, RowDemosaic, RowKernel};
use super::drive::{Pipe, Walk};
use super::opcodes::{self, banded::Tune};
use super::place::{place, BandBody};
use super::pre_demosaic::{CfaSites, FillRow};
use super::render_parts::{Bands, BAND};
use crate::error::{Error, Result};
use crate::raw::RawImage;

/// How [`banded`] makes a row: the pre-demosaic step `sites`, the row demosaicer
/// `kernel`, and `post` on every output row.
pub(crate) struct PlainRows<'a> {
    pub(crate) sites: &'a CfaSites,
    pub(crate) kernel: RowKernel,
    pub(crate) post: &'a Post,
}

/// The plain path's banded render (no opcodes): its rectangle renderer (the pre-demosaic
/// step, demosaic, `post`), placed by [`place`] in bands of `band` output rows.
pub(crate) fn banded<R>(
    img: &RawImage,
    rows: PlainRows,
    (crop, orient): (bool, bool),
    band: usize,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<R> {
    let PlainRows {
        sites,
        kernel,
        post,
    } = rows;
    let bayer = img.bayer()?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let stride = img.width;
    if w == 0 || h == 0 || (top + h - 1) * stride + left + w > img.data.len() {
        return Err(Error::invalid(
            "the active area is empty or outside the pixel buffer",
        ));
    }
    let data = &img.data;
    let rect = |rows: std::ops::Range<usize>,
                cols: std::ops::Range<usize>,
                emit: &mut dyn FnMut(usize, &mut [f32])| {
        let mut blacks = Vec::new();
        let fill = |r: usize, cs: &[usize], out: &mut [f32]| {
            let row = FillRow {
                src: &data[(r + top) * stride + left..][..w],
                offset: 0,
                r,
                w,
                blacks: &mut blacks,
            };
            sites.fill(row, cs, out)
        };
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

/// [`render_bands`](super::render::render_bands): `start(width, height)`, then `f` on
/// each band of [`BAND`] rows, in band order; `None` when the demosaicer is not banded
/// (Menon) or OpcodeList3 has a TrimBounds. A LinearRaw image is rendered whole and handed
/// out in bands.
pub(crate) struct Consumer<S, F> {
    pub(crate) start: S,
    pub(crate) f: F,
}

impl<T, S, F> Walk for Consumer<S, F>
where
    T: Send,
    S: FnOnce(usize, usize) -> Result<()>,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    type Out = Option<Bands<T>>;
    const NAME: &'static str = "band-wise";

    fn walk(self, pipe: &Pipe) -> Result<Option<Bands<T>>> {
        let Consumer { start, f } = self;
        if pipe.img.meta.linear_raw.is_some() {
            return super::render_linear_raw::bands(pipe, start, f).map(Some);
        }
        let Some(kernel) = row_kernel(pipe.method()) else {
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
        banded_any(pipe, kernel, Tune::default(), run)
    }
}

/// The banded render of `pipe` with the row demosaicer `kernel` (the pipe's), bands of
/// `tune.band` rows handed to `run` as [`place`] does: the opcode path
/// ([`opcodes::banded`]) when opcode lists apply (`None` when they cannot be banded: a
/// TrimBounds), else the plain one ([`banded`]).
pub(crate) fn banded_any<R>(
    pipe: &Pipe,
    kernel: RowKernel,
    tune: Tune,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<Option<R>> {
    let r = pipe.rows();
    let post = move |row: &mut [f32]| r.run(row);
    let ends = pipe.geometry();
    let sites = pipe.cfa(true)?;
    match pipe.opcodes() {
        Some(p) => {
            let rows = opcodes::banded::RowRender {
                sites: &sites,
                neutral: pipe.neutral(),
                kernel,
                post: &post,
            };
            opcodes::banded::render(pipe.img, p, rows, ends, tune, run)
        }
        None => {
            let rows = PlainRows {
                sites: &sites,
                kernel,
                post: &post,
            };
            banded(pipe.img, rows, ends, tune.band, run).map(Some)
        }
    }
}
