//! Version-1 sidecars (`day2night-sidecar/1`) still replay byte for byte. The sidecars
//! under tests/sidecars_v1/ were written by the binary before version 2 (one folder per
//! run: local mode with both targets, `--compat release`, a burst, global mode with LJ92
//! DNGs, the network input and PIZ EXRs in two variants, dimmed with a PNG target, day
//! mode on a 7x9 image); tests/sidecars_v1/hashes.txt holds the SHA-256 of every other
//! file those runs wrote. Each is replayed by today's binary on its fixture: every output
//! but the sidecar has the recorded hash, the sidecar written is version 2, and replaying
//! that one rewrites it byte for byte.

use crate::common;
use day2night::synth::sidecar::{sha256_hex, Sidecar, SIDECAR_FORMAT};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn dir() -> PathBuf {
    common::root().join("tests/sidecars_v1")
}

/// `case/file` -> SHA-256, from hashes.txt.
fn recorded() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(dir().join("hashes.txt")).unwrap();
    text.lines()
        .map(|l| {
            let (h, p) = l.split_once("  ").unwrap();
            (p.to_string(), h.to_string())
        })
        .collect()
}

/// Every version-1 sidecar: (case, path).
fn sidecars() -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    for case in std::fs::read_dir(dir()).unwrap() {
        let case = case.unwrap().path();
        if !case.is_dir() {
            continue;
        }
        for f in std::fs::read_dir(&case).unwrap() {
            let f = f.unwrap().path();
            if f.extension().is_some_and(|e| e == "json") {
                let name = case.file_name().unwrap().to_string_lossy().into_owned();
                out.push((name, f));
            }
        }
    }
    out.sort();
    out
}

fn replay(sidecar: &Path, out: &Path) {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sidecar).unwrap()).unwrap();
    let input = common::fixtures().join(v["input"]["name"].as_str().unwrap());
    let o = common::cli(
        "synth",
        &input,
        out,
        &["--replay", sidecar.to_str().unwrap(), "-q"],
    );
    assert!(
        o.status.success(),
        "{}: {}",
        sidecar.display(),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The files of `out` other than sidecars, name -> SHA-256.
fn hashes(out: &Path) -> BTreeMap<String, String> {
    std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_none_or(|e| e != "json"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, sha256_hex(&std::fs::read(&p).unwrap()))
        })
        .collect()
}

/// The recorded hashes of the outputs a sidecar lists (its own file excluded).
fn want(case: &str, sc: &Sidecar, all: &BTreeMap<String, String>) -> BTreeMap<String, String> {
    sc.outputs
        .files
        .iter()
        .filter(|f| !f.ends_with(".json"))
        .map(|f| {
            let h = all.get(&format!("{case}/{f}"));
            (
                f.clone(),
                h.unwrap_or_else(|| panic!("{case}/{f} not recorded"))
                    .clone(),
            )
        })
        .collect()
}

#[test]
fn version_1_sidecars_replay_byte_for_byte() {
    let all = recorded();
    let cases = sidecars();
    assert_eq!(cases.len(), 7, "{cases:?}");
    let mut checked = 0;
    for (case, path) in &cases {
        let text = std::fs::read_to_string(path).unwrap();
        assert!(
            text.contains("\"format\": \"day2night-sidecar/1\""),
            "{case}"
        );
        let sc = Sidecar::from_json(&text).unwrap();
        let want = want(case, &sc, &all);
        let t = tempfile::tempdir().unwrap();
        let a = t.path().join("a");
        replay(path, &a);
        assert_eq!(hashes(&a), want, "{}", path.display());
        checked += want.len();
        // The sidecar written is version 2, holds the migrated document, and replays to
        // itself and the same outputs.
        let name = path.file_name().unwrap();
        let v2_text = std::fs::read_to_string(a.join(name)).unwrap();
        let v2 = Sidecar::from_json(&v2_text).unwrap();
        assert_eq!(v2.format, SIDECAR_FORMAT);
        assert_eq!(v2, sc, "{case}: the written sidecar is the migrated one");
        let b = t.path().join("b");
        replay(&a.join(name), &b);
        assert_eq!(hashes(&b), want, "{case}: replay of the version-2 sidecar");
        assert_eq!(std::fs::read_to_string(b.join(name)).unwrap(), v2_text);
    }
    assert_eq!(checked, all.len(), "every recorded output was compared");
}

/// A version-1 sidecar written before provenance existed (no `calibration.provenance`,
/// no `plan.noise_provenance`) replays to the same outputs, and its replay records none.
#[test]
fn a_version_1_sidecar_without_provenance_replays_byte_for_byte() {
    let all = recorded();
    let path = dir().join("local_both/day.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert!(v["calibration"]["provenance"].is_object());
    v["calibration"]
        .as_object_mut()
        .unwrap()
        .remove("provenance");
    v["plan"]
        .as_object_mut()
        .unwrap()
        .remove("noise_provenance");
    let t = tempfile::tempdir().unwrap();
    let old = t.path().join("day.json");
    std::fs::write(&old, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let sc = Sidecar::read(&old).unwrap();
    assert!(sc.calibration.provenance.is_none() && sc.report.noise_provenance.is_none());
    let a = t.path().join("a");
    replay(&old, &a);
    assert_eq!(hashes(&a), want("local_both", &sc, &all));
    let written = Sidecar::read(&a.join("day.json")).unwrap();
    assert_eq!(written, sc);
}

/// The migration moves each version-1 plan field to its place: the draws stay in the
/// plan, provenance, stages, opcodes and warnings go to the report, absent defaults are
/// written out.
#[test]
fn migration_places_every_field() {
    let path = dir().join("release/day.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let v1: serde_json::Value = serde_json::from_str(&text).unwrap();
    let sc = Sidecar::from_json(&text).unwrap();
    let p = &v1["plan"];
    assert_eq!(sc.plan.format, "day2night-plan/2");
    assert_eq!(serde_json::json!(sc.plan.lights), p["lights"]);
    // Each noise entry as it was, with its absent `physics` written as null.
    let mut noise = p["noise"].clone();
    for n in noise.as_array_mut().unwrap() {
        assert!(n.get("physics").is_none());
        n["physics"] = serde_json::Value::Null;
    }
    assert_eq!(serde_json::json!(sc.plan.noise), noise);
    assert!(sc.plan.truncate && sc.plan.truncate_noise && sc.plan.range_per_site);
    assert_eq!(serde_json::json!(sc.report.stages), p["stages"]);
    assert_eq!(serde_json::json!(sc.report.warnings), p["warnings"]);
    assert_eq!(sc.report.day_neutral_source, p["day_neutral_source"]);
    assert_eq!(
        sc.report.night_neutral_definition,
        p["night_neutral_definition"]
    );
    assert_eq!(sc.report.noise_model_source, p["noise_model_source"]);
    assert_eq!(
        serde_json::json!(sc.report.noise_provenance),
        p["noise_provenance"]
    );
    assert_eq!(sc.report.opcodes, None);
    assert_eq!(sc.plan.opcodes, day2night::isp::opcodes::OpcodeMode::Ignore);
    assert_eq!(serde_json::json!(sc.stages), v1["stages"]);
    assert_eq!(
        (
            sc.outputs.exr_compression.as_str(),
            sc.outputs.exr_zip_level
        ),
        ("zip", 1)
    );
    assert!(sc.run.warnings.is_empty());
    // Version 2 writes every field.
    let j = sc.to_json().unwrap();
    for key in [
        "\"report\"",
        "\"burst\": null",
        "\"exr_zip_level\": 1",
        "\"warnings\": []",
    ] {
        assert!(j.contains(key), "{key}");
    }
    // A format that is neither is refused, naming both.
    let bad = text.replace("day2night-sidecar/1", "day2night-sidecar/9");
    let e = Sidecar::from_json(&bad).unwrap_err().to_string();
    assert!(
        e.contains("day2night-sidecar/9") && e.contains("day2night-sidecar/1"),
        "{e}"
    );
}
