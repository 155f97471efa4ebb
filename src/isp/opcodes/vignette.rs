//! FixVignetteRadial (opcode 3): multiply every sample by `1 + k0 r^2 + k1 r^4 + k2 r^6 +
//! k3 r^8 + k4 r^10`. As in the Adobe DNG SDK (`dng_opcode_FixVignetteRadial::Prepare`): the
//! optical centre is `(l + cx (r - l), t + cy (b - t))` of the stage image extent (pixel
//! edges), `r` is the distance of the pixel centre (`+ 0.5`) to it divided by the largest
//! distance from the centre to a corner of the extent, `r^2` is clamped to 1 (the SDK's
//! table ends there), and results are `min(x * gain, range)` (pinned at 0). Square pixels
//! (the SDK's PixelAspectRatio is taken as 1). The SDK evaluates the gain through a 16-bit
//! table; day2night evaluates the polynomial in f64 (difference below 2^-15 of the gain).

use super::{pin, StageRect};

/// A vignette correction ready for rows.
#[derive(Debug, Clone, Copy)]
pub struct Vignette {
    k: [f64; 5],
    cv: f64,
    ch: f64,
    inv_r: f64,
}

impl Vignette {
    /// The correction of coefficients `k` about the relative centre `center` (x, y) of an
    /// image of `extent`.
    pub fn new(k: [f64; 5], center: [f64; 2], b: StageRect) -> Vignette {
        let lerp = |a: i64, z: i64, f: f64| a as f64 + (z - a) as f64 * f;
        let cv = lerp(b.t, b.b, center[1]);
        let ch = lerp(b.l, b.r, center[0]);
        let dv = (cv - b.t as f64).abs().max((cv - b.b as f64).abs());
        let dh = (ch - b.l as f64).abs().max((ch - b.r as f64).abs());
        let r = dv.hypot(dh);
        Vignette {
            k,
            cv,
            ch,
            inv_r: if r > 0.0 && r.is_finite() {
                1.0 / r
            } else {
                0.0
            },
        }
    }

    /// The gain at stage pixel (r, c).
    pub fn gain(&self, r: usize, c: usize) -> f32 {
        let y = (r as f64 + 0.5 - self.cv) * self.inv_r;
        let x = (c as f64 + 0.5 - self.ch) * self.inv_r;
        let r2 = (x * x + y * y).min(1.0);
        let s = self.k.iter().rev().fold(0.0f64, |acc, &k| r2 * (k + acc));
        (1.0 + s) as f32
    }

    /// Apply to one row (every plane).
    pub fn row(&self, r: usize, left: usize, planes: usize, range: f32, row: &mut [f32]) {
        for (i, px) in row.chunks_exact_mut(planes.max(1)).enumerate() {
            let g = self.gain(r, left + i);
            for v in px {
                *v = pin(*v * g, range);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gain_follows_the_polynomial_of_the_normalized_radius() {
        let b = StageRect::of_size(100, 50);
        let v = Vignette::new([0.5, 0.25, 0.0, 0.0, 0.0], [0.5, 0.5], b);
        // centre (25, 50) in pixel edges; corner distance hypot(25, 50)
        let rmax = 25f64.hypot(50.0);
        let (r, c) = (10usize, 80usize);
        let rr =
            ((r as f64 + 0.5 - 25.0).powi(2) + (c as f64 + 0.5 - 50.0).powi(2)) / (rmax * rmax);
        let want = 1.0 + 0.5 * rr + 0.25 * rr * rr;
        assert!((v.gain(r, c) as f64 - want).abs() < 1e-6);
        // at the centre the gain is 1; a far corner at most 1 + sum k
        assert!((v.gain(24, 49) - 1.0).abs() < 1e-3);
        assert!(v.gain(0, 0) <= 1.75 + 1e-6);
        let mut row = vec![0.9f32; 3];
        v.row(0, 0, 3, 1.0, &mut row);
        assert_eq!(row, vec![1.0; 3]);
    }

    #[test]
    fn off_centre_and_degenerate() {
        let b = StageRect::of_size(1, 1);
        let v = Vignette::new([f64::NAN; 5], [0.0, 0.0], b);
        let mut row = vec![0.5f32];
        v.row(0, 0, 1, 1.0, &mut row);
        assert_eq!(row, vec![0.0], "NaN coefficients pin to 0, not NaN");
        let v = Vignette::new(
            [1.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0],
            StageRect::of_size(10, 10),
        );
        // centre at the top-left corner: radius normalised by the far corner
        assert!((v.gain(9, 9) as f64 - (1.0 + (2.0 * 9.5f64 * 9.5) / 200.0)).abs() < 1e-6);
    }
}
