//! Read throughput on a 12 MP (4000x3000) DNG held in memory, against copying its bytes.
//! `cargo bench --bench dng_read`. Figures in docs/dng-support.md ("Reading").
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use day2night::dng::read::read_dng_bytes;
use std::hint::black_box;

#[path = "../tests/it/dngbuild/mod.rs"]
mod dngbuild;
use dngbuild::{Builder, Pixels};

fn bench(c: &mut Criterion) {
    let (w, h) = (4000, 3000);
    let mut cases = Vec::new();
    for (name, bits, layout) in [
        (
            "uncompressed_16bit_strips",
            16u16,
            Pixels::Strips { rows: 3000 },
        ),
        (
            "uncompressed_12bit_packed",
            12,
            Pixels::Strips { rows: 256 },
        ),
        (
            "uncompressed_14bit_packed",
            14,
            Pixels::Strips { rows: 256 },
        ),
        (
            "uncompressed_16bit_tiles",
            16,
            Pixels::Tiles { w: 256, h: 256 },
        ),
        (
            "ljpeg_16bit_tiles",
            16,
            Pixels::LjpegTiles {
                w: 256,
                h: 256,
                two_components: true,
            },
        ),
    ] {
        let mut b = Builder::new(w, h, bits);
        b.layout = layout;
        cases.push((name, b.build()));
    }
    let mut g = c.benchmark_group("dng_read_12mp");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(3));
    g.warm_up_time(std::time::Duration::from_millis(500));
    let copy_src = &cases[0].1;
    g.throughput(Throughput::Elements((w * h) as u64));
    g.bench_function("copy_file_bytes_16bit", |bn| {
        bn.iter(|| black_box(copy_src.to_vec()))
    });
    for (name, bytes) in &cases {
        g.bench_function(*name, |bn| {
            bn.iter(|| black_box(read_dng_bytes(black_box(bytes)).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
