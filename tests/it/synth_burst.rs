//! `day2night synth --burst N` end to end (issue 25): frame names, frame 00 = the
//! single-frame outputs, replay and thread-count byte identity, the independent validators
//! on every frame (rawpy, DNG SDK, OpenImageIO, tifffile: tests/validators/synth_check.py),
//! the noise statistics, `merge` closing the loop and phase correlation recovering the
//! recorded motion (tests/validators/burst_check.py), the real Canon, usage errors and
//! `dataset --burst`.
use crate::common;
use crate::synth_cli::{files, ok, same, synth};
use std::path::{Path, PathBuf};

fn day() -> PathBuf {
    common::fixtures().join("day.dng")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Run a validator script; fail with its output.
fn check(script: &str, args: &[&str]) {
    let py = common::python();
    let a: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_ref()).collect();
    let out = common::run_validator(&py, script, &a);
    assert!(
        out.status.success(),
        "{script} {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A noise model file without noise (a noise-free test camera) at ISO 1600.
fn zero_model(dir: &Path) -> PathBuf {
    let p = dir.join("zero.json");
    std::fs::write(
        &p,
        r#"{"format":"day2night-noise-model/1","units":"normalized","source":"noise-free test camera","isos":[{"iso":1600,"positions":[[0,0],[0,0],[0,0],[0,0]]}]}"#,
    )
    .unwrap();
    p
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn frame_names_frame_00_replay_and_threads() {
    let t = tempfile::tempdir().unwrap();
    let (single, burst) = (t.path().join("single"), t.path().join("burst"));
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&single),
        "--iso",
        "800,3200",
        "-q",
    ]));
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&burst),
        "--iso",
        "800,3200",
        "--burst",
        "4",
        "-q",
    ]));
    let (a, b) = (files(&single), files(&burst));
    let mut want = vec!["day.json", "day_clean.dng", "day_target.exr"];
    let frames: Vec<String> = [800, 3200]
        .iter()
        .flat_map(|iso| (0..4).map(move |k| format!("day_iso{iso}_f{k:02}.dng")))
        .collect();
    want.extend(frames.iter().map(String::as_str));
    want.sort();
    assert_eq!(b.keys().collect::<Vec<_>>(), want);
    // frame 00 is the single-frame output: clean DNG, target and noisy raws, byte for byte
    for name in ["day_clean.dng", "day_target.exr"] {
        assert!(a[name] == b[name], "{name}");
    }
    for iso in [800, 3200] {
        assert!(
            a[&format!("day_iso{iso}.dng")] == b[&format!("day_iso{iso}_f00.dng")],
            "ISO {iso} frame 00"
        );
        assert!(b[&format!("day_iso{iso}_f01.dng")] != b[&format!("day_iso{iso}_f00.dng")]);
    }
    // --burst 1 is the single frame
    let one = t.path().join("one");
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&one),
        "--iso",
        "800,3200",
        "--burst",
        "1",
        "-q",
    ]));
    same(&files(&one), &a, "--burst 1");
    // the sidecar records the motion; replay reproduces every frame
    let sc: serde_json::Value = serde_json::from_slice(&b["day.json"]).unwrap();
    let bp = &sc["plan"]["burst"];
    assert_eq!(bp["frames"], 4);
    assert_eq!(bp["motion"], "shake");
    assert_eq!(bp["transforms"].as_array().unwrap().len(), 4);
    assert_eq!(sc["options"]["burst"]["frames"], 4);
    let replay = t.path().join("replay");
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&replay),
        "--replay",
        s(&burst.join("day.json")),
        "-q",
    ]));
    same(&files(&replay), &b, "replay");
    // one worker thread, and a rerun: the same bytes
    let j1 = t.path().join("j1");
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&j1),
        "--iso",
        "800,3200",
        "--burst",
        "4",
        "--jobs",
        "1",
        "-q",
    ]));
    same(&files(&j1), &b, "--jobs 1");
    // every frame passes rawpy, the DNG SDK, OpenImageIO and the tag checks
    check(
        "synth_check.py",
        &[s(&day()), s(&burst.join("day.json")), s(&burst)],
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn still_burst_noise_is_independent_and_merges_to_the_clean_scene() {
    let t = tempfile::tempdir().unwrap();
    let o = t.path().join("still");
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&o),
        "--iso",
        "800",
        "--burst",
        "8",
        "--motion",
        "none",
        "--target",
        "none",
        "-q",
    ]));
    let sc = o.join("day.json");
    check("burst_check.py", &["stats", s(&sc), s(&o), "800"]);
    let merged = t.path().join("merged.dng");
    let mut cmd = common::bin();
    cmd.arg("merge");
    for k in 0..8 {
        cmd.arg(o.join(format!("day_iso800_f{k:02}.dng")));
    }
    let out = cmd.arg("-o").arg(&merged).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    check(
        "burst_check.py",
        &["merge", s(&sc), s(&o), "800", s(&merged)],
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn shaken_frames_move_by_the_recorded_transforms() {
    let t = tempfile::tempdir().unwrap();
    let model = zero_model(t.path());
    let o = t.path().join("shake");
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&o),
        "--iso",
        "1600",
        "--burst",
        "8",
        "--noise-model",
        s(&model),
        "--target",
        "none",
        "-q",
    ]));
    // a noise-free camera: frame 00 is the clean raw itself
    let f = files(&o);
    let clean = day2night::dng::read_dng(&o.join("day_clean.dng")).unwrap();
    let f00 = day2night::dng::read_dng(&o.join("day_iso1600_f00.dng")).unwrap();
    assert_eq!(clean.data, f00.data);
    assert!(f["day_iso1600_f01.dng"] != f["day_iso1600_f00.dng"]);
    check(
        "burst_check.py",
        &["phase", s(&o.join("day.json")), s(&o), "1600", "256"],
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn canon_burst_passes_the_validators() {
    let canon = common::shared_file("dng/canon_kissx4_magiclantern_rggb14_strips.dng");
    let t = tempfile::tempdir().unwrap();
    let o = t.path().join("canon");
    ok(&synth(&[
        s(&canon),
        "-o",
        s(&o),
        "--iso",
        "3200",
        "--burst",
        "8",
        "--target",
        "none",
        "-q",
    ]));
    let names: Vec<String> = files(&o).into_keys().collect();
    assert_eq!(names.iter().filter(|n| n.contains("_iso3200_f")).count(), 8);
    let stem = canon.file_stem().unwrap().to_str().unwrap();
    check(
        "synth_check.py",
        &[s(&canon), s(&o.join(format!("{stem}.json"))), s(&o)],
    );
}

#[test]
fn burst_usage_errors_exit_2() {
    let t = tempfile::tempdir().unwrap();
    let o = t.path().join("o");
    let d = day();
    for args in [
        vec!["--burst", "0"],
        vec!["--burst", "65"],
        vec!["--motion", "none"],
        vec!["--burst", "2", "--motion", "tripod"],
        vec!["--burst", "2", "--shake-step", "-1"],
        vec!["--burst", "2", "--shake-roll", "nan"],
        vec!["--burst", "2", "--warp-interp", "nearest"],
    ] {
        let mut a = vec![s(&d), "-o", s(&o)];
        a.extend(args.iter());
        let out = synth(&a);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(!o.exists(), "{args:?} wrote outputs");
    }
}

#[test]
fn dataset_lays_frames_out_per_input_and_lists_them() {
    let t = tempfile::tempdir().unwrap();
    let days = t.path().join("days");
    std::fs::create_dir(&days).unwrap();
    std::fs::copy(day(), days.join("a.dng")).unwrap();
    let out = t.path().join("out");
    let r = common::bin()
        .args([
            "dataset",
            s(&days),
            "-o",
            s(&out),
            "--burst",
            "3",
            "--iso",
            "1600",
        ])
        .args(["--target", "none", "--quiet"])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for k in 0..3 {
        assert!(out
            .join(format!("train/noisy_raw/a/a_iso1600_f{k:02}.dng"))
            .is_file());
    }
    let manifest = std::fs::read_to_string(out.join("manifest.jsonl")).unwrap();
    let rec: serde_json::Value = serde_json::from_str(manifest.lines().next().unwrap()).unwrap();
    let paths: Vec<&str> = rec["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["path"].as_str().unwrap())
        .collect();
    for k in 0..3 {
        let p = format!("train/noisy_raw/a/a_iso1600_f{k:02}.dng");
        assert!(paths.contains(&p.as_str()), "{p} not in {paths:?}");
    }
    // the frames equal synth's (same key: the file name at the top level)
    let o = t.path().join("synth");
    ok(&synth(&[
        s(&days.join("a.dng")),
        "-o",
        s(&o),
        "--burst",
        "3",
        "--iso",
        "1600",
        "--target",
        "none",
        "-q",
    ]));
    for k in 0..3 {
        let a =
            std::fs::read(out.join(format!("train/noisy_raw/a/a_iso1600_f{k:02}.dng"))).unwrap();
        let b = std::fs::read(o.join(format!("a_iso1600_f{k:02}.dng"))).unwrap();
        assert!(a == b, "frame {k}");
    }
    // a rerun finds everything done
    let r = common::bin()
        .args([
            "dataset",
            s(&days),
            "-o",
            s(&out),
            "--burst",
            "3",
            "--iso",
            "1600",
        ])
        .args(["--target", "none", "--json", "--quiet"])
        .output()
        .unwrap();
    assert!(r.status.success());
    let summary = String::from_utf8_lossy(&r.stdout);
    assert!(
        summary.contains("\"done\":0") || summary.contains("\"done\": 0"),
        "{summary}"
    );
}
