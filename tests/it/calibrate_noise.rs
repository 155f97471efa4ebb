//! Closed-loop tests of `calibrate noise`: bursts and pairs generated with a known model
//! (by the project's writer AND by an independent tifffile script) are calibrated, and the
//! recovered S and O are compared with the truth.
use crate::args;
use crate::calibrate_support;
use crate::common;

use calibrate_support::*;
use serde_json::Value;
use std::ffi::OsString;
use std::path::PathBuf;

fn positions(model: &Value, iso: u64) -> Vec<Value> {
    model["isos"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["iso"].as_u64() == Some(iso))
        .unwrap_or_else(|| panic!("no ISO {iso} in {model}"))["fits"]
        .as_array()
        .unwrap()
        .clone()
}

fn assert_close(model: &Value, iso: u64, s: f64, o: f64, tol: f64) {
    for p in positions(model, iso) {
        let (fs, fo) = (p["S"].as_f64().unwrap(), p["O"].as_f64().unwrap());
        eprintln!(
            "ISO {iso} pos {}: S {:+.2}%  O {:+.2}%",
            p["position"],
            100.0 * (fs / s - 1.0),
            100.0 * (fo / o - 1.0)
        );
        assert!((fs / s - 1.0).abs() < tol, "ISO {iso}: S {fs} vs {s}: {p}");
        assert!((fo / o - 1.0).abs() < tol, "ISO {iso}: O {fo} vs {o}: {p}");
    }
}

/// 16 frames of 1024x512 per ISO (the burst size needed for 3 %: O's standard error is
/// about 1 % there), written by the project's writer, 12-bit levels.
#[test]
fn project_writer_bursts_two_isos_within_3_percent() {
    let dir = tempfile::tempdir().unwrap();
    let lv = (256.0, 4095.0);
    let truth = [(800u32, 1.2e-3, 3.0e-6), (3200, 4.8e-3, 4.5e-5)];
    let mut args = args!["calibrate", "noise"];
    for (i, &(iso, s, o)) in truth.iter().enumerate() {
        args.push("--burst".into());
        for p in burst(
            dir.path(),
            &format!("iso{iso}"),
            16,
            (1024, 512),
            lv,
            (s, o),
            iso,
            i as u64 + 1,
        ) {
            args.push(p.into());
        }
    }
    let out = dir.path().join("noise.json");
    args.extend(args!["-o", &out, "--json"]);
    let (code, stdout, stderr) = run_os(&args);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("ISO 800") && stderr.contains("R^2"),
        "{stderr}"
    );
    let model: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(serde_json::from_str::<Value>(&stdout).unwrap(), model);
    assert_eq!(model["format"], "day2night-noise-model/1");
    assert!(model["units"].as_str().unwrap().contains("normalized"));
    for &(iso, s, o) in &truth {
        assert_close(&model, iso as u64, s, o, 0.03);
        for p in positions(&model, iso as u64) {
            // DN form with x including black: beta1 = S*scale, beta2 = O*scale^2 - black*beta1.
            let scale = lv.1 - lv.0;
            let (b1, b2) = (p["beta1"].as_f64().unwrap(), p["beta2"].as_f64().unwrap());
            assert!((b1 - p["S"].as_f64().unwrap() * scale).abs() < 1e-9);
            let want = p["O"].as_f64().unwrap() * scale * scale - lv.0 * b1;
            assert!((b2 - want).abs() < 1e-6 * want.abs().max(1.0));
            assert!(p["chi2_reduced"].as_f64().unwrap() < 1.5, "{p}");
            assert!(p["pixels"].as_u64().unwrap() > 100_000, "{p}");
        }
    }
    let laws = &model["iso_laws"];
    let c = laws["s_per_iso"][0].as_f64().unwrap();
    assert!((c / 1.5e-6 - 1.0).abs() < 0.03, "{laws}");
    // synth's reader takes the file; its `positions` equal the detailed fits.
    let nm = day2night::noise::model::NoiseModel::from_file(&out).unwrap();
    assert_eq!(nm.iso_range(), (800, 3200));
    let at = nm.at(800).unwrap();
    for (p, f) in positions(&model, 800).iter().enumerate() {
        assert_eq!(
            at.params.positions[p],
            [f["S"].as_f64().unwrap(), f["O"].as_f64().unwrap()]
        );
    }
}

/// The same closed loop with bursts written by an independent tifffile script.
#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn independent_python_bursts_within_3_percent() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    let truth = [(1600u64, 2.4e-3, 1.03e-5), (3200, 4.8e-3, 4.33e-5)];
    let mut args = args!["calibrate", "noise"];
    for (i, &(iso, s, o)) in truth.iter().enumerate() {
        let sub = dir.path().join(format!("iso{iso}"));
        let out = common::run_validator(
            &py,
            "calibrate_make_burst.py",
            &[
                sub.as_os_str(),
                "--iso".as_ref(),
                iso.to_string().as_ref(),
                "--s".as_ref(),
                s.to_string().as_ref(),
                "--o".as_ref(),
                o.to_string().as_ref(),
                "--seed".as_ref(),
                (i + 10).to_string().as_ref(),
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let t: Value = serde_json::from_slice(&out.stdout).unwrap();
        args.push("--burst".into());
        for f in t["files"].as_array().unwrap() {
            args.push(f.as_str().unwrap().into());
        }
    }
    let out = dir.path().join("noise.json");
    args.extend(args!["-o", &out]);
    let (code, _, stderr) = run_os(&args);
    assert_eq!(code, 0, "{stderr}");
    let model: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    for &(iso, s, o) in &truth {
        assert_close(&model, iso, s, o, 0.03);
    }
    // The O law: two points fit exactly.
    let laws = &model["iso_laws"];
    let (a, b) = (
        laws["o_at_iso0"][1].as_f64().unwrap(),
        laws["o_per_iso2"][1].as_f64().unwrap(),
    );
    let o1600 = positions(&model, 1600)[1]["O"].as_f64().unwrap();
    assert!((a + b * 1600f64.powi(2) - o1600).abs() < 1e-12);
}

/// Pairs: one noise-free clean frame and 4 noisy frames at ISO 1600 (pooled).
#[test]
fn pairs_recover_model() {
    let dir = tempfile::tempdir().unwrap();
    let (black, white) = (64.0, 1023.0);
    let (w, h) = (1024, 512);
    let (s, o) = (2.4e-3, 1.03e-5);
    let clean = ramp_scene(w, h, black, white, 5);
    let clean_img = frame(
        w,
        h,
        clean.iter().map(|&v| v as u16).collect(),
        black,
        white,
        50,
    );
    let cp = write(dir.path(), "clean.dng", &clean_img);
    let mut args = args!["calibrate", "noise"];
    for k in 0..4 {
        let img = frame(
            w,
            h,
            noisy(&clean, black, white, s, o, 100 + k),
            black,
            white,
            1600,
        );
        let p = write(dir.path(), &format!("noisy{k}.dng"), &img);
        args.extend(args!["--pair", &cp, &p]);
    }
    let out = dir.path().join("noise.json");
    args.extend(args!["-o", &out]);
    let (code, _, stderr) = run_os(&args);
    assert_eq!(code, 0, "{stderr}");
    let model: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(model["isos"][0]["source"], "pair");
    for p in positions(&model, 1600) {
        let (fs, fo) = (p["S"].as_f64().unwrap(), p["O"].as_f64().unwrap());
        let (ss, so) = (
            p["s_stderr"].as_f64().unwrap(),
            p["o_stderr"].as_f64().unwrap(),
        );
        eprintln!(
            "pair pos {}: S {:+.2}% (se {:.2}%)  O {:+.2}% (se {:.2}%)",
            p["position"],
            100.0 * (fs / s - 1.0),
            100.0 * ss / s,
            100.0 * (fo / o - 1.0),
            100.0 * so / o
        );
        // One residual per pixel: less precise than a burst; 3 standard errors and 5 %.
        assert!(
            (fs - s).abs() < 3.0 * ss && (fs / s - 1.0).abs() < 0.05,
            "{p}"
        );
        assert!(
            (fo - o).abs() < 3.0 * so && (fo / o - 1.0).abs() < 0.08,
            "{p}"
        );
    }
}

#[test]
fn from_noise_profile_tags() {
    let dir = tempfile::tempdir().unwrap();
    let mut paths: Vec<PathBuf> = vec![];
    for (iso, s, o) in [(400u32, 4e-4, 2e-6), (1600, 1.6e-3, 5e-6)] {
        let mut img = frame(8, 8, vec![300; 64], 64.0, 1023.0, iso);
        img.meta.noise_profile = Some(vec![(s, o), (s * 0.9, o), (s * 1.1, o)]);
        paths.push(write(dir.path(), &format!("np{iso}.dng"), &img));
    }
    let out = dir.path().join("noise.json");
    let mut args = args!["calibrate", "noise", "--from-noise-profile"];
    args.extend(paths.iter().map(OsString::from));
    args.extend(args!["-o", &out]);
    let (code, _, stderr) = run_os(&args);
    assert_eq!(code, 0, "{stderr}");
    let model: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let p = positions(&model, 1600);
    // RGGB: position 0 = R (first pair), 3 = B (third pair).
    assert!((p[0]["S"].as_f64().unwrap() - 1.6e-3).abs() < 1e-12);
    assert!((p[3]["S"].as_f64().unwrap() - 1.76e-3).abs() < 1e-12);
    assert_eq!(model["isos"][0]["source"], "noise_profile");
    let c = model["iso_laws"]["s_per_iso"][0].as_f64().unwrap();
    assert!((c - 1e-6).abs() < 1e-15, "{c}");
}

#[test]
fn degenerate_inputs_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let lv = (64.0, 1023.0);
    let b = burst(dir.path(), "b", 4, (64, 64), lv, (1e-3, 1e-5), 1600, 1);
    let out = dir.path().join("n.json");
    // Too few frames.
    let mut a = args![
        "calibrate",
        "noise",
        "--burst",
        &b[0],
        &b[1],
        &b[2],
        "-o",
        &out
    ];
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("at least 4 frames"), "{err}");
    // A frame at another ISO, named with its file.
    let other = frame(64, 64, vec![500; 4096], 64.0, 1023.0, 3200);
    let op = write(dir.path(), "other.dng", &other);
    a = args![
        "calibrate",
        "noise",
        "--burst",
        &b[0],
        &b[1],
        &b[2],
        &op,
        "-o",
        &out
    ];
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 1);
    assert!(
        err.contains("other.dng") && err.contains("ISO 3200"),
        "{err}"
    );
    // A frame of another size.
    let small = frame(32, 64, vec![500; 2048], 64.0, 1023.0, 1600);
    let sp = write(dir.path(), "small.dng", &small);
    a = args![
        "calibrate",
        "noise",
        "--burst",
        &b[0],
        &b[1],
        &sp,
        &b[2],
        "-o",
        &out
    ];
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 1);
    assert!(
        err.contains("small.dng") && err.contains("size 32x64"),
        "{err}"
    );
    // The same file twice.
    a = args![
        "calibrate",
        "noise",
        "--burst",
        &b[0],
        &b[0],
        &b[1],
        &b[2],
        "-o",
        &out
    ];
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 1);
    assert!(err.contains("identical"), "{err}");
    // Zero variance: four different files with the same noise-free content except one
    // clipped pixel each.
    let zs: Vec<PathBuf> = (0..4)
        .map(|k| {
            let mut d: Vec<u16> = ramp_scene(64, 64, 64.0, 1023.0, 3)
                .iter()
                .map(|&v| v as u16)
                .collect();
            d[k] = 1023;
            write(
                dir.path(),
                &format!("z{k}.dng"),
                &frame(64, 64, d, 64.0, 1023.0, 1600),
            )
        })
        .collect();
    a = args!["calibrate", "noise", "--burst"];
    a.extend(zs.iter().map(OsString::from));
    a.extend(args!["-o", &out]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 1);
    assert!(err.contains("zero variance"), "{err}");
    // No NoiseProfile.
    a = args![
        "calibrate",
        "noise",
        "--from-noise-profile",
        &b[0],
        "-o",
        &out
    ];
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 1);
    assert!(err.contains("NoiseProfile"), "{err}");
    // Nothing at all: usage.
    let (code, _, _) = run_os(&args!["calibrate", "noise", "-o", &out]);
    assert_eq!(code, 2);
    assert!(!out.exists());
}

/// Calibrate from a burst, then let synth's noise code (`noise::apply_noise` with the model
/// read by `NoiseModel::from_file`) noise flat patches: its variance matches the true
/// generator's within 5 % at every level.
#[test]
fn synth_with_fitted_model_reproduces_true_variance() {
    use day2night::noise::apply::apply_noise;
    use day2night::noise::model::NoiseModel;
    let dir = tempfile::tempdir().unwrap();
    let (black, white) = (64.0, 1023.0);
    let (s, o) = (2.4e-3, 1.03e-5);
    let mut a = args!["calibrate", "noise", "--burst"];
    for p in burst(
        dir.path(),
        "b",
        16,
        (1024, 512),
        (black, white),
        (s, o),
        1600,
        7,
    ) {
        a.push(p.into());
    }
    let out = dir.path().join("noise.json");
    a.extend(args!["-o", &out]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");
    let params = NoiseModel::from_file(&out)
        .unwrap()
        .at(1600)
        .unwrap()
        .params;
    // Flat bands (128 columns each) at these normalized levels.
    let levels = [0.0, 0.01, 0.03, 0.1, 0.2, 0.4, 0.6, 0.8];
    let (w, h) = (1024, 256);
    let scale = white - black;
    let clean: Vec<f64> = (0..w * h)
        .map(|i| (levels[(i % w) / 128] * scale + black).round())
        .collect();
    let clean_img = frame(
        w,
        h,
        clean.iter().map(|&v| v as u16).collect(),
        black,
        white,
        50,
    );
    let synth = apply_noise(&clean_img, &params, 42).unwrap();
    let truth = noisy(&clean, black, white, s, o, 4242);
    let band_var = |data: &dyn Fn(usize) -> f64, b: usize| {
        let xs: Vec<f64> = (0..h)
            .flat_map(|r| (b * 128..(b + 1) * 128).map(move |c| r * w + c))
            .map(data)
            .collect();
        let m = xs.iter().sum::<f64>() / xs.len() as f64;
        xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64
    };
    for (b, y) in levels.iter().enumerate() {
        let vs = band_var(&|i| synth.data[i] as f64, b);
        let vt = band_var(&|i| truth[i] as f64, b);
        let model = (s * y + o) * scale * scale + 1.0 / 12.0;
        eprintln!(
            "level {y}: synth var {vs:.3} DN^2, true generator {vt:.3}, model {model:.3} ({:+.2}%)",
            100.0 * (vs / vt - 1.0)
        );
        assert!((vs / vt - 1.0).abs() < 0.05, "level {y}: {vs} vs {vt}");
        assert!(
            (vs / model - 1.0).abs() < 0.05,
            "level {y}: {vs} vs model {model}"
        );
    }
}

/// The paper's workflow: clean = `merge` of a burst (levels scaled by N), noisy = other frames
/// of the same scene at the same ISO. The residual holds the clean's own noise (1/N of it):
/// the fit returns (1 + 1/N) times the truth, as documented. (Binning by the slightly noisy
/// merged value no longer biases O: each bin's intensity is the mean of the noisy values;
/// with the clean value as intensity O came out +5 % here.)
#[test]
fn pairs_against_a_merged_clean_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (black, white) = (64.0, 1023.0);
    let (w, h) = (1024, 512);
    let (s, o) = (2.4e-3, 1.03e-5);
    let clean = ramp_scene(w, h, black, white, 9);
    let n = 16;
    let frames: Vec<PathBuf> = (0..n + 4)
        .map(|k| {
            let img = frame(
                w,
                h,
                noisy(&clean, black, white, s, o, 500 + k as u64),
                black,
                white,
                1600,
            );
            write(dir.path(), &format!("f{k:02}.dng"), &img)
        })
        .collect();
    let merged = dir.path().join("merged.dng");
    let mut a = args!["merge"];
    a.extend(frames[..n].iter().map(OsString::from));
    a.extend(args!["-o", &merged]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");
    let mut a = args!["calibrate", "noise"];
    for p in &frames[n..] {
        a.extend(args!["--pair", &merged, p]);
    }
    let out = dir.path().join("noise.json");
    a.extend(args!["-o", &out]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");
    let model: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let k = 1.0 + 1.0 / n as f64;
    for p in positions(&model, 1600) {
        let (fs, fo) = (p["S"].as_f64().unwrap(), p["O"].as_f64().unwrap());
        eprintln!(
            "merged-clean pair pos {}: S {:+.2}%  O {:+.2}% vs (1+1/N) truth",
            p["position"],
            100.0 * (fs / (s * k) - 1.0),
            100.0 * (fo / (o * k) - 1.0)
        );
        assert!((fs / (s * k) - 1.0).abs() < 0.03, "{p}");
        assert!((fo / (o * k) - 1.0).abs() < 0.05, "{p}");
    }
}

#[test]
fn assume_iso_fills_only_missing_isos() {
    let dir = tempfile::tempdir().unwrap();
    let mut paths: Vec<PathBuf> = vec![];
    for (iso, s) in [(0u32, 4e-4), (1600, 1.6e-3)] {
        let mut img = frame(8, 8, vec![300; 64], 64.0, 1023.0, iso);
        img.meta.noise_profile = Some(vec![(s, 2e-6)]);
        paths.push(write(dir.path(), &format!("np{iso}.dng"), &img));
    }
    let out = dir.path().join("noise.json");
    // Without --assume-iso the frame without ISO is an error that names the option.
    let mut a = args!["calibrate", "noise", "--from-noise-profile"];
    a.extend(paths.iter().map(OsString::from));
    a.extend(args!["-o", &out]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("np0.dng") && err.contains("--assume-iso"),
        "{err}"
    );
    assert!(!out.exists());
    // With it: the ISO-less frame is ISO 400, the other keeps its 1600.
    a.extend(args!["--assume-iso", "400"]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("np0.dng") && err.contains("--assume-iso 400"),
        "{err}"
    );
    let model: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let isos: Vec<u64> = model["isos"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["iso"].as_u64().unwrap())
        .collect();
    assert_eq!(isos, vec![400, 1600]);
    assert!((positions(&model, 400)[0]["S"].as_f64().unwrap() - 4e-4).abs() < 1e-12);
    assert!((positions(&model, 1600)[0]["S"].as_f64().unwrap() - 1.6e-3).abs() < 1e-12);
    // 0 is not an ISO
    let (code, _, err) = run_os(&args![
        "calibrate",
        "noise",
        "--from-noise-profile",
        &paths[1],
        "--assume-iso",
        "0",
        "-o",
        &out
    ]);
    assert_eq!(code, 2, "{err}");
}
