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
//! domain tag, stream number = row) gives two `u64`: the first seeds the row offset's normal
//! draw, the second `k_r` seeds the row's SplitMix64 sequence. Site `c` takes that
//! sequence's output `c + 1`, `w = mix(k_r + (c + 1) gamma)` (random access: no need to
//! generate the sites before it): a tabulated shot draw uses `w` itself, and the rest of
//! the site's draws (the read noise; an untabulated shot draw, which may take several
//! uniforms) come from a SplitMix64 generator seeded with `w`. So any crop (rows x cols)
//! gives the same samples as the whole frame at the same sites, for any thread count.
//! (Issue 20: the previous layout read each site's word from the ChaCha stream; SplitMix64
//! gives it in a third of the instructions.)

use super::physics::PhysicsParams;
use super::poisson_table::{LevelTables, ShotTables};
use super::tukey;
use super::tukey_table::TukeyTable;
use crate::error::{Error, Result};
#[cfg(test)]
use crate::normalize::round_clamp;
use crate::normalize::Normalizer;
use crate::raw::rows::{ActiveRowMap, MappedRows, RowSource};
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
    h.update(b"day2night physics noise rows v2\0");
    h.update(seed.to_le_bytes());
    h.finalize().into()
}

/// SplitMix64's increment (the golden ratio in 64-bit fixed point).
const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function of state `z`.
#[inline(always)]
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// SplitMix64 (Steele, Lea, Flood 2014): a small generator, one per row (its outputs are
/// the sites' words) and one per site (seeded with the site's word).
struct SiteRng(u64);

impl TryRng for SiteRng {
    type Error = Infallible;
    #[inline]
    fn try_next_u32(&mut self) -> std::result::Result<u32, Infallible> {
        Ok((self.try_next_u64()? >> 32) as u32)
    }
    #[inline]
    fn try_next_u64(&mut self) -> std::result::Result<u64, Infallible> {
        self.0 = self.0.wrapping_add(GAMMA);
        Ok(mix(self.0))
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> std::result::Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let v = self.try_next_u64()?.to_le_bytes();
            chunk.copy_from_slice(&v[..chunk.len()]);
        }
        Ok(())
    }
}

/// Shot noise term in DN for signal `s` DN above black, without a table: an exact
/// `rand_distr::Poisson` draw at or below `poisson_max` electrons, the normal approximation
/// above.
#[inline(never)]
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

/// Precomputed per-call constants and tables.
struct Sampler {
    k: f64,
    poisson_max: f64,
    sigma_read: f64,
    sigma_row: f64,
    /// `sigma_read * Q_lambda / sd(lambda)` tabulated (Tukey read noise, sigma_read > 0).
    tukey: Option<TukeyTable>,
    /// Inverse-CDF tables of the shot noise (black level periodic over the 2x2 tile).
    shots: Option<ShotTables>,
    /// White level (at most 65535) and `white as u32`.
    white: f64,
    white_u: u32,
}

impl Sampler {
    fn new(p: &PhysicsParams, norm: &Normalizer, white: f64) -> Result<Sampler> {
        p.check("physics noise")?;
        let tukey = (!p.gaussian_read && p.sigma_read > 0.0)
            .then(|| TukeyTable::new(p.lambda, p.sigma_read / tukey::std_dev(p.lambda)));
        let shots = norm.black_is_2x2_periodic().then(|| {
            let blacks = std::array::from_fn(|pos| norm.black_at(pos >> 1, pos & 1));
            ShotTables::new(p.k, p.poisson_max_electrons, blacks, white as usize)
        });
        Ok(Sampler {
            k: p.k,
            poisson_max: p.poisson_max_electrons,
            sigma_read: p.sigma_read,
            sigma_row: p.sigma_row,
            tukey,
            shots,
            white,
            white_u: white as u32,
        })
    }

    /// The noisy value of a site: stored value `x`, black `b`, tables `level`, row offset
    /// `row_dn`, the site's random word `word` (module docs); `read` draws the read noise
    /// in DN.
    #[inline(always)]
    fn site<R: Fn(&mut SiteRng) -> f64>(
        &self,
        read: &R,
        word: u64,
        x: u16,
        b: f64,
        level: Option<&LevelTables>,
        row_dn: f64,
    ) -> u16 {
        let mut site = SiteRng(word);
        let shot = match level.and_then(|l| l.get(x)) {
            Some(t) => self.k * t.sample(word),
            None => shot(x as f64 - b, self.k, self.poisson_max, &mut site),
        };
        let v = b + shot + read(&mut site);
        round_clamp_to(v + row_dn, self.white, self.white_u)
    }
}

/// `sigma * z`, `z ~ N(0, 1)` (0 when `sigma` is 0: no draw).
#[inline(never)]
fn gaussian_read(sigma: f64, rng: &mut SiteRng) -> f64 {
    if sigma == 0.0 {
        0.0
    } else {
        let z: f64 = StandardNormal.sample(rng);
        sigma * z
    }
}

/// [`round_clamp`] with `white as u32` precomputed (`white_u`): the same value for every
/// `v` (unit test), without a float-to-integer conversion of `white` per sample.
#[inline(always)]
fn round_clamp_to(v: f64, white: f64, white_u: u32) -> u16 {
    if v.is_nan() || v < 0.5 {
        0
    } else if v >= white {
        white_u as u16
    } else {
        // 0.5 <= v < white <= 65535: v + 0.5 fits an i32 (a one-instruction conversion)
        ((v + 0.5) as i32 as u32).min(white_u) as u16
    }
}

/// The row offset (DN) of active-area row `r` and the seed `k_r` of its sites' words.
fn row_draws(key: &[u8; 32], r: usize, sigma_row: f64) -> (f64, u64) {
    let mut rng = ChaCha8Rng::from_seed(*key);
    rng.set_stream(r as u64);
    let mut site = SiteRng(rng.next_u64());
    let z: f64 = StandardNormal.sample(&mut site);
    (sigma_row * z, rng.next_u64())
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
    let norm = linear_normalizer(clean)?;
    let a = clean.active_area();
    let (top, left, ah, aw) = (a.top as usize, a.left as usize, a.height(), a.width());
    if rows.start > rows.end || cols.start > cols.end || rows.end > ah || cols.end > aw {
        return Err(Error::invalid(format!(
            "physics noise region rows {:?} cols {:?} outside the {}x{} active area",
            rows, cols, aw, ah
        )));
    }
    let src = |r: usize| &clean.data[(top + r) * clean.width + left..][..aw];
    let w = cols.len();
    let region = Region::new(&norm, aw, params, seed, cols, 0, &src)?;
    let mut out = crate::limits::try_filled(0u16, rows.len() * w, "a noisy raw")?;
    region.noise_rows(rows, &mut out, w, 0);
    Ok(out)
}

/// The clean raw's normalizer, refused when the raw is not linear.
fn linear_normalizer(clean: &RawImage) -> Result<Normalizer> {
    let norm = Normalizer::new(clean)?;
    if !norm.is_identity() {
        return Err(Error::unsupported(
            "physics noise needs linear values (the clean raw has a LinearizationTable)",
        ));
    }
    Ok(norm)
}

/// [`apply_physics_noise`] on a crop held as a plane of its own: `plane` holds the clean
/// samples of the active-area rectangle `crop` (row-major) of a frame whose levels are
/// `frame`'s (a LinearizationTable of its metadata is ignored: clean samples are linear).
/// The result equals [`apply_physics_noise`] on the whole frame's clean raw at the crop's
/// sites (every site draws at its frame position).
pub fn apply_physics_noise_crop(
    frame: &RawImage,
    crop: &crate::raw::crop::Crop,
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
    let region = Region::new(&norm, a.width(), params, seed, crop.cols(), crop.left, &src)?;
    let w = crop.width;
    let mut out = crate::limits::try_filled(0u16, crop.height * w, "a noisy raw")?;
    region.noise_rows(crop.rows(), &mut out, w, 0);
    Ok(out)
}

/// The noise of the active-area columns `cols` of any rows; `src(r)` is the clean row `r`
/// from active-area column `src_left` on.
struct Region<'a, 'n> {
    norm: &'n Normalizer,
    aw: usize,
    sampler: Sampler,
    key: [u8; 32],
    cols: Range<usize>,
    src_left: usize,
    src: &'n (dyn Fn(usize) -> &'a [u16] + Sync),
}

impl<'a, 'n> Region<'a, 'n> {
    fn new(
        norm: &'n Normalizer,
        aw: usize,
        params: &PhysicsParams,
        seed: u64,
        cols: Range<usize>,
        src_left: usize,
        src: &'n (dyn Fn(usize) -> &'a [u16] + Sync),
    ) -> Result<Region<'a, 'n>> {
        let white = norm.white.min(u16::MAX as f64);
        Ok(Region {
            norm,
            aw,
            sampler: Sampler::new(params, norm, white)?,
            key: physics_key(seed),
            cols,
            src_left,
            src,
        })
    }

    /// Noise active-area rows `rows` into `dst`: row `rows.start + i` goes to
    /// `dst[i * stride + dst_left..][..cols.len()]`.
    fn noise_rows(&self, rows: Range<usize>, dst: &mut [u16], stride: usize, dst_left: usize) {
        let w = self.cols.len();
        if w == 0 || stride == 0 {
            return;
        }
        dst.par_chunks_mut(stride)
            .zip(rows.into_par_iter())
            .for_each_init(
                || vec![0.0f64; self.aw],
                |blk, (line, r)| self.noise_one_row(r, &mut line[dst_left..][..w], blk),
            );
    }

    /// Noise active-area row `r` into `out` (its `cols`); `blk` is scratch of the
    /// active-area width.
    fn noise_one_row(&self, r: usize, out: &mut [u16], blk: &mut [f64]) {
        let xs = &(self.src)(r)[self.cols.start - self.src_left..][..self.cols.len()];
        self.noise_one_row_from(r, xs, out, blk);
    }

    /// [`Region::noise_one_row`] of the clean samples `xs` (the region's columns of row
    /// `r`).
    fn noise_one_row_from(&self, r: usize, xs: &[u16], out: &mut [u16], blk: &mut [f64]) {
        let s = &self.sampler;
        // one copy of the row loop per kind of read noise
        match &s.tukey {
            Some(t) => self.noise_row(r, xs, out, blk, &|g| t.sample(g.next_u64())),
            None => self.noise_row(r, xs, out, blk, &|g| gaussian_read(s.sigma_read, g)),
        }
    }

    /// Noise active-area row `r` into `out` (its `cols`); `blk` is scratch of the
    /// active-area width.
    #[inline(always)]
    fn noise_row<R: Fn(&mut SiteRng) -> f64>(
        &self,
        r: usize,
        xs: &[u16],
        out: &mut [u16],
        blk: &mut [f64],
        read: &R,
    ) {
        let s = &self.sampler;
        let cols = self.cols.clone();
        let w = cols.len();
        let (row_dn, row_seed) = row_draws(&self.key, r, s.sigma_row);
        // the row's SplitMix64 positioned before site cols.start
        let start = (cols.start as u64).wrapping_mul(GAMMA);
        let mut rng = SiteRng(row_seed.wrapping_add(start));
        let mut site_at = |x: u16, b: f64, level: Option<&LevelTables>| {
            s.site(read, rng.next_u64(), x, b, level, row_dn)
        };
        if let Some(t) = &s.shots {
            // black periodic over the 2x2 tile: the tables' levels, by parity
            let lv = |c: usize| t.level(crate::raw::Bayer::position(r, c));
            let (l0, l1) = (lv(cols.start), lv(cols.start + 1));
            let (b0, b1) = (l0.black(), l1.black());
            let mut pairs = out.chunks_exact_mut(2).zip(xs.chunks_exact(2));
            for (o, x) in &mut pairs {
                o[0] = site_at(x[0], b0, Some(l0));
                o[1] = site_at(x[1], b1, Some(l1));
            }
            if w % 2 == 1 {
                out[w - 1] = site_at(xs[w - 1], b0, Some(l0));
            }
        } else {
            self.norm.black_row(r, &mut blk[..cols.end]);
            for ((o, &x), &b) in out.iter_mut().zip(xs).zip(&blk[cols]) {
                *o = site_at(x, b, None);
            }
        }
    }
}

/// A noisy copy of the whole image: [`apply_physics_noise`] over the active area, samples
/// outside it copied unchanged.
pub fn apply_physics_noise_image(
    clean: &RawImage,
    params: &PhysicsParams,
    seed: u64,
) -> Result<RawImage> {
    let norm = linear_normalizer(clean)?;
    let a = clean.active_area();
    let (top, left, ah, aw) = (a.top as usize, a.left as usize, a.height(), a.width());
    let mut data = crate::limits::try_with_capacity::<u16>(clean.data.len(), "a noisy raw")?;
    data.extend_from_slice(&clean.data);
    let src = |r: usize| &clean.data[(top + r) * clean.width + left..][..aw];
    let region = Region::new(&norm, aw, params, seed, 0..aw, 0, &src)?;
    let width = clean.width;
    region.noise_rows(
        0..ah,
        &mut data[top * width..(top + ah) * width],
        width,
        left,
    );
    Ok(RawImage {
        width: clean.width,
        height: clean.height,
        data,
        meta: clean.meta.clone(),
    })
}

/// Hand `f` the noisy raw of [`apply_physics_noise_image`] as rows made on demand: the
/// same samples, row by row, without a noisy plane (the DNG writer packs them strip by
/// strip). The sampler's tables are built once, before `f` runs.
pub fn with_physics_rows<T>(
    clean: &RawImage,
    params: &PhysicsParams,
    seed: u64,
    f: impl FnOnce(&dyn RowSource) -> Result<T>,
) -> Result<T> {
    let norm = linear_normalizer(clean)?;
    let a = clean.active_area();
    let (top, left, aw) = (a.top as usize, a.left as usize, a.width());
    let src = |r: usize| &clean.data[(top + r) * clean.width + left..][..aw];
    let region = Region::new(&norm, aw, params, seed, 0..aw, 0, &src)?;
    f(&MappedRows::new(clean, PhysicsMap(&region)))
}

/// Hand `f` the physics noise as an [`ActiveRowMap`] that noises the clean samples it is
/// handed in place (e.g. a burst frame's warped clean row), with `clean`'s levels: the
/// samples [`with_physics_rows`] gives for a clean row equal to the one handed over.
pub fn with_physics_map<T>(
    clean: &RawImage,
    params: &PhysicsParams,
    seed: u64,
    f: impl FnOnce(&dyn ActiveRowMap) -> Result<T>,
) -> Result<T> {
    let norm = linear_normalizer(clean)?;
    let aw = clean.active_area().width();
    let none = |_: usize| -> &[u16] { &[] };
    let region = Region::new(&norm, aw, params, seed, 0..aw, 0, &none)?;
    f(&PhysicsInPlace(&region))
}

/// The physics noise of the samples handed over (an [`ActiveRowMap`] reading its input).
struct PhysicsInPlace<'r, 'a, 'n>(&'r Region<'a, 'n>);

impl ActiveRowMap for PhysicsInPlace<'_, '_, '_> {
    fn map_row(&self, r: usize, seg: &mut [u16], scratch: &mut Vec<f64>) {
        scratch.resize(self.0.aw, 0.0);
        let clean = seg.to_vec();
        self.0.noise_one_row_from(r, &clean, seg, scratch);
    }
    fn bound(&self) -> u16 {
        self.0.norm.white.min(u16::MAX as f64) as u16
    }
}

/// The physics noise of the active-area rows (an [`ActiveRowMap`]).
struct PhysicsMap<'r, 'a, 'n>(&'r Region<'a, 'n>);

impl ActiveRowMap for PhysicsMap<'_, '_, '_> {
    fn map_row(&self, r: usize, seg: &mut [u16], scratch: &mut Vec<f64>) {
        scratch.resize(self.0.aw, 0.0);
        self.0.noise_one_row(r, seg, scratch);
    }
    /// Noisy samples are clipped to the white level.
    fn bound(&self) -> u16 {
        self.0.norm.white.min(u16::MAX as f64) as u16
    }
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
    fn rows_on_demand_equal_the_whole_image_for_any_chunking() {
        let mut img = ramp(37, 23);
        img.meta.active_area = Some(crate::raw::Rect {
            top: 2,
            left: 4,
            bottom: 21,
            right: 34,
        });
        for p in [params(2.0, 3.0, 0.0, 1.5), params(0.5, 1.0, 0.14, 0.0)] {
            let whole = apply_physics_noise_image(&img, &p, 9).unwrap();
            with_physics_rows(&img, &p, 9, |rows| {
                assert_eq!(crate::raw::rows::to_plane(rows)?, whole.data);
                assert!(whole.data.iter().all(|&v| v <= rows.max_bound()));
                // odd chunks, one at a time
                let mut out = vec![0u16; 37 * 23];
                for (k, chunk) in out.chunks_mut(37 * 5).enumerate() {
                    rows.fill_rows(k * 5, chunk);
                }
                assert_eq!(out, whole.data);
                Ok(())
            })
            .unwrap();
        }
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
    fn round_clamp_to_equals_round_clamp() {
        for white in [1023.0, 16383.0, 65535.0, 1000.5, 0.0] {
            let wu = white as u32;
            let mut vs = vec![f64::NAN, -1.0, 0.0, 0.49999999, 0.5, 1.5, 2.5, white - 0.5];
            vs.extend([white, white + 0.3, 1e300, f64::INFINITY, f64::NEG_INFINITY]);
            vs.extend((0..200_000).map(|i| i as f64 * 0.3371 - 100.0));
            for v in vs {
                assert_eq!(
                    round_clamp_to(v, white, wu),
                    round_clamp(v, white),
                    "{v} {white}"
                );
            }
        }
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
