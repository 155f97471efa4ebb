//! The random streams of the Gaussian noise rows (docs/noise.md, "Noise streams"). Every
//! active-area row (or crop row) draws its standard normals from a stream of its own, keyed
//! by the plan's noise seed and the row number, so any thread count and any chunking give
//! the same bytes. The plan records which stream it used ([`NoiseStream`], the plan's
//! `noise_stream`):
//!
//! - **2** (the default): xoshiro256++ ([`rand_xoshiro`]), its 256-bit state seeded by
//!   SplitMix64 from a 64-bit row seed that is a bijection of the row number under the
//!   SHA-256 key of the seed; the normals are drawn a row at a time by the ziggurat of
//!   [`rand_distr::StandardNormal`] into a buffer, then applied.
//! - **1**: ChaCha8 with the seed's SHA-256 key, stream number = row, one normal per sample
//!   drawn as it is applied: the stream of plans made before version 2 (they record no
//!   `noise_stream`) and of the `--compat release` preset; kept so that their sidecars
//!   replay byte for byte.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Which random stream the Gaussian noise rows draw from (serialized as its number).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(try_from = "u32", into = "u32")]
pub enum NoiseStream {
    /// ChaCha8 per row, one normal drawn per sample as it is applied (plans without a
    /// `noise_stream`, and `--compat release`).
    V1,
    /// xoshiro256++ per row, the row's normals drawn at once (the default).
    #[default]
    V2,
}

impl NoiseStream {
    /// The stream of plans that record none (made before version 2).
    pub fn v1() -> NoiseStream {
        NoiseStream::V1
    }
}

impl From<NoiseStream> for u32 {
    fn from(s: NoiseStream) -> u32 {
        match s {
            NoiseStream::V1 => 1,
            NoiseStream::V2 => 2,
        }
    }
}

impl TryFrom<u32> for NoiseStream {
    type Error = String;
    fn try_from(v: u32) -> Result<NoiseStream, String> {
        match v {
            1 => Ok(NoiseStream::V1),
            2 => Ok(NoiseStream::V2),
            other => Err(format!("noise_stream {other} (expected 1 or 2)")),
        }
    }
}

/// SHA-256 of a domain tag and a seed: the 32-byte key of a seed's streams.
fn key_of(tag: &[u8], seed: u64, extra: &[u64]) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(tag);
    h.update(seed.to_le_bytes());
    for v in extra {
        h.update(v.to_le_bytes());
    }
    h.finalize().into()
}

/// The 32-byte key of the rows of `seed` under `stream` (`extra`: a crop's rectangle, with
/// `crop` true).
pub fn stream_key(stream: NoiseStream, crop: bool, seed: u64, extra: &[u64]) -> [u8; 32] {
    let tag: &[u8] = match (stream, crop) {
        (NoiseStream::V1, false) => b"day2night noise rows v1\0",
        (NoiseStream::V1, true) => b"day2night noise crop rows v1\0",
        (NoiseStream::V2, false) => b"day2night noise rows v2\0",
        (NoiseStream::V2, true) => b"day2night noise crop rows v2\0",
    };
    key_of(tag, seed, extra)
}

/// The random stream of row `row` under a version-1 key.
pub fn row_rng_v1(key: &[u8; 32], row: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::from_seed(*key);
    rng.set_stream(row as u64);
    rng
}

/// SplitMix64's output function (a bijection of `u64`).
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The 64-bit seed of row `row` under a version-2 key: each step is a bijection of the
/// previous value (odd multiply, xor with a key word, `mix64`), so distinct rows always
/// get distinct seeds, and every key word changes all of them.
pub fn row_seed_v2(key: &[u8; 32], row: usize) -> u64 {
    let k = |i: usize| {
        let mut w = [0u8; 8];
        w.copy_from_slice(&key[8 * i..8 * i + 8]);
        u64::from_le_bytes(w)
    };
    let mut z = (row as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ k(0);
    for i in 1..4 {
        z = mix64(z) ^ k(i);
    }
    mix64(z)
}

/// The random stream of row `row` under a version-2 key: xoshiro256++ seeded by SplitMix64
/// from [`row_seed_v2`].
pub fn row_rng_v2(key: &[u8; 32], row: usize) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(row_seed_v2(key, row))
}

/// Fill `out` with standard normals from the version-2 stream of row `row` (the ziggurat
/// of [`StandardNormal`], one after the other).
///
/// Compiled twice, the second time for AVX2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub fn fill_normals_v2(key: &[u8; 32], row: usize, out: &mut [f64]) {
    let mut rng = row_rng_v2(key, row);
    for n in out.iter_mut() {
        *n = StandardNormal.sample(&mut rng);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_and_others_are_refused() {
        for s in [NoiseStream::V1, NoiseStream::V2] {
            let j = serde_json::to_string(&s).unwrap();
            assert_eq!(serde_json::from_str::<NoiseStream>(&j).unwrap(), s);
        }
        assert_eq!(serde_json::to_string(&NoiseStream::V2).unwrap(), "2");
        let e = serde_json::from_str::<NoiseStream>("3").unwrap_err();
        assert!(e.to_string().contains("noise_stream 3"), "{e}");
        assert_eq!(NoiseStream::default(), NoiseStream::V2);
    }

    #[test]
    fn row_seeds_are_distinct_and_keyed() {
        let a = stream_key(NoiseStream::V2, false, 7, &[]);
        let b = stream_key(NoiseStream::V2, false, 8, &[]);
        let mut seen = std::collections::HashSet::new();
        for r in 0..100_000 {
            assert!(seen.insert(row_seed_v2(&a, r)), "row {r}");
        }
        assert_ne!(row_seed_v2(&a, 0), row_seed_v2(&b, 0));
        // every stream and crop flag has its own key
        let keys = [
            stream_key(NoiseStream::V1, false, 7, &[]),
            stream_key(NoiseStream::V1, true, 7, &[]),
            a,
            stream_key(NoiseStream::V2, true, 7, &[]),
        ];
        for (i, k) in keys.iter().enumerate() {
            assert!(keys[i + 1..].iter().all(|o| o != k), "key {i}");
        }
    }
}
