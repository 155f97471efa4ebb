//! Generate the whole-program benchmark input (issue 7): a deterministic 12 MP 10-bit RGGB
//! day DNG, 4032 x 3024, black 64, white 1023 (same scene model as `make_fixtures`:
//! colour and grey ramps, saturated patches with texture, plus hash noise).
//!
//! ```text
//! cargo run --release --example make_bench_input -- OUT.dng [WIDTH HEIGHT]
//! ```

use day2night::dng::meta::{ExifInfo, RawMeta};
use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::raw::{Bayer, RawImage};

/// Canon EOS 5D Mark II ColorMatrix (D65), dcraw's adobe_coeff table.
const CM1: [f64; 9] = [
    0.4716, 0.0603, -0.0830, -0.7798, 1.5474, 0.2480, -0.1496, 0.1937, 0.6651,
];
const SRGB_TO_XYZ: [f64; 9] = [
    0.4124564, 0.3575761, 0.1804375, 0.2126729, 0.7151522, 0.0721750, 0.0193339, 0.1191920,
    0.9503041,
];

fn mat_vec(m: &[f64; 9], v: [f64; 3]) -> [f64; 3] {
    [
        m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
        m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
        m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
    ]
}

fn hash01(a: u64, b: u64) -> f64 {
    let mut x = a
        .wrapping_mul(0x9E3779B97F4A7C15)
        .wrapping_add(b.wrapping_mul(0xC2B2AE3D27D4EB4F));
    x ^= x >> 33;
    x = x.wrapping_mul(0xFF51AFD7ED558CCD);
    x ^= x >> 33;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

fn scene(x: usize, y: usize, w: usize, h: usize, neutral: [f64; 3]) -> [f64; 3] {
    let u = x as f64 / w as f64;
    let v = y as f64 / h as f64;
    let rgb = if v < 0.25 {
        [u, u, u]
    } else if v < 0.5 {
        [u, 1.0 - u, 0.5 * (1.0 - (2.0 * u - 1.0).abs())]
    } else {
        let patch = ((u * 6.0) as usize + 6 * ((v - 0.5) * 4.0) as usize) % 6;
        let c = [
            [0.8, 0.1, 0.1],
            [0.1, 0.7, 0.1],
            [0.1, 0.1, 0.8],
            [0.8, 0.8, 0.1],
            [0.1, 0.7, 0.8],
            [0.18, 0.18, 0.18],
        ][patch];
        let s = 0.6 + 0.4 * ((x as f64 * 0.03).sin() * (y as f64 * 0.02).cos());
        [c[0] * s, c[1] * s, c[2] * s]
    };
    [
        rgb[0] * neutral[0],
        rgb[1] * neutral[1],
        rgb[2] * neutral[2],
    ]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = args
        .next()
        .ok_or("usage: make_bench_input OUT.dng [WIDTH HEIGHT]")?;
    let w: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(4032);
    let h: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(3024);
    let (black, white) = (64.0, 1023.0);
    let white_xyz = mat_vec(&SRGB_TO_XYZ, [1.0, 1.0, 1.0]);
    let cam = mat_vec(&CM1, white_xyz);
    let neutral = [cam[0] / cam[1], 1.0, cam[2] / cam[1]];
    let mut m = RawMeta::new_bayer(Bayer::RGGB, 10, black, white);
    m.color.color_matrix1 = Some(CM1.to_vec());
    m.color.calibration_illuminant1 = Some(21);
    m.as_shot_neutral = Some(neutral);
    m.default_crop_origin = Some([2.0, 2.0]);
    m.default_crop_size = Some([(w - 4) as f64, (h - 4) as f64]);
    m.exif = ExifInfo {
        iso: Some(100),
        exposure_time: Some(1.0 / 125.0),
        f_number: Some(5.6),
        date_time_original: Some("2024:06:01 12:00:00".into()),
    };
    let mut data = vec![0u16; w * h];
    let peak = neutral.iter().cloned().fold(1.0, f64::max);
    for y in 0..h {
        for x in 0..w {
            let rgb = scene(x, y, w, h, neutral);
            let c = Bayer::RGGB.color_at(y, x) as usize;
            let lin = (rgb[c] / peak * 0.9).clamp(0.0, 1.0);
            let n = (hash01(x as u64, y as u64) - 0.5) * 4.0;
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
