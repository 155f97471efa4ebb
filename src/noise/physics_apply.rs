//! Sampling the physics-based noise model ([`super::physics`]) on a clean raw mosaic:
//! per active-area site `(r, c)` with `s = x - black(r, c)` (DN, linear values):
//!
//! - shot: `s <= 0`: `s` (no electrons, the below-black part kept as is); `s / K <= N`
//!   (`N` = `poisson_max_electrons`): `K * Poisson(s / K)`; above: `s + sqrt(K s) * z`
//!   (the normal approximation, written without forming `s / K` so tiny K cannot overflow);
//! - read: `sigma_read * Q_lambda(u) / sd(lambda)` (Tukey-lambda with unit variance), or
//!   `sigma_read * z` when Gaussian;
//! - row: `sigma_row * z_r`, one draw per active-area row;
//! - `noisy = clip(round(black + shot + read + row), 0, white)`.
//!
//! Randomness: one ChaCha8 stream per active-area row (key = SHA-256 of the seed with its own
//! domain tag, stream number = row). Each site reads exactly one `u64` from it, at word
//! position `2 (c + 1)` (the row offset's seed is at 0), and draws its shot and read noise
//! from a SplitMix64 generator seeded with that word. So any crop (rows x cols) gives the
//! same samples as the whole frame at the same sites, for any thread count.

use super::physics::PhysicsParams;
use super::tukey;
use crate::error::{Error, Result};
use crate::normalize::{round_clamp, Normalizer};
use crate::raw::RawImage;
use rand::{Rng, SeedableRng, TryRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Poisson, StandardNormal};
use rayon::prelude::*;
use sha2::{Digest, Sha256};
use std::convert::Infallible;
use std::ops::Range;

/// The 32-byte ChaCha key of a physics noise seed.
pub fn physics_key(seed: u64) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(b"day2night physics noise rows v1\0");
    h.update(seed.to_le_bytes());
    h.finalize().into()
}

/// SplitMix64 (Steele, Lea, Flood 2014): a small generator seeded per site.
struct SiteRng(u64);

impl TryRng for SiteRng {
    type Error = Infallible;
    #[inline]
    fn try_next_u32(&mut self) -> std::result::Result<u32, Infallible> {
        Ok((self.try_next_u64()? >> 32) as u32)
    }
    #[inline]
    fn try_next_u64(&mut self) -> std::result::Result<u64, Infallible> {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Ok(z ^ (z >> 31))
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> std::result::Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let v = self.try_next_u64()?.to_le_bytes();
            chunk.copy_from_slice(&v[..chunk.len()]);
        }
        Ok(())
    }
}

/// Uniform in the open interval (0, 1).
#[inline]
fn open01(rng: &mut SiteRng) -> f64 {
    ((rng.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

/// Shot noise term in DN for signal `s` DN above black.
#[inline]
fn shot(s: f64, k: f64, poisson_max: f64, rng: &mut SiteRng) -> f64 {
    if s.is_nan() || s <= 0.0 {
        return if s.is_nan() { 0.0 } else { s };
    }
    let e = s / k;
    if e <= poisson_max {
        match Poisson::new(e) {
            Ok(p) => {
                let n: f64 = p.sample(rng);
                k * n
            }
            // e underflowed to 0 (s tiny against K): no electron.
            Err(_) => 0.0,
        }
    } else {
        let z: f64 = StandardNormal.sample(rng);
        s + (k * s).sqrt() * z
    }
}

/// Precomputed per-call constants.
struct Sampler {
    k: f64,
    poisson_max: f64,
    sigma_read: f64,
    lambda: f64,
    gaussian: bool,
    /// `sigma_read / sd(lambda)`.
    read_scale: f64,
    sigma_row: f64,
}

impl Sampler {
    fn new(p: &PhysicsParams) -> Result<Sampler> {
        p.check("physics noise")?;
        Ok(Sampler {
            k: p.k,
            poisson_max: p.poisson_max_electrons,
            sigma_read: p.sigma_read,
            lambda: p.lambda,
            gaussian: p.gaussian_read,
            read_scale: if p.gaussian_read {
                0.0
            } else {
                p.sigma_read / tukey::std_dev(p.lambda)
            },
            sigma_row: p.sigma_row,
        })
    }
    #[inline]
    fn read(&self, rng: &mut SiteRng) -> f64 {
        if self.sigma_read == 0.0 {
            0.0
        } else if self.gaussian {
            let z: f64 = StandardNormal.sample(rng);
            self.sigma_read * z
        } else {
            self.read_scale * tukey::quantile(open01(rng), self.lambda)
        }
    }
}

/// The row offset (DN) of active-area row `r`.
fn row_offset(key: &[u8; 32], r: usize, sigma_row: f64) -> f64 {
    let mut rng = ChaCha8Rng::from_seed(*key);
    rng.set_stream(r as u64);
    let mut site = SiteRng(rng.next_u64());
    let z: f64 = StandardNormal.sample(&mut site);
    sigma_row * z
}

/// Noisy samples of the active-area region `rows` x `cols` (active-area coordinates) of
/// `clean` (linear values: no LinearizationTable), row-major, `rows.len() * cols.len()`
/// values. The same site gets the same value whatever the region and thread count.
pub fn apply_physics_noise(
    clean: &RawImage,
    params: &PhysicsParams,
    seed: u64,
    rows: Range<usize>,
    cols: Range<usize>,
) -> Result<Vec<u16>> {
    let norm = Normalizer::new(clean)?;
    if !norm.is_identity() {
        return Err(Error::unsupported(
            "physics noise needs linear values (the clean raw has a LinearizationTable)",
        ));
    }
    let a = clean.active_area();
    let (top, left, ah, aw) = (a.top as usize, a.left as usize, a.height(), a.width());
    if rows.start > rows.end || cols.start > cols.end || rows.end > ah || cols.end > aw {
        return Err(Error::invalid(format!(
            "physics noise region rows {:?} cols {:?} outside the {}x{} active area",
            rows, cols, aw, ah
        )));
    }
    let src = |r: usize| &clean.data[(top + r) * clean.width + left..][..aw];
    noise_region(&norm, aw, params, seed, rows, cols, 0, &src)
}

/// [`apply_physics_noise`] on a crop held as a plane of its own: `plane` holds the clean
/// samples of the active-area rectangle `crop` (row-major) of a frame whose levels are
/// `frame`'s (a LinearizationTable of its metadata is ignored: clean samples are linear).
/// The result equals [`apply_physics_noise`] on the whole frame's clean raw at the crop's
/// sites (every site draws at its frame position).
pub fn apply_physics_noise_crop(
    frame: &RawImage,
    crop: &crate::synth::crop::Crop,
    plane: &[u16],
    params: &PhysicsParams,
    seed: u64,
) -> Result<Vec<u16>> {
    let a = frame.active_area();
    crop.check(a.width(), a.height())?;
    if plane.len() != crop.width * crop.height {
        return Err(Error::invalid("the crop's plane does not match the crop"));
    }
    let norm = Normalizer::new(frame)?.without_linearization();
    let src = |r: usize| &plane[(r - crop.top) * crop.width..][..crop.width];
    noise_region(
        &norm,
        a.width(),
        params,
        seed,
        crop.rows(),
        crop.cols(),
        crop.left,
        &src,
    )
}

/// The noisy samples of active-area `rows` x `cols`; `src(r)` is the clean row `r` from
/// active-area column `src_left` on.
#[allow(clippy::too_many_arguments)]
fn noise_region<'a>(
    norm: &Normalizer,
    aw: usize,
    params: &PhysicsParams,
    seed: u64,
    rows: Range<usize>,
    cols: Range<usize>,
    src_left: usize,
    src: &(dyn Fn(usize) -> &'a [u16] + Sync),
) -> Result<Vec<u16>> {
    let s = Sampler::new(params)?;
    let white = norm.white.min(u16::MAX as f64);
    let key = physics_key(seed);
    let w = cols.len();
    let mut out = crate::limits::try_filled(0u16, rows.len() * w, "a noisy raw")?;
    if w == 0 {
        return Ok(out);
    }
    out.par_chunks_mut(w)
        .zip(rows.clone().into_par_iter())
        .for_each_init(
            || vec![0.0f64; aw],
            |blk, (dst, r)| {
                let row_dn = row_offset(&key, r, s.sigma_row);
                let mut rng = ChaCha8Rng::from_seed(key);
                rng.set_stream(r as u64);
                rng.set_word_pos(2 * (cols.start as u128 + 1));
                norm.black_row(r, &mut blk[..cols.end]);
                let srow = src(r);
                for (c, o) in cols.clone().zip(dst.iter_mut()) {
                    let mut site = SiteRng(rng.next_u64());
                    let b = blk[c];
                    let x = srow[c - src_left] as f64;
                    let v = b + shot(x - b, s.k, s.poisson_max, &mut site) + s.read(&mut site);
                    *o = round_clamp(v + row_dn, white);
                }
            },
        );
    Ok(out)
}

/// A noisy copy of the whole image: [`apply_physics_noise`] over the active area, samples
/// outside it copied unchanged.
pub fn apply_physics_noise_image(
    clean: &RawImage,
    params: &PhysicsParams,
    seed: u64,
) -> Result<RawImage> {
    let a = clean.active_area();
    let (top, left, ah, aw) = (a.top as usize, a.left as usize, a.height(), a.width());
    let noisy = apply_physics_noise(clean, params, seed, 0..ah, 0..aw)?;
    let mut data = clean.data.clone();
    if aw > 0 {
        for (r, src) in noisy.chunks_exact(aw).enumerate() {
            data[(top + r) * clean.width + left..][..aw].copy_from_slice(src);
        }
    }
    Ok(RawImage {
        width: clean.width,
        height: clean.height,
        data,
        meta: clean.meta.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::Bayer;

    fn flat(w: usize, h: usize, v: u16) -> RawImage {
        RawImage {
            width: w,
            height: h,
            data: vec![v; w * h],
            meta: RawMeta::new_bayer(Bayer::RGGB, 14, 512.0, 16383.0),
        }
    }

    fn params(k: f64, read: f64, lambda: f64, row: f64) -> PhysicsParams {
        PhysicsParams {
            k,
            sigma_read: read,
            lambda,
            gaussian_read: false,
            sigma_row: row,
            poisson_max_electrons: 1000.0,
        }
    }

    fn ramp(w: usize, h: usize) -> RawImage {
        let mut img = flat(w, h, 0);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = ((i * 7919) % 17000) as u16;
        }
        img
    }

    #[test]
    fn crops_equal_the_full_frame_and_threads_do_not_matter() {
        let img = ramp(41, 23);
        let p = params(1.3, 3.0, -0.1, 2.0);
        let full = apply_physics_noise(&img, &p, 5, 0..23, 0..41).unwrap();
        let crop = apply_physics_noise(&img, &p, 5, 3..17, 7..30).unwrap();
        for (i, r) in (3..17).enumerate() {
            assert_eq!(&crop[i * 23..][..23], &full[r * 41 + 7..][..23]);
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let one = pool.install(|| apply_physics_noise(&img, &p, 5, 0..23, 0..41).unwrap());
        assert_eq!(one, full);
        assert_ne!(
            apply_physics_noise(&img, &p, 6, 0..23, 0..41).unwrap(),
            full
        );
        assert!(apply_physics_noise(&img, &p, 5, 0..24, 0..41).is_err());
        assert!(apply_physics_noise(&img, &p, 5, 0..0, 0..41)
            .unwrap()
            .is_empty());
    }

    #[test]
    fn zero_noise_is_identity_and_clipping_holds() {
        let img = ramp(16, 8);
        let out = apply_physics_noise_image(&img, &params(1e-6, 0.0, 0.0, 0.0), 1).unwrap();
        // K tiny: shot std sqrt(1e-6 s) < 0.13 DN: rounds back (values clipped to white)
        // but for rare draws beyond 3.9 sigma.
        let same = out
            .data
            .iter()
            .zip(&img.data)
            .filter(|(a, b)| **a == (**b).min(16383));
        assert!(same.count() >= img.data.len() - 2);
        for (a, b) in out.data.iter().zip(&img.data) {
            assert!((*a as i32 - (*b).min(16383) as i32).abs() <= 1);
        }
        let img = flat(32, 32, 16383);
        let out = apply_physics_noise_image(&img, &params(4.0, 5.0, 0.1, 1.0), 1).unwrap();
        assert!(out.data.iter().all(|&v| v <= 16383));
        assert!(out.data.iter().any(|&v| v < 16383));
    }

    #[test]
    fn extreme_parameters_are_finite() {
        let img = ramp(32, 16);
        for p in [
            params(1e-6, 0.0, 0.0, 0.0),
            params(1e6, 1.0, 0.0, 0.0),
            params(1.0, 1e6, -0.24, 1e6),
            params(1.0, 2.0, 1e-12, 0.0),
            params(1.0, 2.0, 1.0, 0.0),
        ] {
            let out = apply_physics_noise_image(&img, &p, 3).unwrap();
            assert!(out.data.iter().all(|&v| v <= 16383));
        }
        // K huge: at most a few electrons; a dark site with s < K gets 0 or K electrons.
        let mut p = params(1e6, 0.0, 0.0, 0.0);
        p.poisson_max_electrons = 1e12;
        let img = flat(64, 64, 600);
        let out = apply_physics_noise_image(&img, &p, 3).unwrap();
        assert!(out.data.iter().all(|&v| v == 512 || v == 16383));
        assert!(apply_physics_noise_image(&img, &params(0.0, 1.0, 0.0, 0.0), 1).is_err());
        assert!(apply_physics_noise_image(&img, &params(1.0, f64::NAN, 0.0, 0.0), 1).is_err());
        let mut p = params(1.0, 1.0, 0.0, 0.0);
        p.poisson_max_electrons = f64::INFINITY;
        assert!(apply_physics_noise_image(&img, &p, 1).is_err());
    }

    #[test]
    fn shot_term_mean_and_variance() {
        // Exact and approximate branches both give mean s and variance K s.
        for (s, k, n) in [
            (3.0, 0.5, 1000.0),
            (3000.0, 2.0, 1000.0),
            (3000.0, 2.0, 1e9),
        ] {
            let mut rng = SiteRng(42);
            let m = 200_000;
            let v: Vec<f64> = (0..m).map(|_| shot(s, k, n, &mut rng)).collect();
            let mean = v.iter().sum::<f64>() / m as f64;
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (m - 1) as f64;
            assert!((mean / s - 1.0).abs() < 0.01, "{s} {k} {mean}");
            assert!((var / (k * s) - 1.0).abs() < 0.02, "{s} {k} {var}");
        }
        let mut rng = SiteRng(1);
        assert_eq!(shot(0.0, 1.0, 10.0, &mut rng), 0.0);
        assert_eq!(shot(-3.0, 1.0, 10.0, &mut rng), -3.0);
        assert_eq!(shot(f64::NAN, 1.0, 10.0, &mut rng), 0.0);
    }
}
