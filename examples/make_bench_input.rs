//! Generate the whole-program benchmark input (issue 7): a deterministic 12 MP 10-bit RGGB
//! day DNG, 4032 x 3024, black 64, white 1023 (same scene model as `make_fixtures`:
//! colour and grey ramps, saturated patches with texture, plus hash noise).
//!
//! ```text
//! cargo run --release --example make_bench_input -- OUT.dng [WIDTH HEIGHT]
//! ```

#[path = "common/scene.rs"]
mod scene;

use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::raw::{Bayer, RawImage};
use scene::{d65_neutral, day_meta, hash01, synthetic_scene};

/// Texture frequency of the benchmark scene (radians per pixel, x and y): ten times coarser
/// than the fixtures', for a 12 MP frame.
const TEXTURE: [f64; 2] = [0.03, 0.02];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = args
        .next()
        .ok_or("usage: make_bench_input OUT.dng [WIDTH HEIGHT]")?;
    let w: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(4032);
    let h: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(3024);
    let (black, white) = (64.0, 1023.0);
    let neutral = d65_neutral();
    let mut m = day_meta(Bayer::RGGB, 10, black, white);
    m.default_crop_origin = Some([2.0, 2.0]);
    m.default_crop_size = Some([(w - 4) as f64, (h - 4) as f64]);
    let mut data = vec![0u16; w * h];
    let peak = neutral.iter().cloned().fold(1.0, f64::max);
    for y in 0..h {
        for x in 0..w {
            let rgb = synthetic_scene(x, y, w, h, neutral, TEXTURE);
            let c = Bayer::RGGB.color_at(y, x) as usize;
            let lin = (rgb[c] / peak * 0.9).clamp(0.0, 1.0);
            let n = (hash01(x as u64, y as u64, 0) - 0.5) * 4.0;
            let v = black + lin * (white - black) + n;
            data[y * w + x] = v.round().clamp(0.0, white) as u16;
        }
    }
    let img = RawImage {
        width: w,
        height: h,
        data,
        meta: m,
    };
    img.validate()?;
    let bytes = encode_dng(&img, &WriteOptions::default())?;
    std::fs::write(&out, bytes)?;
    Ok(())
}
