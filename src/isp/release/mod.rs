//! The authors' release ISP (SamsungLabs/day-to-night, the target render of its
//! `prepare_data.py`), reproduced: `day2night render --isp release` and the Python
//! package's `isp="release"` (docs/isp.md, "The release's ISP").
//!
//! Stages, each in its own module, in the release's arithmetic (float32 where NumPy keeps
//! float32, float64 elsewhere):
//! 1. [`meta`]: the tags as the release reads them, with its fallbacks;
//! 2. [`mosaic`]: the visible raw as LibRaw gives it (active area, LinearizationTable
//!    applied), the release's second crop by ActiveArea, black/white normalization, white
//!    balance by the neutral, 14-bit codes;
//! 3. [`menon`]: Menon 2007 as the `colour-demosaicing` package computes it;
//! 4. [`colour`]: camera -> XYZ by the release's CCT-mixed matrices, XYZ -> sRGB, clipped;
//! 5. [`finish`]: its orientation, gamma 1/2.2, the "simple s-curve", x 255 truncated.
//!
//! Stages 3 and 4 run in bands of [`BAND_ROWS`] rows (with [`menon::HALO`] rows of context on
//! each side, the same values as over the whole image), so a render holds the raw, its
//! 14-bit codes and the output, not float64 planes of the whole image (docs/limits.md).
//! Before any pixel work the white balance is resolved as the project's ISP resolves it
//! ([`ReleaseMeta::of`]); a render that comes out constant warns as the project's does.
//!
//! The DNG opcode lists and DefaultCrop are not used (the release's target stages skip
//! them); nothing here touches the project's own ISP.

pub mod colour;
pub mod conflicts;
pub mod finish;
pub mod menon;
pub mod meta;
pub mod mosaic;

pub use conflicts::{conflicts, Conflict, Isp};
pub use finish::{Rgb, Rgb64};
pub use meta::ReleaseMeta;

use crate::diagnostics::Warning;
use crate::error::Result;
use crate::isp::flat::FlatCheck;
use crate::isp::rgb::RgbImage;
use crate::raw::RawImage;
use rayon::prelude::*;

/// Output rows per band: the demosaic and colour stages hold a band of this many rows plus
/// [`menon::HALO`] rows on each side (about 14 float64 planes of it), never the whole image.
pub const BAND_ROWS: usize = 128;

/// A release render and what it warns about (a constant result, as the project's own
/// render: `warning[render-constant]`, docs/warnings.md).
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered<T> {
    /// The image.
    pub image: Rgb<T>,
    /// The warnings, in order.
    pub warnings: Vec<Warning>,
}

/// The release's linear sRGB (its "srgb" stage: float64 in [0, 1], before its orientation)
/// of the image window of `raw`, band by band: `sink(first_row, rows)` gets each band of
/// [`BAND_ROWS`] rows (interleaved RGB), top to bottom.
fn linear_bands(
    raw: &RawImage,
    meta: &ReleaseMeta,
    mut sink: impl FnMut(usize, &[f64]) -> Result<()>,
) -> Result<()> {
    let codes = mosaic::codes(raw, meta)?;
    let (w, h) = (codes.width, codes.height);
    let (cam, _) = colour::camera_to_xyz(meta)?;
    let out = colour::xyz_to_srgb();
    let scale = mosaic::CODE_SCALE as f32;
    for y0 in (0..h).step_by(BAND_ROWS) {
        let rows = y0..(y0 + BAND_ROWS).min(h);
        let mut rgb = menon::demosaic_rows(&codes.data, w, h, meta.cfa, rows);
        rgb.par_chunks_mut(3).for_each(|px| {
            // float64 -> float32, / 16383 in float32, as the release's demosaic stage returns.
            let cam_rgb = [0, 1, 2].map(|c| f64::from(px[c] as f32 / scale));
            px.copy_from_slice(&colour::to_srgb(&cam, &out, cam_rgb));
        });
        sink(y0, &rgb)?;
    }
    Ok(())
}

/// The release's render of `raw` with each linear sample mapped by `f` into a `T` image,
/// turned by its Orientation unless `orient` is false; the constant-result check made on
/// the linear samples (as float32, the project's render checks its own). `neutral` replaces
/// the file's white balance (see [`ReleaseMeta::of`]).
fn render_with<T: Copy + Default + Send>(
    raw: &RawImage,
    neutral: Option<[f64; 3]>,
    orient: bool,
    f: impl Fn(f64) -> T + Sync,
) -> Result<Rendered<T>> {
    let meta = ReleaseMeta::of(raw, neutral)?;
    let (_, _, h, w) = mosaic::window(raw, &meta)?;
    let mut img = Rgb {
        width: w,
        height: h,
        data: crate::limits::try_filled(T::default(), 3 * w * h, "the release's render")?,
    };
    let flat = FlatCheck::new();
    linear_bands(raw, &meta, |y0, rows| {
        let linear: Vec<f32> = rows.par_iter().map(|v| *v as f32).collect();
        flat.rows(&linear);
        let o = &mut img.data[3 * w * y0..][..rows.len()];
        o.par_iter_mut().zip(rows).for_each(|(o, v)| *o = f(*v));
        Ok(())
    })?;
    Ok(Rendered {
        image: img.oriented(if orient { meta.orientation } else { 1 })?,
        warnings: flat.warning("the render").into_iter().collect(),
    })
}

/// The release's linear sRGB image of `raw` (its "srgb" stage, then its orientation unless
/// `orient` is false: before gamma), float64 in [0, 1]. `neutral` replaces the file's
/// white balance for white balance and the colour matrix alike ([`ReleaseMeta::of`]).
pub fn render_linear(raw: &RawImage, neutral: Option<[f64; 3]>, orient: bool) -> Result<Rgb64> {
    Ok(render_with(raw, neutral, orient, |v| v)?.image)
}

/// [`render_linear`] as float32 (the linear EXR and Python's `render(isp="release")`), with
/// its warnings.
pub fn render_f32(
    raw: &RawImage,
    neutral: Option<[f64; 3]>,
    orient: bool,
) -> Result<Rendered<f32>> {
    render_with(raw, neutral, orient, |v| v as f32)
}

/// The release's 8-bit render of `raw`, the bytes of its target PNGs (`orient` false:
/// before its orientation stage), with its warnings.
pub fn render_u8(raw: &RawImage, neutral: Option<[f64; 3]>, orient: bool) -> Result<Rendered<u8>> {
    render_with(raw, neutral, orient, finish::code8)
}

/// The release's image window of `raw` in active-area coordinates, before its orientation:
/// (top, left, height, width).
pub fn window(raw: &RawImage) -> Result<(usize, usize, usize, usize)> {
    mosaic::window(raw, &ReleaseMeta::of(raw, Some([1.0; 3]))?)
}

impl Rgb64 {
    /// The release's 8-bit codes of this linear image (gamma, s-curve, x 255 truncated).
    pub fn to_u8(&self) -> Vec<u8> {
        self.data.par_iter().map(|v| finish::code8(*v)).collect()
    }

    /// As the project's float32 RGB image (linear, for EXR output).
    pub fn to_rgb_image(&self) -> RgbImage {
        RgbImage {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(|v| *v as f32).collect(),
        }
    }
}

impl Rgb<f32> {
    /// As the project's float32 RGB image (moved, not copied).
    pub fn into_rgb_image(self) -> RgbImage {
        RgbImage {
            width: self.width,
            height: self.height,
            data: self.data,
        }
    }
}
