//! Display-referred PNG (and 16-bit TIFF) renders: linear RGB encoded with a
//! [`DisplayTone`] (sRGB OETF by default), quantized to 8 bits (default) or 16 bits.

use crate::error::{Error, Result};
use crate::isp::tone::DisplayTone;
use crate::isp::RgbImage;
use crate::output::{write_atomic, OutputPolicy};
use image::ImageEncoder;
use rayon::prelude::*;
use std::path::Path;

/// Options of [`write_png`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PngOptions {
    /// 16-bit samples instead of 8.
    pub sixteen_bit: bool,
    /// Display encoding.
    pub tone: DisplayTone,
}

impl Default for PngOptions {
    fn default() -> Self {
        PngOptions {
            sixteen_bit: false,
            tone: DisplayTone::Srgb,
        }
    }
}

/// Display-encoded 8-bit samples.
pub fn encode_u8(img: &RgbImage, tone: DisplayTone) -> Vec<u8> {
    img.data
        .par_iter()
        .map(|&v| (tone.encode(v) * 255.0 + 0.5) as u8)
        .collect()
}

/// Display-encoded 16-bit samples.
pub fn encode_u16(img: &RgbImage, tone: DisplayTone) -> Vec<u16> {
    img.data
        .par_iter()
        .map(|&v| (tone.encode(v) * 65535.0 + 0.5) as u16)
        .collect()
}

fn dims(img: &RgbImage) -> Result<(u32, u32)> {
    img.validate()?;
    let w = u32::try_from(img.width).map_err(|_| Error::limits("image too wide"))?;
    let h = u32::try_from(img.height).map_err(|_| Error::limits("image too tall"))?;
    if w == 0 || h == 0 {
        return Err(Error::invalid("cannot write an empty image"));
    }
    Ok((w, h))
}

fn img_err(e: image::ImageError) -> Error {
    match e {
        image::ImageError::IoError(io) => Error::Io(io),
        other => Error::invalid(format!("image encoding failed: {other}")),
    }
}

/// Display-encoded samples as the `image` encoders take them (native-endian for 16 bit).
fn encoded(img: &RgbImage, opts: &PngOptions) -> (Vec<u8>, image::ExtendedColorType) {
    if opts.sixteen_bit {
        let native = encode_u16(img, opts.tone)
            .iter()
            .flat_map(|v| v.to_ne_bytes())
            .collect();
        (native, image::ExtendedColorType::Rgb16)
    } else {
        (encode_u8(img, opts.tone), image::ExtendedColorType::Rgb8)
    }
}

/// Write a display-referred PNG of the linear image `img` atomically.
pub fn write_png(
    img: &RgbImage,
    path: &Path,
    opts: &PngOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    let (w, h) = dims(img)?;
    write_atomic(path, policy, |out| {
        let (bytes, color) = encoded(img, opts);
        image::codecs::png::PngEncoder::new(out)
            .write_image(&bytes, w, h, color)
            .map_err(img_err)
    })
}

/// Write a display-referred 16-bit (or 8-bit) RGB TIFF of the linear image atomically.
pub fn write_tiff(
    img: &RgbImage,
    path: &Path,
    opts: &PngOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    let (w, h) = dims(img)?;
    write_atomic(path, policy, |out| {
        let (bytes, color) = encoded(img, opts);
        image::codecs::tiff::TiffEncoder::new(out)
            .write_image(&bytes, w, h, color)
            .map_err(img_err)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_8_and_16_bit_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = RgbImage::new(4, 2);
        img.data[0] = 1.0;
        img.data[1] = 0.18;
        img.data[2] = f32::NAN;
        for sixteen in [false, true] {
            let p = dir.path().join(format!("a{sixteen}.png"));
            let opts = PngOptions {
                sixteen_bit: sixteen,
                tone: DisplayTone::Srgb,
            };
            write_png(&img, &p, &opts, &OutputPolicy::default()).unwrap();
            let back = image::open(&p).unwrap();
            if sixteen {
                let b = back.to_rgb16();
                assert_eq!(b.get_pixel(0, 0).0, [65535, 30235, 0]);
            } else {
                let b = back.to_rgb8();
                assert_eq!(b.get_pixel(0, 0).0, [255, 118, 0]);
            }
            let t = dir.path().join(format!("a{sixteen}.tif"));
            write_tiff(&img, &t, &opts, &OutputPolicy::default()).unwrap();
            assert_eq!(image::open(&t).unwrap().width(), 4);
        }
    }
}
