//! A fast zlib (RFC 1950) / DEFLATE (RFC 1951) encoder for run-heavy, match-poor data.
//!
//! Built for the ZIP-compressed OpenEXR blocks that `synth` writes (half-float samples split
//! into low/high byte planes and delta-coded around 128): on that data LZ77 matches other than
//! byte runs are rare, so this encoder only looks for runs of 8 or more equal bytes (coded
//! as matches at distance 1, length 3..=258) and spends its time on good Huffman codes
//! instead: the input is cut into equal
//! chunks of at most [`DEFAULT_CHUNK`] bytes and each chunk becomes one dynamic-Huffman block
//! built from its exact symbol counts, or a fixed-Huffman or stored block when that is smaller
//! by exact bit count. So the stream is never longer than the input plus 6 bytes (zlib
//! header and Adler-32) plus 5 bytes per chunk. See `docs/deflate.md` for the measurements
//! behind the choices.
//!
//! Not a general-purpose compressor: repeats at distances other than 1 (text, periodic data)
//! are not found, so such data compresses far worse than with zlib.
//!
//! The output is a complete zlib stream (header `78 01`, blocks, big-endian Adler-32) that any
//! inflater accepts, and a pure function of the input.
//!
//! ```
//! use day2night::deflate::{compress_zlib_rle_to_vec, Encoder};
//! let data = [128u8; 1000];
//! let z = compress_zlib_rle_to_vec(&data);
//! assert!(z.len() < 30);
//! let mut enc = Encoder::new();
//! let mut out = Vec::new();
//! enc.compress_zlib(&data, &mut out);
//! assert_eq!(out, z);
//! ```

mod bits;
mod encode;
mod huffman;

use bits::BitWriter;
use encode::BlockEncoder;

/// Default largest chunk (block) in input bytes: the largest stored block, so that a chunk
/// that does not compress costs one 5-byte stored-block header.
pub const DEFAULT_CHUNK: usize = 65535;

/// A reusable encoder: keeps its scratch buffers between calls.
pub struct Encoder {
    blocks: BlockEncoder,
    chunk: usize,
}

impl Default for Encoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Encoder {
    /// An encoder with the default chunk size.
    pub fn new() -> Self {
        Self::with_chunk(DEFAULT_CHUNK)
    }

    /// An encoder cutting its input into equal chunks (one block each) of at most `chunk`
    /// bytes (clamped to 1 KiB..=16 MiB). Smaller chunks adapt faster to changing statistics
    /// at the cost of more block headers; chunks over 65 535 bytes that do not compress are
    /// stored as several blocks.
    pub fn with_chunk(chunk: usize) -> Self {
        Encoder {
            blocks: BlockEncoder::new(),
            chunk: chunk.clamp(1 << 10, 1 << 24),
        }
    }

    /// Append the zlib stream of `input` to `out`.
    pub fn compress_zlib(&mut self, input: &[u8], out: &mut Vec<u8>) {
        // CMF: deflate, 32 KiB window; FLG: FLEVEL 0 (fastest), no dictionary, FCHECK
        out.extend_from_slice(&[0x78, 0x01]);
        self.compress_raw(input, out);
        out.extend_from_slice(&simd_adler32::adler32(&input).to_be_bytes());
    }

    /// Append the raw DEFLATE stream (no zlib header or checksum) of `input` to `out`.
    pub fn compress_raw(&mut self, input: &[u8], out: &mut Vec<u8>) {
        let mut w = BitWriter::new(out);
        if input.is_empty() {
            // final fixed-Huffman block holding only end-of-block (7 zero bits)
            w.put(0b011, 3);
            w.put(0, 7);
        }
        // equal chunks of at most `self.chunk` bytes: an input made of two equal halves (the
        // EXR predictor's low and high byte planes) gets a block boundary at the middle
        let n = input.len().div_ceil(self.chunk);
        let mut start = 0;
        for i in 1..=n {
            let end = (input.len() as u128 * i as u128 / n as u128) as usize;
            self.blocks.encode_chunk(input, start, end, i == n, &mut w);
            start = end;
        }
        w.finish();
    }
}

impl Encoder {
    /// Append `input` as one segment of a raw DEFLATE stream made of independently
    /// compressed pieces: its blocks are not final and it ends byte-aligned with an empty
    /// stored block (zlib's "sync flush"). Segments compressed separately (e.g. in parallel)
    /// and concatenated in order, then followed by [`FINAL_EMPTY_BLOCK`], form a valid raw
    /// DEFLATE stream of the concatenated inputs: a segment's matches never reach back into
    /// an earlier one. An empty input gives just the 5-byte empty stored block.
    pub fn compress_segment(&mut self, input: &[u8], out: &mut Vec<u8>) {
        let mut w = BitWriter::new(out);
        let n = input.len().div_ceil(self.chunk);
        let mut start = 0;
        for i in 1..=n {
            let end = (input.len() as u128 * i as u128 / n as u128) as usize;
            self.blocks.encode_chunk(input, start, end, false, &mut w);
            start = end;
        }
        // BFINAL 0, BTYPE 00 (stored), pad to a byte, LEN 0, NLEN 0xFFFF
        w.put(0, 3);
        w.align();
        w.put_bytes(&[0, 0, 0xFF, 0xFF]);
        w.finish();
    }
}

/// A final, empty fixed-Huffman block (BFINAL 1, BTYPE 01, end-of-block): ends a stream made
/// of [`Encoder::compress_segment`] pieces.
pub const FINAL_EMPTY_BLOCK: [u8; 2] = [0x03, 0x00];

/// Adler-32 (RFC 1950) of `data`.
pub fn adler32(data: &[u8]) -> u32 {
    simd_adler32::adler32(&data)
}

/// The Adler-32 of `a ++ b` from the Adler-32s of `a` and `b` and the length of `b`.
pub fn adler32_combine(adler_a: u32, adler_b: u32, len_b: u64) -> u32 {
    const BASE: u64 = 65521;
    let rem = len_b % BASE;
    let (a1, b1) = (u64::from(adler_a & 0xffff), u64::from(adler_a >> 16));
    let (a2, b2) = (u64::from(adler_b & 0xffff), u64::from(adler_b >> 16));
    // sum1 = a1 + a2 - 1, sum2 = b1 + b2 + rem * a1 - rem (mod BASE), kept non-negative
    let sum1 = (a1 + a2 + BASE - 1) % BASE;
    let sum2 = (b1 + b2 + rem * a1 % BASE + BASE - rem) % BASE;
    (sum1 | (sum2 << 16)) as u32
}

/// Append the zlib stream of `input` to `out` (see the module docs).
pub fn compress_zlib_rle(input: &[u8], out: &mut Vec<u8>) {
    Encoder::new().compress_zlib(input, out);
}

/// The zlib stream of `input` (see the module docs).
pub fn compress_zlib_rle_to_vec(input: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(input.len() / 2 + 64);
    compress_zlib_rle(input, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Compress, check the zlib framing and Adler-32 by hand, inflate with miniz and compare.
    fn roundtrip_with(enc: &mut Encoder, data: &[u8]) -> Vec<u8> {
        let mut z = vec![0xEE]; // appends after existing content
        enc.compress_zlib(data, &mut z);
        assert_eq!(z[0], 0xEE);
        let z = z.split_off(1);
        assert_eq!(z[0], 0x78);
        assert_eq!((u16::from(z[0]) << 8 | u16::from(z[1])) % 31, 0);
        assert_eq!(z[1] & 0x20, 0, "no preset dictionary");
        let n = z.len();
        assert_eq!(z[n - 4..], adler_ref(data).to_be_bytes());
        let back = miniz_oxide::inflate::decompress_to_vec_zlib(&z).expect("valid zlib stream");
        assert_eq!(back.len(), data.len());
        assert!(back == data, "round trip differs");
        // never much worse than stored
        // never longer than all-stored: 5 bytes per stored piece of <= 65535 bytes
        let n = data.len();
        let pieces = n.div_ceil(enc.chunk) * enc.chunk.div_ceil(65535);
        assert!(z.len() <= n + 5 * pieces.max(1) + 6, "{n} -> {}", z.len());
        z
    }

    /// Segments compressed separately and joined with a zlib frame inflate to the whole.
    fn segments_roundtrip(parts: &[&[u8]]) {
        let mut enc = Encoder::new();
        let mut z = vec![0x78, 0x01];
        let mut adler = 1u32; // Adler-32 of the empty string
        let mut whole = Vec::new();
        for p in parts {
            let before = z.len();
            enc.compress_segment(p, &mut z);
            // a segment ends with an empty stored block
            assert_eq!(z[z.len() - 4..], [0, 0, 0xFF, 0xFF]);
            assert!(z.len() > before);
            adler = adler32_combine(adler, adler32(p), p.len() as u64);
            whole.extend_from_slice(p);
        }
        z.extend_from_slice(&FINAL_EMPTY_BLOCK);
        z.extend_from_slice(&adler.to_be_bytes());
        assert_eq!(adler, adler_ref(&whole));
        let back = miniz_oxide::inflate::decompress_to_vec_zlib(&z).expect("valid zlib stream");
        assert!(back == whole, "segments round trip differs");
    }

    #[test]
    fn segments_concatenate() {
        let runs = vec![7u8; 70_000];
        let ramp: Vec<u8> = (0..200_000u32).map(|i| (i / 3 % 251) as u8).collect();
        segments_roundtrip(&[]);
        segments_roundtrip(&[b""]);
        segments_roundtrip(&[b"", b"a", b""]);
        segments_roundtrip(&[&runs, &runs, &ramp, b"x", &ramp[..1000]]);
        // a run crossing a segment boundary cannot reach back: still correct
        segments_roundtrip(&[&runs[..10], &runs[..300]]);
    }

    proptest! {
        #[test]
        fn adler32_combine_matches_the_whole(a in proptest::collection::vec(any::<u8>(), 0..3000),
                                             b in proptest::collection::vec(any::<u8>(), 0..3000),
                                             fill in any::<u8>(), extra in 0usize..200_000) {
            let mut b2 = b.clone();
            b2.extend(std::iter::repeat_n(fill, extra));
            let mut whole = a.clone();
            whole.extend_from_slice(&b2);
            prop_assert_eq!(adler32_combine(adler32(&a), adler32(&b2), b2.len() as u64), adler_ref(&whole));
        }
    }

    fn roundtrip(data: &[u8]) -> Vec<u8> {
        let z = roundtrip_with(&mut Encoder::new(), data);
        assert_eq!(z, compress_zlib_rle_to_vec(data), "deterministic");
        z
    }

    /// Plain Adler-32 (RFC 1950 8.2).
    fn adler_ref(data: &[u8]) -> u32 {
        let (mut a, mut b) = (1u32, 0u32);
        for &x in data {
            a = (a + u32::from(x)) % 65521;
            b = (b + a) % 65521;
        }
        b << 16 | a
    }

    /// Deterministic xorshift bytes.
    fn noise(n: usize, seed: u64) -> Vec<u8> {
        let mut s = seed | 1;
        (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 24) as u8
            })
            .collect()
    }

    /// EXR-like predicted bytes: a smooth noisy image's half samples byte-split and
    /// delta-coded (low bytes noisy around 128, high bytes long runs of 128).
    fn exr_like(w: usize, lines: usize, seed: u64) -> Vec<u8> {
        let r = noise(w * lines * 3, seed);
        let mut lo = Vec::new();
        let mut hi = Vec::new();
        for y in 0..lines {
            for x in 0..w * 3 {
                let v = 0.2 + 0.15 * ((x as f32 * 0.01).sin() + (y as f32 * 0.05).cos());
                let v = v + (f32::from(r[y * w * 3 + x]) - 128.0) * 1e-5;
                let h = half_bits(v);
                lo.push(h as u8);
                hi.push((h >> 8) as u8);
            }
        }
        lo.extend_from_slice(&hi);
        let mut prev = lo[0];
        for t in lo.iter_mut().skip(1) {
            let cur = *t;
            *t = cur.wrapping_sub(prev).wrapping_add(128);
            prev = cur;
        }
        lo
    }

    /// f32 -> f16 bits for normal positive values (truncating; enough for test data).
    fn half_bits(v: f32) -> u16 {
        let b = v.to_bits();
        let e = ((b >> 23) & 0xff) as i32 - 127 + 15;
        ((e.clamp(1, 30) as u16) << 10) | ((b >> 13) & 0x3ff) as u16
    }

    #[test]
    fn empty() {
        let z = roundtrip(&[]);
        assert_eq!(z, [0x78, 0x01, 0x03, 0x00, 0, 0, 0, 1]);
    }

    #[test]
    fn one_byte() {
        for b in [0u8, 1, 128, 255] {
            roundtrip(&[b]);
        }
    }

    #[test]
    fn short_inputs() {
        for n in 0..40 {
            roundtrip(&noise(n, n as u64));
            roundtrip(&vec![7u8; n]);
            let v: Vec<u8> = (0..n).map(|i| (i / 4) as u8).collect();
            roundtrip(&v);
        }
    }

    #[test]
    fn long_runs_and_block_boundaries() {
        for n in [
            258,
            259,
            260,
            261,
            262,
            516,
            517,
            100_000,
            DEFAULT_CHUNK * 3 + 5,
        ] {
            let z = roundtrip(&vec![128u8; n]);
            assert!(z.len() < 30 + n / 200, "{n} -> {}", z.len());
        }
        // runs crossing chunk boundaries with a small chunk
        let mut enc = Encoder::with_chunk(1024);
        let mut v = vec![0u8; 5000];
        v[1023] = 1;
        v[1024..1030].fill(9);
        v[2046..2050].fill(3);
        roundtrip_with(&mut enc, &v);
        let mut enc = Encoder::with_chunk(1024);
        roundtrip_with(&mut enc, &vec![5u8; 4096]);
    }

    #[test]
    fn all_byte_values() {
        let v: Vec<u8> = (0..=255u8).collect();
        roundtrip(&v);
        let v: Vec<u8> = (0..100_000).map(|i| (i % 256) as u8).collect();
        roundtrip(&v);
        let v: Vec<u8> = (0..=255u8).flat_map(|b| [b; 5]).collect();
        roundtrip(&v);
    }

    #[test]
    fn random_falls_back_to_stored() {
        for n in [1000, 65535, 65536, 200_001] {
            let v = noise(n, 99);
            let z = roundtrip(&v);
            assert_eq!(z.len(), n + 6 + 5 * n.div_ceil(DEFAULT_CHUNK));
        }
    }

    #[test]
    fn big_chunks_store_in_several_pieces() {
        // one chunk of 200 001 random bytes: four stored blocks of <= 65 535 bytes
        let v = noise(200_001, 3);
        let z = roundtrip_with(&mut Encoder::with_chunk(1 << 20), &v);
        assert_eq!(z.len(), v.len() + 6 + 5 * 4);
    }

    #[test]
    fn raw_stream_inflates() {
        let v = exr_like(300, 16, 9);
        let mut raw = Vec::new();
        Encoder::new().compress_raw(&v, &mut raw);
        assert_eq!(miniz_oxide::inflate::decompress_to_vec(&raw).unwrap(), v);
        // the zlib stream is the raw one framed
        let z = compress_zlib_rle_to_vec(&v);
        assert_eq!(&z[2..z.len() - 4], &raw[..]);
    }

    #[test]
    fn skewed_needs_length_limit() {
        // Fibonacci-distributed byte frequencies: unlimited Huffman depth would exceed 15
        let mut fib = vec![1usize, 1];
        while fib.len() < 25 {
            fib.push(fib[fib.len() - 1] + fib[fib.len() - 2]);
        }
        let mut v = Vec::new();
        for (s, &f) in fib.iter().enumerate() {
            for k in 0..f {
                // interleave so that runs do not swallow the counts
                v.push((s as u8).wrapping_mul(7).wrapping_add((k % 2) as u8 * 100));
            }
        }
        let r = noise(v.len(), 5);
        // deterministic shuffle
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by_key(|&i| (r[i], i));
        let v: Vec<u8> = idx.iter().map(|&i| v[i]).collect();
        roundtrip(&v);
        roundtrip_with(&mut Encoder::with_chunk(1 << 20), &v);
    }

    #[test]
    fn exr_like_data_compresses() {
        let v = exr_like(1000, 16, 1);
        let z = roundtrip(&v);
        let miniz = miniz_oxide::deflate::compress_to_vec_zlib(&v, 1);
        assert!(
            z.len() < v.len() / 2,
            "{} -> {} (miniz {})",
            v.len(),
            z.len(),
            miniz.len()
        );
        // smaller than miniz level 1 (96000 -> 31999 vs 35040 when written)
        assert!(
            z.len() < miniz.len(),
            "{} vs miniz {}",
            z.len(),
            miniz.len()
        );
    }

    #[test]
    fn encoder_reuse_and_chunk_sizes() {
        let v = exr_like(500, 16, 2);
        let mut enc = Encoder::new();
        let a = roundtrip_with(&mut enc, &v);
        roundtrip_with(&mut enc, &noise(3000, 1));
        let b = roundtrip_with(&mut enc, &v);
        assert_eq!(a, b);
        for chunk in [1000, 4096, 30_000, 1 << 20] {
            let mut enc = Encoder::with_chunk(chunk);
            for n in [chunk - 1, chunk, chunk + 1, 2 * chunk + 3] {
                roundtrip_with(&mut enc, &v[..n.min(v.len())]);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn roundtrips_any_bytes(v in proptest::collection::vec(any::<u8>(), 0..5000)) {
            roundtrip_with(&mut Encoder::with_chunk(1024), &v);
            roundtrip(&v);
        }

        #[test]
        fn roundtrips_runny_bytes(
            parts in proptest::collection::vec((any::<u8>(), 1usize..600), 0..40),
        ) {
            let v: Vec<u8> = parts.iter().flat_map(|&(b, n)| std::iter::repeat_n(b, n)).collect();
            roundtrip_with(&mut Encoder::with_chunk(1024), &v);
            roundtrip(&v);
        }
    }
}
