//! The output geometry of a banded render: the output (after DefaultCrop and orientation)
//! cut into bands, each band asking a rectangle renderer ([`RectFn`]) for the active-area
//! rectangle it shows and copying its rows to their final place. Shared by the plain
//! banded render ([`super::render_bands`]) and the opcode render
//! ([`super::opcodes::banded`]).

use super::geometry::default_crop;
use super::render_parts::BAND;
use super::rgb::RgbImage;
use crate::error::Result;
use crate::raw::meta::RawMeta;
use rayon::prelude::*;
use std::ops::Range;

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

/// The output geometry of a banded render: DefaultCrop and orientation, the output size and
/// the active-area rectangle each band of output rows shows.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Placement {
    x0: usize,
    y0: usize,
    cw: usize,
    ch: usize,
    o: u16,
    /// Output width and height.
    pub(crate) ow: usize,
    pub(crate) oh: usize,
    band_rows: usize,
}

impl Placement {
    /// The geometry of an active area of `w x h`: DefaultCrop (if `crop`) and orientation
    /// (if `orient`) of `meta`, bands of `band_rows` output rows.
    pub(crate) fn new(
        meta: &RawMeta,
        (w, h): (usize, usize),
        crop: bool,
        orient: bool,
        band_rows: usize,
    ) -> Placement {
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
        let (ow, oh) = if o >= 5 { (ch, cw) } else { (cw, ch) };
        Placement {
            x0,
            y0,
            cw,
            ch,
            o,
            ow,
            oh,
            band_rows: band_rows.max(1),
        }
    }

    /// True when the orientation transposes (5-8): bands are columns of the active area.
    pub(crate) fn turned(&self) -> bool {
        self.o >= 5
    }

    /// The number of bands.
    pub(crate) fn bands(&self) -> usize {
        self.oh.div_ceil(self.band_rows)
    }

    /// Output rows `[a0, b0)` of band `bi`.
    fn band_span(&self, bi: usize) -> (usize, usize) {
        let a0 = bi * self.band_rows;
        (a0, (a0 + self.band_rows).min(self.oh))
    }

    /// The active-area rectangle (rows, columns) band `bi` shows: crop rows for
    /// Orientation 1-4 (from the bottom for 3 and 4), crop columns for 5-8 (from the right
    /// for 7 and 8).
    pub(crate) fn rect(&self, bi: usize) -> (Range<usize>, Range<usize>) {
        let (a0, b0) = self.band_span(bi);
        let (x0, y0, cw, ch, o) = (self.x0, self.y0, self.cw, self.ch, self.o);
        if o < 5 {
            let (s0, s1) = if o <= 2 { (a0, b0) } else { (ch - b0, ch - a0) };
            (y0 + s0..y0 + s1, x0..x0 + cw)
        } else {
            let (s0, s1) = if o <= 6 { (a0, b0) } else { (cw - b0, cw - a0) };
            (y0..y0 + ch, x0 + s0..x0 + s1)
        }
    }
}

/// The output geometry of a banded render of an active area of `w x h`: DefaultCrop (if
/// `crop`) and orientation (if `orient`) of `meta`. Calls `run(ow, oh, body)`, where
/// `body(bi, band)` renders output band `bi` by asking `rect` for the active-area rectangle
/// it shows ([`Placement::rect`]: the same crop rows for Orientation 1-4, in reverse order
/// for 3 and 4; crop columns for 5-8) and copying each row to its final place (mirrored or
/// transposed as the orientation asks).
pub(crate) fn place<R>(
    meta: &RawMeta,
    dims: (usize, usize),
    crop: bool,
    orient: bool,
    band_rows: usize,
    rect: &RectFn,
    run: impl FnOnce(usize, usize, &BandBody) -> Result<R>,
) -> Result<R> {
    let g = Placement::new(meta, dims, crop, orient, band_rows);
    let (cw, ch, o, ow) = (g.cw, g.ch, g.o, g.ow);
    let body = |bi: usize, band: &mut [f32]| -> Result<()> {
        let a0 = bi * g.band_rows;
        let (rows, cols) = g.rect(bi);
        if o < 5 {
            // Output rows [a0, b0) are crop rows [s0, s1), in reverse order for 3 and 4,
            // mirrored left-right for 2 and 3.
            let s0 = rows.start - g.y0;
            let flip = o == 2 || o == 3;
            rect(rows, cols, &mut |i, rgb| {
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
            let s0 = cols.start - g.x0;
            rect(rows, cols, &mut |y, rgb| {
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
    run(ow, g.oh, &body)
}
