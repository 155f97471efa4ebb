//! `info` tells the truth about readiness and `synth` lists every problem at once (issue 24
//! point 4): a PiDNG-like file without AsShotNeutral and without ColorMatrix1 is "not
//! usable" in `info`, naming every missing item with the flag that fixes it, `synth`
//! refuses it with the same list and writes nothing, and with those flags it runs.
use crate::common;
use crate::dngbuild::Builder;
use std::path::Path;
use std::process::Output;

const AS_SHOT_NEUTRAL: u16 = 50728;
const COLOR_MATRIX1: u16 = 50721;
const FLAGS: [&str; 3] = ["--day-neutral", "--illuminants paper", "--target none"];

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn synth(input: &Path, out: &Path, extra: &[&str]) -> Output {
    common::bin()
        .args(["synth", s(input), "-o", s(out), "--iso", "1600"])
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn every_missing_item_is_listed_at_once_with_its_flag() {
    let t = tempfile::tempdir().unwrap();
    let bare = t.path().join("pidng.dng");
    let dng = Builder::new(64, 48, 12)
        .without(AS_SHOT_NEUTRAL)
        .without(COLOR_MATRIX1)
        .build();
    std::fs::write(&bare, dng).unwrap();

    let o = common::bin().arg("info").arg(&bare).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("synthesis:"))
        .unwrap_or_else(|| panic!("no synthesis line: {text}"));
    assert!(
        line.contains("not usable: ") && line.contains("3 problems: (1) "),
        "{line}"
    );
    for f in FLAGS {
        assert!(line.contains(f), "{f} missing: {line}");
    }
    let o = common::bin()
        .args(["info", "--json"])
        .arg(&bare)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["synth_ready"], false);
    let reason = v[0]["reason"].as_str().unwrap();
    assert!(
        reason.contains("AsShotNeutral") && reason.contains("ColorMatrix1"),
        "{reason}"
    );

    // synth: the same list, nothing written.
    let out = t.path().join("night");
    let o = synth(&bare, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("3 problems: "), "{err}");
    for f in FLAGS {
        assert!(err.contains(f), "{f} missing: {err}");
    }
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none());

    // Each flag removes its item; all three make it run.
    let o = synth(&bare, &out, &["--day-neutral", "0.5,1,0.6"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("2 problems: ") && !err.contains("--day-neutral"),
        "{err}"
    );
    let o = synth(
        &bare,
        &out,
        &[
            "--day-neutral",
            "0.5,1,0.6",
            "--illuminants",
            "paper",
            "--target",
            "none",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(out.join("pidng_clean.dng").exists() && out.join("pidng_iso1600.dng").exists());
    // The phone's neutrals on another camera: said.
    assert!(
        err.contains("warning") && err.contains("night illuminants"),
        "{err}"
    );
}
