//! Render a DNG with the default options (MHC, crop, orientation) and encode the 8-bit
//! sRGB PNG samples, to measure peak memory (`/usr/bin/time -f %M`) and to profile:
//!
//! ```text
//! cargo run --release --example render_peak -- IN.dng [banded|reference] [REPEAT] [render-only]
//! ```
//! `reference` uses the unfused whole-image render and the per-sample PNG formula;
//! `render-only` skips the PNG samples (peak memory of the render alone).
use day2night::dng::read::read_dng;
use day2night::encode::png::{encode_u8, encode_u8_slow};
use day2night::isp::render::{render, render_with, Execution, RenderOptions};
use std::hint::black_box;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: render_peak IN.dng [banded|reference] [REPEAT]")?;
    let reference = args.get(2).is_some_and(|m| m == "reference");
    let repeat: usize = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let render_only = args.get(4).is_some_and(|m| m == "render-only");
    let raw = read_dng(std::path::Path::new(path))?;
    let opts = RenderOptions::default();
    for _ in 0..repeat {
        let t = std::time::Instant::now();
        let rgb = if reference {
            render_with(&raw, &opts, Execution::WholeFrame)?
                .ok_or("the whole-frame render is always made")?
                .image
        } else {
            render(&raw, &opts)?
        };
        let t_render = t.elapsed();
        let t = std::time::Instant::now();
        let bytes = if render_only {
            Vec::new()
        } else if reference {
            encode_u8_slow(&rgb, Default::default())
        } else {
            encode_u8(&rgb, Default::default())
        };
        eprintln!(
            "{}x{}: render {:.1} ms, encode_u8 {:.1} ms",
            rgb.width,
            rgb.height,
            t_render.as_secs_f64() * 1e3,
            t.elapsed().as_secs_f64() * 1e3
        );
        black_box(bytes);
    }
    Ok(())
}
