//! The render pipeline: normalize -> white balance -> demosaic -> camera -> XYZ -> linear
//! sRGB -> DefaultCrop -> orientation. Every stage is parallel over rows and deterministic.

use super::color::{normalize_neutral, CameraColor, Mat3};
use super::demosaic::{demosaic_rows, Demosaic, Post};
use super::RgbImage;
use crate::dng::meta::RawMeta;
use crate::error::{Error, Result};
use crate::normalize::Normalizer;
use crate::raw::RawImage;
use rayon::prelude::*;

/// Options of [`render_linear`].
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Demosaicing method.
    pub demosaic: Demosaic,
    /// White balance by this camera neutral instead of the file's AsShotNeutral
    /// (normalized to green = 1 internally).
    pub neutral: Option<[f64; 3]>,
    /// Apply DefaultCropOrigin/DefaultCropSize (relative to the active area).
    pub crop: bool,
    /// Apply the EXIF/TIFF Orientation.
    pub orient: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            demosaic: Demosaic::default(),
            neutral: None,
            crop: true,
            orient: true,
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

/// Normalized, white-balanced (clipped to [0, 1]) and demosaiced camera RGB of the whole
/// active area, not clipped after demosaicing: no colour matrix, no crop, no orientation.
/// Normalization uses the shared [`Normalizer`] (DNG chapter 5), fused with the white
/// balance into the demosaicer's input, in parallel over rows.
fn render_camera_with(
    img: &RawImage,
    neutral: [f64; 3],
    method: Demosaic,
    post: &Post,
) -> Result<RgbImage> {
    let bayer = img.bayer()?;
    let n = normalize_neutral(neutral)?;
    let norm = Normalizer::new(img)?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let inv = [1.0 / n[0], 1.0, 1.0 / n[2]];
    let data = &img.data;
    let stride = img.width;
    Ok(demosaic_rows(
        w,
        h,
        bayer,
        method,
        |r, out| {
            let src = &data[(r + top) * stride + left..][..w];
            for (c, (o, &x)) in out.iter_mut().zip(src).enumerate() {
                let y = norm.normalize(x, r, c) * inv[bayer.color_at(r, c) as usize];
                *o = y.clamp(0.0, 1.0) as f32;
            }
        },
        post,
    ))
}

/// White-balanced demosaiced camera RGB of the whole active area, not clipped after
/// demosaicing (see [`render_camera`]).
pub fn render_camera_unclipped(
    img: &RawImage,
    neutral: [f64; 3],
    method: Demosaic,
) -> Result<RgbImage> {
    render_camera_with(img, neutral, method, &|_| {})
}

/// [`render_camera_unclipped`] clipped to [0, 1]: the network input before geometry.
pub fn render_camera(img: &RawImage, neutral: [f64; 3], method: Demosaic) -> Result<RgbImage> {
    render_camera_with(img, neutral, method, &|row: &mut [f32]| {
        row.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0))
    })
}

/// The network input of the paper: normalized, white-balanced, demosaiced camera RGB
/// (no colour matrix), with the same DefaultCrop and orientation as [`render_linear`]'s
/// defaults so that input and target align. `neutral` None = the file's neutral.
pub fn render_input(
    img: &RawImage,
    neutral: Option<[f64; 3]>,
    method: Demosaic,
) -> Result<RgbImage> {
    let n = resolve_neutral(&img.meta, neutral)?;
    let rgb = render_camera(img, n, method)?;
    Ok(apply_geometry(rgb, &img.meta, true, true))
}

/// The white-balanced camera -> linear sRGB matrix this render uses.
pub fn color_matrix(meta: &RawMeta, neutral: [f64; 3]) -> Result<Mat3> {
    CameraColor::new(&meta.color)?.wb_camera_to_srgb(normalize_neutral(neutral)?)
}

/// Linear sRGB (Rec.709 primaries, D65) render of a raw image, values in [0, 1].
pub fn render_linear(img: &RawImage, opts: &RenderOptions) -> Result<RgbImage> {
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let rgb = render_camera_with(img, n, opts.demosaic, &move |row: &mut [f32]| {
        matrix_row(row, &mf)
    })?;
    Ok(apply_geometry(rgb, &img.meta, opts.crop, opts.orient))
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
fn matrix_row(row: &mut [f32], mf: &[[f32; 3]; 3]) {
    for px in row.chunks_exact_mut(3) {
        let cl = |v: f32| v.clamp(0.0, 1.0);
        let (r, g, b) = (cl(px[0]), cl(px[1]), cl(px[2]));
        for (c, out) in px.iter_mut().enumerate() {
            let v = mf[c][0] * r + mf[c][1] * g + mf[c][2] * b;
            *out = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        }
    }
}

/// DefaultCrop rectangle (x, y, width, height) within an active area of `w x h`: origin and
/// size rounded to whole pixels and clamped inside the area; the whole area when absent.
pub fn default_crop(meta: &RawMeta, w: usize, h: usize) -> (usize, usize, usize, usize) {
    let fin = |v: f64| {
        if v.is_finite() {
            v.max(0.0).round() as usize
        } else {
            0
        }
    };
    let (x0, y0) = meta
        .default_crop_origin
        .map(|o| {
            (
                fin(o[0]).min(w.saturating_sub(1)),
                fin(o[1]).min(h.saturating_sub(1)),
            )
        })
        .unwrap_or((0, 0));
    let (cw, ch) = meta
        .default_crop_size
        .map(|s| (fin(s[0]), fin(s[1])))
        .unwrap_or((w, h));
    let cw = cw.clamp(1, w - x0);
    let ch = ch.clamp(1, h - y0);
    (x0, y0, cw, ch)
}

/// Crop (DefaultCrop) then orient (Orientation 1..8) an image of the active area.
pub fn apply_geometry(rgb: RgbImage, meta: &RawMeta, crop: bool, orient: bool) -> RgbImage {
    let rgb = if crop && rgb.width > 0 && rgb.height > 0 {
        let (x0, y0, cw, ch) = default_crop(meta, rgb.width, rgb.height);
        if (x0, y0, cw, ch) == (0, 0, rgb.width, rgb.height) {
            rgb
        } else {
            // In place: row y moves from 3 * ((y + y0) * width + x0) down to 3 * y * cw,
            // never after its source, so rows copied in order do not overwrite unread data
            // (no second full-size buffer; same pixels as copying into a new image).
            let mut rgb = rgb;
            for y in 0..ch {
                let s = 3 * ((y + y0) * rgb.width + x0);
                rgb.data.copy_within(s..s + 3 * cw, 3 * y * cw);
            }
            rgb.data.truncate(3 * cw * ch);
            rgb.width = cw;
            rgb.height = ch;
            rgb
        }
    } else {
        rgb
    };
    if orient && (2..=8).contains(&meta.orientation) {
        orient_image(&rgb, meta.orientation)
    } else {
        // Orientation 1 (or unknown): the image as it is, not a copy.
        rgb
    }
}

/// Transform an image for display according to the TIFF/EXIF Orientation code (1..8;
/// anything else is treated as 1).
pub fn orient_image(img: &RgbImage, orientation: u16) -> RgbImage {
    let (w, h) = (img.width, img.height);
    if !(2..=8).contains(&orientation) {
        return img.clone();
    }
    let swap = orientation >= 5;
    let (ow, oh) = if swap { (h, w) } else { (w, h) };
    let mut out = RgbImage::new(ow, oh);
    out.data
        .par_chunks_mut(3 * ow.max(1))
        .enumerate()
        .for_each(|(yo, row)| {
            for (xo, px) in row.chunks_exact_mut(3).enumerate() {
                let (x, y) = match orientation {
                    2 => (w - 1 - xo, yo),
                    3 => (w - 1 - xo, h - 1 - yo),
                    4 => (xo, h - 1 - yo),
                    5 => (yo, xo),
                    6 => (yo, h - 1 - xo),
                    7 => (w - 1 - yo, h - 1 - xo),
                    _ => (w - 1 - yo, xo),
                };
                let s = 3 * (y * w + x);
                px.copy_from_slice(&img.data[s..s + 3]);
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::{Bayer, Rect};

    fn numbered(w: usize, h: usize) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        for (i, px) in img.data.chunks_exact_mut(3).enumerate() {
            px[0] = i as f32;
        }
        img
    }

    #[test]
    fn orientations_match_their_definitions() {
        // 3x2 image: 0 1 2 / 3 4 5
        let img = numbered(3, 2);
        let red = |o: u16| -> (usize, usize, Vec<f32>) {
            let r = orient_image(&img, o);
            (r.width, r.height, r.data.chunks(3).map(|p| p[0]).collect())
        };
        assert_eq!(red(1), (3, 2, vec![0., 1., 2., 3., 4., 5.]));
        assert_eq!(red(2), (3, 2, vec![2., 1., 0., 5., 4., 3.]));
        assert_eq!(red(3), (3, 2, vec![5., 4., 3., 2., 1., 0.]));
        assert_eq!(red(4), (3, 2, vec![3., 4., 5., 0., 1., 2.]));
        assert_eq!(red(5), (2, 3, vec![0., 3., 1., 4., 2., 5.]));
        // rotate 90 clockwise
        assert_eq!(red(6), (2, 3, vec![3., 0., 4., 1., 5., 2.]));
        assert_eq!(red(7), (2, 3, vec![5., 2., 4., 1., 3., 0.]));
        // rotate 90 counter-clockwise
        assert_eq!(red(8), (2, 3, vec![2., 5., 1., 4., 0., 3.]));
        assert_eq!(red(0), red(1));
    }

    fn flat_raw(value: u16) -> RawImage {
        let (w, h) = (16, 12);
        let meta = RawMeta::new_bayer(Bayer::RGGB, 12, 64.0, 4095.0);
        RawImage {
            width: w,
            height: h,
            data: vec![value; w * h],
            meta,
        }
    }

    #[test]
    fn grey_card_renders_grey_and_crop_orientation_apply() {
        // A raw whose sites equal the neutral times a constant renders neutral grey.
        let mut img = flat_raw(0);
        let n = img.meta.as_shot_neutral.unwrap();
        let k = 0.3;
        for y in 0..img.height {
            for x in 0..img.width {
                let c = Bayer::RGGB.color_at(y, x) as usize;
                img.data[y * img.width + x] = (64.0 + k * n[c] * (4095.0 - 64.0)).round() as u16;
            }
        }
        img.meta.active_area = Some(Rect {
            top: 2,
            left: 2,
            bottom: 12,
            right: 16,
        });
        img.meta.default_crop_origin = Some([1.0, 2.0]);
        img.meta.default_crop_size = Some([10.0, 6.0]);
        img.meta.orientation = 6;
        for d in Demosaic::ALL {
            let out = render_linear(
                &img,
                &RenderOptions {
                    demosaic: d,
                    ..RenderOptions::default()
                },
            )
            .unwrap();
            assert_eq!((out.width, out.height), (6, 10));
            for px in out.data.chunks(3) {
                for v in px {
                    assert!((v - k as f32).abs() < 2e-3, "{d}: {px:?}");
                }
            }
        }
        let inp = render_input(&img, None, Demosaic::Bilinear).unwrap();
        assert_eq!((inp.width, inp.height), (6, 10));
        let off = render_linear(
            &img,
            &RenderOptions {
                crop: false,
                orient: false,
                ..RenderOptions::default()
            },
        )
        .unwrap();
        assert_eq!((off.width, off.height), (14, 10));
    }

    #[test]
    fn neutral_sources_and_errors() {
        let mut img = flat_raw(1000);
        assert_eq!(
            resolve_neutral(&img.meta, Some([2.0, 4.0, 1.0])).unwrap(),
            [0.5, 1.0, 0.25]
        );
        img.meta.as_shot_neutral = None;
        assert!(resolve_neutral(&img.meta, None).is_err());
        img.meta.as_shot_white_xy = Some(super::super::color::D65_XY);
        let n = resolve_neutral(&img.meta, None).unwrap();
        // the fixture matrix is Lindbloom's (white 0.31271, 0.32902): close to (1, 1, 1)
        assert!(n.iter().all(|v| (v - 1.0).abs() < 1e-3), "{n:?}");
        assert!(resolve_neutral(&img.meta, Some([0.0, 1.0, 1.0])).is_err());
    }

    #[test]
    fn default_crop_is_clamped() {
        let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        assert_eq!(default_crop(&m, 10, 8), (0, 0, 10, 8));
        m.default_crop_origin = Some([8.0, 100.0]);
        m.default_crop_size = Some([50.0, f64::NAN]);
        assert_eq!(default_crop(&m, 10, 8), (8, 7, 2, 1));
    }

    #[test]
    fn render_is_deterministic_across_thread_counts() {
        let mut img = flat_raw(0);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = (64 + (i * 7919) % 4000) as u16;
        }
        let opts = RenderOptions {
            demosaic: Demosaic::Menon,
            ..RenderOptions::default()
        };
        let a = render_linear(&img, &opts).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| render_linear(&img, &opts).unwrap());
        assert_eq!(a, b);
    }
}
