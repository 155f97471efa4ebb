//! DNG read/write throughput on a 12 MP raw (4032x3024, 10-bit, RGGB), uncompressed (packed
//! 10-bit strips) and lossless JPEG, against a plain copy of a file of the same size.
//!
//! `cargo bench --bench dng_io` (figures in docs/benchmarks.md, "DNG I/O"); the group
//! `unique_id` (`cargo bench --bench dng_io -- unique_id`) times RawDataUniqueID's chunk
//! hash, XXH3-128 against the SHA-256 it replaced, over the 12 MP DNG's bytes in strips of
//! 1 MiB (single-threaded, as one worker hashes its strip), and the uncompressed encode
//! with each.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use day2night::dng::read::read_dng;
use day2night::dng::write::{encode_dng, write_dng, Compression, UniqueIdHash, WriteOptions};
use day2night::output::{write_bytes_atomic, OutputPolicy};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use sha2::{Digest, Sha256};
use std::hint::black_box;
use std::time::Duration;
use twox_hash::XxHash3_128;

fn image() -> RawImage {
    let (w, h) = (4032usize, 3024usize);
    let meta = RawMeta::new_bayer(Bayer::RGGB, 10, 64.0, 1023.0);
    // Smooth scene plus noise, so lossless JPEG sees realistic entropy.
    let mut s = 0x2545F4914F6CDD1Du64;
    let data = (0..w * h)
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            let base = 300.0 + 250.0 * ((x / 400.0).sin() * (y / 300.0).cos());
            (base + (s % 16) as f64).clamp(0.0, 1023.0) as u16
        })
        .collect();
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

fn bench(c: &mut Criterion) {
    let img = image();
    let dir = tempfile::tempdir().unwrap();
    let mut g = c.benchmark_group("dng_io");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(4))
        .warm_up_time(Duration::from_millis(500));
    for (name, compression) in [
        ("uncompressed", Compression::None),
        ("ljpeg", Compression::Ljpeg),
    ] {
        let opts = WriteOptions {
            compression,
            ..Default::default()
        };
        let bytes = encode_dng(&img, &opts).unwrap();
        let src = dir.path().join(format!("{name}.dng"));
        std::fs::write(&src, &bytes).unwrap();
        let out = dir.path().join(format!("{name}_out.dng"));
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        let policy = OutputPolicy {
            overwrite: true,
            inputs: vec![src.clone()],
            ..OutputPolicy::default()
        };
        g.bench_function(format!("copy_file_{name}"), |b| {
            b.iter(|| {
                // Read the file's bytes and write them through the same atomic path
                // (temp file, fsync, rename): the floor for reading + writing this file.
                let v = std::fs::read(&src).unwrap();
                write_bytes_atomic(&out, &policy, &v).unwrap();
            })
        });
        g.bench_function(format!("read_{name}"), |b| {
            b.iter(|| black_box(read_dng(&src).unwrap()))
        });
        g.bench_function(format!("write_{name}"), |b| {
            b.iter(|| write_dng(&img, &out, &opts, &policy).unwrap())
        });
        g.bench_function(format!("encode_{name}"), |b| {
            b.iter(|| black_box(encode_dng(&img, &opts).unwrap()))
        });
    }
    g.finish();
    unique_id(c, &img);
}

/// RawDataUniqueID's hash: XXH3-128 against SHA-256 over the 12 MP DNG's bytes.
fn unique_id(c: &mut Criterion, img: &RawImage) {
    let bytes = encode_dng(img, &WriteOptions::default()).unwrap();
    let mut g = c.benchmark_group("unique_id");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500))
        .throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("sha256_1MiB_chunks", |b| {
        b.iter(|| {
            for c in bytes.chunks(1 << 20) {
                black_box(Sha256::digest(c));
            }
        })
    });
    g.bench_function("xxh3_128_1MiB_chunks", |b| {
        b.iter(|| {
            for c in bytes.chunks(1 << 20) {
                black_box(XxHash3_128::oneshot(c));
            }
        })
    });
    for hash in [UniqueIdHash::Sha256, UniqueIdHash::Xxh3_128] {
        let opts = WriteOptions {
            unique_id: hash,
            ..Default::default()
        };
        g.bench_function(format!("encode_uncompressed_{}", hash.name()), |b| {
            b.iter(|| black_box(encode_dng(img, &opts).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
