//! Typed warnings end to end (docs/warnings.md): a real run's warning has its code on
//! stderr (once), in the sidecar and in `info --json`; a sidecar whose warnings are plain
//! strings (written before codes) still loads and replays to the same bytes.
use crate::common;
use crate::synth_cli::{files, ok, same, synth};
use day2night::synth::sidecar::Sidecar;
use day2night::Code;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn synth_says_each_warning_once_with_its_code_and_the_sidecar_keeps_it() {
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let o = t.path().join("o");
    let r = synth(&[s(&day), "-o", s(&o), "--iso", "25,100", "--seed", "3"]);
    ok(&r);
    let err = String::from_utf8_lossy(&r.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("warning[")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].starts_with("warning[noise-extrapolated]: day.dng: ISO 25 scaled from"),
        "{err}"
    );
    let sc = Sidecar::read(&o.join("day.json")).unwrap();
    let w: Vec<(Code, &str)> = sc
        .report
        .warnings
        .iter()
        .map(|w| (w.code, w.subject.as_str()))
        .collect();
    assert_eq!(w, [(Code::NoiseExtrapolated, "day.dng")]);
    let raw: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(o.join("day.json")).unwrap()).unwrap();
    assert_eq!(raw["report"]["warnings"][0]["code"], "noise-extrapolated");
    assert!(raw["report"]["warnings"][0]["message"]
        .as_str()
        .unwrap()
        .starts_with("ISO 25 scaled from the single calibrated ISO 100"));
}

#[test]
fn info_json_carries_codes_and_subjects() {
    // The 1x1 fixture has no NoiseProfile and too few samples for an estimate.
    let f = common::fixtures().join("edge_1x1.dng");
    let r = common::bin()
        .args(["info", "--json", s(&f)])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let j: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let j = if j.is_array() { j[0].clone() } else { j };
    let w = &j["warnings"][0];
    assert_eq!(w["code"], "noise-estimate-untrusted", "{j}");
    assert_eq!(w["subject"], s(&f), "{j}");
    assert!(w["message"]
        .as_str()
        .unwrap()
        .starts_with("noise: the input has no NoiseProfile"));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains(&format!(
            "warning[noise-estimate-untrusted]: {}: noise: ",
            f.display()
        )),
        "{err}"
    );
}

#[test]
fn a_sidecar_with_plain_string_warnings_loads_and_replays_byte_for_byte() {
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let (a, b) = (t.path().join("a"), t.path().join("b"));
    ok(&synth(&[
        s(&day),
        "-o",
        s(&a),
        "--iso",
        "25",
        "--seed",
        "9",
    ]));
    // The sidecar as an older day2night wrote it: warnings as plain strings.
    let mut sc = Sidecar::read(&a.join("day.json")).unwrap();
    let text = sc.to_json().unwrap();
    let msg = sc.report.warnings[0].message.clone();
    let old = text.replace(
        &serde_json::to_string_pretty(&sc.report.warnings[0])
            .unwrap()
            .replace('\n', "\n      "),
        &serde_json::to_string(&msg).unwrap(),
    );
    assert_ne!(old, text, "the warning object was not found in {text}");
    let old_path = t.path().join("old.json");
    std::fs::write(&old_path, &old).unwrap();
    let read = Sidecar::read(&old_path).unwrap();
    assert_eq!(read.report.warnings[0].code, Code::Legacy);
    assert_eq!(read.report.warnings[0].message, msg);
    // Written back as the same string: the old file round-trips byte for byte.
    assert_eq!(read.to_json().unwrap(), old);
    ok(&synth(&[s(&day), "-o", s(&b), "--replay", s(&old_path)]));
    // Every output the same; the replayed sidecar is the old file.
    let (mut fa, fb) = (files(&a), files(&b));
    fa.insert("day.json".into(), old.clone().into_bytes());
    same(&fa, &fb, "replay of a plain-string sidecar");
    // The legacy warning is said with its code.
    sc.report.warnings = read.report.warnings.clone();
    assert_eq!(
        sc.report.warnings[0].line("day.dng"),
        format!("warning[legacy]: day.dng: {msg}")
    );
}
