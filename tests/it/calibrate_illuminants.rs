//! `calibrate illuminants` and `calibrate brightness`: gray cards generated under known
//! illuminants are recovered within 0.5 %, the fitted Gaussian equals numpy's, the shared
//! s20fe dictionary refits to the spec's figures, degenerate inputs give clear errors.
use crate::args;
use crate::calibrate_support;
use crate::common;

use calibrate_support::*;
use day2night::raw::Bayer;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde_json::Value;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// A noisy gray card under illuminant [r/g, 1, b/g] with a few hot and saturated pixels.
fn gray_card(dir: &Path, name: &str, bayer: Bayer, ill: [f64; 3], seed: u64) -> PathBuf {
    let (w, h, black, white) = (256, 192, 256.0, 4095.0);
    let g = 1500.0;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut data: Vec<u16> = (0..w * h)
        .map(|i| {
            let (r, c) = (i / w, i % w);
            let mean = g * ill[bayer.color_at(r, c) as usize];
            let z: f64 = StandardNormal.sample(&mut rng);
            (black + mean + z * (0.01 * mean + 4.0))
                .round()
                .clamp(0.0, white) as u16
        })
        .collect();
    // Dust (dark) and specular (saturated) specks inside the central ROI.
    for k in 0..20 {
        let (r, c) = (80 + k, 100 + 3 * k);
        data[r * w + c] = if k % 2 == 0 { 4095 } else { 300 };
    }
    let mut img = frame(w, h, data, black, white, 100);
    img.meta.cfa.pattern = bayer.0.to_vec();
    write(dir, name, &img)
}

fn read_json(p: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn gray_cards_recovered_and_gaussian_matches_numpy() {
    let dir = tempfile::tempdir().unwrap();
    let ills = [
        [0.85, 1.0, 0.31],
        [0.56, 1.0, 0.44],
        [1.08, 1.0, 0.21],
        [0.72, 1.0, 0.33],
        [0.63, 1.0, 0.39],
        [0.90, 1.0, 0.30],
    ];
    let mut args = args!["calibrate", "illuminants"];
    for (i, ill) in ills.iter().enumerate() {
        let bayer = Bayer::ALL[i % 4];
        args.push(gray_card(dir.path(), &format!("card{i}.dng"), bayer, *ill, i as u64).into());
    }
    let out = dir.path().join("ill.json");
    args.extend(args!["-o", &out]);
    let (code, _, err) = run_os(&args);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("fit over 6 illuminants (unbiased covariance)"),
        "{err}"
    );
    let d = read_json(&out);
    assert_eq!(d["format"], "day2night-illuminants/1");
    for (i, ill) in ills.iter().enumerate() {
        let got = &d["illuminants_rgb_over_g"][i];
        for k in [0, 2] {
            let v = got[k].as_f64().unwrap();
            assert!(
                (v / ill[k] - 1.0).abs() < 0.005,
                "card {i}: {got} vs {ill:?}"
            );
        }
        let f = &d["files"][i];
        assert_eq!(f["roi"], serde_json::json!([96, 72, 64, 48]));
        assert!(
            f["saturated"]
                .as_array()
                .unwrap()
                .iter()
                .any(|v| v.as_u64() > Some(0)),
            "{f}"
        );
    }
    // synth's reader takes the file and its own fit gives the same Gaussian.
    let src = day2night::synth::dictionaries::load_illuminants(&out).unwrap();
    let g = day2night::synth::illuminant::Gaussian2::from_source(&src, Default::default()).unwrap();
    assert_eq!(g.count, 6);
    for i in 0..2 {
        assert!((g.mean[i] - d["fit"]["mean"][i].as_f64().unwrap()).abs() < 1e-15);
    }
    let py = common::python();
    {
        let o = common::run_validator(&py, "calibrate_gaussian_check.py", &[out.as_os_str()]);
        assert!(
            o.status.success(),
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // Refit the written dictionary with the ML estimator: same points, covariance x (M-1)/M.
    let ml = dir.path().join("ml.json");
    let (code, _, err) = run_os(&args![
        "calibrate",
        "illuminants",
        &out,
        "--estimator",
        "ml",
        "-o",
        &ml
    ]);
    assert_eq!(code, 0, "{err}");
    let m = read_json(&ml);
    assert_eq!(m["count"], 6);
    let (cu, cm) = (
        d["fit"]["covariance"][0][0].as_f64().unwrap(),
        m["fit"]["covariance"][0][0].as_f64().unwrap(),
    );
    assert!((cm - cu * 5.0 / 6.0).abs() < 1e-15);
    {
        let o = common::run_validator(&py, "calibrate_gaussian_check.py", &[ml.as_os_str()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    }
}

/// A gray-card session records its camera and each card's xy; synth uses the camera
/// neutrals for that camera and the xy through its own matrices for another.
#[test]
fn one_cameras_gray_cards_serve_another_through_xy() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = args!["calibrate", "illuminants"];
    for (i, ill) in [[0.85, 1.0, 0.31], [0.56, 1.0, 0.44], [0.72, 1.0, 0.33]]
        .iter()
        .enumerate()
    {
        args.push(
            gray_card(
                dir.path(),
                &format!("c{i}.dng"),
                Bayer::RGGB,
                *ill,
                i as u64,
            )
            .into(),
        );
    }
    let out = dir.path().join("ill.json");
    args.extend(args!["-o", &out]);
    let (code, _, err) = run_os(&args);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("camera: day2night Synthetic: synth uses the camera neutrals"),
        "{err}"
    );
    eprintln!("{err}");
    let d = read_json(&out);
    assert_eq!(d["camera"]["model"], "Synthetic");
    assert_eq!(d["observer"], "CIE 1931 2 degree");
    // each xy maps back to its card's neutral through the capture's matrices
    let meta = day2night::raw::meta::RawMeta::new_bayer(Bayer::RGGB, 12, 256.0, 4095.0);
    let cc = day2night::isp::color::CameraColor::new(&meta.color).unwrap();
    for i in 0..3 {
        let xy = [
            d["xy"][i][0].as_f64().unwrap(),
            d["xy"][i][1].as_f64().unwrap(),
        ];
        let n = cc.xy_to_neutral(xy).unwrap();
        let c = &d["illuminants_rgb_over_g"][i];
        assert!(
            (n[0] - c[0].as_f64().unwrap()).abs() < 1e-9
                && (n[2] - c[2].as_f64().unwrap()).abs() < 1e-9
        );
    }
    // synth: the same camera uses the neutrals, the fixture camera the xy
    let same_cam = gray_card(dir.path(), "scene.dng", Bayer::RGGB, [0.6, 1.0, 0.5], 9);
    let day = common::fixtures().join("day.dng");
    for (input, want) in [(&same_cam, "file_camera_rgb"), (&day, "file_xy")] {
        let o = dir.path().join(want);
        let r = common::bin()
            .arg("synth")
            .arg(input)
            .args(["--iso", "none", "--target", "none", "--illuminants"])
            .arg(&out)
            .arg("-o")
            .arg(&o)
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let stem = input.file_stem().unwrap().to_str().unwrap();
        let sc = read_json(&o.join(format!("{stem}.json")));
        assert_eq!(
            sc["calibration"]["provenance"]["illuminants"]["source"],
            want
        );
        // No warning about the lights (a gray-card capture without a NoiseProfile gets the
        // noise chain's warning, which is not this test's subject).
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            !err.lines()
                .any(|l| l.contains("warning") && !l.contains(": noise: ")),
            "{err}"
        );
    }
}

/// The paper phone's 45 gray cards (shared data) refit to the spec's figures.
#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn shared_s20fe_dictionary_refits_to_spec() {
    let data = common::shared_data();
    let src = data.join("../calibration/night_illuminants_s20fe.json");
    assert!(
        src.is_file(),
        "{} not found (the real-camera data is incomplete)",
        src.display()
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ill.json");
    let (code, _, err) = run_os(&args!["calibrate", "illuminants", &src, "-o", &out]);
    assert_eq!(code, 0, "{err}");
    let f = &read_json(&out)["fit"];
    assert_eq!(f["count"], 45);
    let want_mean = [0.766125, 0.328891];
    let want_cov = [[0.0288803, -0.0109222], [-0.0109222, 0.00489429]];
    for i in 0..2 {
        assert!(
            (f["mean"][i].as_f64().unwrap() - want_mean[i]).abs() < 5e-7,
            "{f}"
        );
        for j in 0..2 {
            let v = f["covariance"][i][j].as_f64().unwrap();
            assert!((v / want_cov[i][j] - 1.0).abs() < 1e-5, "{f}");
        }
    }
}

#[test]
fn degenerate_gray_cards() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ill.json");
    // All saturated.
    let sat = frame(64, 64, vec![4095; 4096], 256.0, 4095.0, 100);
    let sp = write(dir.path(), "sat.dng", &sat);
    let (code, _, err) = run_os(&args!["calibrate", "illuminants", &sp, "-o", &out]);
    assert_eq!(code, 1);
    assert!(
        err.contains("sat.dng") && err.contains("saturated"),
        "{err}"
    );
    // One illuminant: documented fallback, zero covariance (synth always draws it) + warning.
    let one = gray_card(dir.path(), "one.dng", Bayer::RGGB, [0.7, 1.0, 0.3], 1);
    let one_out = dir.path().join("one.json");
    let (code, _, err) = run_os(&args!["calibrate", "illuminants", &one, "-o", &one_out]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning[illuminants-degenerate]: one illuminant"),
        "{err}"
    );
    let d = read_json(&one_out);
    assert_eq!(
        d["fit"]["covariance"],
        serde_json::json!([[0.0, 0.0], [0.0, 0.0]])
    );
    let src = day2night::synth::dictionaries::load_illuminants(&one_out).unwrap();
    let g = day2night::synth::illuminant::Gaussian2::from_source(&src, Default::default()).unwrap();
    assert!((g.mean[0] / 0.7 - 1.0).abs() < 0.005 && g.cov == [[0.0; 2]; 2]);
    // Bad ROI syntax is a usage error; an ROI outside the image is a bad input.
    let (code, _, _) = run_os(&args![
        "calibrate",
        "illuminants",
        &one,
        "--roi",
        "1,2,3",
        "-o",
        &out
    ]);
    assert_eq!(code, 2);
    let (code, _, err) = run_os(&args![
        "calibrate",
        "illuminants",
        &one,
        "--roi",
        "200,100,100,10",
        "-o",
        &out
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("outside"), "{err}");
    // Black card.
    let dark = write(
        dir.path(),
        "dark.dng",
        &frame(64, 64, vec![100; 4096], 256.0, 4095.0, 100),
    );
    let (code, _, err) = run_os(&args!["calibrate", "illuminants", &dark, &one, "-o", &out]);
    assert_eq!(code, 1);
    assert!(
        err.contains("dark.dng") && err.contains("not above black"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn brightness_dictionary() {
    let dir = tempfile::tempdir().unwrap();
    let (black, white): (f64, f64) = (64.0, 1023.0);
    let means: [f64; 4] = [0.01, 0.03, 0.002, 0.12];
    let mut paths: Vec<OsString> = vec![];
    for (i, m) in means.iter().enumerate() {
        // Half the sites at 0, half at 2m: mean m exactly when 2m*959 is an integer DN.
        let dn = (2.0 * m * (white - black)).round();
        let data: Vec<u16> = (0..64 * 64)
            .map(|k| if k % 2 == 0 { 64 } else { (64.0 + dn) as u16 })
            .collect();
        paths.push(
            write(
                dir.path(),
                &format!("n{i}.dng"),
                &frame(64, 64, data, black, white, 3200),
            )
            .into(),
        );
    }
    let out = dir.path().join("b.json");
    let mut a = args!["calibrate", "brightness"];
    a.extend(paths.iter().cloned());
    a.extend(args!["-o", &out]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");
    let d = read_json(&out);
    let vals: Vec<f64> = d["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let exact: Vec<f64> = means
        .iter()
        .map(|m| (2.0 * m * 959.0f64).round() / 2.0 / 959.0)
        .collect();
    for (v, e) in vals.iter().zip(&exact) {
        // The shared normalize path works in f32.
        assert!((v / e - 1.0).abs() < 1e-6, "{v} vs {e}");
    }
    let mean = vals.iter().sum::<f64>() / 4.0;
    let std = (vals.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / 3.0).sqrt();
    assert!((d["fit"]["mean"].as_f64().unwrap() - mean).abs() < 1e-15);
    assert!((d["fit"]["std"].as_f64().unwrap() - std).abs() < 1e-15);
    assert!(d["fit"]["distribution"]
        .as_str()
        .unwrap()
        .starts_with("normal"));
    // synth's reader takes the file and agrees.
    let b = day2night::synth::dictionaries::load_brightness(&out).unwrap();
    assert_eq!(
        (b.count, b.mean, b.std),
        (
            4,
            d["fit"]["mean"].as_f64().unwrap(),
            d["fit"]["std"].as_f64().unwrap()
        )
    );
    // One image: documented fallback (sigma 0, warning).
    let one = dir.path().join("one.json");
    let (code, _, err) = run_os(&args!["calibrate", "brightness", &paths[0], "-o", &one]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning[brightness-single-image]: one image"),
        "{err}"
    );
    assert_eq!(read_json(&one)["fit"]["std"], 0.0);
    // A black image is an error; an existing output is refused.
    let black_img = write(
        dir.path(),
        "black.dng",
        &frame(8, 8, vec![60; 64], black, white, 3200),
    );
    let (code, _, err) = run_os(&args![
        "calibrate",
        "brightness",
        &black_img,
        "-o",
        dir.path().join("x.json")
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("black.dng") && err.contains("black"), "{err}");
    let (code, _, err) = run_os(&args!["calibrate", "brightness", &paths[0], "-o", &one]);
    assert_eq!(code, 1);
    assert!(err.contains("--overwrite"), "{err}");
}
