//! `day2night dataset` and `day2night report` end to end with the real binary and the real
//! synthesis, on copies of the committed fixture fixtures/day.dng.

use crate::common;
use crate::dataset_fake;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

fn day_dir(n: usize, bad: bool) -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    let src = common::fixtures().join("day.dng");
    for i in 0..n {
        let p = if i % 2 == 0 {
            d.path().join(format!("IMG_{i:02}.dng"))
        } else {
            d.path().join("phone").join(format!("IMG_{i:02}.DNG"))
        };
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::copy(&src, &p).unwrap();
    }
    if bad {
        std::fs::write(d.path().join("IMG_bad.dng"), b"II*\0garbage").unwrap();
    }
    d
}

fn dataset(day: &Path, out: &Path, extra: &[&str]) -> Output {
    common::bin()
        .arg("dataset")
        .arg(day)
        .arg("-o")
        .arg(out)
        .arg("--json")
        .args(if extra.contains(&"--jobs") {
            &[][..]
        } else {
            &["--jobs", "2"][..]
        })
        .args(extra)
        .output()
        .unwrap()
}

fn summary(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not the JSON summary ({e}); stderr: {}",
            String::from_utf8_lossy(&o.stderr)
        )
    })
}

/// Every file (relative path -> SHA-256) except manifests and the report.
fn tree(dir: &Path) -> BTreeMap<String, String> {
    fn walk(root: &Path, d: &Path, out: &mut BTreeMap<String, String>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                if !rel.starts_with("manifest") && !rel.starts_with("report") {
                    out.insert(
                        rel,
                        day2night::dataset::sha256_hex(&std::fs::read(&p).unwrap()),
                    );
                }
            }
        }
    }
    let mut m = BTreeMap::new();
    walk(dir, dir, &mut m);
    m
}

fn assert_same_tree(got: &BTreeMap<String, String>, want: &BTreeMap<String, String>, what: &str) {
    let mut diffs = Vec::new();
    for k in got.keys().chain(want.keys()) {
        if got.get(k) != want.get(k) && !diffs.contains(k) {
            diffs.push(k.clone());
        }
    }
    assert!(
        diffs.is_empty(),
        "{what}: files differ or are missing: {diffs:?}"
    );
}

fn validate_layout(out: &Path, ok_units: usize) {
    let py = common::python();
    let o = common::run_validator(
        &py,
        "dataset_layout.py",
        &[out.as_os_str(), std::ffi::OsStr::new(&ok_units.to_string())],
    );
    assert!(
        o.status.success(),
        "dataset_layout.py failed:\n{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn bad_input_fails_the_run_but_not_the_others_then_resume_does_nothing() {
    let day = day_dir(4, true);
    let out = tempfile::tempdir().unwrap();
    let o = dataset(day.path(), out.path(), &["--val", "1"]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&o);
    assert_eq!(
        (
            s["images"].as_u64(),
            s["done"].as_u64(),
            s["failed"].as_u64()
        ),
        (Some(5), Some(4), Some(1))
    );
    assert_eq!((s["train"].as_u64(), s["val"].as_u64()), (Some(4), Some(1)));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("FAILED IMG_bad.dng") && err.contains("day2night: "),
        "{err}"
    );
    // Not a terminal: one plain progress line per input, then the summary.
    assert_eq!(
        err.lines().filter(|l| l.starts_with("dataset: [")).count(),
        5,
        "{err}"
    );
    assert!(
        err.contains("dataset: 5 images (4 train, 1 val; 5 found)"),
        "{err}"
    );
    validate_layout(out.path(), 4);
    let manifest = std::fs::read_to_string(out.path().join("manifest.jsonl")).unwrap();
    assert_eq!(manifest.lines().count(), 5);
    assert!(manifest
        .lines()
        .any(|l| l.contains("\"IMG_bad.dng\"") && l.contains("\"failed\"")));

    // Resume: no work on the good ones, no byte changed.
    let before = tree(out.path());
    std::fs::remove_file(day.path().join("IMG_bad.dng")).unwrap();
    let o = dataset(day.path(), out.path(), &["--val", "1"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&o);
    assert_eq!(
        (
            s["done"].as_u64(),
            s["skipped"].as_u64(),
            s["outputs_written"].as_u64()
        ),
        (Some(0), Some(4), Some(0))
    );
    assert_same_tree(&tree(out.path()), &before, "resume");
    assert_eq!(
        std::fs::read_to_string(out.path().join("manifest.jsonl"))
            .unwrap()
            .lines()
            .count(),
        4
    );

    // An option change recomputes everything and removes replaced outputs.
    let o = dataset(
        day.path(),
        out.path(),
        &["--val", "1", "--target", "png", "--iso", "800"],
    );
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&o);
    assert_eq!(s["recomputed"]["options changed"].as_u64(), Some(4));
    let files = tree(out.path());
    assert!(
        files
            .keys()
            .all(|k| !k.ends_with(".exr") && !k.contains("_iso1600")),
        "{:?}",
        files.keys()
    );
    validate_layout(out.path(), 4);
}

#[test]
fn shards_and_thread_counts_give_identical_bytes() {
    let day = day_dir(5, false);
    let full = tempfile::tempdir().unwrap();
    let o = dataset(
        day.path(),
        full.path(),
        &[
            "--val-fraction",
            "0.4",
            "--variants",
            "2",
            "--jobs",
            "1",
            "--iso",
            "3200",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let want = tree(full.path());
    assert_eq!(want.len(), 5 * 2 * 4);
    let shared = tempfile::tempdir().unwrap();
    for i in 0..3 {
        let shard = format!("{i}/3");
        let o = dataset(
            day.path(),
            shared.path(),
            &[
                "--val-fraction",
                "0.4",
                "--variants",
                "2",
                "--shard",
                &shard,
                "--iso",
                "3200",
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert_eq!(
        tree(shared.path()),
        want,
        "union of shards differs from the unsharded run"
    );
    let o = dataset(
        day.path(),
        shared.path(),
        &["--val-fraction", "0.4", "--variants", "2", "--iso", "3200"],
    );
    assert_eq!(summary(&o)["done"].as_u64(), Some(0));
    assert_eq!(
        std::fs::read(shared.path().join("manifest.jsonl")).unwrap(),
        std::fs::read(full.path().join("manifest.jsonl")).unwrap()
    );
}

#[test]
fn usage_errors_exit_2_with_nothing_on_stdout() {
    let day = day_dir(2, false);
    let out = tempfile::tempdir().unwrap();
    for extra in [
        &["--shard", "3/2"][..],
        &["--val-fraction", "1.5"],
        &["--val", "5"],
        &["--val", "1", "--val-fraction", "0.5"],
        &["--iso", "abc"],
        &["--jobs", "0"],
        &["--replay", "x.json"],
        &["--mask-eval", "bogus"],
        &["--mode", "noon"],
    ] {
        let o = dataset(day.path(), out.path(), extra);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(o.stdout.is_empty(), "{extra:?}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("day2night")
                || String::from_utf8_lossy(&o.stderr).contains("error")
        );
    }
    let help = common::bin().args(["dataset", "--help"]).output().unwrap();
    assert!(String::from_utf8_lossy(&help.stdout).contains("Examples:"));
}

#[test]
fn killed_run_then_rerun_equals_an_uninterrupted_run() {
    let day = day_dir(8, false);
    let reference = tempfile::tempdir().unwrap();
    let o = dataset(day.path(), reference.path(), &["--val", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let out = tempfile::tempdir().unwrap();
    // The last input's unit is locked as if another process were writing it: the run
    // (--wait, one worker, inputs in name order) completes the others, then waits for it
    // and cannot finish before the kill. --overwrite: the lock file makes OUT non-empty.
    let held =
        day2night::output::OutputSetLock::acquire(out.path(), "phone__IMG_07", false).unwrap();
    let mut child = common::bin()
        .arg("dataset")
        .arg(day.path())
        .arg("-o")
        .arg(out.path())
        .args(["--val", "2", "--jobs", "1", "--wait", "--overwrite"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Its progress (one line per input, stderr not being a terminal) says when the first
    // input is in the manifest: no clock.
    let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut said = Vec::new();
    for line in std::io::BufRead::lines(stderr) {
        let line = line.unwrap();
        let first = line.starts_with("dataset: [1/8]");
        said.push(line);
        if first {
            break;
        }
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "the run ended before the kill:\n{}",
        said.join("\n")
    );
    child.kill().unwrap();
    child.wait().unwrap();
    drop(held);
    let manifest: PathBuf = out.path().join("manifest.jsonl");
    let partial = std::fs::read_to_string(&manifest).unwrap().lines().count();
    assert!((1..8).contains(&partial), "{partial} records");

    let o = dataset(day.path(), out.path(), &["--val", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&o);
    assert!(s["skipped"].as_u64().unwrap() >= 1, "{s}");
    assert_same_tree(
        &tree(out.path()),
        &tree(reference.path()),
        "killed + rerun vs uninterrupted",
    );
    assert_eq!(
        std::fs::read(manifest).unwrap(),
        std::fs::read(reference.path().join("manifest.jsonl")).unwrap()
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "chromium",
    ignore = "needs chromium (D2N_ALLOW_MISSING)"
)]
fn report_of_a_real_dataset() {
    let day = day_dir(3, false);
    let out = tempfile::tempdir().unwrap();
    let o = dataset(day.path(), out.path(), &["--val", "1", "--report"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = out.path().join("report/index.html");
    let html = std::fs::read_to_string(&page).unwrap();
    for needle in [
        "Day render",
        "Clean night render",
        "Noisy crop",
        "Mask: local lights",
        "Mask: bulbs",
        "Sampled illuminants",
        "Dimming factor",
    ] {
        assert!(html.contains(needle), "page lacks {needle}");
    }
    assert!(
        !html.contains("not available"),
        "something could not be shown"
    );
    let pngs: Vec<_> = std::fs::read_dir(out.path().join("report/img"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(pngs.len(), 3 * 6);
    for p in &pngs {
        image::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    }
    {
        let chromium = common::chromium();
        let (console, shot) = dataset_fake::load_in_browser(&chromium, &page);
        assert!(console.is_empty(), "console output: {console:#?}");
        image::load_from_memory(&shot).expect("screenshot is not a PNG");
    }
    // `report` alone, without DAY_DIR: the day column says why it is missing.
    let o = common::bin()
        .arg("report")
        .arg(out.path())
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["samples"].as_u64(), Some(3));
    assert!(std::fs::read_to_string(&page)
        .unwrap()
        .contains("pass --day-dir"));
    let o = common::bin()
        .arg("report")
        .arg(day.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a dataset folder"));
}

/// Run `dataset` and `synth` with the same synthesis/output options on one top-level input
/// and assert equal bytes for every output (`ids`: the dataset ids, `_vK` included).
fn assert_dataset_equals_synth(args: &[&str], ids: &[&str], isos: &[u32], targets: &[&str]) {
    let day = day_dir(1, false);
    let out = tempfile::tempdir().unwrap();
    let o = dataset(day.path(), out.path(), args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let syn = tempfile::tempdir().unwrap();
    let o = common::bin()
        .arg("synth")
        .arg(day.path().join("IMG_00.dng"))
        .arg("-o")
        .arg(syn.path())
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let input_exr = args.contains(&"--input-exr");
    let mut n = 0;
    for id in ids {
        let mut pairs = vec![(
            format!("train/clean_raw/{id}.dng"),
            format!("{id}_clean.dng"),
        )];
        for iso in isos {
            pairs.push((
                format!("train/noisy_raw/{id}_iso{iso}.dng"),
                format!("{id}_iso{iso}.dng"),
            ));
        }
        for ext in targets {
            pairs.push((
                format!("train/target/{id}.{ext}"),
                format!("{id}_target.{ext}"),
            ));
        }
        if input_exr {
            pairs.push((format!("train/input/{id}.exr"), format!("{id}_input.exr")));
        }
        for (ours, theirs) in pairs {
            let a = std::fs::read(out.path().join(&ours)).unwrap();
            let b = std::fs::read(syn.path().join(&theirs)).unwrap();
            assert!(a == b, "{ours} differs from synth's {theirs}");
            n += 1;
        }
        let a: serde_json::Value = serde_json::from_slice(
            &std::fs::read(out.path().join(format!("train/meta/{id}.json"))).unwrap(),
        )
        .unwrap();
        let b: serde_json::Value =
            serde_json::from_slice(&std::fs::read(syn.path().join(format!("{id}.json"))).unwrap())
                .unwrap();
        for key in ["plan", "options", "calibration", "run", "stages", "input"] {
            assert_eq!(a[key], b[key], "sidecar {key} differs");
        }
        let mut oa = a["outputs"].clone();
        let mut ob = b["outputs"].clone();
        assert_eq!(
            oa["files"].as_array().unwrap().len(),
            ob["files"].as_array().unwrap().len()
        );
        oa["files"] = serde_json::Value::Null;
        ob["files"] = serde_json::Value::Null;
        assert_eq!(oa, ob, "sidecar outputs (besides file names) differ");
    }
    // Nothing else was written by either command.
    assert_eq!(tree(syn.path()).len(), n + ids.len());
    assert_eq!(tree(out.path()).len(), n + ids.len());
}

#[test]
fn outputs_equal_synth_for_top_level_files() {
    // For a file directly in DAY_DIR the random stream is keyed exactly as `synth` keys it,
    // and both commands run the library's SynthJob, so they write the same bytes under
    // their own names.
    assert_dataset_equals_synth(
        &["--seed", "5", "--target", "both", "--input-exr"],
        &["IMG_00"],
        &[1600, 3200],
        &["exr", "png"],
    );
}

#[test]
fn every_synth_output_option_applies_to_dataset() {
    // --exr-compression (was ignored by dataset), --compression, --variants, a PNG-only
    // target on a fresh OUT_DIR (its folder used to be missing) and the input EXR.
    assert_dataset_equals_synth(
        &[
            "--seed",
            "2",
            "--variants",
            "2",
            "--iso",
            "800",
            "--target",
            "png",
            "--compression",
            "ljpeg",
            "--exr-compression",
            "piz",
            "--input-exr",
        ],
        &["IMG_00_v1", "IMG_00_v2"],
        &[800],
        &["png"],
    );
    // No render at all without a target (only what the scene needs), stages say so.
    let day = day_dir(1, false);
    let out = tempfile::tempdir().unwrap();
    let o = dataset(
        day.path(),
        out.path(),
        &["--target", "none", "--iso", "none"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let files: Vec<String> = tree(out.path()).into_keys().collect();
    assert_eq!(
        files,
        ["train/clean_raw/IMG_00.dng", "train/meta/IMG_00.json"]
    );
    let m = std::fs::read_to_string(out.path().join("manifest.jsonl")).unwrap();
    let rec: serde_json::Value = serde_json::from_str(m.lines().next().unwrap()).unwrap();
    let stages: Vec<&str> = rec["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    assert_eq!(stages.last(), Some(&"write_clean_dng"), "{stages:?}");
    assert!(!stages
        .iter()
        .any(|s| s.starts_with("target") || s.contains("noisy")));
    // Switching the EXR compression is an option change: recomputed, not skipped.
    let o = dataset(
        day.path(),
        out.path(),
        &["--target", "none", "--iso", "none"],
    );
    assert_eq!(summary(&o)["skipped"].as_u64(), Some(1));
    let o = dataset(
        day.path(),
        out.path(),
        &[
            "--target",
            "exr",
            "--iso",
            "none",
            "--exr-compression",
            "piz",
        ],
    );
    let s = summary(&o);
    assert_eq!(
        (s["done"].as_u64(), s["skipped"].as_u64()),
        (Some(1), Some(0))
    );
    let sc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("train/meta/IMG_00.json")).unwrap())
            .unwrap();
    assert_eq!(sc["outputs"]["exr_compression"], "piz");
    // A bad value is a usage error, as in synth.
    let o = dataset(day.path(), out.path(), &["--exr-compression", "jpeg"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--exr-compression"));
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
fn real_camera_files_among_unusable_ones() {
    // A real Canon capture is synthesized; the LG LinearRaw DNG is refused with its reason
    // and recorded as failed; the GoPro .gpr (not a .dng name) is not an input at all.
    let shared = common::shared_data();
    let day = tempfile::tempdir().unwrap();
    for (dir, name) in [
        ("dng", "canon_kissx4_magiclantern_rggb14_strips.dng"),
        ("dng-bad", "lg_g4_linearraw_lossyjpeg_subifd.dng"),
        ("dng-bad", "gopro_hero7_vc5_compression9.gpr"),
    ] {
        std::fs::copy(shared.join(dir).join(name), day.path().join(name)).unwrap();
    }
    let out = tempfile::tempdir().unwrap();
    let o = dataset(day.path(), out.path(), &["--report"]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&o);
    assert_eq!(
        (
            s["found"].as_u64(),
            s["done"].as_u64(),
            s["failed"].as_u64()
        ),
        (Some(2), Some(1), Some(1))
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("lg_g4_linearraw_lossyjpeg_subifd.dng") && err.contains("LinearRaw"),
        "{err}"
    );
    validate_layout(out.path(), 1);
    let html = std::fs::read_to_string(out.path().join("report/index.html")).unwrap();
    assert!(html.contains("LinearRaw") && !html.contains("not available"));
}
