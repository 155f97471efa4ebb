//! The noise model chain of `synth` end to end (issue 24 points 2 and 3): which source a
//! run takes (estimate from the image, NoiseProfile, model file, the embedded S20 FE table)
//! with its warnings, the provenance in the sidecar and in `info`, the estimate's model
//! file round trip (`calibrate noise --from-image` -> `synth --noise-model`), the measured
//! noise of the noisy raws against the scaled estimate, and the replay of a sidecar written
//! before provenance existed.
use crate::common;
use day2night::dng::read_dng;
use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::noise::estimate::{estimate, EstimateOptions};
use day2night::noise::NoiseModel;
use day2night::raw::{Bayer, RawImage};
use day2night::synth::sidecar::Sidecar;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

use crate::noise_estimate::accuracy::{synthetic_frame, Content, Grey};

const A: f64 = 1e-4;
const B: f64 = 1e-6;

/// A 14-bit textured day frame at ISO 100 with known noise (a = 1e-4, b = 1e-6), no
/// NoiseProfile, a neutral; `make`/`model` override the camera.
fn day_frame(camera: Option<(&str, &str)>) -> RawImage {
    let grey = Grey::astronaut().halved();
    let mut img = synthetic_frame(Content::Texture, &grey, Bayer::RGGB, 14, 768, 512, A, B, 11);
    img.meta.as_shot_neutral = Some([0.55, 1.0, 0.75]);
    if let Some((make, model)) = camera {
        img.meta.make = Some(make.into());
        img.meta.model = Some(model.into());
        img.meta.unique_camera_model = None;
    }
    img
}

fn write(dir: &Path, name: &str, img: &RawImage) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, encode_dng(img, &WriteOptions::default()).unwrap()).unwrap();
    p
}

fn synth(input: &Path, out: &Path, extra: &[&str]) -> Output {
    let o = common::cli(
        "synth",
        input,
        out,
        &[
            &["--mode", "day", "--iso", "1600", "--target", "none"],
            extra,
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn sidecar(out: &Path, stem: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join(format!("{stem}.json"))).unwrap())
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn estimate_is_used_recorded_and_measured_in_the_noisy_raw() {
    let t = tempfile::tempdir().unwrap();
    let img = day_frame(None);
    let p = write(t.path(), "day.dng", &img);
    let out = t.path().join("o");
    let o = synth(&p, &out, &[]);
    assert!(!stderr(&o).contains(": noise: "), "{}", stderr(&o));
    let sc = sidecar(&out, "day");
    let prov = &sc["calibration"]["provenance"]["noise"];
    assert_eq!(prov, &sc["report"]["noise_provenance"]);
    assert_eq!(prov["source"], "image_estimate");
    assert_eq!(prov["camera"]["make"], "day2night");
    assert_eq!(prov["camera"]["model"], "Synthetic");
    assert!(prov["note"].as_str().unwrap().contains("ISO 100"), "{prov}");
    // The plan's parameters at ISO 1600 are the estimate at ISO 100 scaled: S x16, O x256.
    let read = read_dng(&p).unwrap();
    let est = estimate(&read, &EstimateOptions::default())
        .unwrap()
        .trusted()
        .unwrap();
    let planned = &sc["plan"]["noise"][0]["params"]["positions"];
    for pos in 0..4 {
        let s = planned[pos][0].as_f64().unwrap();
        let o = planned[pos][1].as_f64().unwrap();
        assert!((s - 16.0 * est.positions[pos][0]).abs() <= 1e-12 * s, "{s}");
        assert!(
            (o - 256.0 * est.positions[pos][1]).abs() <= 1e-12 * o.max(1e-30),
            "{o}"
        );
        // ... and the estimate is the truth within its documented tolerance.
        assert!((est.positions[pos][0] / A - 1.0).abs() < 0.1);
    }
    // The noisy raw's measured noise is the scaled estimate (plus the rounding's 1/12 DN^2).
    let clean = read_dng(&out.join("day_clean.dng")).unwrap();
    let noisy = read_dng(&out.join("day_iso1600.dng")).unwrap();
    let (black, white) = (1024.0, 16383.0);
    let scale = white - black;
    for pos in 0..4 {
        // Bins of the clean value: (n, sum d, sum d^2, sum y).
        let mut bins = vec![(0.0f64, 0.0f64, 0.0f64, 0.0f64); 8];
        for r in (pos >> 1..clean.height).step_by(2) {
            for c in (pos & 1..clean.width).step_by(2) {
                let x = clean.get(r, c) as f64;
                let y = (x - black) / scale;
                let d = noisy.get(r, c) as f64 - x;
                let nz = noisy.get(r, c);
                if !(0.05..0.85).contains(&y) || nz == 0 || nz as f64 >= white {
                    continue;
                }
                let b = &mut bins[(y * 8.0) as usize];
                b.0 += 1.0;
                b.1 += d;
                b.2 += d * d;
                b.3 += y;
            }
        }
        let s = planned[pos][0].as_f64().unwrap();
        let o = planned[pos][1].as_f64().unwrap();
        for (n, s1, s2, sy) in bins.into_iter().filter(|b| b.0 > 2000.0) {
            let var = s2 / n - (s1 / n).powi(2);
            let want = (s * sy / n + o) * scale * scale + 1.0 / 12.0;
            let rel = (var - want).abs() / want;
            assert!(
                rel < 4.0 * (2.0 / n).sqrt() + 0.005,
                "pos {pos}: {var} vs {want} ({n} sites)"
            );
        }
    }
}

#[test]
fn calibrate_from_image_round_trips_through_noise_model() {
    let t = tempfile::tempdir().unwrap();
    let p = write(t.path(), "day.dng", &day_frame(None));
    let model = t.path().join("noise.json");
    let o = common::bin()
        .args(["calibrate", "noise", "--from-image"])
        .arg(&p)
        .arg("-o")
        .arg(&model)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(doc["format"], "day2night-noise-model/1");
    assert_eq!(doc["camera"]["make"], "day2night");
    assert_eq!(doc["isos"][0]["iso"], 100);
    assert_eq!(doc["isos"][0]["source"], "image_estimate");
    let m = NoiseModel::from_file(&model).unwrap();
    assert_eq!(
        m.camera.as_ref().unwrap().model.as_deref(),
        Some("Synthetic")
    );
    // synth with the file gives the same noisy raw as synth's own estimate, and says so.
    let (a, b) = (t.path().join("a"), t.path().join("b"));
    synth(&p, &a, &[]);
    let o = synth(&p, &b, &["--noise-model", model.to_str().unwrap()]);
    assert!(!stderr(&o).contains(": noise: "), "{}", stderr(&o));
    for f in ["day_clean.dng", "day_iso1600.dng"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}"
        );
    }
    let prov = &sidecar(&b, "day")["calibration"]["provenance"]["noise"];
    assert_eq!(prov["source"], "file");
    assert_eq!(prov["camera"]["make"], "day2night");
    assert!(
        prov["note"].as_str().unwrap().contains("noise.json"),
        "{prov}"
    );
}

#[test]
fn a_model_file_of_another_camera_warns() {
    let t = tempfile::tempdir().unwrap();
    let p = write(t.path(), "day.dng", &day_frame(None));
    let points = r#""isos": [{"iso": 100, "positions": [[1e-4, 1e-6], [1e-4, 1e-6], [1e-4, 1e-6], [1e-4, 1e-6]]}]"#;
    let head = r#""format": "day2night-noise-model/1", "units": "normalized", "source": "t""#;
    for (name, camera, warns) in [
        (
            "object",
            r#""camera": {"make": "Nikon", "model": "D3"},"#,
            true,
        ),
        ("legacy", r#""camera": "Nikon D3","#, true),
        (
            "same",
            r#""camera": {"make": "day2night", "model": "Synthetic"},"#,
            false,
        ),
        ("none", "", false),
    ] {
        let f = t.path().join(format!("{name}.json"));
        std::fs::write(&f, format!("{{{head}, {camera} {points}}}")).unwrap();
        let out = t.path().join(name);
        let o = synth(&p, &out, &["--noise-model", f.to_str().unwrap()]);
        let err = stderr(&o);
        let want = format!(
            ": noise: {} was calibrated on Nikon D3, not on this camera (day2night Synthetic)",
            f.display()
        );
        assert_eq!(err.contains(&want), warns, "{name}: {err}");
        assert_eq!(
            err.contains("warning[noise-other-camera]: "),
            warns,
            "{name}: {err}"
        );
        let prov = &sidecar(&out, "day")["calibration"]["provenance"]["noise"];
        assert_eq!(prov["source"], "file");
        assert_eq!(prov["camera"].is_null(), name == "none", "{name}: {prov}");
    }
}

#[test]
fn noise_profile_paper_phone_release_and_unknown_iso() {
    let t = tempfile::tempdir().unwrap();
    // The file's own NoiseProfile: no warning.
    let out = t.path().join("fixture");
    let o = synth(&common::fixtures().join("day.dng"), &out, &[]);
    assert!(!stderr(&o).contains(": noise: "), "{}", stderr(&o));
    let prov = &sidecar(&out, "day")["calibration"]["provenance"]["noise"];
    assert_eq!(prov["source"], "noise_profile");
    assert_eq!(
        prov["camera"]["unique_camera_model"],
        "day2night Fixture Camera"
    );
    // The paper's phone without a NoiseProfile: its own table, no warning, no estimate.
    let phone = write(
        t.path(),
        "phone.dng",
        &day_frame(Some(("samsung", "SM-G781B"))),
    );
    let out = t.path().join("phone");
    let o = synth(&phone, &out, &[]);
    assert!(!stderr(&o).contains(": noise: "), "{}", stderr(&o));
    let prov = &sidecar(&out, "phone")["calibration"]["provenance"]["noise"];
    assert_eq!(prov["source"], "embedded_s20fe");
    assert_eq!(prov["camera"]["make"], "samsung");
    // --compat release keeps the release's table for every input, and says so.
    let p = write(t.path(), "day.dng", &day_frame(None));
    let out = t.path().join("release");
    let o = synth(&p, &out, &["--compat", "release"]);
    assert!(
        stderr(&o).contains("warning[noise-compat-table]: ") && stderr(&o).contains(": noise: the input has no NoiseProfile and --compat release keeps the release's noise table; using the embedded noise table of the paper's phone (Samsung Galaxy S20 FE): another camera's noise, not day2night Synthetic's"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        sidecar(&out, "day")["calibration"]["provenance"]["noise"]["source"],
        "embedded_s20fe"
    );
    // Unknown ISO: the embedded table, with the reason and how to calibrate.
    let mut img = day_frame(None);
    img.meta.exif.iso = Some(0);
    let p = write(t.path(), "noiso.dng", &img);
    let out = t.path().join("noiso");
    let o = synth(&p, &out, &[]);
    let err = stderr(&o);
    assert!(err.contains("warning[unknown-iso]: ") && err.contains(": noise: the input has no NoiseProfile and its ISO is unknown (Exif ISO 0 or absent)"), "{err}");
    assert!(
        err.contains("day2night calibrate noise --from-image DAY.dng [--assume-iso N]"),
        "{err}"
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn real_canon_without_iso_is_named_another_cameras_noise() {
    let canon = common::shared_file("dng/canon_kissx4_magiclantern_rggb14_strips.dng");
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("o");
    let o = synth(&canon, &out, &[]);
    let err = stderr(&o);
    assert!(
        err.contains("ISO is unknown") && err.contains("not Canon EOS Kiss X4's"),
        "{err}"
    );
    let sc = sidecar(&out, "canon_kissx4_magiclantern_rggb14_strips");
    assert_eq!(
        sc["calibration"]["provenance"]["noise"]["source"],
        "embedded_s20fe"
    );
    // info says the same before any synthesis.
    let o = common::bin()
        .args(["info", "--json"])
        .arg(&canon)
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["noise_model"]["source"], "embedded_s20fe");
    assert!(stderr(&o).contains(": noise: "), "{}", stderr(&o));
}

#[test]
fn info_says_where_the_noise_model_comes_from() {
    let t = tempfile::tempdir().unwrap();
    let p = write(t.path(), "day.dng", &day_frame(None));
    let fix = common::fixtures().join("day.dng");
    let o = common::bin()
        .args(["info", "--json"])
        .arg(&p)
        .arg(&fix)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["noise_model"]["source"], "image_estimate");
    assert_eq!(v[0]["noise_model"]["camera"]["model"], "Synthetic");
    assert_eq!(v[1]["noise_model"]["source"], "noise_profile");
    let o = common::bin().arg("info").arg(&fix).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("  noise model:   noise_profile (camera day2night Fixture Camera): input DNG NoiseProfile at ISO 100"),
        "{text}"
    );
}

#[test]
fn a_sidecar_without_provenance_replays_byte_for_byte() {
    // A sidecar as written before provenance existed (version 1 without the two entries,
    // migrated): today's, with the two entries null.
    let t = tempfile::tempdir().unwrap();
    let p = write(t.path(), "day.dng", &day_frame(None));
    let a = t.path().join("a");
    synth(&p, &a, &[]);
    let mut sc = Sidecar::read(&a.join("day.json")).unwrap();
    assert!(sc.report.noise_provenance.is_some() && sc.calibration.provenance.is_some());
    sc.report.noise_provenance = None;
    sc.calibration.provenance = None;
    let old = sc.to_json().unwrap();
    assert!(old.contains("\"noise_provenance\": null") && old.contains("\"provenance\": null"));
    let old_path = t.path().join("old.json");
    std::fs::write(&old_path, &old).unwrap();
    let b = t.path().join("b");
    synth(&p, &b, &["--replay", old_path.to_str().unwrap()]);
    for f in ["day_clean.dng", "day_iso1600.dng"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap()
        );
    }
    assert_eq!(std::fs::read_to_string(b.join("day.json")).unwrap(), old);
}
