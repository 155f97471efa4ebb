//! Scratch: time `encode_exr` (into memory) of a rendered 12 MP target per EXR compression.
//! `cargo run --release --example exr_speed -- DAY.dng`
use day2night::exr::{encode_exr, ExrCompression, ExrOptions};
use day2night::isp::render::{render_linear, RenderOptions};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let p = std::env::args().nth(1).ok_or("usage: exr_speed DAY.dng")?;
    let img = day2night::dng::read::read_dng(std::path::Path::new(&p))?;
    let t = Instant::now();
    let rgb = render_linear(&img, &RenderOptions::default())?;
    println!("render_linear {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
    for c in ExrCompression::ALL {
        let mut best = f64::MAX;
        let mut len = 0;
        for _ in 0..3 {
            let mut buf = std::io::Cursor::new(Vec::new());
            let t = Instant::now();
            encode_exr(
                &rgb,
                &mut buf,
                &ExrOptions {
                    half: true,
                    compression: c,
                },
                &[],
            )?;
            best = best.min(t.elapsed().as_secs_f64());
            len = buf.into_inner().len();
        }
        println!("{:?}: {:.0} ms, {:.1} MB", c, best * 1e3, len as f64 / 1e6);
    }
    Ok(())
}
