//! Small 8-bit sRGB images for the report: box-filter downscaling, crops, markers, and PNG
//! encoding through the `image` crate.

use crate::color::srgb::encode8;
use crate::error::{Error, Result};
use crate::output::{write_atomic, OutputPolicy};
use std::path::Path;

/// An 8-bit RGB image, row-major, 3 bytes per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgb8 {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// `width * height * 3` bytes.
    pub data: Vec<u8>,
}

impl Rgb8 {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Rgb8 {
        Rgb8 {
            width,
            height,
            data: vec![0; width * height * 3],
        }
    }

    /// From linear floats in [0, 1] (any range; clipped), encoded with the sRGB curve
    /// ([`encode8`]).
    /// `get(r, c)` returns the linear RGB of a pixel.
    pub fn from_linear(
        width: usize,
        height: usize,
        get: impl Fn(usize, usize) -> [f32; 3],
    ) -> Rgb8 {
        let mut img = Rgb8::new(width, height);
        for r in 0..height {
            for c in 0..width {
                let v = get(r, c);
                img.put(r, c, [encode8(v[0]), encode8(v[1]), encode8(v[2])]);
            }
        }
        img
    }

    /// Set a pixel (ignored outside).
    pub fn put(&mut self, r: usize, c: usize, rgb: [u8; 3]) {
        if r < self.height && c < self.width {
            let i = (r * self.width + c) * 3;
            if let Some(px) = self.data.get_mut(i..i + 3) {
                px.copy_from_slice(&rgb);
            }
        }
    }

    /// A cross of half-size `s` at (x, y) with a dark outline so it shows on any background.
    pub fn mark(&mut self, x: f64, y: f64, s: i64, rgb: [u8; 3]) {
        if !x.is_finite() || !y.is_finite() {
            return;
        }
        let (cx, cy) = (x.round() as i64, y.round() as i64);
        for (d, color) in [(1i64, [0u8, 0, 0]), (0, rgb)] {
            for k in -s..=s {
                for w in -d..=d {
                    for (r, c) in [(cy + w, cx + k), (cy + k, cx + w)] {
                        if r >= 0 && c >= 0 {
                            self.put(r as usize, c as usize, color);
                        }
                    }
                }
            }
        }
    }

    /// PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        use image::ImageEncoder;
        let mut out = Vec::new();
        let w = u32::try_from(self.width).map_err(|_| Error::limits("image too wide"))?;
        let h = u32::try_from(self.height).map_err(|_| Error::limits("image too tall"))?;
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(&self.data, w, h, image::ExtendedColorType::Rgb8)
            .map_err(|e| Error::invalid(format!("PNG encoding: {e}")))?;
        Ok(out)
    }

    /// Write as PNG atomically (replacing an older report file).
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let bytes = self.png()?;
        let policy = OutputPolicy {
            overwrite: true,
            inputs: vec![],
            ..OutputPolicy::default()
        };
        write_atomic(path, &policy, |w| {
            use std::io::Write;
            Ok(w.write_all(&bytes)?)
        })
    }
}

/// Output size keeping the aspect ratio with the longer side at most `max`.
pub fn fit(width: usize, height: usize, max: usize) -> (usize, usize) {
    let m = width.max(height).max(1);
    if m <= max {
        return (width.max(1), height.max(1));
    }
    let s = max as f64 / m as f64;
    (
        ((width as f64 * s).round() as usize).max(1),
        ((height as f64 * s).round() as usize).max(1),
    )
}

/// Box-filter downscale of a linear float RGB image (`get(r, c)`) to `(tw, th)`.
pub fn downscale(
    width: usize,
    height: usize,
    tw: usize,
    th: usize,
    get: impl Fn(usize, usize) -> [f32; 3],
) -> Vec<[f32; 3]> {
    let mut out = vec![[0f32; 3]; tw * th];
    if width == 0 || height == 0 {
        return out;
    }
    for ty in 0..th {
        let r0 = ty * height / th;
        let r1 = ((ty + 1) * height / th).max(r0 + 1).min(height);
        for tx in 0..tw {
            let c0 = tx * width / tw;
            let c1 = ((tx + 1) * width / tw).max(c0 + 1).min(width);
            let mut acc = [0f64; 3];
            for r in r0..r1 {
                for c in c0..c1 {
                    let v = get(r, c);
                    for k in 0..3 {
                        acc[k] += f64::from(v[k]);
                    }
                }
            }
            let n = ((r1 - r0) * (c1 - c0)).max(1) as f64;
            if let Some(o) = out.get_mut(ty * tw + tx) {
                *o = [
                    (acc[0] / n) as f32,
                    (acc[1] / n) as f32,
                    (acc[2] / n) as f32,
                ];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_decode_and_helpers() {
        assert_eq!(fit(4000, 3000, 320), (320, 240));
        assert_eq!(fit(10, 5, 320), (10, 5));
        let d = downscale(4, 2, 2, 1, |r, c| [(r * 4 + c) as f32, 0.0, 1.0]);
        assert_eq!(d, vec![[2.5, 0.0, 1.0], [4.5, 0.0, 1.0]]);
        let mut img = Rgb8::from_linear(16, 8, |_, c| [c as f32 / 15.0, 0.2, 0.5]);
        img.mark(8.0, 4.0, 3, [255, 0, 0]);
        let png = img.png().unwrap();
        let back = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!((back.width(), back.height()), (16, 8));
        assert_eq!(back.get_pixel(8, 4).0, [255, 0, 0]);
        assert_eq!(back.as_raw(), &img.data);
    }
}
