//! Sidecars written before noise stream 2 replay byte for byte. tests/sidecars_v1/ holds
//! sidecars and the SHA-256 of the outputs written by a build with only noise stream 1
//! (ChaCha8 per row) and SHA-256 RawDataUniqueIDs (tests/it/sidecar_v1.rs replays them as
//! they are). Here the local-mode run's sidecar (ISO 800 and 3200, both targets) is replayed,
//! and the version-2 sidecar that replay writes is stripped of `plan.noise_stream` and
//! `outputs.raw_data_unique_id`, as every version-2 sidecar written before them is: replayed
//! again it gives the recorded bytes (stream 1, SHA-256 IDs). Set to stream 2 and XXH3-128 it
//! gives new noisy DNGs and new IDs, and the same renders.

use crate::common;
use day2night::noise::NoiseStream;
use day2night::synth::sidecar::{sha256_hex, Sidecar};
use std::collections::BTreeMap;
use std::path::Path;

/// `local_both/<file>` -> SHA-256, from tests/sidecars_v1/hashes.txt.
fn recorded() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(common::root().join("tests/sidecars_v1/hashes.txt"));
    text.unwrap()
        .lines()
        .filter_map(|l| {
            let (h, p) = l.split_once("  ")?;
            let f = p.strip_prefix("local_both/")?;
            Some((f.to_string(), h.to_string()))
        })
        .collect()
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

fn replay(sidecar: &Path, out: &Path) {
    let o = common::cli(
        "synth",
        &common::fixtures().join("day.dng"),
        out,
        &["--replay", sidecar.to_str().unwrap(), "-q"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn version_2_sidecars_without_a_noise_stream_replay_stream_1_byte_for_byte() {
    let want = recorded();
    assert_eq!(want.len(), 5, "{want:?}");
    let t = tempfile::tempdir().unwrap();
    let v1 = common::root().join("tests/sidecars_v1/local_both/day.json");
    let a = t.path().join("a");
    replay(&v1, &a);
    let text = std::fs::read_to_string(a.join("day.json")).unwrap();
    assert!(text.contains("\"noise_stream\": 1"), "{text}");
    assert!(text.contains("\"raw_data_unique_id\": \"sha256\""));
    // a version-2 sidecar as written before issue 48: neither field
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["plan"].as_object_mut().unwrap().remove("noise_stream");
    v["outputs"]
        .as_object_mut()
        .unwrap()
        .remove("raw_data_unique_id");
    let old = serde_json::to_string_pretty(&v).unwrap();
    let sc = Sidecar::from_json(&old).unwrap();
    assert_eq!(sc.plan.noise_stream, NoiseStream::V1);
    assert_eq!(sc.outputs.raw_data_unique_id, "sha256");
    let old_path = t.path().join("old.json");
    std::fs::write(&old_path, &old).unwrap();
    let b = t.path().join("b");
    replay(&old_path, &b);
    assert_eq!(hashes(&b), want, "stream 1 and SHA-256 IDs, byte for byte");
    assert_eq!(std::fs::read_to_string(b.join("day.json")).unwrap(), text);

    // the same plan on stream 2 with XXH3-128 IDs: new noise, new IDs, the same renders
    v["plan"]["noise_stream"] = 2.into();
    v["outputs"]["raw_data_unique_id"] = "xxh3-128".into();
    let new_path = t.path().join("new.json");
    std::fs::write(&new_path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let c = t.path().join("c");
    replay(&new_path, &c);
    let now = hashes(&c);
    assert_eq!(now.len(), want.len());
    for (f, h) in &now {
        if f.ends_with(".dng") {
            assert_ne!(&want[f], h, "{f}");
        } else {
            assert_eq!(&want[f], h, "{f}: the renders are unchanged");
        }
    }
    // the clean DNG differs in its RawDataUniqueID only
    let (old_clean, new_clean) = (
        std::fs::read(b.join("day_clean.dng")).unwrap(),
        std::fs::read(c.join("day_clean.dng")).unwrap(),
    );
    assert_eq!(old_clean.len(), new_clean.len());
    let differ = old_clean
        .iter()
        .zip(&new_clean)
        .filter(|(x, y)| x != y)
        .count();
    assert!((1..=16).contains(&differ), "{differ} bytes differ");
}

/// A run of today records stream 2 and XXH3-128 IDs; `--compat release` keeps stream 1.
#[test]
fn todays_sidecars_record_stream_2_and_xxh3_and_the_release_preset_stream_1() {
    let t = tempfile::tempdir().unwrap();
    for (extra, stream) in [
        (&[][..], NoiseStream::V2),
        (&["--compat", "release"][..], NoiseStream::V1),
    ] {
        let out = t.path().join(format!("{stream:?}"));
        let mut args = vec!["--iso", "1600", "--target", "none", "-q"];
        args.extend_from_slice(extra);
        let o = common::cli("synth", &common::fixtures().join("day.dng"), &out, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let sc = Sidecar::read(&out.join("day.json")).unwrap();
        assert_eq!(sc.plan.noise_stream, stream, "{extra:?}");
        assert_eq!(sc.outputs.raw_data_unique_id, "xxh3-128");
    }
}
