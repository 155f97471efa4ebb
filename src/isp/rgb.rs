//! [`RgbImage`]: the interleaved `f32` RGB image every render, encoder and metric uses.

/// An RGB image of `f32` samples, interleaved (`data[3 * (y * width + x) + c]`), usually
/// linear light (Rec.709/sRGB primaries, D65) unless stated otherwise.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `3 * width * height` samples, interleaved RGB, row-major.
    pub data: Vec<f32>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: usize, height: usize) -> RgbImage {
        RgbImage {
            width,
            height,
            data: vec![0.0; 3 * width * height],
        }
    }

    /// [`RgbImage::new`], or [`crate::Error::Limits`] naming the size when the allocator
    /// refuses it (instead of aborting the process).
    pub fn try_new(width: usize, height: usize) -> crate::Result<RgbImage> {
        let n = width
            .checked_mul(height)
            .and_then(|n| n.checked_mul(3))
            .ok_or_else(|| crate::Error::limits(format!("a {width}x{height} RGB image")))?;
        Ok(RgbImage {
            width,
            height,
            data: crate::limits::try_filled(0.0, n, "an RGB image")?,
        })
    }

    /// The pixel at (x, y); `None` outside the image.
    pub fn pixel(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 3 * (y * self.width + x);
        Some([
            *self.data.get(i)?,
            *self.data.get(i + 1)?,
            *self.data.get(i + 2)?,
        ])
    }

    /// Number of NaN or infinite samples.
    pub fn count_non_finite(&self) -> usize {
        self.data.iter().filter(|v| !v.is_finite()).count()
    }

    /// Replace NaN by 0 and +-infinity by +-`max_abs`, and clamp every sample to
    /// [-max_abs, max_abs]. Returns how many samples changed.
    pub fn sanitize(&mut self, max_abs: f32) -> usize {
        let mut n = 0;
        for v in &mut self.data {
            let s = if v.is_nan() {
                0.0
            } else {
                v.clamp(-max_abs, max_abs)
            };
            if s.to_bits() != v.to_bits() {
                n += 1;
                *v = s;
            }
        }
        n
    }

    /// Check that `data` holds `3 * width * height` samples.
    pub fn validate(&self) -> crate::Result<()> {
        let want = self
            .width
            .checked_mul(self.height)
            .and_then(|p| p.checked_mul(3))
            .ok_or_else(|| crate::Error::limits("image dimensions overflow"))?;
        if self.data.len() != want {
            return Err(crate::Error::invalid(format!(
                "RGB buffer holds {} samples, expected 3x{}x{}",
                self.data.len(),
                self.width,
                self.height
            )));
        }
        Ok(())
    }
}
