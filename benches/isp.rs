//! ISP benchmarks on a generated 12 MP (4000x3000) RGGB frame: demosaic per method, the
//! colour stage, the whole default render, EXR writing per compression and zip level, on
//! 1 thread and the default pool, against the exr crate's ZIP writer used before (sizes
//! printed once), and PNG writing. Run: `cargo bench --bench isp` (or a filter such as
//! `cargo bench --bench isp -- render`).
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use day2night::encode::exr::{encode_exr, ExrCompression, ExrOptions};
use day2night::isp::demosaic::{demosaic, Demosaic};
use day2night::isp::render::{
    apply_matrix, color_matrix, render, render_with, Execution, RenderOptions,
};
use day2night::isp::RgbImage;
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use std::hint::black_box;
use std::io::Cursor;
use std::time::Duration;

/// The previous EXR writer (before the own encoder): the exr crate's ZIP16, level 4 fixed,
/// pixels through a per-pixel closure; `parallel` = the crate's own thread pool.
fn old_exr_crate_zip(img: &RgbImage, parallel: bool) -> usize {
    use exr::prelude::*;
    let w = img.width;
    let d = &img.data;
    let at = |x: usize, y: usize, c: usize| {
        let v = d[3 * (y * w + x) + c];
        f16::from_f32(if v.is_nan() {
            0.0
        } else {
            v.clamp(-65504.0, 65504.0)
        })
    };
    let ch =
        SpecificChannels::rgb(|p: Vec2<usize>| (at(p.0, p.1, 0), at(p.0, p.1, 1), at(p.0, p.1, 2)));
    let enc = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let size = (img.width, img.height);
    let image = Image::from_layer(Layer::new(size, LayerAttributes::default(), enc, ch));
    let mut buf = Cursor::new(Vec::with_capacity(1 << 26));
    if parallel {
        image.write().to_buffered(&mut buf).unwrap();
    } else {
        image.write().non_parallel().to_buffered(&mut buf).unwrap();
    }
    buf.into_inner().len()
}

const W: usize = 4000;
const H: usize = 3000;

/// A deterministic photo-like frame: smooth shading, edges, texture and a little noise.
fn frame() -> RawImage {
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 12, 64.0, 4095.0);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
    let mut data = vec![0u16; W * H];
    let mut s: u64 = 1;
    for y in 0..H {
        for x in 0..W {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let n = ((s >> 40) as f64 / (1u64 << 24) as f64 - 0.5) * 0.01;
            let (fx, fy) = (x as f64 / W as f64, y as f64 / H as f64);
            let base = 0.3 + 0.2 * (fx * 9.0).sin() * (fy * 7.0).cos();
            let edge = if ((x / 250) + (y / 250)) % 2 == 0 {
                0.15
            } else {
                0.0
            };
            let tex = 0.05 * ((x as f64 * 0.7).sin() * (y as f64 * 0.3).cos());
            let gain = [0.5, 1.0, 0.6][Bayer::RGGB.color_at(y, x) as usize];
            let v = ((base + edge + tex) * gain + n).clamp(0.0, 1.0);
            data[y * W + x] = (64.0 + v * 4031.0) as u16;
        }
    }
    RawImage {
        width: W,
        height: H,
        data,
        meta,
    }
}

/// CPU time (user + system) of this process in seconds, from /proc/self/stat (Linux).
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = s.rsplit(')').next()?;
    let f: Vec<&str> = rest.split_whitespace().collect();
    // fields 14 and 15 of stat (utime, stime) are at 11 and 12 after the ')'
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// On a shared, loaded machine wall time overstates the cost; print the CPU time of the
/// default render as well (on an idle 2-core machine the wall time is at least half of it).
fn print_cpu_time(raw: &RawImage) {
    for d in Demosaic::ALL {
        let opts = RenderOptions {
            demosaic: d,
            ..RenderOptions::default()
        };
        let n = 5;
        let (c0, t0) = (cpu_seconds(), std::time::Instant::now());
        for _ in 0..n {
            black_box(render(raw, &opts).unwrap());
        }
        let wall = t0.elapsed().as_secs_f64() / n as f64;
        if let (Some(a), Some(b)) = (c0, cpu_seconds()) {
            eprintln!(
                "render_linear 12 MP {d}: wall {:.0} ms, CPU {:.0} ms per render (threads {})",
                wall * 1e3,
                (b - a) / n as f64 * 1e3,
                rayon::current_num_threads()
            );
        }
    }
}

fn benches(c: &mut Criterion) {
    let raw = frame();
    if std::env::var("D2N_BENCH_CPU").is_ok() {
        print_cpu_time(&raw);
    }
    let plane: Vec<f32> = raw
        .data
        .iter()
        .map(|&v| (v as f32 - 64.0) / 4031.0)
        .collect();

    let mut g = c.benchmark_group("demosaic_12mp");
    g.sample_size(10).warm_up_time(Duration::from_secs(1));
    for m in Demosaic::ALL {
        g.bench_with_input(BenchmarkId::from_parameter(m), &m, |b, &m| {
            b.iter(|| black_box(demosaic(&plane, W, H, Bayer::RGGB, m).unwrap()))
        });
    }
    g.finish();

    let rgb = demosaic(&plane, W, H, Bayer::RGGB, Demosaic::Mhc).unwrap();
    let m = color_matrix(&raw.meta, [0.5, 1.0, 0.6]).unwrap();
    let mut g = c.benchmark_group("stages_12mp");
    g.sample_size(10).warm_up_time(Duration::from_secs(1));
    g.bench_function("color", |b| {
        b.iter_batched(
            || rgb.clone(),
            |mut x| {
                apply_matrix(&mut x, &m);
                x
            },
            criterion::BatchSize::LargeInput,
        )
    });
    g.bench_function("normalize", |b| {
        b.iter(|| black_box(day2night::normalize::normalize(&raw, Default::default()).unwrap()))
    });
    for d in Demosaic::ALL {
        g.bench_with_input(BenchmarkId::new("render_linear", d), &d, |b, &d| {
            let opts = RenderOptions {
                demosaic: d,
                ..RenderOptions::default()
            };
            b.iter(|| black_box(render(&raw, &opts).unwrap()))
        });
    }
    g.finish();

    let lin: RgbImage = render(&raw, &RenderOptions::default()).unwrap();
    let mut g = c.benchmark_group("write_12mp");
    g.sample_size(10).warm_up_time(Duration::from_millis(500));
    // (compression, half, zip level): every compression at the default level, then the
    // zip levels and float
    let configs = ExrCompression::ALL
        .iter()
        .map(|&c| (c, true, ExrOptions::DEFAULT_ZIP_LEVEL))
        .chain([
            (ExrCompression::Zip, true, 4),
            (ExrCompression::Zip, true, 6),
            (ExrCompression::None, false, 1),
            (ExrCompression::Zip, false, 1),
            (ExrCompression::Piz, false, 1),
        ]);
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for (comp, half, zip_level) in configs {
        let opts = ExrOptions {
            half,
            compression: comp,
            zip_level,
        };
        let mut buf = Cursor::new(Vec::new());
        encode_exr(&lin, &mut buf, &opts, &[]).unwrap();
        let kind = if half { "half" } else { "float" };
        let level = if matches!(comp, ExrCompression::Zip | ExrCompression::Zips) {
            format!("_l{zip_level}")
        } else {
            String::new()
        };
        eprintln!(
            "exr size {comp}{level} {kind}: {} bytes ({:.2} bytes/pixel)",
            buf.get_ref().len(),
            buf.get_ref().len() as f64 / (W * H) as f64
        );
        let enc = || {
            let mut buf = Cursor::new(Vec::with_capacity(1 << 26));
            encode_exr(&lin, &mut buf, &opts, &[]).unwrap();
            black_box(buf.into_inner().len())
        };
        g.bench_function(format!("exr_{comp}{level}_{kind}"), |b| b.iter(enc));
        if comp == ExrCompression::Zip && half {
            g.bench_function(format!("exr_{comp}{level}_{kind}_1thread"), |b| {
                b.iter(|| one_thread.install(enc))
            });
        }
    }
    // the writer used before the own encoder: the exr crate's ZIP (level 4, fixed)
    eprintln!(
        "exr size exr-crate zip_l4 half: {} bytes",
        old_exr_crate_zip(&lin, true)
    );
    g.bench_function("exr_crate_zip_l4_half", |b| {
        b.iter(|| black_box(old_exr_crate_zip(&lin, true)))
    });
    g.bench_function("exr_crate_zip_l4_half_1thread", |b| {
        b.iter(|| black_box(old_exr_crate_zip(&lin, false)))
    });
    g.bench_function("png8", |b| {
        b.iter(|| {
            let bytes = day2night::encode::png::encode_u8(&lin, Default::default());
            let mut out = Vec::new();
            let enc = image::codecs::png::PngEncoder::new(&mut out);
            image::ImageEncoder::write_image(
                enc,
                &bytes,
                W as u32,
                H as u32,
                image::ExtendedColorType::Rgb8,
            )
            .unwrap();
            black_box(out.len())
        })
    });
    g.finish();
}

/// CPU time (user + system, all threads) per call of the banded and reference renders and
/// of the PNG quantizer (lookup and formula), interleaved so that both see the same load.
fn print_cpu_time_render_png(raw: &RawImage) {
    let opts = RenderOptions::default();
    let lin = render(raw, &opts).unwrap();
    let n = 8;
    let mut cpu = [0.0f64; 4];
    let mut wall = [0.0f64; 4];
    for _ in 0..n {
        for (k, cell) in cpu.iter_mut().enumerate() {
            let (c0, t0) = (cpu_seconds().unwrap_or(0.0), std::time::Instant::now());
            match k {
                0 => drop(black_box(render(raw, &opts).unwrap())),
                1 => drop(black_box(
                    render_with(raw, &opts, Execution::WholeFrame).unwrap(),
                )),
                2 => drop(black_box(day2night::encode::png::encode_u8(
                    &lin,
                    Default::default(),
                ))),
                _ => drop(black_box(day2night::encode::png::encode_u8_slow(
                    &lin,
                    Default::default(),
                ))),
            }
            wall[k] += t0.elapsed().as_secs_f64();
            *cell += cpu_seconds().unwrap_or(0.0) - c0;
        }
    }
    let names = [
        "render_linear mhc (banded)",
        "render_linear mhc (reference)",
        "encode_u8 srgb (lookup)",
        "encode_u8 srgb (formula)",
    ];
    for k in 0..4 {
        eprintln!(
            "{}: wall {:.0} ms, CPU {:.0} ms per call (mean of {n}, threads {})",
            names[k],
            wall[k] / n as f64 * 1e3,
            cpu[k] / n as f64 * 1e3,
            rayon::current_num_threads()
        );
    }
}

/// Render and PNG quantization on the whole-program benchmark input (12 MP 10-bit RGGB DNG
/// from `cargo run --release --example make_bench_input -- /tmp/isp2-day.dng`; path in
/// `D2N_BENCH_DNG`). Skipped with a message when the file is missing.
fn render_png_benches(c: &mut Criterion) {
    let path = std::env::var("D2N_BENCH_DNG").unwrap_or_else(|_| "/tmp/isp2-day.dng".into());
    let raw = match day2night::dng::read::read_dng(std::path::Path::new(&path)) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("render_png benches skipped: {path}: {e}");
            return;
        }
    };
    if std::env::var("D2N_BENCH_CPU").is_ok() {
        print_cpu_time_render_png(&raw);
    }
    let mut g = c.benchmark_group("render_png_12mp_dng");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4));
    let opts = RenderOptions::default();
    g.bench_function("render_linear_mhc", |b| {
        b.iter(|| black_box(render(&raw, &opts).unwrap()))
    });
    // the unfused whole-image path the banded render replaced (same output bits)
    g.bench_function("render_linear_mhc_reference", |b| {
        b.iter(|| black_box(render_with(&raw, &opts, Execution::WholeFrame).unwrap()))
    });
    let lin = render(&raw, &opts).unwrap();
    g.bench_function("encode_u8_srgb", |b| {
        b.iter(|| black_box(day2night::encode::png::encode_u8(&lin, Default::default())))
    });
    // the per-sample formula the lookup replaced (same bytes)
    g.bench_function("encode_u8_srgb_formula", |b| {
        b.iter(|| {
            black_box(day2night::encode::png::encode_u8_slow(
                &lin,
                Default::default(),
            ))
        })
    });
    g.finish();
}

criterion_group!(isp, benches);
criterion_group!(render_png, render_png_benches);
criterion_main!(isp, render_png);
