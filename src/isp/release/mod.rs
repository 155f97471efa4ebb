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
//! The DNG opcode lists and DefaultCrop are not used (the release's target stages skip
//! them); nothing here touches the project's own ISP.

pub mod colour;
pub mod finish;
pub mod menon;
pub mod meta;
pub mod mosaic;

pub use finish::Rgb64;
pub use meta::ReleaseMeta;

use crate::error::Result;
use crate::isp::RgbImage;
use crate::raw::RawImage;
use rayon::prelude::*;

/// The release's linear sRGB image of `raw` (its "srgb" stage, then its orientation unless
/// `orient` is false: before gamma), float64 in [0, 1]. `neutral` replaces the file's
/// AsShotNeutral for white balance and the colour matrix alike.
pub fn render_linear(raw: &RawImage, neutral: Option<[f64; 3]>, orient: bool) -> Result<Rgb64> {
    let meta = ReleaseMeta::of(raw, neutral)?;
    let codes = mosaic::codes(raw, &meta)?;
    let (w, h) = (codes.width, codes.height);
    let mut rgb = menon::demosaic(&codes.data, w, h, meta.cfa);
    drop(codes);
    let (cam, _) = colour::camera_to_xyz(&meta)?;
    let out = colour::xyz_to_srgb();
    let scale = mosaic::CODE_SCALE as f32;
    rgb.par_chunks_mut(3).for_each(|px| {
        // float64 -> float32, / 16383 in float32, as the release's demosaic stage returns.
        let cam_rgb = [0, 1, 2].map(|c| f64::from(px[c] as f32 / scale));
        px.copy_from_slice(&colour::to_srgb(&cam, &out, cam_rgb));
    });
    Ok(Rgb64 {
        width: w,
        height: h,
        data: rgb,
    }
    .oriented(if orient { meta.orientation } else { 1 }))
}

/// The release's 8-bit render of `raw`: (width, height, interleaved RGB bytes), the bytes of
/// its target PNGs (`orient` false: before its orientation stage).
pub fn render_u8(
    raw: &RawImage,
    neutral: Option<[f64; 3]>,
    orient: bool,
) -> Result<(usize, usize, Vec<u8>)> {
    let img = render_linear(raw, neutral, orient)?;
    Ok((img.width, img.height, img.to_u8()))
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
