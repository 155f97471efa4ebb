//! Checks that used to disagree between entry points (issue 30, "Checks that disagree"), on
//! the input side: each refusal is the same in `info`, `synth`, `render` and `calibrate`,
//! and each message names the tag or option, the value and the rule.
use crate::common;
use crate::dngbuild::Builder;
use day2night::tiff::value::Value;
use std::path::Path;
use std::process::Output;

const FORWARD_MATRIX1: u16 = 50964;
const CALIBRATION_ILLUMINANT1: u16 = 50778;
const NOISE_PROFILE: u16 = 51041;
const ISO: u16 = 34855;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn write(dir: &Path, name: &str, b: Builder) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, b.build()).unwrap();
    p
}

fn synthesis_line(o: &Output) -> String {
    let out = String::from_utf8_lossy(&o.stdout);
    out.lines()
        .find(|l| l.trim_start().starts_with("synthesis:"))
        .unwrap_or_else(|| panic!("no synthesis line: {out}"))
        .to_string()
}

fn srational(v: &[f64]) -> Value {
    Value::SRational(v.iter().map(|x| ((x * 10000.0) as i32, 10000)).collect())
}

#[test]
fn a_forward_matrix_mapping_white_to_no_light_is_refused_by_info_synth_and_render() {
    let t = tempfile::tempdir().unwrap();
    let fm = [0.6, 0.3, 0.1, 0.25, 0.7, 0.05, 0.0, 0.1, 0.75];
    let good = write(
        t.path(),
        "good.dng",
        Builder::new(64, 48, 12).set(FORWARD_MATRIX1, srational(&fm)),
    );
    let o = common::bin().arg("info").arg(&good).output().unwrap();
    assert!(synthesis_line(&o).contains("ready"), "{}", text(&o));
    let negated: Vec<f64> = fm.iter().map(|v| -v).collect();
    for (name, m) in [("zero.dng", vec![0.0; 9]), ("negated.dng", negated)] {
        let bad = write(
            t.path(),
            name,
            Builder::new(64, 48, 12).set(FORWARD_MATRIX1, srational(&m)),
        );
        // info: not ready, for the reason synth and render give.
        let o = common::bin().arg("info").arg(&bad).output().unwrap();
        let line = synthesis_line(&o);
        assert!(
            line.contains("not usable") && line.contains("non-positive luminance"),
            "{name}: {line}"
        );
        assert!(line.contains("--target none"), "{name}: {line}");
        let o = common::bin()
            .args(["info", "--json"])
            .arg(&bad)
            .output()
            .unwrap();
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v[0]["synth_ready"], false, "{name}");
        // synth refuses, naming the same reason, and writes nothing.
        let out = t.path().join(format!("{name}.night"));
        let o = common::bin()
            .args(["synth", s(&bad), "-o", s(&out), "--iso", "1600"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{name}: {}", text(&o));
        assert!(text(&o).contains("non-positive luminance"), "{}", text(&o));
        assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none());
        // render refuses for the same reason.
        let png = t.path().join(format!("{name}.png"));
        let o = common::bin()
            .args(["render", s(&bad), "-o", s(&png)])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{name}: render accepted it");
        assert!(text(&o).contains("non-positive luminance"), "{}", text(&o));
        // Without a render the matrices are not used: synth runs, as info's hint says.
        let o = common::bin()
            .args(["synth", s(&bad), "-o", s(&out), "--iso", "1600"])
            .args(["--target", "none", "-q"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{name}: {}", text(&o));
    }
}

#[test]
fn calibrate_refuses_an_iso_synth_would_refuse() {
    let t = tempfile::tempdir().unwrap();
    let day = write(t.path(), "day.dng", Builder::new(64, 48, 12));
    let model = t.path().join("noise.json");
    for iso in ["999999999", "4000001", "0"] {
        let o = common::bin()
            .args(["calibrate", "noise", "--from-image", s(&day)])
            .args(["--assume-iso", iso, "-o", s(&model)])
            .output()
            .unwrap();
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(2), "{iso}: {msg}");
        assert!(
            msg.contains("--assume-iso")
                && msg.contains(&format!("ISO {iso} is outside 1..=4000000")),
            "{iso}: {msg}"
        );
        assert!(!model.exists(), "{iso}: a model was written");
    }
}

#[test]
fn an_invalid_noise_profile_is_reported_as_invalid_not_as_missing() {
    let t = tempfile::tempdir().unwrap();
    let mut b = Builder::new(64, 48, 12).set(NOISE_PROFILE, Value::Double(vec![-1e-4, 1e-6]));
    b.exif.push((ISO, Value::Short(vec![100])));
    let day = write(t.path(), "day.dng", b);
    let out = t.path().join("night");
    let o = common::bin()
        .args([
            "synth",
            s(&day),
            "-o",
            s(&out),
            "--iso",
            "1600",
            "--target",
            "none",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let sidecar = std::fs::read_to_string(out.join("day.json")).unwrap();
    let all = format!("{}{sidecar}", text(&o));
    assert!(
        all.contains("invalid NoiseProfile pair 0 (S -1e-4, O 1e-6)"),
        "{all}"
    );
    assert!(!all.contains("has no NoiseProfile"), "{all}");
}

#[test]
fn a_negative_noise_model_parameter_is_warned_about() {
    let t = tempfile::tempdir().unwrap();
    let day = write(t.path(), "day.dng", Builder::new(64, 48, 12));
    let model = t.path().join("neg.json");
    std::fs::write(
        &model,
        r#"{"format":"day2night-noise-model/1","units":"normalized","source":"test","isos":[{"iso":1600,"positions":[[1e-4,-1],[1e-4,1e-6],[1e-4,1e-6],[1e-4,1e-6]]}]}"#,
    )
    .unwrap();
    let out = t.path().join("night");
    let o = common::bin()
        .args([
            "synth",
            s(&day),
            "-o",
            s(&out),
            "--iso",
            "1600",
            "--target",
            "none",
        ])
        .args(["--noise-model", s(&model)])
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(o.status.success(), "{msg}");
    assert!(
        msg.contains("negative parameters at ISO 1600 position 0 (S 1e-4, O -1)")
            && msg.contains("clamps them to 0"),
        "{msg}"
    );
}

#[test]
fn a_calibration_illuminant_outside_the_exif_table_is_warned_about() {
    let t = tempfile::tempdir().unwrap();
    let day = write(
        t.path(),
        "day.dng",
        Builder::new(64, 48, 12).set(CALIBRATION_ILLUMINANT1, Value::Short(vec![99])),
    );
    let o = common::bin().arg("info").arg(&day).output().unwrap();
    let msg = text(&o);
    assert!(
        msg.contains("CalibrationIlluminant1 99 is not an EXIF LightSource code"),
        "{msg}"
    );
    let out = t.path().join("night");
    let o = common::bin()
        .args([
            "synth",
            s(&day),
            "-o",
            s(&out),
            "--iso",
            "1600",
            "--target",
            "none",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("CalibrationIlluminant1 99"),
        "{}",
        text(&o)
    );
}
