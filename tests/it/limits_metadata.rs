//! Absurd metadata: every extreme case (made here with the independent builder) is run
//! through the Adobe DNG SDK (dngpy, tests/validators/sdk_accepts.py) and through day2night
//! (`info`, `render`, `synth` clean + noisy, `convert`). Whenever the SDK accepts the input,
//! every DNG day2night writes from it must pass the SDK too; inputs the SDK rejects must be refused
//! (exit 1, the tag named) or corrected with a warning naming the tag. Each case also states
//! day2night's expected verdict (docs/limits.md, "Metadata").
use crate::common;
use crate::dngbuild::Builder;
use day2night::tiff::value::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

/// What day2night does with a case.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Verdict {
    /// Used as is: no warning.
    Ok,
    /// Used as is, but every pixel is at black or at white: only `render` warns,
    /// saying that its picture is constant.
    Constant,
    /// Corrected, with a warning naming this tag.
    Warn(&'static str),
    /// Refused (exit 1), the message naming this tag.
    Refuse(&'static str),
}
use Verdict::*;

/// SRATIONALs close to `v` (the largest denominator that keeps the numerator in range).
fn srat(v: &[f64]) -> Value {
    Value::SRational(
        v.iter()
            .map(|&x| {
                let max = i32::MAX as f64;
                let den = if x.abs() <= 1.0 {
                    max
                } else {
                    (max / x.abs()).floor().min(1e6)
                };
                (
                    (x * den).round().clamp(-max, max) as i32,
                    den.max(1.0) as i32,
                )
            })
            .collect(),
    )
}

fn rat(v: &[f64]) -> Value {
    Value::Rational(
        v.iter()
            .map(|&x| {
                let max = u32::MAX as f64;
                let den = if x <= 1.0 {
                    i32::MAX as f64
                } else {
                    (max / x).floor().min(1e6)
                };
                ((x * den).round().min(max) as u32, den.max(1.0) as u32)
            })
            .collect(),
    )
}

fn diag(a: f64, b: f64, c: f64) -> Vec<f64> {
    vec![a, 0.0, 0.0, 0.0, b, 0.0, 0.0, 0.0, c]
}

const COLOR_MATRIX1: u16 = 50721;
const AS_SHOT_NEUTRAL: u16 = 50728;
const WHITE_LEVEL: u16 = 50717;
const BLACK_LEVEL: u16 = 50714;
const BLACK_LEVEL_DELTA_H: u16 = 50715;
const LINEARIZATION_TABLE: u16 = 50712;
const NOISE_PROFILE: u16 = 51041;
const ISO_SPEED_RATINGS: u16 = 34855;

/// A capture's own noise calibration: Exif ISO 100 and a NoiseProfile, so that the noise
/// model is the file's and no case meets the warning of an uncalibrated camera (the
/// subject of `noise_chain`, not of this test).
fn calibrated(mut b: Builder) -> Builder {
    b.exif = vec![(ISO_SPEED_RATINGS, Value::Short(vec![100]))];
    b.set(NOISE_PROFILE, Value::Double(vec![2e-4, 1e-6]))
}

/// A plausible 16 x 12 14-bit scene (black 512).
fn base() -> Builder {
    let mut b = Builder::new(16, 12, 14);
    b.pixels = (0..16 * 12)
        .map(|i| 600 + ((i * 97) % 9000) as u16)
        .collect();
    calibrated(b)
        .set(BLACK_LEVEL, Value::Short(vec![512]))
        .set(WHITE_LEVEL, Value::Short(vec![16383]))
}

fn cases() -> Vec<(&'static str, Builder, Verdict)> {
    let b = base;
    let sized = |w: usize, h: usize| {
        let mut x = Builder::new(w, h, 14);
        x.pixels = vec![4000; w * h];
        calibrated(x).set(BLACK_LEVEL, Value::Short(vec![512]))
    };
    let flat = |v: u16| {
        let mut x = base();
        x.pixels = vec![v; 16 * 12];
        x
    };
    vec![
        ("base", b(), Ok),
        // Colour matrices: condition number, not the determinant alone.
        (
            "cm_diag_2e31",
            b().set(
                COLOR_MATRIX1,
                srat(&diag(2147483647.0, 1.0, 1.0 / 2147483647.0)),
            ),
            Refuse("ColorMatrix1"),
        ),
        (
            "cm_cond_1e9",
            b().set(COLOR_MATRIX1, srat(&diag(1e4, 1.0, 1e-5))),
            Refuse("ColorMatrix1"),
        ),
        (
            "cm_cond_1e5",
            b().set(COLOR_MATRIX1, srat(&diag(100.0, 1.0, 1e-3))),
            Refuse("ColorMatrix1"),
        ),
        (
            "cm_cond_at_bound",
            b().set(COLOR_MATRIX1, srat(&diag(10.0, 1.0, 1e-3))),
            Ok,
        ),
        (
            "cm_cond_past_bound",
            b().set(COLOR_MATRIX1, srat(&diag(10.0, 1.0, 9.9e-4))),
            Refuse("ColorMatrix1"),
        ),
        (
            "cm_tiny_det",
            b().set(COLOR_MATRIX1, srat(&diag(1e-4, 1e-4, 1e-4))),
            Ok,
        ),
        (
            "cm_singular",
            b().set(
                COLOR_MATRIX1,
                srat(&[1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 0.0, 1.0]),
            ),
            Refuse("ColorMatrix1"),
        ),
        // WhiteLevel against BitsPerSample.
        (
            "white_1e6_16bit",
            {
                let mut x = Builder::new(16, 12, 16);
                x.pixels = vec![3000; 192];
                x.set(WHITE_LEVEL, Value::Long(vec![1_000_000]))
            },
            Refuse("WhiteLevel"),
        ),
        (
            "white_above_14bit",
            b().set(WHITE_LEVEL, Value::Short(vec![16384])),
            Refuse("WhiteLevel"),
        ),
        // LinearizationTable length.
        (
            "lin_one_entry",
            b().set(LINEARIZATION_TABLE, Value::Short(vec![5])),
            Refuse("LinearizationTable"),
        ),
        (
            "lin_two_entries",
            // Every stored value past the table's end maps to its last entry
            // (DNG 1.7, LinearizationTable): the picture is all white.
            b().set(LINEARIZATION_TABLE, Value::Short(vec![0, 16383])),
            Constant,
        ),
        // Neutrals.
        (
            "neutral_1e6",
            b().set(AS_SHOT_NEUTRAL, rat(&[1e-6, 1.0, 1.0])),
            Refuse("AsShotNeutral"),
        ),
        (
            "neutral_2e3_above",
            b().set(AS_SHOT_NEUTRAL, rat(&[1.0, 1.0, 2000.0])),
            Refuse("AsShotNeutral"),
        ),
        (
            "neutral_at_bound",
            b().set(AS_SHOT_NEUTRAL, rat(&[1e-3, 1.0, 1.0])),
            Ok,
        ),
        (
            "neutral_zero",
            b().set(AS_SHOT_NEUTRAL, rat(&[0.0, 1.0, 1.0])),
            Refuse("AsShotNeutral"),
        ),
        // NoiseProfile.
        (
            "noise_zero",
            b().set(NOISE_PROFILE, Value::Double(vec![0.0, 0.0])),
            Warn("NoiseProfile"),
        ),
        (
            "noise_negative",
            b().set(NOISE_PROFILE, Value::Double(vec![-1e-4, 1e-6])),
            Warn("NoiseProfile"),
        ),
        (
            "noise_huge",
            b().set(NOISE_PROFILE, Value::Double(vec![1e30, 1e30])),
            Warn("NoiseProfile"),
        ),
        (
            "noise_ok",
            b().set(NOISE_PROFILE, Value::Double(vec![2e-4, 1e-6])),
            Ok,
        ),
        // Black levels.
        (
            "black_delta_below_zero",
            b().set(BLACK_LEVEL_DELTA_H, srat(&[-700.0; 16])),
            Refuse("BlackLevelDeltaH"),
        ),
        (
            "black_at_white",
            b().set(BLACK_LEVEL, Value::Short(vec![16383])),
            Refuse("BlackLevel"),
        ),
        (
            "black_above_white",
            b().set(BLACK_LEVEL, Value::Long(vec![20000])),
            Refuse("BlackLevel"),
        ),
        // Exif ISO out of range.
        (
            "iso_5e6",
            {
                let mut x = b();
                x.exif = vec![(ISO_SPEED_RATINGS, Value::Long(vec![5_000_000]))];
                x
            },
            Warn("ISOSpeedRatings"),
        ),
        // Geometry and content extremes.
        ("size_2x2", sized(2, 2), Ok),
        ("size_odd_7x5", sized(7, 5), Ok),
        ("size_1x1", sized(1, 1), Ok),
        ("all_black", flat(512), Constant),
        ("all_saturated", flat(16383), Constant),
    ]
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The SDK's own warnings about the tiny test images' geometry (no border for its
/// demosaicer): not about values, and the same for every input and output.
fn benign(m: &str) -> bool {
    m.contains("Too little padding")
}

/// The SDK's verdict on each file: (accepted, messages other than [`benign`] ones).
fn sdk(py: &Path, files: &[PathBuf]) -> Vec<(bool, Vec<String>)> {
    if files.is_empty() {
        return vec![];
    }
    let args: Vec<&std::ffi::OsStr> = files.iter().map(|f| f.as_os_str()).collect();
    let out = common::run_validator(py, "sdk_accepts.py", &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let msgs = v["messages"]
                .as_array()
                .unwrap()
                .iter()
                .map(|m| m.as_str().unwrap().to_string())
                .filter(|m| !benign(m))
                .collect::<Vec<_>>();
            (msgs.is_empty(), msgs)
        })
        .collect()
}

fn dngs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    v.retain(|p| p.extension().is_some_and(|e| e == "dng"));
    v.sort();
    v
}

/// day2night's verdict from one command's output.
fn verdict_of(out: &Output) -> (bool, String) {
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn check_verdict(case: &str, cmd: &str, out: &Output, want: Verdict) {
    let (ok, err) = verdict_of(out);
    match want {
        Ok => assert!(
            ok && !err.contains("warning"),
            "{case}: {cmd} should succeed without warning: {err}"
        ),
        Constant if cmd == "render" => {
            let warnings: Vec<&str> = err.lines().filter(|l| l.contains("warning")).collect();
            assert!(
                ok && warnings.len() == 1 && warnings[0].contains("the render is constant"),
                "{case}: {cmd} should succeed, warning only that the render is constant: {err}"
            );
        }
        Constant => check_verdict(case, cmd, out, Ok),
        Warn(tag) => assert!(
            ok && err.contains("warning") && err.contains(tag),
            "{case}: {cmd} should succeed with a warning naming {tag}: {err}"
        ),
        Refuse(tag) => {
            assert!(
                !ok,
                "{case}: {cmd} should refuse (naming {tag}) but succeeded: {err}"
            );
            assert_eq!(out.status.code(), Some(1), "{case}: {cmd}: {err}");
            assert!(
                err.contains(tag) && err.starts_with("day2night: "),
                "{case}: {cmd} should name {tag}: {err}"
            );
        }
    }
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn extreme_metadata_never_gives_a_dng_the_sdk_rejects() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    let cases = cases();
    let inputs: Vec<PathBuf> = cases
        .iter()
        .map(|(name, b, _)| {
            let p = dir.path().join(format!("{name}.dng"));
            std::fs::write(&p, b.build()).unwrap();
            p
        })
        .collect();
    let verdicts = sdk(&py, &inputs);
    let mut report = String::new();
    let mut failures = Vec::new();
    for (((name, _, want), input), (sdk_ok, msgs)) in cases.iter().zip(&inputs).zip(&verdicts) {
        report.push_str(&format!(
            "{name}: SDK {} {:?}; want {:?}\n",
            if *sdk_ok { "accepts" } else { "rejects" },
            msgs,
            want
        ));
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            // Inputs the SDK rejects are never used as is.
            assert!(
                *sdk_ok || !matches!(want, Ok | Constant),
                "{name}: the SDK rejects it ({msgs:?}) but day2night would use it as is"
            );
            let out_dir = dir.path().join(format!("{name}_synth"));
            let info = common::bin().arg("info").arg(input).output().unwrap();
            let info_text = String::from_utf8_lossy(&info.stdout).into_owned();
            match want {
                Ok | Constant => assert!(
                    info_text.contains("synthesis:     ready\n"),
                    "{name}: info: {info_text}"
                ),
                Warn(tag) => assert!(
                    info_text.contains("ready, with warnings") && info_text.contains(tag),
                    "{name}: info: {info_text}"
                ),
                Refuse(_) => check_verdict(name, "info", &info, *want),
            }
            // At the NoiseProfile's own ISO ([`calibrated`]): no ISO scaling to warn about.
            let synth = common::bin()
                .args([
                    "synth",
                    s(input),
                    "-o",
                    s(&out_dir),
                    "--iso",
                    "100",
                    "--target",
                    "none",
                ])
                .output()
                .unwrap();
            check_verdict(name, "synth", &synth, *want);
            let png = dir.path().join(format!("{name}_render.png"));
            let render = common::bin()
                .args(["render", s(input), "-o", s(&png)])
                .output()
                .unwrap();
            check_verdict(name, "render", &render, *want);
            let conv = dir.path().join(format!("{name}_conv.dng"));
            let convert = common::bin()
                .args(["convert", s(input), s(&conv)])
                .output()
                .unwrap();
            check_verdict(name, "convert", &convert, *want);
            let mut written = dngs(&out_dir);
            if conv.exists() {
                written.push(conv.clone());
            }
            if matches!(want, Refuse(_)) {
                assert!(written.is_empty(), "{name}: refused but wrote {written:?}");
                return;
            }
            assert!(
                written.len() >= 3,
                "{name}: expected clean + noisy + converted DNGs, got {written:?}"
            );
            for (f, (ok, m)) in written.iter().zip(sdk(&py, &written)) {
                assert!(ok, "{name}: the SDK rejects {}: {m:?}", f.display());
            }
        }));
        if r.is_err() {
            failures.push(*name);
        }
    }
    eprintln!("{report}");
    assert!(failures.is_empty(), "failed cases: {failures:?}");
}

/// A probe, not a check: which conditionings the Adobe DNG SDK accepts (needs the
/// validators; run with `--ignored --nocapture`).
#[test]
#[ignore = "probe of the DNG SDK's matrix limits: run with --ignored --nocapture"]
fn probe_sdk_matrices() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    let mut mats: Vec<(String, Vec<f64>)> = Vec::new();
    for e in [1.0, 2.0, 3.0, 3.5, 4.0, 4.5, 5.0, 6.0] {
        let t = 10f64.powf(-e);
        mats.push((format!("diag(1,1,1e-{e})"), diag(1.0, 1.0, t)));
        mats.push((format!("diag(1e{e},1,1)"), diag(1.0 / t, 1.0, 1.0)));
        mats.push((format!("diag(1e{e},1e{e},1)"), diag(1.0 / t, 1.0 / t, 1.0)));
        mats.push((
            format!("diag(0.01,0.01,1e-2-{e})"),
            diag(0.01, 0.01, 0.01 * t),
        ));
    }
    let files: Vec<PathBuf> = mats
        .iter()
        .enumerate()
        .map(|(i, (_, m))| {
            let p = dir.path().join(format!("m{i}.dng"));
            std::fs::write(&p, base().set(COLOR_MATRIX1, srat(m)).build()).unwrap();
            p
        })
        .collect();
    for ((n, _), (ok, msgs)) in mats.iter().zip(sdk(&py, &files)) {
        let errs: Vec<_> = msgs.iter().filter(|m| !m.contains("padding")).collect();
        eprintln!("{n}: {} {errs:?}", ok || errs.is_empty());
    }
}

/// `synth --iso` and the `--replay` sidecar check use one bound: the largest ISO synthesizes
/// and its sidecar replays; one past it is refused by both, naming the field.
#[test]
fn synth_and_replay_agree_on_the_iso_bound() {
    let (lo, hi) = day2night::bounds::ISO_RANGE;
    assert_eq!(lo, 1);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let day = common::fixtures().join("day.dng");
    let synth = |args: &[&str]| {
        common::bin()
            .arg("synth")
            .arg(&day)
            .args(args)
            .output()
            .unwrap()
    };
    let at = hi.to_string();
    let past = (hi + 1).to_string();
    let a = d.join("a");
    let o = synth(&["-o", s(&a), "--iso", &at, "--target", "none"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sidecar = a.join("day.json");
    let o = synth(&["-o", s(&d.join("r")), "--replay", s(&sidecar)]);
    assert!(
        o.status.success(),
        "replay at the bound: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    // One past: the option is a usage error...
    let o = synth(&["-o", s(&d.join("b")), "--iso", &past, "--target", "none"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("--iso: ISO {past} is outside 1..={hi}")),
        "{err}"
    );
    assert!(!d.join("b").join("day.json").exists());
    // ...and a sidecar saying so is refused by the replay check, naming the field.
    let text = std::fs::read_to_string(&sidecar).unwrap();
    let needle = format!("\"iso\": {at}");
    assert!(text.contains(&needle), "{text}");
    let bad = d.join("bad.json");
    std::fs::write(&bad, text.replace(&needle, &format!("\"iso\": {past}"))).unwrap();
    let o = synth(&["-o", s(&d.join("r2")), "--replay", s(&bad)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("plan field noise[0].iso: ISO {past} is outside")),
        "{err}"
    );
}
