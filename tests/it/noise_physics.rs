//! Physics-based noise model, closed loop: dark and flat frames of synthetic cameras with
//! known K, lambda, sigma_read and sigma_row (generated here, independently of the crate's
//! sampler, and written with the project's DNG writer) are calibrated with
//! `calibrate noise --physics`; the fitted file then drives `synth --noise-model`, whose
//! added noise is measured against the model at a calibrated ISO and between two.
use crate::args;
use crate::calibrate_support;
use crate::common;

use calibrate_support::*;
use day2night::dng::read_dng;
use day2night::noise::physics::PhysicsModel;
use day2night::noise::tukey;
use day2night::noise::NoiseModel;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Poisson, StandardNormal};
use serde_json::Value;
use std::path::{Path, PathBuf};

const BLACK: f64 = 512.0;
const WHITE: f64 = 16383.0;
const W: usize = 256;
const H: usize = 256;

/// A synthetic camera at one ISO.
#[derive(Clone, Copy, Debug)]
struct Truth {
    iso: u32,
    k: f64,
    read: f64,
    lambda: f64,
    row: f64,
}

const CAMERA: [Truth; 3] = [
    Truth {
        iso: 400,
        k: 0.5,
        read: 2.0,
        lambda: 0.0,
        row: 0.6,
    },
    Truth {
        iso: 800,
        k: 1.0,
        read: 3.0,
        lambda: 0.05,
        row: 1.0,
    },
    Truth {
        iso: 1600,
        k: 2.0,
        read: 5.0,
        lambda: -0.05,
        row: 2.0,
    },
];

/// Tukey-lambda quantile, written out here (not the crate's).
fn q(p: f64, l: f64) -> f64 {
    if l == 0.0 {
        (p / (1.0 - p)).ln()
    } else {
        (p.powf(l) - (1.0 - p).powf(l)) / l
    }
}

/// Standard deviation of the standard Tukey-lambda distribution by midpoint quadrature.
fn tukey_sd(l: f64) -> f64 {
    let n = 400_000;
    let s: f64 = (0..n)
        .map(|i| q((i as f64 + 0.5) / n as f64, l).powi(2))
        .sum();
    (s / n as f64).sqrt()
}

/// One frame: black + K * Poisson(mu / K) + read + row, rounded and clipped.
fn frame_data(t: &Truth, mu: f64, seed: u64) -> Vec<u16> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sd = tukey_sd(t.lambda);
    let mut out = Vec::with_capacity(W * H);
    for _ in 0..H {
        let z: f64 = StandardNormal.sample(&mut rng);
        let row = t.row * z;
        for _ in 0..W {
            let shot = if mu > 0.0 {
                let n: f64 = Poisson::new(mu / t.k).unwrap().sample(&mut rng);
                t.k * n
            } else {
                0.0
            };
            let u: f64 = rand::RngExt::random(&mut rng);
            let u = u.clamp(1e-300, 1.0 - 1e-16);
            let read = t.read * q(u, t.lambda) / sd;
            out.push((BLACK + shot + read + row).round().clamp(0.0, WHITE) as u16);
        }
    }
    out
}

fn write_frames(dir: &Path, t: &Truth) -> (Vec<PathBuf>, Vec<PathBuf>) {
    let mut darks = vec![];
    let mut flats = vec![];
    for k in 0..4u64 {
        let img = frame(
            W,
            H,
            frame_data(t, 0.0, t.iso as u64 * 100 + k),
            BLACK,
            WHITE,
            t.iso,
        );
        darks.push(write(dir, &format!("dark{}_{k}.dng", t.iso), &img));
    }
    // two pairs at two levels
    for (k, mu) in [2000.0, 2000.0, 6000.0, 6000.0].into_iter().enumerate() {
        let img = frame(
            W,
            H,
            frame_data(t, mu, t.iso as u64 * 100 + 50 + k as u64),
            BLACK,
            WHITE,
            t.iso,
        );
        flats.push(write(dir, &format!("flat{}_{k}.dng", t.iso), &img));
    }
    (darks, flats)
}

/// Calibrate the synthetic camera; returns the model file's path and its JSON.
fn calibrate(dir: &Path) -> (PathBuf, Value) {
    let mut args = args!["calibrate", "noise", "--physics"];
    let mut flats_all = vec![];
    args.push("--dark".into());
    for t in &CAMERA {
        let (d, f) = write_frames(dir, t);
        args.extend(d.into_iter().map(Into::into));
        flats_all.extend(f);
    }
    args.push("--flat".into());
    args.extend(flats_all.into_iter().map(Into::into));
    let out = dir.join("physics.json");
    let plot = dir.join("physics.svg");
    args.extend(args!["-o", &out, "--plot", &plot]);
    let (code, _, err) = run_os(&args);
    assert_eq!(code, 0, "{err}");
    eprintln!("{err}");
    assert!(err.contains("K DN/e-"), "table printed: {err}");
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("ISO 800"));
    // D2N_WRITE_DOC_FIGURES=1 refreshes the figure of docs/calibration.md.
    if std::env::var_os("D2N_WRITE_DOC_FIGURES").is_some() {
        std::fs::write(
            common::root().join("docs/img/calibration_physics.svg"),
            &svg,
        )
        .unwrap();
    }
    let text = std::fs::read_to_string(&out).unwrap();
    (out, serde_json::from_str(&text).unwrap())
}

#[test]
fn closed_loop_calibration_and_synthesis() {
    let dir = tempfile::tempdir().unwrap();
    let (model_path, v) = calibrate(dir.path());
    assert_eq!(v["model"], "physics");
    // Fitted parameters against the truth.
    for t in &CAMERA {
        let p = v["isos"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["iso"].as_u64() == Some(t.iso as u64))
            .unwrap();
        let f = |k: &str| p[k].as_f64().unwrap();
        eprintln!(
            "ISO {}: K {:+.2}%  read {:+.2}%  row {:+.2}%  lambda {:+.3}",
            t.iso,
            100.0 * (f("k") / t.k - 1.0),
            100.0 * (f("sigma_read") / t.read - 1.0),
            100.0 * (f("sigma_row") / t.row - 1.0),
            f("lambda") - t.lambda
        );
        assert!((f("k") / t.k - 1.0).abs() < 0.05, "K {p}");
        assert!((f("sigma_read") / t.read - 1.0).abs() < 0.10, "read {p}");
        assert!((f("sigma_row") / t.row - 1.0).abs() < 0.10, "row {p}");
        assert!((f("lambda") - t.lambda).abs() < 0.05, "lambda {p}");
    }
    // The same file is a synth noise model.
    let text = std::fs::read_to_string(&model_path).unwrap();
    let nm = NoiseModel::from_json(&text).unwrap();
    let pm = nm.physics.clone().unwrap();
    assert_eq!(pm, PhysicsModel::from_json(&text).unwrap());
    synth_reproduces(dir.path(), &model_path, &pm, 800);
    synth_reproduces(dir.path(), &model_path, &pm, 600);
}

/// Clean test chart: rows 0..DARK_ROWS at black, then bands at three levels.
const CW: usize = 128;
const CH: usize = 1280;
const DARK_ROWS: usize = 1024;
const LEVELS: [f64; 3] = [1500.0, 4000.0, 9000.0];

fn chart() -> Vec<u16> {
    let mut d = vec![0u16; CW * CH];
    for r in 0..CH {
        let v = if r < DARK_ROWS {
            BLACK
        } else {
            BLACK + LEVELS[(r - DARK_ROWS) * 3 / (CH - DARK_ROWS)]
        };
        d[r * CW..][..CW].fill(v as u16);
    }
    d
}

fn var(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    (
        m,
        v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0),
    )
}

fn synth_reproduces(dir: &Path, model: &Path, pm: &PhysicsModel, iso: u32) {
    let e = pm.at(iso).unwrap();
    assert!(!e.extrapolated);
    let p = e.params;
    let mut img = frame(CW, CH, chart(), BLACK, WHITE, 100);
    img.meta.as_shot_neutral = Some([1.0, 1.0, 1.0]);
    let input = write(dir, &format!("chart{iso}.dng"), &img);
    let out = dir.join(format!("out{iso}"));
    let (code, _, err) = run_os(&args![
        "synth",
        &input,
        "-o",
        &out,
        "--mode",
        "day",
        "--iso",
        iso.to_string(),
        "--target",
        "none",
        "--noise-model",
        model
    ]);
    assert_eq!(code, 0, "{err}");
    let stem = format!("chart{iso}");
    let clean = read_dng(&out.join(format!("{stem}_clean.dng"))).unwrap();
    assert_eq!(clean.data, img.data);
    let noisy = read_dng(&out.join(format!("{stem}_iso{iso}.dng"))).unwrap();
    // NoiseProfile = the equivalent Gaussian.
    let prof = noisy.meta.noise_profile.clone().unwrap();
    let scale = WHITE - BLACK;
    for (s, o) in &prof {
        assert!(
            (s - p.k / scale).abs() < 1e-12 * s.abs().max(1.0),
            "{prof:?}"
        );
        let want = (p.sigma_read.powi(2) + p.sigma_row.powi(2)) / (scale * scale);
        assert!((o - want).abs() < 1e-9 * want, "{prof:?}");
    }
    // The sidecar records the physics parameters.
    let sc = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "json"))
        .unwrap();
    let sc: Value = serde_json::from_str(&std::fs::read_to_string(sc).unwrap()).unwrap();
    let ph = &sc["plan"]["noise"][0]["physics"];
    assert_eq!(ph["k"].as_f64(), Some(p.k), "{ph}");

    let d: Vec<f64> = noisy
        .data
        .iter()
        .zip(&clean.data)
        .map(|(a, b)| *a as f64 - *b as f64)
        .collect();
    // Dark variance: read + row + rounding.
    let dark = &d[..DARK_ROWS * CW];
    let (_, vd) = var(dark);
    let want_dark = p.sigma_read.powi(2) + p.sigma_row.powi(2) + 1.0 / 12.0;
    // Row variance: variance of row means minus the per-sample share.
    let means: Vec<f64> = dark
        .chunks(CW)
        .map(|r| r.iter().sum::<f64>() / CW as f64)
        .collect();
    let (_, vm) = var(&means);
    let read_var = p.sigma_read.powi(2) + 1.0 / 12.0;
    let row_var = vm - read_var / CW as f64;
    // Read-noise excess kurtosis of the row-corrected residuals (read + rounding).
    let mut m2 = 0.0;
    let mut m4 = 0.0;
    for (r, row) in dark.chunks(CW).enumerate() {
        for x in row {
            let e = x - means[r];
            m2 += e * e;
            m4 += e.powi(4);
        }
    }
    let n = dark.len() as f64;
    let (m2, m4) = (m2 / n, m4 / n);
    let kurt = m4 / (m2 * m2) - 3.0;
    let kr = p.read_excess_kurtosis();
    let want_kurt = (kr * p.sigma_read.powi(4) - 1.2 / 144.0) / read_var.powi(2);
    // Shot gain: slope of var(noisy - clean) against the signal over the bands.
    let band_rows = (CH - DARK_ROWS) / 3;
    let mut sxy = 0.0;
    let mut sxx = 0.0;
    for (b, mu) in LEVELS.iter().enumerate() {
        let s = DARK_ROWS + b * band_rows;
        let (_, v) = var(&d[s * CW..(s + band_rows) * CW]);
        sxy += mu * (v - vd);
        sxx += mu * mu;
    }
    let k = sxy / sxx;
    eprintln!(
        "synth ISO {iso}: shot gain {:+.2}%  dark var {:+.2}%  row var {:+.2}%  read kurtosis {kurt:.3} vs {want_kurt:.3}",
        100.0 * (k / p.k - 1.0),
        100.0 * (vd / want_dark - 1.0),
        100.0 * (row_var / p.sigma_row.powi(2) - 1.0),
    );
    assert!((k / p.k - 1.0).abs() < 0.05, "shot gain {k} vs {}", p.k);
    assert!(
        (vd / want_dark - 1.0).abs() < 0.10,
        "dark {vd} vs {want_dark}"
    );
    assert!(
        (row_var / p.sigma_row.powi(2) - 1.0).abs() < 0.20,
        "row {row_var} vs {}",
        p.sigma_row.powi(2)
    );
    assert!(
        (kurt - want_kurt).abs() < 0.35 * want_kurt.abs(),
        "kurtosis {kurt} vs {want_kurt}"
    );
    assert!(tukey::excess_kurtosis(p.lambda).is_finite());
}

#[test]
fn calibration_refusals() {
    let dir = tempfile::tempdir().unwrap();
    let t = CAMERA[1];
    let (darks, flats) = write_frames(dir.path(), &t);
    let run_cal = |d: &[PathBuf], f: &[PathBuf]| {
        let mut a = args!["calibrate", "noise", "--physics", "--dark"];
        a.extend(d.iter().map(Into::into));
        a.push("--flat".into());
        a.extend(f.iter().map(Into::into));
        a.extend(args!["-o", dir.path().join("x.json"), "--overwrite"]);
        run_os(&a)
    };
    // too few frames
    let (code, _, err) = run_cal(&darks[..1], &flats);
    assert_ne!(code, 0);
    assert!(err.contains("need at least"), "{err}");
    let (code, _, err) = run_cal(&darks, &flats[..1]);
    assert_ne!(code, 0);
    assert!(err.contains("need at least"), "{err}");
    // saturated flats
    let sat: Vec<PathBuf> = (0..2)
        .map(|k| {
            let mut img = frame(W, H, frame_data(&t, 15000.0, 900 + k), BLACK, WHITE, t.iso);
            img.data[7] = WHITE as u16;
            img.data[77] = WHITE as u16;
            img.data[777] = WHITE as u16;
            img.data[7777] = WHITE as u16;
            img.data[17777] = WHITE as u16;
            img.data[27777] = WHITE as u16;
            img.data[37777] = WHITE as u16;
            write(dir.path(), &format!("sat{k}.dng"), &img)
        })
        .collect();
    let (code, _, err) = run_cal(&darks, &sat);
    assert_ne!(code, 0);
    assert!(err.contains("saturated"), "{err}");
    // uneven flats: a left-to-right ramp
    let uneven: Vec<PathBuf> = (0..2)
        .map(|k| {
            let mut img = frame(W, H, frame_data(&t, 0.0, 950 + k), BLACK, WHITE, t.iso);
            for (i, v) in img.data.iter_mut().enumerate() {
                *v += (20 * (i % W)) as u16;
            }
            write(dir.path(), &format!("uneven{k}.dng"), &img)
        })
        .collect();
    let (code, _, err) = run_cal(&darks, &uneven);
    assert_ne!(code, 0);
    assert!(err.contains("uneven"), "{err}");
    // --dark without --physics is a usage error
    let (code, _, _) = run_os(&args![
        "calibrate",
        "noise",
        "--dark",
        &darks[0],
        "-o",
        dir.path().join("y.json")
    ]);
    assert_ne!(code, 0);
}

/// The Gaussian model file format still loads as before (no `physics`), and writing it
/// gives the same bytes.
#[test]
fn gaussian_files_unchanged() {
    let m = day2night::synth::dictionaries::embedded::noise_model();
    let j = m.to_json();
    assert!(!j.contains("physics"));
    let back = NoiseModel::from_json(&j).unwrap();
    assert!(back.physics.is_none());
    assert_eq!(back.to_json(), j);
}
