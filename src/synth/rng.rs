//! Seeded random streams (docs/synthesis.md, "Plan, then run").
//!
//! Each (master seed, input file name, variant) gets its own ChaCha20 stream whose key is
//! `SHA-256("day2night synth v1\0" || seed (u64 LE) || name (UTF-8) || "\0" || variant (u32 LE))`.
//! The input *file name* (not its directory) is used, so a result does not depend on where
//! the file lives, on thread count, order or the other files of the batch.
//!
//! Uniform and normal variates are computed here from raw 64-bit words (53-bit uniforms,
//! Box-Muller normals) so that plans stay reproducible whatever the `rand` version.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha20Rng;
use sha2::{Digest, Sha256};

/// The 32-byte key of the stream for (master seed, input name, variant).
pub fn stream_key(master_seed: u64, input_name: &str, variant: u32) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(b"day2night synth v1\0");
    h.update(master_seed.to_le_bytes());
    h.update(input_name.as_bytes());
    h.update([0u8]);
    h.update(variant.to_le_bytes());
    h.finalize().into()
}

/// The random stream a plan samples from.
#[derive(Debug, Clone)]
pub struct SynthRng {
    rng: ChaCha20Rng,
}

impl SynthRng {
    /// Stream for (master seed, input file name, variant).
    pub fn new(master_seed: u64, input_name: &str, variant: u32) -> SynthRng {
        SynthRng::from_key(stream_key(master_seed, input_name, variant))
    }
    /// Stream from an explicit key.
    pub fn from_key(key: [u8; 32]) -> SynthRng {
        SynthRng {
            rng: ChaCha20Rng::from_seed(key),
        }
    }
    /// A raw 64-bit word.
    pub fn next_u64(&mut self) -> u64 {
        self.rng.next_u64()
    }
    /// Uniform in [0, 1) with 53 bits.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    /// Integer uniform in [lo, hi) (returns `lo` when the range is empty).
    pub fn int_range(&mut self, lo: u64, hi: u64) -> u64 {
        if hi <= lo {
            return lo;
        }
        // Multiply-shift: bias below 2^-32 for the ranges used here (image sizes).
        let n = hi - lo;
        lo + ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }
    /// Standard normal variate (Box-Muller, one value per call).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_depend_on_every_part_of_the_key() {
        let a = SynthRng::new(0, "a.dng", 0).next_u64();
        assert_eq!(a, SynthRng::new(0, "a.dng", 0).next_u64());
        assert_ne!(a, SynthRng::new(1, "a.dng", 0).next_u64());
        assert_ne!(a, SynthRng::new(0, "b.dng", 0).next_u64());
        assert_ne!(a, SynthRng::new(0, "a.dng", 1).next_u64());
    }

    #[test]
    fn variates_in_range_with_right_moments() {
        let mut r = SynthRng::new(3, "x", 0);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            let z = r.normal();
            assert!(z.is_finite());
            s += z;
            s2 += z * z;
        }
        let m = s / n as f64;
        let v = s2 / n as f64 - m * m;
        assert!(m.abs() < 0.01 && (v - 1.0).abs() < 0.01, "{m} {v}");
        for _ in 0..1000 {
            let k = r.int_range(5, 9);
            assert!((5..9).contains(&k));
        }
        assert_eq!(r.int_range(4, 4), 4);
    }
}
