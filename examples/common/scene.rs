//! The synthetic day scene shared by the example generators (`make_fixtures`,
//! `make_bench_input`): a plausible camera (Canon EOS 5D Mark II ColorMatrix, D65), its
//! metadata, deterministic hash noise, and a scene of colour and grey ramps with textured
//! saturated patches. Included with `#[path = "common/scene.rs"] mod scene;` (not an example
//! of its own). Changing anything here changes the committed fixtures
//! (tests/it/fixtures_reproducible.rs) and the benchmark input.

use day2night::raw::meta::{ExifInfo, RawMeta};
use day2night::raw::Bayer;

/// Canon EOS 5D Mark II ColorMatrix (D65), as published in dcraw's adobe_coeff table: a
/// plausible real camera's XYZ -> camera matrix.
pub const CM1: [f64; 9] = [
    0.4716, 0.0603, -0.0830, -0.7798, 1.5474, 0.2480, -0.1496, 0.1937, 0.6651,
];
/// Linear sRGB -> XYZ (D65): the library's tabulated 7-digit matrix.
pub const SRGB_TO_XYZ: [f64; 9] = day2night::color::xyz::SRGB_TO_XYZ_TABULATED;

/// 3x3 matrix (row-major) times vector.
pub fn mat_vec(m: &[f64; 9], v: [f64; 3]) -> [f64; 3] {
    [
        m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
        m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
        m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
    ]
}

/// Deterministic hash noise in [0, 1).
pub fn hash01(a: u64, b: u64, seed: u64) -> f64 {
    let mut x = a
        .wrapping_mul(0x9E3779B97F4A7C15)
        .wrapping_add(b.wrapping_mul(0xC2B2AE3D27D4EB4F))
        .wrapping_add(seed.wrapping_mul(0x165667B19E3779F9));
    x ^= x >> 33;
    x = x.wrapping_mul(0xFF51AFD7ED558CCD);
    x ^= x >> 33;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// Camera-space neutral of D65 white through CM1, green = 1.
pub fn d65_neutral() -> [f64; 3] {
    let white = mat_vec(&SRGB_TO_XYZ, [1.0, 1.0, 1.0]);
    let cam = mat_vec(&CM1, white);
    [cam[0] / cam[1], 1.0, cam[2] / cam[1]]
}

/// Metadata of a synthetic day capture: CM1 under D65 (illuminant 21), the D65 neutral,
/// ISO 100, 1/125 s, f/5.6, a fixed date; levels `black` and `white`.
pub fn day_meta(bayer: Bayer, bits: u16, black: f64, white: f64) -> RawMeta {
    let mut m = RawMeta::new_bayer(bayer, bits, black, white);
    m.color.color_matrix1 = Some(CM1.to_vec());
    m.color.calibration_illuminant1 = Some(21);
    m.as_shot_neutral = Some(d65_neutral());
    m.exif = ExifInfo {
        iso: Some(100),
        exposure_time: Some(1.0 / 125.0),
        f_number: Some(5.6),
        date_time_original: Some("2024:06:01 12:00:00".into()),
    };
    m
}

/// The synthetic scene at pixel (x, y) of a w x h frame in linear camera RGB
/// (white-balanced camera space times `neutral`): a grey ramp (top quarter), colour ramps
/// (second quarter) and six saturated patches (bottom half) modulated by a sine texture of
/// angular frequency `texture` = (per column, per row) radians per pixel.
pub fn synthetic_scene(
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    neutral: [f64; 3],
    texture: [f64; 2],
) -> [f64; 3] {
    let u = x as f64 / w.max(1) as f64;
    let v = y as f64 / h.max(1) as f64;
    let rgb = if v < 0.25 {
        [u, u, u] // grey ramp
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
        let s = 0.6 + 0.4 * ((x as f64 * texture[0]).sin() * (y as f64 * texture[1]).cos());
        [c[0] * s, c[1] * s, c[2] * s]
    };
    [
        rgb[0] * neutral[0],
        rgb[1] * neutral[1],
        rgb[2] * neutral[2],
    ]
}
