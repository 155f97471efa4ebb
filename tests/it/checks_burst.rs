//! Checks of a burst that used to disagree or say too little (issue 30, "Checks that
//! disagree"): the options' rules, a shake step too large for the image, frames with little
//! valid area, and a replayed sidecar's transforms checked in full. Python's side is
//! python/tests/test_checks_burst.py (the same rules and messages).
use crate::common;
use crate::dngbuild::Builder;
use std::path::{Path, PathBuf};
use std::process::Output;

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

fn synth(input: &Path, out: &Path, extra: &[&str]) -> Output {
    common::bin()
        .args([
            "synth",
            s(input),
            "-o",
            s(out),
            "--iso",
            "1600",
            "--target",
            "none",
        ])
        .args(extra)
        .output()
        .unwrap()
}

fn small(dir: &Path) -> PathBuf {
    let p = dir.join("small.dng");
    std::fs::write(&p, Builder::new(64, 48, 12).build()).unwrap();
    p
}

#[test]
fn option_rules_and_messages_speak_in_flags_and_rounded_values() {
    let t = tempfile::tempdir().unwrap();
    let day = small(t.path());
    let out = t.path().join("o");
    for (args, want) in [
        (
            vec!["--burst", "3", "--motion", "none", "--shake-step", "5"],
            "--shake-step has no effect with --motion none",
        ),
        (
            vec!["--burst", "1", "--motion", "none"],
            "--motion needs a burst (--burst N with N > 1)",
        ),
        (vec!["--shake-step", "2"], "--shake-step needs a burst"),
        (
            vec!["--burst", "3", "--shake-step", "1e308"],
            "--shake-step: 1e308 is outside 0..=1000",
        ),
    ] {
        let o = synth(&day, &out, &args);
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {msg}");
        assert!(msg.contains(want), "{args:?}: {msg}");
        assert!(msg.len() < 400, "{args:?}: a long message: {msg}");
        assert!(!out.exists(), "{args:?} wrote outputs");
    }
}

#[test]
fn a_shake_step_too_large_for_the_image_is_refused_before_the_draw() {
    let t = tempfile::tempdir().unwrap();
    let day = small(t.path());
    let out = t.path().join("o");
    let o = synth(&day, &out, &["--burst", "3", "--shake-step", "50"]);
    let msg = text(&o);
    assert_eq!(o.status.code(), Some(1), "{msg}");
    assert!(
        msg.contains("--shake-step")
            && msg.contains("50 px is too large for the 64x48 active area"),
        "{msg}"
    );
    assert!(!out.join("small_iso1600_f01.dng").exists());
    // A 1x1 image: the same refusal whatever the seed, never an internal plan field.
    let one = common::fixtures().join("edge_1x1.dng");
    for seed in ["1", "2", "3", "4", "5", "6"] {
        let out = t.path().join(format!("one{seed}"));
        let o = synth(
            &one,
            &out,
            &["--burst", "3", "--shake-step", "100", "--seed", seed],
        );
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(1), "seed {seed}: {msg}");
        assert!(
            msg.contains("too large for the 1x1 active area") && !msg.contains("plan field"),
            "seed {seed}: {msg}"
        );
    }
}

/// Frames' valid areas from a sidecar: (frame, width * height).
fn valid_areas(sidecar: &serde_json::Value) -> Vec<(u64, u64)> {
    sidecar["plan"]["burst"]["transforms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            let v = &t["valid"];
            (
                t["frame"].as_u64().unwrap(),
                v["width"].as_u64().unwrap() * v["height"].as_u64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn frames_with_little_valid_area_are_warned_about() {
    let t = tempfile::tempdir().unwrap();
    let day = small(t.path());
    let mut warned = 0;
    for seed in ["1", "2", "3", "4"] {
        let out = t.path().join(format!("o{seed}"));
        let o = synth(
            &day,
            &out,
            &["--burst", "16", "--shake-step", "12", "--seed", seed],
        );
        let msg = text(&o);
        assert!(o.status.success(), "{msg}");
        let sc: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("small.json")).unwrap()).unwrap();
        let small: Vec<u64> = valid_areas(&sc)
            .into_iter()
            .filter(|&(_, a)| (a as f64) < 0.5 * 64.0 * 48.0)
            .map(|(f, _)| f)
            .collect();
        let warning = msg
            .lines()
            .find(|l| l.contains("keep a valid area under half of the 64x48 active area"));
        match warning {
            None => assert!(
                small.is_empty(),
                "seed {seed}: no warning for {small:?}: {msg}"
            ),
            Some(w) => {
                warned += 1;
                assert!(w.contains(&format!("{} of 16 frames", small.len())), "{w}");
                for f in &small {
                    assert!(w.contains(&format!("f{f:02} ")), "f{f:02} missing: {w}");
                }
                assert!(w.starts_with("warning[burst-valid-area]: "), "{w}");
                let plan_warnings = sc["report"]["warnings"].to_string();
                assert!(
                    plan_warnings.contains("valid area under half")
                        && plan_warnings.contains("\"code\":\"burst-valid-area\""),
                    "{plan_warnings}"
                );
            }
        }
    }
    assert!(warned > 0, "no seed gave a frame with little valid area");
}

/// A shaken burst's sidecar and its input, to be edited and replayed.
fn burst_sidecar(dir: &Path) -> (PathBuf, serde_json::Value) {
    let day = common::fixtures().join("day.dng");
    let out = dir.join("burst");
    let o = synth(&day, &out, &["--burst", "3", "--shake-step", "2"]);
    assert!(o.status.success(), "{}", text(&o));
    let sc = serde_json::from_slice(&std::fs::read(out.join("day.json")).unwrap()).unwrap();
    (day, sc)
}

fn replay(dir: &Path, day: &Path, sc: &serde_json::Value, name: &str) -> Output {
    let p = dir.join(format!("{name}.json"));
    std::fs::write(&p, serde_json::to_vec_pretty(sc).unwrap()).unwrap();
    common::bin()
        .args([
            "synth",
            s(day),
            "-o",
            s(&dir.join(name)),
            "--replay",
            s(&p),
            "-q",
        ])
        .output()
        .unwrap()
}

#[test]
fn a_replayed_burst_transform_is_checked_in_full() {
    let t = tempfile::tempdir().unwrap();
    let (day, sc) = burst_sidecar(t.path());
    let o = replay(t.path(), &day, &sc, "same");
    assert!(o.status.success(), "{}", text(&o));
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = sc.clone();
        f(&mut v["plan"]["burst"]["transforms"][1]);
        v
    };
    let cases: Vec<(&str, serde_json::Value, &str)> = vec![
        (
            "overflow",
            edit(&|t| t["valid"]["top"] = serde_json::json!(u64::MAX)),
            "outside the 512x512 active area",
        ),
        (
            "shear",
            edit(&|t| {
                t["affine"][0][0] = 1.0.into();
                t["affine"][0][1] = 1.0.into();
                t["affine"][1][0] = 0.0.into();
                t["affine"][1][1] = 1.0.into();
            }),
            "is not a rotation",
        ),
        (
            "theta",
            edit(&|t| t["theta_deg"] = (t["theta_deg"].as_f64().unwrap() + 2.0).into()),
            "theta_deg says",
        ),
        (
            "dx",
            edit(&|t| t["dx"] = (t["dx"].as_f64().unwrap() + 3.0).into()),
            "does not move the centre",
        ),
        (
            "far",
            edit(&|t| {
                // A consistent 20,000 px shift that claims a 44x60 valid area.
                let (cx, cy) = (255.5, 255.5);
                t["dx"] = 20000.0.into();
                t["dy"] = 0.0.into();
                t["theta_deg"] = 0.0.into();
                t["affine"] = serde_json::json!([[1.0, 0.0, 20000.0], [0.0, 1.0, 0.0]]);
                let _ = (cx, cy);
                t["valid"] = serde_json::json!({"top": 10, "left": 10, "height": 60, "width": 44});
            }),
            "44x60 at (10, 10) claims samples the transform takes from outside the image",
        ),
    ];
    for (name, v, want) in cases {
        let o = replay(t.path(), &day, &v, name);
        let msg = text(&o);
        assert!(!o.status.success(), "{name}: replayed");
        assert!(msg.contains(want), "{name}: {msg}");
        assert!(msg.contains("burst.transforms[1]"), "{name}: {msg}");
        assert!(!t.path().join(name).join("day_iso1600_f01.dng").exists());
    }
}
