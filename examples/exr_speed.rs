//! Time `encode_exr` (into memory) of the rendered 12 MP linear target per EXR compression,
//! zip level and thread count, against the `exr` crate's own ZIP writer (the path used
//! before: level 4 fixed, per-pixel closure). Best of `RUNS` (default 3) runs per row.
//!
//! `cargo run --release --example make_bench_input -- /tmp/day.dng`
//! `cargo run --release --example exr_speed -- /tmp/day.dng [RUNS]`
use day2night::encode::exr::{encode_exr, ExrCompression, ExrOptions};
use day2night::isp::render::{render, RenderOptions};
use day2night::isp::RgbImage;
use exr::prelude::*;
use std::io::Cursor;
use std::time::Instant;

/// The previous writer: the exr crate's ZIP16 through its per-pixel closure.
fn old_exr_crate_zip(img: &RgbImage, parallel: bool) -> usize {
    let w = img.width;
    let d = &img.data;
    let at = |x: usize, y: usize, c: usize| {
        let v = d[3 * (y * w + x) + c];
        if v.is_nan() {
            f16::ZERO
        } else {
            f16::from_f32(v.clamp(-65504.0, 65504.0))
        }
    };
    let ch =
        SpecificChannels::rgb(|p: Vec2<usize>| (at(p.0, p.1, 0), at(p.0, p.1, 1), at(p.0, p.1, 2)));
    let enc = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let image = Image::from_layer(Layer::new(
        (img.width, img.height),
        LayerAttributes::default(),
        enc,
        ch,
    ));
    let mut buf = Cursor::new(Vec::with_capacity(1 << 26));
    if parallel {
        image.write().to_buffered(&mut buf).unwrap();
    } else {
        image.write().non_parallel().to_buffered(&mut buf).unwrap();
    }
    buf.into_inner().len()
}

fn best<F: FnMut() -> usize>(runs: usize, mut f: F) -> (f64, usize) {
    let mut best = f64::MAX;
    let mut len = 0;
    for _ in 0..runs {
        let t = Instant::now();
        len = f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best * 1e3, len)
}

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let p = std::env::args()
        .nth(1)
        .ok_or("usage: exr_speed DAY.dng [RUNS]")?;
    let runs: usize = std::env::args().nth(2).map_or(Ok(3), |s| s.parse())?;
    let img = day2night::dng::read::read_dng(std::path::Path::new(&p))?;
    let t = Instant::now();
    let rgb = render(&img, &RenderOptions::default())?;
    let px = (rgb.width * rgb.height) as f64;
    eprintln!(
        "render_linear {}x{} {:.0} ms",
        rgb.width,
        rgb.height,
        t.elapsed().as_secs_f64() * 1e3
    );
    println!("| writer | samples | threads | ms (best of {runs}) | MB | bytes/pixel |");
    println!("|---|---|---|---|---|---|");
    let rows: Vec<(ExrCompression, bool, u8)> = vec![
        (ExrCompression::None, true, 1),
        (ExrCompression::Zips, true, 1),
        (ExrCompression::Zip, true, 1),
        (ExrCompression::Zip, true, 4),
        (ExrCompression::Zip, true, 6),
        (ExrCompression::Zip, false, 1),
        (ExrCompression::Piz, true, 1),
    ];
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        for &(compression, half, zip_level) in &rows {
            let opts = ExrOptions {
                half,
                compression,
                zip_level,
            };
            let (ms, len) = pool.install(|| {
                best(runs, || {
                    let mut buf = Cursor::new(Vec::with_capacity(1 << 26));
                    encode_exr(&rgb, &mut buf, &opts, &[]).unwrap();
                    buf.into_inner().len()
                })
            });
            let name = match compression {
                ExrCompression::Zip | ExrCompression::Zips => {
                    format!("own {compression} level {zip_level}")
                }
                ExrCompression::None => "own none".into(),
                _ => format!("exr crate {compression}"),
            };
            println!(
                "| {name} | {} | {threads} | {ms:.0} | {:.1} | {:.2} |",
                if half { "half" } else { "float" },
                len as f64 / 1e6,
                len as f64 / px
            );
        }
        let (ms, len) = best(runs, || old_exr_crate_zip(&rgb, threads > 1));
        println!(
            "| old: exr crate zip (level 4) | half | {threads} | {ms:.0} | {:.1} | {:.2} |",
            len as f64 / 1e6,
            len as f64 / px
        );
    }
    Ok(())
}
