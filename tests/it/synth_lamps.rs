//! Night lamps that are right in every camera (issue 24): the CIE 015:2018 table against
//! colour-science, lights sampled through each camera's own matrices measured in CIE xy
//! (the fixture, the real Canon, a synthetic small-sensor camera), the paper's phone and the
//! release preset keeping the paper's dictionary, xy and camera-RGB files, provenance in the
//! sidecar and `info`, and replay of sidecars written before provenance existed.
use crate::common;
use crate::dngbuild::Builder;
use crate::synth_cli::{files, ok, same, synth};

use day2night::color::planck::{cct_duv, planck_xy};
use day2night::dng::read_dng;
use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::isp::color::CameraColor;
use day2night::raw::RawImage;
use day2night::synth::dictionaries::cie_lamps;
use day2night::synth::sidecar::Sidecar;
use day2night::synth::{self, Calibration, IlluminantChoice, SynthOptions};
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn day() -> RawImage {
    read_dng(&common::fixtures().join("day.dng")).unwrap()
}

fn canon() -> RawImage {
    read_dng(&common::shared_file(
        "dng/canon_kissx4_magiclantern_rggb14_strips.dng",
    ))
    .unwrap()
}

/// The fixture re-described as a small-sensor camera: strongly off-diagonal ColorMatrix1 (A)
/// and 2 (D65), CameraCalibration, AnalogBalance, AsShotNeutral = D65 through them.
fn small_sensor() -> RawImage {
    let mut img = day();
    let m = &mut img.meta;
    m.make = Some("Example".into());
    m.model = Some("Small Sensor".into());
    m.unique_camera_model = Some("Example Small Sensor".into());
    m.color.color_matrix1 = Some(vec![
        1.32, -0.78, 0.02, -0.60, 1.52, 0.10, -0.30, 0.72, 0.38,
    ]);
    m.color.color_matrix2 = Some(vec![
        1.10, -0.62, 0.08, -0.72, 1.62, 0.12, -0.22, 0.55, 0.48,
    ]);
    m.color.camera_calibration1 = Some(vec![1.03, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.97]);
    m.color.camera_calibration2 = Some(vec![1.02, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.98]);
    m.color.calibration_illuminant1 = Some(17);
    m.color.calibration_illuminant2 = Some(21);
    m.color.analog_balance = Some(vec![1.1, 1.0, 0.9]);
    let cc = CameraColor::new(&m.color).unwrap();
    m.as_shot_neutral = Some(cc.xy_to_neutral([0.3127, 0.3290]).unwrap());
    img
}

/// The fixture as the paper's phone (Make samsung, Model SM-G781B).
fn s20_fe() -> RawImage {
    let mut img = day();
    img.meta.make = Some("samsung".into());
    img.meta.model = Some("SM-G781B".into());
    img.meta.unique_camera_model = Some("samsung SM-G781B".into());
    img
}

fn write(dir: &Path, name: &str, img: &RawImage) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, encode_dng(img, &WriteOptions::default()).unwrap()).unwrap();
    p
}

/// CIE xy of `n` sampled lights (plans of `local` mode: ambient, 4 lights, 5 bulbs each)
/// through the image's own matrices.
fn sampled_xy(img: &RawImage, cal: &Calibration, n: usize) -> Vec<[f64; 2]> {
    let opts = SynthOptions {
        isos: vec![],
        ..SynthOptions::default()
    };
    let cc = CameraColor::new(&img.meta.color).unwrap();
    let mut out = Vec::new();
    let mut seed = 0;
    while out.len() < n {
        let p = synth::Planner::new(img, &opts)
            .calibration(cal)
            .name("x.dng")
            .seed(seed)
            .plan()
            .map(|p| p.plan)
            .unwrap();
        for l in &p.lights {
            out.push(cc.neutral_to_xy(l.illuminant).unwrap());
        }
        seed += 1;
    }
    out.truncate(n);
    out
}

/// (CCT median, p5, p95, Duv median, |Duv| median, fraction with CCT in 1,800-6,500 K).
fn stats(xy: &[[f64; 2]]) -> [f64; 6] {
    let (mut cct, mut duv): (Vec<f64>, Vec<f64>) = xy.iter().map(|p| cct_duv(*p).unwrap()).unzip();
    let inside = cct
        .iter()
        .filter(|t| (1800.0..=6500.0).contains(*t))
        .count() as f64;
    let q = |v: &mut Vec<f64>, f: f64| {
        v.sort_by(f64::total_cmp);
        v[((v.len() - 1) as f64 * f).round() as usize]
    };
    let mut abs: Vec<f64> = duv.iter().map(|d| d.abs()).collect();
    [
        q(&mut cct, 0.5),
        q(&mut cct, 0.05),
        q(&mut cct, 0.95),
        q(&mut duv, 0.5),
        q(&mut abs, 0.5),
        inside / xy.len() as f64,
    ]
}

fn row(name: &str, dict: &str, st: [f64; 6]) -> String {
    format!(
        "| {name} | {dict} | {:.0} K ({:.0}-{:.0}) | {:+.4} | {:.4} | {:.1} % |",
        st[0],
        st[1],
        st[2],
        st[3],
        st[4],
        100.0 * st[5]
    )
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn cie_table_matches_colour_science() {
    let locus: Vec<[f64; 3]> = [
        1000.0, 1500.0, 1900.0, 2500.0, 3000.0, 4000.0, 5000.0, 6500.0, 10000.0, 15000.0,
    ]
    .iter()
    .map(|&t| {
        let xy = planck_xy(t);
        [t, xy[0], xy[1]]
    })
    .collect();
    let lamps: Vec<serde_json::Value> = cie_lamps::LAMPS
        .iter()
        .map(|l| {
            let (cct, duv) = cct_duv(l.xy).unwrap();
            serde_json::json!({"name": l.name, "xy": l.xy, "cct": cct, "duv": duv})
        })
        .collect();
    // Off-locus points too (Duv up to +-0.03).
    let points: Vec<serde_json::Value> = [
        [0.50, 0.43],
        [0.45, 0.38],
        [0.40, 0.42],
        [0.33, 0.31],
        [0.36, 0.40],
    ]
    .iter()
    .map(|xy| {
        let (cct, duv) = cct_duv(*xy).unwrap();
        serde_json::json!({"xy": xy, "cct": cct, "duv": duv})
    })
    .collect();
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("lamps.json");
    let doc = serde_json::json!({"lamps": lamps, "locus": locus, "points": points});
    std::fs::write(&p, doc.to_string()).unwrap();
    let o = common::run_validator(&py, "cie_lamps_check.py", &[p.as_os_str()]);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{text}");
    eprintln!("{text}");
}

#[test]
fn sampled_lights_are_lamp_colours_through_each_cameras_own_matrices() {
    let mut cams = vec![
        ("fixtures/day.dng", day()),
        ("small-sensor (synthetic)", small_sensor()),
    ];
    // The real Canon row too, unless the real-camera files were absent at build time
    // (build.rs); then the table says so.
    if cfg!(d2n_missing = "shared-data") {
        eprintln!("no real Canon row: the real-camera files were absent at build time");
    } else {
        cams.insert(1, ("real Canon (real-camera test data)", canon()));
    }
    let opts = SynthOptions::default();
    let cie = Calibration::embedded(&opts).unwrap();
    let paper = Calibration {
        illuminants: IlluminantChoice::Paper,
        ..cie.clone()
    };
    let mut table = vec![
        "| camera | dictionary | CCT median (p5-p95) | Duv median | abs Duv median | CCT 1,800-6,500 K |".to_string(),
        "|---|---|---|---|---|---|".to_string(),
    ];
    for (name, img) in &cams {
        for n in [600, 2000] {
            let st = stats(&sampled_xy(img, &cie, n));
            table.push(row(name, &format!("CIE lamps, {n} lights"), st));
            assert!(st[4] <= 0.006, "{name}: median |Duv| {}", st[4]);
            assert!(st[5] >= 0.95, "{name}: {} in range", st[5]);
            // the documented range (docs/synthesis.md): median 2,500-2,800 K
            assert!(
                (2450.0..2850.0).contains(&st[0]),
                "{name}: median CCT {}",
                st[0]
            );
            assert!(st[1] > 1850.0 && st[2] < 5000.0, "{name}: {st:?}");
        }
        let before = stats(&sampled_xy(img, &paper, 2000));
        table.push(row(name, "paper S20 FE (before), 2000 lights", before));
        if name.starts_with("small") {
            // the test can fail: another camera's neutrals are green here
            assert!(before[3] > 0.01, "{before:?}");
        }
    }
    eprintln!("{}", table.join("\n"));
}

#[test]
fn written_neutral_maps_back_to_the_mean_lights_xy() {
    let t = tempfile::tempdir().unwrap();
    let input = write(t.path(), "small.dng", &small_sensor());
    let out = t.path().join("o");
    let r = synth(&[
        s(&input),
        "-o",
        s(&out),
        "--iso",
        "none",
        "--target",
        "none",
        "--seed",
        "4",
    ]);
    ok(&r);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("night illuminants: CIE 015:2018 night lamps through this file's colour matrices (Example Small Sensor)"),
        "{err}"
    );
    let sc = Sidecar::read(&out.join("small.json")).unwrap();
    let prov = sc
        .calibration
        .provenance
        .as_ref()
        .unwrap()
        .illuminants
        .as_ref()
        .unwrap();
    assert_eq!(serde_json::to_value(prov.source).unwrap(), "cie_lamps");
    assert_eq!(
        prov.camera.as_ref().unwrap().label(),
        "Example Small Sensor"
    );
    let clean = read_dng(&out.join("small_clean.dng")).unwrap();
    let cc = CameraColor::new(&clean.meta.color).unwrap();
    let written = cc
        .neutral_to_xy(clean.meta.as_shot_neutral.unwrap())
        .unwrap();
    let n = sc.plan.lights.len() as f64;
    let mut mean = [0.0; 3];
    for l in &sc.plan.lights {
        for (m, v) in mean.iter_mut().zip(l.illuminant) {
            *m += v / n;
        }
    }
    let want = cc.neutral_to_xy(mean).unwrap();
    assert!(
        (written[0] - want[0]).abs() < 1e-6 && (written[1] - want[1]).abs() < 1e-6,
        "{written:?} {want:?}"
    );
    let (cct, duv) = cct_duv(written).unwrap();
    assert!(
        (1800.0..6500.0).contains(&cct) && duv.abs() < 0.01,
        "{cct} {duv}"
    );
}

#[test]
fn the_paper_phone_keeps_the_paper_dictionary_byte_for_byte() {
    let t = tempfile::tempdir().unwrap();
    let input = write(t.path(), "phone.dng", &s20_fe());
    let run = |dir: &str, extra: &[&str]| {
        let out = t.path().join(dir);
        let mut a = vec![
            s(&input),
            "-o",
            s(&out),
            "--seed",
            "9",
            "--iso",
            "1600",
            "--target",
            "exr",
        ];
        a.extend(extra);
        let r = synth(&a);
        ok(&r);
        (out, String::from_utf8_lossy(&r.stderr).into_owned())
    };
    let (auto, err) = run("auto", &[]);
    assert!(!err.contains("warning[illuminants-other-camera]"), "{err}");
    assert!(
        err.contains("night illuminants: embedded paper phone gray cards"),
        "{err}"
    );
    let (paper, _) = run("paper", &["--illuminants", "paper"]);
    same(
        &files(&auto),
        &files(&paper),
        "default vs --illuminants paper on the S20 FE",
    );
    let sc = Sidecar::read(&auto.join("phone.json")).unwrap();
    let prov = sc.calibration.provenance.unwrap().illuminants.unwrap();
    assert_eq!(serde_json::to_value(prov.source).unwrap(), "embedded_s20fe");
    assert!(
        !sc.report
            .warnings
            .iter()
            .any(|w| w.message.contains("illuminants")),
        "{:?}",
        sc.report.warnings
    );
    // The Gaussian is the embedded fit itself (docs/synthesis.md, "4. Night illuminants").
    let g = &sc.calibration.illuminants;
    assert!((g.mean[0] - 0.766125).abs() < 1e-6 && (g.cov[1][1] - 0.00489429).abs() < 1e-8);
    // The CIE lamps on the phone are an explicit choice, and give other pixels.
    let (cie, _) = run("cie", &["--illuminants", "cie"]);
    assert_ne!(
        files(&auto)["phone_clean.dng"],
        files(&cie)["phone_clean.dng"]
    );
}

#[test]
fn the_release_preset_keeps_the_paper_dictionary_and_says_so() {
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let out = t.path().join("r");
    let r = synth(&[
        s(&day),
        "-o",
        s(&out),
        "--compat",
        "release",
        "--iso",
        "none",
        "--target",
        "none",
    ]);
    ok(&r);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("warning[illuminants-other-camera]: ")
            && err.contains(": night illuminants: the paper phone's dictionary"),
        "{err}"
    );
    assert!(err.contains("day2night Fixture Camera"), "{err}");
    let sc = Sidecar::read(&out.join("day.json")).unwrap();
    assert!(sc.options.compat.paper_illuminants);
    let prov = sc.calibration.provenance.unwrap().illuminants.unwrap();
    assert_eq!(serde_json::to_value(prov.source).unwrap(), "embedded_s20fe");
    assert!(
        sc.report
            .warnings
            .iter()
            .any(|w| w.message.contains("S20 FE")
                && w.code == day2night::Code::IlluminantsOtherCamera)
    );
    // An explicit choice wins over the preset.
    let o2 = t.path().join("c");
    ok(&synth(&[
        s(&day),
        "-o",
        s(&o2),
        "--compat",
        "release",
        "--illuminants",
        "cie",
        "--iso",
        "none",
        "--target",
        "none",
    ]));
    let sc = Sidecar::read(&o2.join("day.json")).unwrap();
    let prov = sc.calibration.provenance.unwrap().illuminants.unwrap();
    assert_eq!(serde_json::to_value(prov.source).unwrap(), "cie_lamps");
}

#[test]
fn xy_and_camera_rgb_files() {
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let run = |name: &str, json: &str| {
        let f = t.path().join(format!("{name}.json"));
        std::fs::write(&f, json).unwrap();
        let out = t.path().join(name);
        let r = synth(&[
            s(&day),
            "-o",
            s(&out),
            "--illuminants",
            s(&f),
            "--iso",
            "none",
            "--target",
            "none",
        ]);
        (r, out, f)
    };
    // An xy dictionary: CIE names and own lamps, weighted.
    let (r, out, _) = run(
        "xy",
        r#"{"observer": "CIE 1931 2 degree", "lamps": [{"name": "HP1", "weight": 3}, {"name": "A"},
            {"name": "porch", "xy": [0.46, 0.41], "weight": 2}]}"#,
    );
    ok(&r);
    let sc = Sidecar::read(&out.join("day.json")).unwrap();
    let prov = sc.calibration.provenance.unwrap().illuminants.unwrap();
    assert_eq!(serde_json::to_value(prov.source).unwrap(), "file_xy");
    assert_eq!(sc.calibration.illuminants.count, 3);
    let cc = CameraColor::new(&self::day().meta.color).unwrap();
    for l in &sc.plan.lights {
        let (cct, duv) = cct_duv(cc.neutral_to_xy(l.illuminant).unwrap()).unwrap();
        assert!(
            (1700.0..3300.0).contains(&cct) && duv.abs() < 0.02,
            "{cct} {duv}"
        );
    }
    // Camera neutrals of another camera: a warning naming both.
    let (r, _, _) = run(
        "nikon",
        r#"{"illuminants": [[0.7, 0.3], [0.8, 0.28]], "camera": {"make": "Nikon", "model": "D3"}}"#,
    );
    ok(&r);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("warning[illuminants-other-camera]: ")
            && err.contains("Nikon D3")
            && err.contains("day2night Fixture Camera"),
        "{err}"
    );
    // A bad file: exit 1, the file and the field named, nothing written.
    let (r, out, f) = run("bad", r#"{"lamps": [{"xy": [0.7, 0.35]}]}"#);
    assert_eq!(r.status.code(), Some(1));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains(s(&f)) && err.contains("lamps[0].xy: x + y = 1.05"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn degenerate_matrices_are_a_clear_error_without_outputs() {
    let t = tempfile::tempdir().unwrap();
    let mut img = day();
    img.meta.color.color_matrix1 = Some(vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0]);
    let input = write(t.path(), "neg.dng", &img);
    let out = t.path().join("o");
    let r = synth(&[s(&input), "-o", s(&out)]);
    assert_eq!(r.status.code(), Some(1));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("neg.dng") && err.contains("degenerate") && err.contains("lamp"),
        "{err}"
    );
    assert!(!err.contains("NaN"), "{err}");
    assert!(!out.exists());
    // The paper's dictionary is still available for it, with the warning.
    ok(&synth(&[
        s(&input),
        "-o",
        s(&out),
        "--illuminants",
        "paper",
        "--iso",
        "none",
        "--target",
        "none",
    ]));
}

#[test]
fn sidecars_without_provenance_replay_their_old_outputs() {
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let a = t.path().join("a");
    ok(&synth(&[
        s(&day),
        "-o",
        s(&a),
        "--seed",
        "2",
        "--iso",
        "800",
    ]));
    // A sidecar as written before provenance existed (neither the illuminants' nor the
    // noise model's: the report's `noise_provenance` came with the latter).
    let mut v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("day.json")).unwrap()).unwrap();
    assert!(v["calibration"]["provenance"]["illuminants"].is_object());
    assert!(v["calibration"]["provenance"]["noise"].is_object());
    v["calibration"]["provenance"] = serde_json::Value::Null;
    v["report"]["noise_provenance"] = serde_json::Value::Null;
    let old = t.path().join("old.json");
    std::fs::write(
        &old,
        format!("{}\n", serde_json::to_string_pretty(&v).unwrap()),
    )
    .unwrap();
    let b = t.path().join("b");
    ok(&synth(&[s(&day), "-o", s(&b), "--replay", s(&old)]));
    let (mut fa, fb) = (files(&a), files(&b));
    // same pixels; the replayed sidecar is the old one (no provenance added), as synth
    // writes it
    let canonical = Sidecar::read(&old).unwrap().to_json().unwrap();
    assert!(canonical.contains("\"provenance\": null"));
    assert!(canonical.contains("\"noise_provenance\": null"));
    fa.insert("day.json".into(), canonical.into_bytes());
    same(&fa, &fb, "replay of a sidecar without provenance");
    // and a new sidecar replays byte for byte, provenance included
    let c = t.path().join("c");
    ok(&synth(&[
        s(&day),
        "-o",
        s(&c),
        "--replay",
        s(&a.join("day.json")),
    ]));
    same(&files(&a), &files(&c), "replay");
}

#[test]
fn info_says_where_the_lamps_come_from() {
    let day = common::fixtures().join("day.dng");
    let o = common::bin().arg("info").arg(&day).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("night illuminants: CIE 015:2018 night lamps through this file's colour matrices (day2night Fixture Camera)"),
        "{text}"
    );
    assert!(text.contains("synthesis:     ready"), "{text}");
    let o = common::bin()
        .args(["info", "--json"])
        .arg(&day)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["night_illuminants"]["source"], "cie_lamps");
    assert_eq!(
        v[0]["night_illuminants"]["camera"]["model"],
        "Fixture Camera"
    );
    // The phone, and a file without colour matrices.
    let t = tempfile::tempdir().unwrap();
    let phone = write(t.path(), "phone.dng", &s20_fe());
    let o = common::bin().arg("info").arg(&phone).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stdout)
        .contains("night illuminants: embedded paper phone gray cards"));
    // (the project's writer always writes a ColorMatrix1: a hand-made file without one)
    let bare = t.path().join("bare.dng");
    std::fs::write(&bare, Builder::new(64, 48, 12).without(50721).build()).unwrap();
    let o = common::bin()
        .args(["info", "--json"])
        .arg(&bare)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["synth_ready"], false);
    let e = v[0]["night_illuminants"]["error"].as_str().unwrap();
    assert!(
        e.contains("no ColorMatrix1") && e.contains("--illuminants paper"),
        "{e}"
    );
    let o = synth(&[s(&bare), "-o", s(&t.path().join("x"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--illuminants paper"));
}
