//! `day2night eval` on images holding NaN or Inf: an error naming the file and the count by
//! default; `--nonfinite zero` replaces them by 0, warns, and says so in the JSON.
use crate::common;
use std::path::{Path, PathBuf};

/// An 8 x 8 f32 RGB EXR holding `data` as is (day2night's own writer sanitizes NaN/Inf).
fn exr(dir: &Path, name: &str, data: Vec<f32>) -> PathBuf {
    let p = dir.join(name);
    exr::prelude::write_rgb_file(&p, 8, 8, |x, y| {
        let i = 3 * (y * 8 + x);
        (data[i], data[i + 1], data[i + 2])
    })
    .unwrap();
    p
}

fn eval(a: &Path, b: &Path, extra: &[&str]) -> std::process::Output {
    common::bin()
        .arg("eval")
        .arg(a)
        .arg(b)
        .arg("--json")
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn nan_or_inf_is_an_error_unless_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let clean: Vec<f32> = (0..192).map(|i| (i % 17) as f32 / 20.0).collect();
    let mut inf = clean.clone();
    inf[5] = f32::INFINITY;
    inf[6] = f32::NEG_INFINITY;
    let (c, i) = (exr(d, "clean.exr", clean), exr(d, "inf.exr", inf));
    let nan_a = exr(d, "nan_a.exr", vec![f32::NAN; 192]);
    let nan_b = exr(d, "nan_b.exr", vec![f32::NAN; 192]);

    // Default: refused, naming the file and the count.
    let o = eval(&i, &c, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("day2night: ") && err.contains("inf.exr") && err.contains("2 NaN/Inf"),
        "{err}"
    );
    assert!(o.stdout.is_empty());
    // Two all-NaN images do not "match perfectly".
    let o = eval(&nan_a, &nan_b, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("nan_a.exr") && err.contains("192 NaN/Inf"),
        "{err}"
    );

    // --nonfinite zero: replaced by 0 (not by the largest float: PSNR stays sane).
    let o = eval(&i, &c, &["--nonfinite", "zero"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning[nonfinite-replaced]: ")
            && err.contains(": 2 NaN/Inf samples replaced by 0"),
        "{err}"
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["nonfinite"], "zero");
    assert_eq!(j["nonfinite_replaced"], serde_json::json!([2, 0]));
    // The warning with its code in the JSON (absent when nothing was replaced).
    assert_eq!(j["warnings"][0]["code"], "nonfinite-replaced", "{j}");
    assert!(
        j["warnings"][0]["subject"]
            .as_str()
            .unwrap()
            .ends_with(".exr"),
        "{j}"
    );
    let psnr = j["psnr"].as_f64().unwrap();
    assert!(psnr > 20.0, "{j}");
    // Clean pairs: the JSON says the mode, nothing replaced.
    let o = eval(&c, &c, &[]);
    assert!(o.status.success());
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j.get("warnings").is_none(), "{j}");
    assert_eq!(j["nonfinite"], "error");
    assert_eq!(j["nonfinite_replaced"], serde_json::json!([0, 0]));
    // A bad mode is a usage error.
    assert_eq!(
        eval(&c, &c, &["--nonfinite", "clamp"]).status.code(),
        Some(2)
    );
}
