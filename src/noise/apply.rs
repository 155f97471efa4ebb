//! Adding heteroscedastic Gaussian noise to a clean raw mosaic (docs/synthesis.md, "7. Noise"):
//! `x_noisy = clip(round(x + N(0, max(0, var(x)))), 0, white)` in DN, where
//! `var(x) = (S * y + O) * (white - black_max)^2` and `y = (x - black(site)) / (white - black_max)`.
//!
//! With `truncate` (the authors' release, `SynthOptions::compat.truncate_noise`) the sum is
//! truncated instead of rounded: `clip(trunc(x + n), 0, white)`, a -0.5 DN bias.
//!
//! Each active-area row draws from its own stream, keyed by the plan's noise seed and the
//! row ([`super::stream`]: version 2, xoshiro256++ with the row's normals drawn at once, or
//! version 1, ChaCha8 with stream number = row), so the result does not depend on how rayon
//! splits the rows.

use super::model::NoiseParams;
use super::stream::{fill_normals_v2, row_rng_v1, stream_key, NoiseStream};
use crate::error::Result;
use crate::normalize::{round_clamp, Normalizer, RoundClamp};
use crate::raw::crop::Crop;
use crate::raw::rows::{ActiveRowMap, MappedRows};
use crate::raw::{Bayer, RawImage};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

/// The 32-byte ChaCha key of a noise seed (stream version 1).
pub fn noise_key(seed: u64) -> [u8; 32] {
    stream_key(NoiseStream::V1, false, seed, &[])
}

/// The random stream of active-area row `row` (stream version 1).
pub fn row_rng(key: &[u8; 32], row: usize) -> ChaCha8Rng {
    row_rng_v1(key, row)
}

/// Per-site noise standard deviation in DN, `sqrt(var_norm(pos, (x - black) / scale) * scale^2)`,
/// tabulated for every stored value `x <= white` of each 2x2 position when the black level
/// depends on the 2x2 position only (no BlackLevelDeltaH/V, repeat dims 1 or 2: the usual
/// case). The table entries are computed with exactly the per-sample expression, so the
/// noisy bytes are the same as without it; it replaces a division, a multiply-add, a branch
/// and a square root per sample by one load.
struct SigmaTable {
    len: usize,
    sigma: [Vec<f64>; 4],
}

impl SigmaTable {
    fn new(norm: &Normalizer, params: &NoiseParams, white: f64) -> Option<SigmaTable> {
        if !norm.black_is_2x2_periodic() {
            return None;
        }
        let scale = norm.scale;
        let scale2 = scale * scale;
        let len = (white.max(0.0) as usize).saturating_add(1).min(1 << 16);
        let sigma = std::array::from_fn(|pos| {
            let b = norm.black_at(pos >> 1, pos & 1);
            (0..len)
                .map(|x| {
                    let y = (x as f64 - b) / scale;
                    (params.var_norm(pos, y) * scale2).sqrt()
                })
                .collect()
        });
        Some(SigmaTable { len, sigma })
    }
}

/// `v` truncated toward zero and clipped to `[0, white]` (NaN gives 0): the release's
/// `astype(uint16)` of a clipped value.
#[inline]
pub fn trunc_clamp(v: f64, white: f64) -> u16 {
    let v = v.trunc();
    if v.is_nan() {
        0
    } else {
        v.clamp(0.0, white) as u16
    }
}

/// A noisy copy of `clean` (which must hold linear values: no LinearizationTable), drawn
/// from the default stream ([`NoiseStream::V2`]). Samples outside the ActiveArea are copied
/// unchanged.
pub fn apply_noise(clean: &RawImage, params: &NoiseParams, seed: u64) -> Result<RawImage> {
    apply_noise_with(clean, params, seed, false)
}

/// [`apply_noise`], the noisy sum truncated instead of rounded when `truncate`.
pub fn apply_noise_with(
    clean: &RawImage,
    params: &NoiseParams,
    seed: u64,
    truncate: bool,
) -> Result<RawImage> {
    apply_noise_stream(clean, params, seed, truncate, NoiseStream::default())
}

/// [`apply_noise_with`] drawing from `stream`.
pub fn apply_noise_stream(
    clean: &RawImage,
    params: &NoiseParams,
    seed: u64,
    truncate: bool,
    stream: NoiseStream,
) -> Result<RawImage> {
    let rows = gaussian_rows(clean, params, seed, truncate, stream)?;
    Ok(RawImage {
        width: clean.width,
        height: clean.height,
        data: crate::raw::rows::to_plane(&rows)?,
        meta: clean.meta.clone(),
    })
}

/// The noisy raw of [`apply_noise_stream`] as rows made on demand: the same samples, row by
/// row, without a noisy plane (the DNG writer packs them strip by strip).
pub type GaussianRows<'a> = MappedRows<'a, GaussianMap<'a>>;

/// The Gaussian noise of the active-area rows (an [`ActiveRowMap`]).
pub struct GaussianMap<'a> {
    rows: RowNoise<'a>,
    key: [u8; 32],
    stream: NoiseStream,
}

/// The noisy rows of `clean` (which must hold linear values) under `params` and `seed`,
/// drawn from `stream`.
pub fn gaussian_rows<'a>(
    clean: &'a RawImage,
    params: &'a NoiseParams,
    seed: u64,
    truncate: bool,
    stream: NoiseStream,
) -> Result<GaussianRows<'a>> {
    Ok(MappedRows::new(
        clean,
        gaussian_map(clean, params, seed, truncate, stream)?,
    ))
}

/// The Gaussian noise of [`gaussian_rows`] as an [`ActiveRowMap`] that noises any active-area
/// row handed to it (e.g. a burst frame's warped clean row) with `clean`'s levels, drawing
/// row `r` from row `r`'s stream of `seed`'s key.
pub fn gaussian_map<'a>(
    clean: &RawImage,
    params: &'a NoiseParams,
    seed: u64,
    truncate: bool,
    stream: NoiseStream,
) -> Result<GaussianMap<'a>> {
    let mut rows = RowNoise::new(clean, params)?;
    rows.truncate = truncate;
    Ok(GaussianMap {
        rows,
        key: stream_key(stream, false, seed, &[]),
        stream,
    })
}

impl ActiveRowMap for GaussianMap<'_> {
    fn map_row(&self, r: usize, seg: &mut [u16], scratch: &mut Vec<f64>) {
        self.rows
            .row_from(self.stream, &self.key, (r, r), 0, seg, scratch);
    }
    /// Noisy samples are clipped to the white level.
    fn bound(&self) -> u16 {
        self.rows.white as u16
    }
}

/// The 32-byte ChaCha key of the noise of a crop (stream version 1): its own stream per
/// crop, keyed by the noise seed and the crop's rectangle (documented in docs/noise.md).
pub fn crop_noise_key(seed: u64, crop: &Crop) -> [u8; 32] {
    stream_key(NoiseStream::V1, true, seed, &crop_words(crop))
}

/// The rectangle of a crop as the key of its streams hashes it.
fn crop_words(crop: &Crop) -> [u64; 4] {
    [crop.top, crop.left, crop.height, crop.width].map(|v| v as u64)
}

/// Noise on a crop of a clean raw: `plane` holds the clean samples of the active-area
/// rectangle `crop` (row-major) and becomes noisy in place, with the same per-site model
/// as [`apply_noise`]; crop row `i` draws from row `i`'s stream of the crop's key (the seed
/// and the rectangle), so a crop's noise depends on (seed, crop) only, not on the thread
/// count. `frame` supplies the levels (a LinearizationTable of its metadata is ignored:
/// clean samples are linear). Draws from the default stream ([`NoiseStream::V2`]).
pub fn apply_noise_crop(
    frame: &RawImage,
    crop: &Crop,
    plane: &mut [u16],
    params: &NoiseParams,
    seed: u64,
) -> Result<()> {
    apply_noise_crop_with(frame, crop, plane, params, seed, false)
}

/// [`apply_noise_crop`], the noisy sum truncated instead of rounded when `truncate`.
pub fn apply_noise_crop_with(
    frame: &RawImage,
    crop: &Crop,
    plane: &mut [u16],
    params: &NoiseParams,
    seed: u64,
    truncate: bool,
) -> Result<()> {
    apply_noise_crop_stream(
        frame,
        crop,
        plane,
        params,
        (seed, truncate),
        NoiseStream::default(),
    )
}

/// [`apply_noise_crop_with`] of `(seed, truncate)`, drawing from `stream`.
pub fn apply_noise_crop_stream(
    frame: &RawImage,
    crop: &Crop,
    plane: &mut [u16],
    params: &NoiseParams,
    (seed, truncate): (u64, bool),
    stream: NoiseStream,
) -> Result<()> {
    let norm = Normalizer::new(frame)?.without_linearization();
    let mut rows = RowNoise::with(norm, params);
    rows.truncate = truncate;
    if plane.len() != crop.width * crop.height {
        return Err(crate::error::Error::invalid(format!(
            "crop plane holds {} samples, expected {}x{}",
            plane.len(),
            crop.height,
            crop.width
        )));
    }
    let key = stream_key(stream, true, seed, &crop_words(crop));
    let aw = frame.active_area().width();
    plane
        .par_chunks_mut(crop.width.max(1))
        .enumerate()
        .for_each_init(
            || Vec::with_capacity(2 * aw),
            |blk, (i, seg)| {
                rows.row_from(stream, &key, (crop.top + i, i), crop.left, seg, blk);
            },
        );
    Ok(())
}

/// The per-row noise of one model on one frame's levels.
struct RowNoise<'a> {
    norm: Normalizer,
    params: &'a NoiseParams,
    white: f64,
    table: Option<SigmaTable>,
    /// Truncate instead of rounding.
    truncate: bool,
}

impl<'a> RowNoise<'a> {
    fn new(clean: &RawImage, params: &'a NoiseParams) -> Result<RowNoise<'a>> {
        Ok(RowNoise::with(Normalizer::new(clean)?, params))
    }

    fn with(norm: Normalizer, params: &'a NoiseParams) -> RowNoise<'a> {
        let white = norm.white.min(u16::MAX as f64);
        let table = SigmaTable::new(&norm, params, white);
        RowNoise {
            norm,
            params,
            white,
            table,
            truncate: false,
        }
    }

    /// Noise on `seg`, the samples of active-area row `r` from column `x0` (even), drawn
    /// from row `sr` of `key`'s `stream` (`sr` = `r` for whole images, the crop row for
    /// crops); `scratch` is reused between rows.
    fn row_from(
        &self,
        stream: NoiseStream,
        key: &[u8; 32],
        rows: (usize, usize),
        x0: usize,
        seg: &mut [u16],
        scratch: &mut Vec<f64>,
    ) {
        noise_row_from(self, stream, key, rows, x0, seg, scratch);
    }

    /// [`RowNoise::row_from`]'s body.
    #[inline(always)]
    fn row_from_body(
        &self,
        stream: NoiseStream,
        key: &[u8; 32],
        (r, sr): (usize, usize),
        x0: usize,
        seg: &mut [u16],
        scratch: &mut Vec<f64>,
    ) {
        // the black levels of columns 0..x0 + len when there is no sigma table
        let bl = if self.table.is_none() {
            x0 + seg.len()
        } else {
            0
        };
        match stream {
            NoiseStream::V1 => {
                scratch.resize(bl, 0.0);
                let mut rng = row_rng_v1(key, sr);
                self.row(r, x0, seg, scratch, |_| draw(&mut rng));
            }
            NoiseStream::V2 => {
                scratch.resize(bl + seg.len(), 0.0);
                let (blk, normals) = scratch.split_at_mut(bl);
                fill_normals_v2(key, sr, normals);
                match &self.table {
                    Some(t) if !self.truncate => self.row_table(t, r, x0, seg, normals),
                    _ => self.row(r, x0, seg, blk, |i| normals[i]),
                }
            }
        }
    }

    /// [`RowNoise::row`]'s sigma-table path with rounding, in two passes: the normals are
    /// scaled by each sample's sigma in place (a table lookup per sample), then every
    /// sample gets its scaled normal and is rounded ([`RoundClamp`]: a loop the compiler
    /// turns into whole-register operations). The same products and sums, so the same bits.
    #[inline(always)]
    fn row_table(&self, t: &SigmaTable, r: usize, x0: usize, seg: &mut [u16], normals: &mut [f64]) {
        let (norm, params) = (&self.norm, self.params);
        let scale = norm.scale;
        let scale2 = scale * scale;
        let p0 = Bayer::position(r, x0);
        let (s0, s1): (&[f64], &[f64]) = (&t.sigma[p0], &t.sigma[p0 ^ 1]);
        for (i, (&x, n)) in seg.iter().zip(normals.iter_mut()).enumerate() {
            let s = if i & 1 == 0 { s0 } else { s1 };
            let sigma = match s.get(x as usize) {
                Some(&v) => v,
                None => {
                    let c = x0 + i;
                    let y = (x as f64 - norm.black_at(r, c)) / scale;
                    (params.var_norm(Bayer::position(r, c), y) * scale2).sqrt()
                }
            };
            *n *= sigma;
        }
        let round = RoundClamp::new(self.white);
        for (x, &d) in seg.iter_mut().zip(normals.iter()) {
            *x = round.apply(*x as f64 + d);
        }
    }

    /// Noise on `seg` (see [`RowNoise::row_from`]), sample `i` with normal `normal(i)`
    /// (called once per sample, in order); `blk` is scratch of at least `x0 + seg.len()`
    /// values when there is no sigma table.
    #[inline(always)]
    fn row(
        &self,
        r: usize,
        x0: usize,
        seg: &mut [u16],
        blk: &mut [f64],
        mut normal: impl FnMut(usize) -> f64,
    ) {
        let (norm, params, white) = (&self.norm, self.params, self.white);
        let quantize = |v: f64| {
            if self.truncate {
                trunc_clamp(v, white)
            } else {
                round_clamp(v, white)
            }
        };
        let scale = norm.scale;
        let scale2 = scale * scale;
        if let Some(t) = &self.table {
            // even and odd columns of this row: positions (r&1)*2 and (r&1)*2+1
            let p0 = Bayer::position(r, x0);
            let (s0, s1) = (&t.sigma[p0], &t.sigma[p0 ^ 1]);
            for (i, x) in seg.iter_mut().enumerate() {
                let s = if i & 1 == 0 { s0 } else { s1 };
                let xi = *x as usize;
                let sigma = if xi < t.len {
                    s[xi]
                } else {
                    let c = x0 + i;
                    let y = (*x as f64 - norm.black_at(r, c)) / scale;
                    (params.var_norm(Bayer::position(r, c), y) * scale2).sqrt()
                };
                let n = normal(i);
                *x = quantize(*x as f64 + sigma * n);
            }
            return;
        }
        let blk = &mut blk[..x0 + seg.len()];
        norm.black_row(r, blk);
        for (i, (x, &b)) in seg.iter_mut().zip(blk[x0..].iter()).enumerate() {
            let xf = *x as f64;
            let y = (xf - b) / scale;
            let var = params.var_norm(Bayer::position(r, x0 + i), y) * scale2;
            let n = normal(i);
            *x = quantize(xf + var.sqrt() * n);
        }
    }
}

/// One standard normal from `rng` (the ziggurat of [`StandardNormal`]).
#[inline]
fn draw<R: Rng>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// [`RowNoise::row_from`], compiled twice, the second time for AVX2, picked at run time (the
/// same operations per sample, so the same bits).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn noise_row_from(
    rows: &RowNoise<'_>,
    stream: NoiseStream,
    key: &[u8; 32],
    at: (usize, usize),
    x0: usize,
    seg: &mut [u16],
    scratch: &mut Vec<f64>,
) {
    rows.row_from_body(stream, key, at, x0, seg, scratch);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::rows::RowSource;

    fn flat(w: usize, h: usize, v: u16) -> RawImage {
        RawImage {
            width: w,
            height: h,
            data: vec![v; w * h],
            meta: RawMeta::new_bayer(Bayer::RGGB, 14, 512.0, 16383.0),
        }
    }

    #[test]
    fn zero_noise_is_identity_and_clipping_holds() {
        let img = flat(8, 6, 3000);
        let out = apply_noise(&img, &NoiseParams::uniform(0.0, 0.0), 1).unwrap();
        assert_eq!(out.data, img.data);
        let img = flat(64, 64, 16383);
        let out = apply_noise(&img, &NoiseParams::uniform(0.0, 0.01), 1).unwrap();
        assert!(out.data.iter().all(|&v| v <= 16383));
        assert!(out.data.iter().any(|&v| v < 16383));
        let img = flat(64, 64, 0);
        let out = apply_noise(&img, &NoiseParams::uniform(0.0, 0.01), 1).unwrap();
        assert!(out.data.iter().any(|&v| v > 0));
    }

    #[test]
    fn rows_on_demand_equal_the_whole_image_for_any_chunking() {
        let mut img = flat(37, 23, 5000);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = (i * 7919 % 16383) as u16;
        }
        img.meta.active_area = Some(crate::raw::Rect {
            top: 3,
            left: 2,
            bottom: 20,
            right: 36,
        });
        let p = NoiseParams::uniform(1e-3, 1e-5);
        let cases = [false, true].map(|t| [(t, NoiseStream::V1), (t, NoiseStream::V2)]);
        for (truncate, stream) in cases.into_iter().flatten() {
            let whole = apply_noise_stream(&img, &p, 5, truncate, stream).unwrap();
            let rows = gaussian_rows(&img, &p, 5, truncate, stream).unwrap();
            assert!(whole.data.iter().all(|&v| v <= rows.max_bound()));
            let mut out = vec![0u16; 37 * 23];
            for (k, chunk) in out.chunks_mut(37 * 4).enumerate() {
                rows.fill_rows(k * 4, chunk);
            }
            assert_eq!(out, whole.data);
            // outside the active area the clean samples, inside noisy ones
            assert_eq!(out[..37 * 3], img.data[..37 * 3]);
            assert_ne!(
                out[37 * 5 + 2..37 * 5 + 36],
                img.data[37 * 5 + 2..37 * 5 + 36]
            );
        }
    }

    #[test]
    fn deterministic_per_seed_and_thread_count() {
        let img = flat(33, 17, 5000);
        let p = NoiseParams::uniform(1e-3, 1e-5);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        for s in [NoiseStream::V1, NoiseStream::V2] {
            let a = apply_noise_stream(&img, &p, 7, false, s).unwrap();
            let b = pool.install(|| apply_noise_stream(&img, &p, 7, false, s).unwrap());
            assert_eq!(a.data, b.data);
            let c = apply_noise_stream(&img, &p, 8, false, s).unwrap();
            assert_ne!(a.data, c.data);
        }
        // the two streams differ
        assert_ne!(
            apply_noise_stream(&img, &p, 7, false, NoiseStream::V1)
                .unwrap()
                .data,
            apply_noise(&img, &p, 7).unwrap().data
        );
        // a crop's noise: the same whatever the thread count, per stream
        let crop = Crop {
            top: 2,
            left: 4,
            height: 9,
            width: 20,
        };
        let clean: Vec<u16> = vec![5000; 9 * 20];
        for s in [NoiseStream::V1, NoiseStream::V2] {
            let run = || {
                let mut d = clean.clone();
                apply_noise_crop_stream(&img, &crop, &mut d, &p, (7, false), s).unwrap();
                d
            };
            assert_eq!(run(), pool.install(run));
        }
    }

    #[test]
    fn round_clamp_matches_round_then_clamp() {
        let reference = |v: f64, white: f64| -> u16 {
            let v = v.round();
            if v.is_nan() {
                0
            } else {
                v.clamp(0.0, white) as u16
            }
        };
        let whites = [1023.0, 1023.5, 1023.6, 16383.0, 65535.0, 0.0, 0.4, 0.6];
        let mut vals = vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
            0.0,
            0.5,
            0.49999999999999994,
            1.5,
            2.5,
            -0.5,
            -0.49,
            1022.5,
            1022.4999999,
            1023.2,
            1023.5,
            1023.6,
            1023.55,
            0.55,
            65534.5,
            65535.49,
            70000.0,
            f64::MIN_POSITIVE,
        ];
        // halves and integers with their neighbours, across binade boundaries
        let prev = |x: f64| f64::from_bits(x.to_bits() - 1);
        let next = |x: f64| f64::from_bits(x.to_bits() + 1);
        let ks = (0..1100u32).chain((1..17).flat_map(|m| [(1u32 << m) - 1, 1 << m]));
        for k in ks {
            let (h, i) = (k as f64 + 0.5, k as f64);
            vals.extend([h, prev(h), next(h), next(i)]);
            if k > 0 {
                vals.push(prev(i));
            }
        }
        let mut s = 1u64;
        for _ in 0..20000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            vals.push((s >> 11) as f64 / (1u64 << 53) as f64 * 70000.0 - 1000.0);
            vals.push((s >> 40) as f64 + 0.5);
        }
        for &w in whites
            .iter()
            .chain(&[70000.0, -3.0, f64::NAN, f64::INFINITY])
        {
            let wide = crate::normalize::RoundClamp::new(w);
            for &v in &vals {
                if (0.0..=65535.0).contains(&w) {
                    assert_eq!(round_clamp(v, w), reference(v, w), "v {v} white {w}");
                }
                assert_eq!(wide.apply(v), round_clamp(v, w), "v {v} white {w}");
            }
        }
    }

    #[test]
    fn truncation_keeps_the_draws_and_drops_the_fraction() {
        let mut img = flat(64, 40, 3000);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = 400 + (i % 9000) as u16;
        }
        let p = NoiseParams::uniform(2e-4, 1e-5);
        let r = apply_noise(&img, &p, 9).unwrap();
        let t = apply_noise_with(&img, &p, 9, true).unwrap();
        let mut n = 0f64;
        let mut sum = 0f64;
        for (&a, &b) in r.data.iter().zip(&t.data) {
            let d = a as i32 - b as i32;
            assert!(d == 0 || d == 1, "{a} {b}");
            sum += d as f64;
            n += 1.0;
        }
        assert!((sum / n - 0.5).abs() < 0.05, "{}", sum / n);
        assert_eq!(trunc_clamp(-0.7, 100.0), 0);
        assert_eq!(trunc_clamp(f64::NAN, 100.0), 0);
        assert_eq!(trunc_clamp(99.99, 100.0), 99);
        assert_eq!(trunc_clamp(1e9, 100.0), 100);
        // the crop path truncates the same way
        let crop = Crop {
            top: 0,
            left: 0,
            height: 40,
            width: 64,
        };
        let (mut pr, mut pt) = (img.data.clone(), img.data.clone());
        apply_noise_crop(&img, &crop, &mut pr, &p, 9).unwrap();
        apply_noise_crop_with(&img, &crop, &mut pt, &p, 9, true).unwrap();
        assert!(pr.iter().zip(&pt).all(|(&a, &b)| a == b || a == b + 1));
        assert_ne!(pr, pt);
    }

    /// The per-sample formula without the sigma table (the pre-table implementation), the
    /// normals of row `r` from `stream`'s row `r`.
    fn reference(
        clean: &RawImage,
        params: &NoiseParams,
        seed: u64,
        stream: NoiseStream,
    ) -> Vec<u16> {
        let norm = Normalizer::new(clean).unwrap();
        let a = clean.active_area();
        let (top, left) = (a.top as usize, a.left as usize);
        let white = norm.white.min(u16::MAX as f64);
        let key = stream_key(stream, false, seed, &[]);
        let mut data = clean.data.clone();
        for r in 0..a.height() {
            let normals: Vec<f64> = match stream {
                NoiseStream::V1 => {
                    let mut rng = row_rng(&key, r);
                    (0..a.width()).map(|_| draw(&mut rng)).collect()
                }
                NoiseStream::V2 => {
                    let mut n = vec![0.0; a.width()];
                    fill_normals_v2(&key, r, &mut n);
                    n
                }
            };
            for (c, n) in normals.into_iter().enumerate() {
                let x = &mut data[(top + r) * clean.width + left + c];
                let xf = *x as f64;
                let y = (xf - norm.black_at(r, c)) / norm.scale;
                let var = params.var_norm(Bayer::position(r, c), y) * norm.scale * norm.scale;
                *x = round_clamp(xf + var.sqrt() * n, white);
            }
        }
        data
    }

    /// [`reference`] against the code, both streams.
    fn check_reference(img: &RawImage, p: &NoiseParams, what: &str) {
        for stream in [NoiseStream::V1, NoiseStream::V2] {
            let out = apply_noise_stream(img, p, 11, false, stream).unwrap();
            assert_eq!(out.data, reference(img, p, 11, stream), "{what} {stream:?}");
        }
    }

    #[test]
    fn sigma_table_gives_the_per_sample_formula_bytes() {
        let p = NoiseParams {
            positions: [[2e-3, 1e-5], [1e-3, -2e-5], [1.5e-3, 3e-6], [4e-3, 0.0]],
        };
        let mut img = flat(37, 23, 0);
        img.meta.levels.white = 1023.0;
        img.meta.bits_per_sample = 10;
        // values below black, across the range, at and above white (stored > white)
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = ((i * 7919) % 1400) as u16;
        }
        for (black, repeat) in [
            (vec![64.0], (1, 1)),
            (vec![60.0, 64.0, 66.0, 70.5], (2, 2)),
            (vec![60.0, 64.0], (1, 2)),
            (vec![60.0, 64.0], (2, 1)),
        ] {
            img.meta.levels.black = black.clone();
            img.meta.levels.black_repeat = repeat;
            let n = Normalizer::new(&img).unwrap();
            assert!(n.black_is_2x2_periodic());
            check_reference(&img, &p, &format!("{black:?} {repeat:?}"));
        }
        // per-column deltas: the table is not used, same formula
        img.meta.levels.black = vec![64.0];
        img.meta.levels.black_repeat = (1, 1);
        img.meta.levels.black_delta_h = (0..37).map(|c| c as f64 * 0.25).collect();
        assert!(!Normalizer::new(&img).unwrap().black_is_2x2_periodic());
        check_reference(&img, &p, "deltas");
    }

    #[test]
    fn white_65535_no_overflow() {
        let mut img = flat(16, 16, 65535);
        img.meta.levels.white = 65535.0;
        img.meta.levels.black = vec![0.0];
        img.meta.bits_per_sample = 16;
        let out = apply_noise(&img, &NoiseParams::uniform(0.01, 0.01), 3).unwrap();
        assert!(out.data.iter().any(|&v| v < 65535));
    }
}
