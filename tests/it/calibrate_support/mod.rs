//! Generators shared by the calibrate_* integration tests: synthetic frames written through
//! the project's own DNG writer.
#![allow(dead_code)]

use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::path::{Path, PathBuf};

/// A frame with the given samples.
pub fn frame(w: usize, h: usize, data: Vec<u16>, black: f64, white: f64, iso: u32) -> RawImage {
    let bits = if white > 4095.0 { 16 } else { 12 };
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, bits, black, white);
    meta.exif.iso = Some(iso);
    // An 8-pixel border outside the default crop: the DNG SDK wants room to demosaic.
    if w > 32 && h > 32 {
        meta.default_crop_origin = Some([8.0, 8.0]);
        meta.default_crop_size = Some([(w - 16) as f64, (h - 16) as f64]);
    }
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

/// Write `img` to `dir/name` with the project's writer.
pub fn write(dir: &Path, name: &str, img: &RawImage) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, encode_dng(img, &WriteOptions::default()).unwrap()).unwrap();
    p
}

/// Dark-heavy ramp scene (stored values), like the Python generator.
pub fn ramp_scene(w: usize, h: usize, black: f64, white: f64, seed: u64) -> Vec<f64> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let scale = white - black;
    (0..w * h)
        .map(|i| {
            let t = (i % w) as f64 / w as f64;
            let u: f64 = rand::RngExt::random(&mut rng);
            ((0.9 * t * t + 0.01 * u) * scale + black).round()
        })
        .collect()
}

/// One noisy frame of `clean` with `var(y) = s y + o` (normalized), rounded and clipped.
pub fn noisy(clean: &[f64], black: f64, white: f64, s: f64, o: f64, seed: u64) -> Vec<u16> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let scale = white - black;
    clean
        .iter()
        .map(|&x| {
            let y = (x - black) / scale;
            let sd = (s * y + o).max(0.0).sqrt() * scale;
            let z: f64 = StandardNormal.sample(&mut rng);
            (x + z * sd).round().clamp(0.0, white) as u16
        })
        .collect()
}

/// Write a burst of `n` frames; returns the paths.
#[allow(clippy::too_many_arguments)]
pub fn burst(
    dir: &Path,
    prefix: &str,
    n: usize,
    (w, h): (usize, usize),
    (black, white): (f64, f64),
    (s, o): (f64, f64),
    iso: u32,
    seed: u64,
) -> Vec<PathBuf> {
    let clean = ramp_scene(w, h, black, white, seed);
    (0..n)
        .map(|k| {
            let img = frame(
                w,
                h,
                noisy(&clean, black, white, s, o, seed * 1000 + k as u64 + 1),
                black,
                white,
                iso,
            );
            write(dir, &format!("{prefix}_{k:02}.dng"), &img)
        })
        .collect()
}

/// Run the binary; returns (exit code, stdout, stderr).
pub fn run(args: &[&std::ffi::OsStr]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_day2night"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `OsStr` argument list from anything path-like.
#[macro_export]
macro_rules! args {
    ($($a:expr),* $(,)?) => {{
        let v: Vec<std::ffi::OsString> = vec![$(std::ffi::OsString::from($a)),*];
        v
    }};
}

/// Run with an owned argument list.
pub fn run_os(args: &[std::ffi::OsString]) -> (i32, String, String) {
    let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    run(&refs)
}
