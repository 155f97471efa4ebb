//! What every execution of the render shares (the plain CFA render of `render_bands.rs`,
//! the LinearRaw render of `render_linear_raw.rs`, the crop render of `render_crop.rs`, the
//! opcode render of `opcodes/`): the options, the neutral a
//! render white-balances by, the camera -> linear sRGB matrix and its application to rows,
//! and the band size and result of the banded render. Kept apart so that those renders use
//! it without using each other.

use super::color::{normalize_neutral, CameraColor};
use super::demosaic::Demosaic;
use super::opcodes::OpcodeMode;
use super::rgb::RgbImage;
use crate::color::matrix3::Mat3;
use crate::error::{Error, Result};
use crate::raw::meta::RawMeta;
use rayon::prelude::*;

/// What a render makes: the linear sRGB target or the network input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Output {
    /// Linear sRGB (Rec.709 primaries, D65), values in [0, 1]: the colour matrix applied.
    #[default]
    Linear,
    /// The network input of the paper: white-balanced, demosaiced camera RGB clipped to
    /// [0, 1], no colour matrix.
    Camera,
}

/// Options of a render ([`render`](super::render::render)).
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Linear sRGB or the network input's camera RGB.
    pub output: Output,
    /// Demosaicing method.
    pub demosaic: Demosaic,
    /// White balance by this camera neutral instead of the file's AsShotNeutral
    /// (normalized to green = 1 internally).
    pub neutral: Option<[f64; 3]>,
    /// Apply DefaultCropOrigin/DefaultCropSize (relative to the active area).
    pub crop: bool,
    /// Apply the EXIF/TIFF Orientation.
    pub orient: bool,
    /// Apply the file's DNG opcode lists ([`super::opcodes`]); files without opcodes take
    /// the plain path either way.
    pub opcodes: OpcodeMode,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            output: Output::Linear,
            demosaic: Demosaic::default(),
            neutral: None,
            crop: true,
            orient: true,
            opcodes: OpcodeMode::Apply,
        }
    }
}

/// The neutral used for white balance: `override_neutral`, else AsShotNeutral, else
/// AsShotWhiteXY converted through the colour matrices; normalized to green = 1.
pub fn resolve_neutral(meta: &RawMeta, override_neutral: Option<[f64; 3]>) -> Result<[f64; 3]> {
    if let Some(n) = override_neutral {
        return normalize_neutral(n);
    }
    if let Some(n) = meta.as_shot_neutral {
        return normalize_neutral(n);
    }
    if let Some(xy) = meta.as_shot_white_xy {
        return CameraColor::new(&meta.color)?.xy_to_neutral(xy);
    }
    Err(Error::invalid(
        "the DNG has neither AsShotNeutral nor AsShotWhiteXY: pass a neutral (--neutral R,G,B)",
    ))
}

/// Output rows per band of the banded render.
pub const BAND: usize = 32;

/// What [`render_bands`](super::render::render_bands) returns: the output size and one result per band, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Bands<T> {
    /// Output width.
    pub width: usize,
    /// Output height.
    pub height: usize,
    /// The consumer's result for each band of [`BAND`] rows, top to bottom.
    pub bands: Vec<T>,
}

/// The white-balanced camera -> linear sRGB matrix this render uses.
pub fn color_matrix(meta: &RawMeta, neutral: [f64; 3]) -> Result<Mat3> {
    CameraColor::new(&meta.color)?.wb_camera_to_srgb(normalize_neutral(neutral)?)
}

/// Clip every pixel to [0, 1], apply a 3x3 matrix and clip the result to [0, 1].
pub fn apply_matrix(rgb: &mut RgbImage, m: &Mat3) {
    let mf = m.map(|r| r.map(|v| v as f32));
    let w = rgb.width.max(1);
    rgb.data
        .par_chunks_mut(3 * w)
        .for_each(|row| matrix_row(row, &mf));
}

/// [`apply_matrix`] on one interleaved row.
#[inline]
pub(crate) fn matrix_row(row: &mut [f32], mf: &[[f32; 3]; 3]) {
    for px in row.chunks_exact_mut(3) {
        let cl = |v: f32| v.clamp(0.0, 1.0);
        let (r, g, b) = (cl(px[0]), cl(px[1]), cl(px[2]));
        for (c, out) in px.iter_mut().enumerate() {
            let v = mf[c][0] * r + mf[c][1] * g + mf[c][2] * b;
            *out = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        }
    }
}

/// Clip every sample of a row to [0, 1].
pub(crate) fn clip_row(row: &mut [f32]) {
    row.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0))
}
