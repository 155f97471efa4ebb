//! zlib encoder benchmark: the own run-length + dynamic-Huffman encoder
//! (`day2night::deflate`) against miniz_oxide level 1 (what the EXR writer used) on a
//! deterministic EXR-like buffer: 8 ZIP blocks of 16 scan lines of a 4032-pixel-wide RGB
//! half-float image (smooth shading, edges, a dark region and noise), each block's half
//! samples byte-split into low/high planes and delta-coded +128 as OpenEXR's predictor does.
//! One thread. Sizes are printed once. Run: `cargo bench --bench deflate`.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use day2night::deflate::Encoder;
use std::hint::black_box;
use std::time::Duration;

const W: usize = 4032;
const LINES: usize = 16;
const BLOCKS: usize = 8;

/// f32 -> IEEE half bits, round to nearest even, for finite values (enough here).
fn half_bits(v: f32) -> u16 {
    let b = v.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let e = ((b >> 23) & 0xff) as i32 - 127 + 15;
    let m = b & 0x7f_ffff;
    if e >= 31 {
        return sign | 0x7bff;
    }
    if e <= 0 {
        // subnormal
        if e < -10 {
            return sign;
        }
        let m = m | 0x80_0000;
        let shift = (14 - e) as u32;
        let half = 1u32 << (shift - 1);
        let r = (m + half - 1 + ((m >> shift) & 1)) >> shift;
        return sign | r as u16;
    }
    let r = (m + 0xfff + ((m >> 13) & 1)) >> 13;
    (sign as u32 | (((e as u32) << 10) + r)) as u16
}

/// The predicted bytes of block `b`: OpenEXR's ZIP predictor applied to a photo-like image.
fn block(b: usize) -> Vec<u8> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15 ^ b as u64;
    let mut lo = Vec::with_capacity(W * LINES * 3);
    let mut hi = Vec::with_capacity(W * LINES * 3);
    for l in 0..LINES {
        let y = (b * LINES + l) as f32;
        for c in 0..3 {
            for x in 0..W {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let noise = ((s >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 0.004;
                let xf = x as f32;
                let v = if xf < 900.0 {
                    // dark, flat region: values a few ulps apart
                    0.002 + 0.0005 * c as f32 + noise * 0.05
                } else {
                    let shade = 0.25 + 0.2 * (xf * 0.002 + y * 0.003).sin();
                    let edge = if (x / 500 + c) % 3 == 0 { 0.3 } else { 0.0 };
                    shade + edge + 0.05 * (xf * 0.05).sin() * (c as f32 + 1.0) + noise
                };
                let h = half_bits(v.max(0.0));
                lo.push(h as u8);
                hi.push((h >> 8) as u8);
            }
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

fn benches(c: &mut Criterion) {
    let blocks: Vec<Vec<u8>> = (0..BLOCKS).map(block).collect();
    let total: usize = blocks.iter().map(Vec::len).sum();
    let mut enc = Encoder::new();
    let mut out = Vec::new();
    let ours: usize = blocks
        .iter()
        .map(|b| {
            out.clear();
            enc.compress_zlib(b, &mut out);
            assert_eq!(
                miniz_oxide::inflate::decompress_to_vec_zlib(&out).unwrap(),
                *b
            );
            out.len()
        })
        .sum();
    let miniz: usize = blocks
        .iter()
        .map(|b| miniz_oxide::deflate::compress_to_vec_zlib(b, 1).len())
        .sum();
    eprintln!(
        "deflate bench input {} bytes: ours {} ({:.3}), miniz L1 {} ({:.3})",
        total,
        ours,
        ours as f64 / total as f64,
        miniz,
        miniz as f64 / total as f64
    );

    let mut g = c.benchmark_group("deflate");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Bytes(total as u64));
    g.bench_function("ours", |bch| {
        bch.iter(|| {
            let mut n = 0;
            for b in &blocks {
                out.clear();
                enc.compress_zlib(black_box(b), &mut out);
                n += out.len();
            }
            n
        })
    });
    g.bench_function("miniz_l1", |bch| {
        bch.iter(|| {
            blocks
                .iter()
                .map(|b| miniz_oxide::deflate::compress_to_vec_zlib(black_box(b), 1).len())
                .sum::<usize>()
        })
    });
    g.finish();
}

criterion_group!(deflate, benches);
criterion_main!(deflate);
