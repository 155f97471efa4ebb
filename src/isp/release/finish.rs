//! The release's last stages: orientation (its own reading of the codes), gamma 1/2.2, the
//! "simple s-curve" `3x^2 - 2x^3`, and `x * 255` truncated to 8 bits.
//!
//! The release turns the image with OpenCV flips and rotations: code 2 flips top to bottom
//! and 4 left to right (the EXIF meanings swapped), 5 and 7 flip top to bottom then rotate
//! a quarter turn anticlockwise (5) or clockwise (7); 3, 6 and 8 rotate as EXIF says.

use crate::error::Result;

/// An interleaved RGB image.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgb<T> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `3 * width * height` samples, row-major.
    pub data: Vec<T>,
}

/// An interleaved RGB float64 image.
pub type Rgb64 = Rgb<f64>;

impl<T: Copy + Default> Rgb<T> {
    /// The image whose pixel (x, y) is this one's `src(x, y)`, `w x h` pixels (its buffer
    /// reserved fallibly: a refusal is a limits error, not an abort).
    fn remap(
        &self,
        w: usize,
        h: usize,
        src: impl Fn(usize, usize) -> (usize, usize),
    ) -> Result<Rgb<T>> {
        let mut data = crate::limits::try_filled(T::default(), 3 * w * h, "the turned image")?;
        for y in 0..h {
            for x in 0..w {
                let (sx, sy) = src(x, y);
                let s = 3 * (sy * self.width + sx);
                data[3 * (y * w + x)..][..3].copy_from_slice(&self.data[s..s + 3]);
            }
        }
        Ok(Rgb {
            width: w,
            height: h,
            data,
        })
    }
    fn flip_top_bottom(&self) -> Result<Rgb<T>> {
        let h = self.height;
        self.remap(self.width, h, |x, y| (x, h - 1 - y))
    }
    fn flip_left_right(&self) -> Result<Rgb<T>> {
        let w = self.width;
        self.remap(w, self.height, |x, y| (w - 1 - x, y))
    }
    fn rotate_180(&self) -> Result<Rgb<T>> {
        let (w, h) = (self.width, self.height);
        self.remap(w, h, |x, y| (w - 1 - x, h - 1 - y))
    }
    /// A quarter turn clockwise: the left column, read upwards, becomes the top row.
    fn rotate_cw(&self) -> Result<Rgb<T>> {
        let h = self.height;
        self.remap(h, self.width, |x, y| (y, h - 1 - x))
    }
    /// A quarter turn anticlockwise: the right column, read downwards, becomes the top row.
    fn rotate_ccw(&self) -> Result<Rgb<T>> {
        let w = self.width;
        self.remap(self.height, w, |x, y| (w - 1 - y, x))
    }

    /// The image turned as the release turns it for Orientation `code` (anything outside
    /// 2..=8 leaves it). The turn moves whole pixels, so it commutes with any per-sample
    /// map (the 8-bit codes of a turned image are the turned codes).
    pub fn oriented(self, code: u16) -> Result<Rgb<T>> {
        match code {
            2 => self.flip_top_bottom(),
            3 => self.rotate_180(),
            4 => self.flip_left_right(),
            5 => self.flip_top_bottom()?.rotate_ccw(),
            6 => self.rotate_cw(),
            7 => self.flip_top_bottom()?.rotate_cw(),
            8 => self.rotate_ccw(),
            _ => Ok(self),
        }
    }
}

/// The release's display value of a linear sample in [0, 1]: gamma 1/2.2 then
/// `3x^2 - 2x^3`, in float64.
#[inline]
pub fn display(v: f64) -> f64 {
    let g = v.powf(1.0 / 2.2);
    3.0 * (g * g) - 2.0 * g.powf(3.0)
}

/// The release's 8-bit code of a linear sample: `display(v) * 255` truncated.
#[inline]
pub fn code8(v: f64) -> u8 {
    (display(v) * 255.0) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3x2 image whose red sample is its index (x + 3y).
    fn img() -> Rgb64 {
        let mut data = vec![0.0; 18];
        for i in 0..6 {
            data[3 * i] = i as f64;
        }
        Rgb64 {
            width: 3,
            height: 2,
            data,
        }
    }

    fn reds(i: &Rgb64) -> Vec<f64> {
        i.data.iter().step_by(3).copied().collect()
    }

    #[test]
    fn orientations_as_the_release_turns_them() {
        // 0 1 2
        // 3 4 5
        let o = |c| reds(&img().oriented(c).unwrap());
        assert_eq!(o(1), vec![0., 1., 2., 3., 4., 5.]);
        assert_eq!(o(2), vec![3., 4., 5., 0., 1., 2.]);
        assert_eq!(o(3), vec![5., 4., 3., 2., 1., 0.]);
        assert_eq!(o(4), vec![2., 1., 0., 5., 4., 3.]);
        // Clockwise: 3 0 / 4 1 / 5 2; anticlockwise: 2 5 / 1 4 / 0 3.
        assert_eq!(o(6), vec![3., 0., 4., 1., 5., 2.]);
        assert_eq!(o(8), vec![2., 5., 1., 4., 0., 3.]);
        // Top-bottom flip (3 4 5 / 0 1 2), then anticlockwise / clockwise.
        assert_eq!(o(5), vec![5., 2., 4., 1., 3., 0.]);
        assert_eq!(o(7), vec![0., 3., 1., 4., 2., 5.]);
        assert_eq!(img().oriented(6).unwrap().width, 2);
    }

    #[test]
    fn display_curve_ends_and_truncation() {
        assert_eq!(code8(0.0), 0);
        assert_eq!(code8(1.0), 255);
        // 0.5 ** (1 / 2.2) = 0.7297..., s-curve 0.8203..., x 255 = 209.18 -> 209.
        assert_eq!(code8(0.5), 209);
    }
}
