//! The linear render of a crop: the same pixels as [`super::render_linear`]'s whole-frame
//! render (before DefaultCrop and orientation), computed from the clean samples of the crop
//! and the `PAD`-sample neighbourhood the demosaicer reads, so a training crop's target
//! costs its own size, not the frame's.
//!
//! Every pixel is computed by the same expressions as the banded whole-frame render: the
//! CFA samples are normalized and white-balanced like there (tabulated per 2x2 position
//! when the black level allows), demosaiced by `demosaic_rect` over the frame's geometry
//! (mirrored at the frame's edges, never at the crop's) and passed through the colour
//! matrix. The result equals the frame render's region bit for bit.

use super::color::normalize_neutral;
use super::demosaic::{demosaic_rect, row_kernel, Demosaic, RowDemosaic, PAD};
use super::opcodes::{self, pipeline, OpcodeMode};
use super::render_parts::{color_matrix, matrix_row, resolve_neutral};
use super::RgbImage;
use crate::error::{Error, Result};
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::crop::Crop;
use crate::raw::{RawImage, RawMeta};
use rayon::prelude::*;

/// Samples of margin a crop render needs around the crop (the demosaicer's reach).
pub const CROP_MARGIN: usize = PAD;

/// Linear sRGB (Rec.709, D65) render of the active-area rectangle `crop` of a frame whose
/// levels and colour metadata are `frame`'s (a LinearizationTable is ignored: the samples
/// are linear), white-balanced by `neutral` (None = the frame's AsShotNeutral), from
/// `plane`, the samples of the rectangle `outer` (row-major), which must contain `crop`
/// grown by [`CROP_MARGIN`] and cut to the active area ([`Crop::grown`]). No DefaultCrop,
/// no orientation: the result is `crop.width x crop.height`, aligned with the crop's CFA
/// samples. Bilinear and MHC only (Menon needs the whole frame). The frame's opcode lists
/// are applied ([`render_linear_crop_with`] chooses).
pub fn render_linear_crop(
    frame: &RawImage,
    neutral: Option<[f64; 3]>,
    method: Demosaic,
    outer: &Crop,
    plane: &[u16],
    crop: &Crop,
) -> Result<RgbImage> {
    render_linear_crop_with(
        frame,
        neutral,
        method,
        outer,
        plane,
        crop,
        OpcodeMode::Apply,
    )
}

/// [`render_linear_crop`] with the frame's opcode lists applied or ignored. With opcodes
/// that need the whole frame ([`crate::isp::opcodes::Prepared::needs_whole_frame`]: bad
/// pixels, warps, TrimBounds) this is an error: render the frame and cut the region
/// (`synth::night` does).
pub fn render_linear_crop_with(
    frame: &RawImage,
    neutral: Option<[f64; 3]>,
    method: Demosaic,
    outer: &Crop,
    plane: &[u16],
    crop: &Crop,
    mode: OpcodeMode,
) -> Result<RgbImage> {
    let Some(kernel) = row_kernel(method) else {
        return Err(Error::unsupported(format!(
            "a crop render needs a row demosaicer (bilinear or mhc), not {}",
            method.name()
        )));
    };
    let a = frame.active_area();
    let (w, h) = (a.width(), a.height());
    crop.check(w, h)?;
    let need = crop.grown(CROP_MARGIN, w, h);
    if need.top < outer.top
        || need.left < outer.left
        || need.top + need.height > outer.top + outer.height
        || need.left + need.width > outer.left + outer.width
        || plane.len() != outer.width * outer.height
    {
        return Err(Error::invalid(
            "the crop's sample plane does not cover the crop and its margin",
        ));
    }
    let bayer = frame.bayer()?;
    let n = normalize_neutral(resolve_neutral(&frame.meta, neutral)?)?;
    let m = color_matrix(&frame.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let post = move |row: &mut [f32]| matrix_row(row, &mf);
    if let Some(p) = opcodes::active_image(frame, mode)? {
        let stored = pipeline::StoredCrop { outer, plane };
        return pipeline::render_crop(frame, &p, n, method, stored, crop, &post);
    }
    let norm = Normalizer::new(frame)?.without_linearization();
    let inv = [1.0 / n[0], 1.0, 1.0 / n[2]];
    let site = |x: u16, r: usize, c: usize, black: f64| -> f32 {
        let y = norm.normalize_with_black(x, black) * inv[bayer.color_at(r, c) as usize];
        y.clamp(0.0, 1.0) as f32
    };
    let table = SiteTable::new(&norm, |r, c, x| site(x, r, c, norm.black_at(r, c)));
    let fill = |r: usize, cs: &[usize], out: &mut [f32]| {
        let src = &plane[(r - outer.top) * outer.width..][..outer.width];
        for (o, &c) in out.iter_mut().zip(cs) {
            let x = src[c - outer.left];
            *o = match table.as_ref().and_then(|t| t.get(r, c, x)) {
                Some(v) => v,
                None => site(x, r, c, norm.black_at(r, c)),
            };
        }
    };
    let mut out = RgbImage::try_new(crop.width, crop.height)?;
    const BAND: usize = 32;
    out.data
        .par_chunks_mut(3 * crop.width * BAND)
        .enumerate()
        .for_each(|(bi, band)| {
            let r0 = crop.top + bi * BAND;
            let rows = r0..r0 + band.len() / (3 * crop.width);
            let cfa = RowDemosaic {
                width: w,
                height: h,
                bayer,
                kernel,
            };
            demosaic_rect(cfa, rows, crop.cols(), fill, &post, |i, rgb| {
                band[3 * crop.width * i..][..3 * crop.width].copy_from_slice(rgb)
            });
        });
    Ok(out)
}

/// Where the target of `crop` sits in the whole-frame target (DefaultCrop applied, before
/// orientation): `(row, column)` of its top-left pixel, `None` unless the crop lies inside
/// the DefaultCrop (then the crop's target equals that region of the frame's).
pub fn target_origin(meta: &RawMeta, aw: usize, ah: usize, crop: &Crop) -> Option<(usize, usize)> {
    let (x0, y0, cw, ch) = super::geometry::default_crop(meta, aw, ah);
    let inside = crop.left >= x0
        && crop.top >= y0
        && crop.left + crop.width <= x0 + cw
        && crop.top + crop.height <= y0 + ch;
    inside.then(|| (crop.top - y0, crop.left - x0))
}
