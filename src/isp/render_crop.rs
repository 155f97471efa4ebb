//! The render of a crop ([`super::render::CropSamples::Stored`]): the same pixels as the
//! whole-frame render (before DefaultCrop and orientation), computed from the clean samples of the crop
//! and the `PAD`-sample neighbourhood the demosaicer reads, so a training crop's target
//! costs its own size, not the frame's.
//!
//! Every pixel is computed by the same expressions as the banded whole-frame render: the
//! CFA samples go through the same pre-demosaic step
//! (`CfaSites`, pre_demosaic.rs), demosaiced by `demosaic_rect` over the frame's geometry
//! (mirrored at the frame's edges, never at the crop's) and passed through the colour
//! matrix. The result equals the frame render's region bit for bit.

use super::demosaic::{demosaic_rect, row_kernel, RowDemosaic, RowKernel, PAD};
use super::drive::{drive, Pipe, Walk};
use super::opcodes::pipeline;
use super::pre_demosaic::FillRow;
use super::render_parts::RenderOptions;
use super::rgb::RgbImage;
use crate::error::{Error, Result};
use crate::raw::crop::Crop;
use crate::raw::{RawImage, RawMeta};
use rayon::prelude::*;

/// Samples of margin a crop render needs around the crop (the demosaicer's reach).
pub const CROP_MARGIN: usize = PAD;

/// [`CropSamples::Stored`](super::render::CropSamples::Stored): the render of the
/// active-area rectangle `crop` of `frame` (levels, colour and opcodes from it; a
/// LinearizationTable is ignored: the samples are linear) from `plane`, the samples of the
/// rectangle `outer` (row-major), which must contain `crop` grown by [`CROP_MARGIN`] and
/// cut to the active area ([`Crop::grown`]). Bilinear and MHC only (Menon needs the whole
/// frame). With opcodes that need the whole frame
/// ([`crate::isp::opcodes::Prepared::needs_whole_frame`]: bad pixels, warps, TrimBounds)
/// this is an error: render from [`CropSamples::Frame`](super::render::CropSamples::Frame)
/// (`synth::night` does).
pub(crate) fn stored(
    frame: &RawImage,
    opts: &RenderOptions,
    outer: &Crop,
    plane: &[u16],
    crop: &Crop,
) -> Result<RgbImage> {
    let method = opts.demosaic;
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
    let walk = Stored {
        kernel,
        outer,
        plane,
        crop,
    };
    Ok(drive(frame, opts, walk)?.out)
}

/// The walk of [`stored`]: the crop's rows, from its samples and their margin.
struct Stored<'a> {
    kernel: RowKernel,
    outer: &'a Crop,
    plane: &'a [u16],
    crop: &'a Crop,
}

impl Walk for Stored<'_> {
    type Out = RgbImage;
    const NAME: &'static str = "stored crop";

    fn walk(self, pipe: &Pipe) -> Result<RgbImage> {
        stored_walk(pipe, self)
    }
}

fn stored_walk(pipe: &Pipe, walk: Stored) -> Result<RgbImage> {
    let Stored {
        kernel,
        outer,
        plane,
        crop,
    } = walk;
    let frame = pipe.img;
    let a = frame.active_area();
    let (w, h) = (a.width(), a.height());
    let bayer = frame.bayer()?;
    let r = pipe.rows();
    let post = move |row: &mut [f32]| r.run(row);
    // Before DefaultCrop and orientation: `render_crop` checked that both are off.
    let method = pipe.method();
    let sites = pipe.cfa(false)?;
    if let Some(p) = pipe.opcodes() {
        let stored = pipeline::StoredCrop { outer, plane };
        let n = pipe.neutral();
        return pipeline::render_crop(frame, p, (&sites, n), method, stored, crop, &post);
    }
    let fill = |blacks: &mut Vec<f64>, r: usize, cs: &[usize], out: &mut [f32]| {
        let row = FillRow {
            src: &plane[(r - outer.top) * outer.width..][..outer.width],
            offset: outer.left,
            r,
            w,
            blacks,
        };
        sites.fill(row, cs, out)
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
            let mut blacks = Vec::new();
            let fill = |r: usize, cs: &[usize], out: &mut [f32]| fill(&mut blacks, r, cs, out);
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
