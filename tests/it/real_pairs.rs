//! `real-pairs`: real night pairs from captures (docs/real-pairs.md). Scenes are made with the
//! project's own tools (`synth --burst N` at ISO 50/1600/3200 of the fixture, renamed into each
//! layout; the processed tree's 16-bit clean_raw PNG from the frames' truncated mean) and
//! checked: the merged raw against the frames (here and with rawpy + the Adobe DNG SDK), the
//! target against `render`, the noisy inputs as byte copies, the manifest fields across the
//! three layouts, every bad-input error naming its scene, motion, and resume.
use crate::common;
use day2night::dng::read_dng;
use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::raw::RawImage;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

const ISOS: [u32; 3] = [50, 1600, 3200];

pub(crate) fn ok(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    err
}

/// `synth --burst n` of the fixture at ISO 50, 1600 and 3200 into `dir`.
pub(crate) fn synth(dir: &Path, n: u32, extra: &[&str]) {
    let mut c = common::bin();
    c.arg("synth")
        .arg(common::fixtures().join("day.dng"))
        .arg("-o")
        .arg(dir)
        .args(["--iso", "50,1600,3200", "--burst", &n.to_string()])
        .args(["--seed", "1", "--target", "none"])
        .args(extra);
    ok(&c.output().unwrap());
}

/// The frames synth wrote for `iso`, sorted.
pub(crate) fn frames(synth_dir: &Path, iso: u32) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(synth_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            n.starts_with(&format!("day_iso{iso}_f")) && n.ends_with(".dng")
        })
        .collect();
    v.sort();
    v
}

/// A scene in the simple layout: the frames under their synth names.
pub(crate) fn simple_scene(dir: &Path, synth_dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for iso in ISOS {
        for f in frames(synth_dir, iso) {
            std::fs::copy(&f, dir.join(f.file_name().unwrap())).unwrap();
        }
    }
}

/// A scene in the release layout: `RAW_0_00<ISO 4 digits>_<frame>.dng`.
pub(crate) fn release_scene(dir: &Path, synth_dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for iso in ISOS {
        for (k, f) in frames(synth_dir, iso).iter().enumerate() {
            std::fs::copy(f, dir.join(format!("RAW_0_00{iso:04}_{k:04}.dng"))).unwrap();
        }
    }
}

/// The processed tree of one scene `NNN`: clean_raw/NNN.png = the truncated mean of the ISO
/// 50 frames' active area (rawpy's visible raw), clean/NNN.png = a render, dng/iso_<ISO>/.
pub(crate) fn processed_scene(root: &Path, nnn: &str, synth_dir: &Path) {
    for sub in [
        "clean_raw",
        "clean",
        "dng/iso_50",
        "dng/iso_1600",
        "dng/iso_3200",
    ] {
        std::fs::create_dir_all(root.join(sub)).unwrap();
    }
    let low = frames(synth_dir, 50);
    let imgs: Vec<RawImage> = low.iter().map(|p| read_dng(p).unwrap()).collect();
    let a = imgs[0].active_area();
    let mut mean = Vec::with_capacity(a.width() * a.height());
    for r in a.top as usize..a.bottom as usize {
        for c in a.left as usize..a.right as usize {
            let s: u32 = imgs.iter().map(|i| i.get(r, c) as u32).sum();
            mean.push((s / imgs.len() as u32) as u16);
        }
    }
    let png: image::ImageBuffer<image::Luma<u16>, Vec<u16>> =
        image::ImageBuffer::from_raw(a.width() as u32, a.height() as u32, mean).unwrap();
    png.save(root.join(format!("clean_raw/{nnn}.png"))).unwrap();
    let target = root.join(format!("clean/{nnn}.png"));
    ok(&common::cli("render", &low[0], &target, &[]));
    std::fs::copy(&low[0], root.join(format!("dng/iso_50/{nnn}.dng"))).unwrap();
    for iso in [1600, 3200] {
        let first = &frames(synth_dir, iso)[0];
        std::fs::copy(first, root.join(format!("dng/iso_{iso}/{nnn}.dng"))).unwrap();
    }
}

/// Scenes `a` and `b` of the simple layout under `d/scenes`, each from `n` still frames
/// synthesized into `d/synth`, made by one `real-pairs` run into `d/out` with `extra` flags;
/// returns (SCENES, OUT).
pub(crate) fn two_simple_scenes(d: &Path, n: u32, extra: &[&str]) -> (PathBuf, PathBuf) {
    let s = d.join("synth");
    synth(&s, n, &["--motion", "none"]);
    let root = d.join("scenes");
    simple_scene(&root.join("a"), &s);
    simple_scene(&root.join("b"), &s);
    let out = d.join("out");
    ok(&real_pairs(&root, &out, extra));
    (root, out)
}

pub(crate) fn real_pairs(scenes: &Path, out: &Path, extra: &[&str]) -> Output {
    common::cli("real-pairs", scenes, out, extra)
}

pub(crate) fn manifest(out: &Path) -> Vec<Value> {
    std::fs::read_to_string(out.join("manifest.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn keys(v: &Value) -> Vec<String> {
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    k.sort();
    k
}

/// rawpy + the Adobe DNG SDK on the merged raw: its normalized values are the frames' mean
/// (calibrate_merge_check.py), and floor(sum / N) of the samples rawpy reads is the release's
/// truncated mean of the frames.
fn validate_merge(merged: &Path, frames: &[PathBuf]) {
    let py = common::python();
    let mut a: Vec<&std::ffi::OsStr> = vec![merged.as_os_str()];
    a.extend(frames.iter().map(|p| p.as_os_str()));
    let o = common::run_validator(&py, "calibrate_merge_check.py", &a);
    let msg = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{msg}");
    let code = "import sys, rawpy, numpy as np
m = rawpy.imread(sys.argv[1]); s = m.raw_image_visible.astype(np.int64)
fs = [rawpy.imread(p).raw_image_visible.astype(np.int64) for p in sys.argv[2:]]
trunc = (np.sum(fs, axis=0).astype(np.float32) / len(fs)).astype(np.uint16)
sat = np.any([f >= rawpy.imread(sys.argv[2]).white_level for f in fs], axis=0)
ours = (s // len(fs)).astype(np.uint16)
assert np.array_equal(ours[~sat], trunc[~sat]), 'floor(sum/N) differs from the truncated mean'
assert m.black_level_per_channel[0] == len(fs) * rawpy.imread(sys.argv[2]).black_level_per_channel[0]
print('truncated mean ok')";
    let o = std::process::Command::new(&py)
        .arg("-c")
        .arg(code)
        .args(&a)
        .output()
        .unwrap();
    let msg = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{msg}");
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (rawpy, dngpy): run scripts/test.sh"
)]
fn three_layouts_make_the_pairs() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 4, &["--motion", "none"]);
    let (simple, release, processed) = (
        d.path().join("simple"),
        d.path().join("release"),
        d.path().join("night_real"),
    );
    simple_scene(&simple.join("night/a"), &s);
    release_scene(&release.join("night/a"), &s);
    processed_scene(&processed, "007", &s);
    let outs: Vec<PathBuf> = ["o_simple", "o_release", "o_processed"]
        .iter()
        .map(|n| d.path().join(n))
        .collect();
    for (src, out) in [&simple, &release, &processed].iter().zip(&outs) {
        ok(&real_pairs(src, out, &["--target", "both"]));
    }
    let ms: Vec<Value> = outs.iter().map(|o| manifest(o).remove(0)).collect();
    let (rs, rr, rp) = (&ms[0], &ms[1], &ms[2]);
    // The same fields in all three layouts, the contract's values.
    assert_eq!(keys(rs), keys(rr));
    assert_eq!(keys(rs), keys(rp));
    for r in &ms {
        assert_eq!(r["status"], "ok", "{r}");
        assert_eq!(
            (&r["split"], &r["kind"], &r["variant"], &r["seed"]),
            (
                &Value::from("real"),
                &Value::from("real"),
                &Value::from(1),
                &Value::from(0)
            )
        );
        assert_eq!(r["iso"], serde_json::json!([1600, 3200]));
    }
    assert_eq!(
        (&rs["input"], &rs["scene"]),
        (&Value::from("night/a"), &Value::from("night__a"))
    );
    assert_eq!(
        (&rp["input"], &rp["scene"]),
        (&Value::from("007"), &Value::from("007"))
    );
    assert_eq!(
        rs["frames"],
        serde_json::json!({"50": 4, "1600": 4, "3200": 4})
    );
    assert_eq!(
        rp["frames"],
        serde_json::json!({"50": 1, "1600": 1, "3200": 1})
    );
    // Simple and release read the same frames in the same order: identical outputs (the
    // scene records differ in the layout and frame names).
    let pairs = |r: &Value| -> Vec<Value> {
        let v = r["outputs"].as_array().unwrap();
        v.iter().filter(|o| o["kind"] != "meta").cloned().collect()
    };
    assert_eq!(pairs(rs), pairs(rr));
    assert_eq!(pairs(rs).len(), 5);
    assert_eq!(rs["night_neutral"], rr["night_neutral"]);
    assert_eq!(rs["night_neutral"], rp["night_neutral"]);
    let first = read_dng(&frames(&d.path().join("synth"), 50)[0]).unwrap();
    let n = first.meta.as_shot_neutral.unwrap();
    let nn: Vec<f64> = serde_json::from_value(rs["night_neutral"].clone()).unwrap();
    assert!(
        nn.iter()
            .zip(n.iter())
            .all(|(a, b)| (a - b / n[1]).abs() < 1e-9),
        "{nn:?} {n:?}"
    );

    let o = &outs[0];
    let merged_path = o.join("real/clean_raw/night__a.dng");
    let merged = read_dng(&merged_path).unwrap();
    let low: Vec<RawImage> = frames(&d.path().join("synth"), 50)
        .iter()
        .map(|p| read_dng(p).unwrap())
        .collect();
    assert_eq!(
        merged.meta.levels.black,
        vec![first.meta.levels.black[0] * 4.0]
    );
    assert_eq!(merged.meta.levels.white, first.meta.levels.white * 4.0);
    for i in 0..merged.data.len() {
        let sum: u32 = low.iter().map(|f| f.data[i] as u32).sum();
        if low
            .iter()
            .all(|f| (f.data[i] as f64) < first.meta.levels.white)
        {
            assert_eq!(merged.data[i] as u32, sum, "site {i}");
        }
    }
    validate_merge(&merged_path, &frames(&d.path().join("synth"), 50));
    // The target is `render` of the clean raw, byte for byte.
    let r = d.path().join("render.png");
    ok(&common::cli("render", &merged_path, &r, &[]));
    assert_eq!(
        std::fs::read(&r).unwrap(),
        std::fs::read(o.join("real/target/night__a.png")).unwrap()
    );
    let r = d.path().join("render.exr");
    ok(&common::cli("render", &merged_path, &r, &[]));
    assert!(o.join("real/target/night__a.exr").is_file());
    // The noisy inputs are byte copies of the first frame of each ISO.
    for iso in [1600, 3200] {
        let src = std::fs::read(&frames(&s, iso)[0]).unwrap();
        assert_eq!(
            std::fs::read(o.join(format!("real/noisy_raw/night__a_iso{iso}.dng"))).unwrap(),
            src
        );
        let p = &outs[2];
        assert_eq!(
            std::fs::read(p.join(format!("real/noisy_raw/007_iso{iso}.dng"))).unwrap(),
            src
        );
    }
    // Processed tree: the PNG's samples in the iso_50 frame's active area, the release's
    // target copied.
    let clean = read_dng(&outs[2].join("real/clean_raw/007.dng")).unwrap();
    let a = clean.active_area();
    let png = image::open(processed.join("clean_raw/007.png"))
        .unwrap()
        .into_luma16();
    for (r, row) in png.rows().enumerate() {
        for (c, px) in row.enumerate() {
            assert_eq!(clean.get(r + a.top as usize, c + a.left as usize), px.0[0]);
        }
    }
    assert_eq!(clean.meta.levels, first.meta.levels);
    assert_eq!(
        std::fs::read(outs[2].join("real/target/007.png")).unwrap(),
        std::fs::read(processed.join("clean/007.png")).unwrap()
    );
    // Every output is listed with its hash; the scene record names the layout and frames.
    for (r, o) in ms.iter().zip(&outs) {
        for f in r["outputs"].as_array().unwrap() {
            let b = std::fs::read(o.join(f["path"].as_str().unwrap())).unwrap();
            assert_eq!(f["bytes"].as_u64().unwrap(), b.len() as u64);
        }
    }
    let meta: Value =
        serde_json::from_slice(&std::fs::read(outs[1].join("real/meta/night__a.json")).unwrap())
            .unwrap();
    assert_eq!(meta["layout"], "release");
    assert_eq!(meta["frames"].as_array().unwrap().len(), 6);
    assert!(
        meta["checks"]["motion_max_measured_px"].as_f64().unwrap() < 0.05,
        "{meta}"
    );
}

/// A change made to a frame.
type Alter = Box<dyn FnOnce(&mut RawImage)>;

/// A copy of `src` changed by `f`, written as `dst`.
pub(crate) fn altered(src: &Path, dst: &Path, f: impl FnOnce(&mut RawImage)) {
    let mut img = read_dng(src).unwrap();
    img.meta.storage = None;
    f(&mut img);
    std::fs::write(dst, encode_dng(&img, &WriteOptions::default()).unwrap()).unwrap();
}

#[test]
fn bad_scenes_fail_by_name_and_good_ones_are_made() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 3, &["--motion", "none"]);
    let root = d.path().join("scenes");
    simple_scene(&root.join("good"), &s);
    // One frame in the low-ISO burst.
    simple_scene(&root.join("one"), &s);
    for f in &frames(&d.path().join("synth"), 50)[1..] {
        std::fs::remove_file(root.join("one").join(f.file_name().unwrap())).unwrap();
    }
    // A frame of another size / CFA / camera / black / white level.
    let second = frames(&d.path().join("synth"), 50)[1].clone();
    let cases: [(&str, Alter, &str); 5] = [
        (
            "size",
            Box::new(|i: &mut RawImage| {
                i.height -= 2;
                i.data.truncate(i.width * i.height);
                i.meta.active_area = None;
                i.meta.default_crop_origin = None;
                i.meta.default_crop_size = None;
            }),
            "size",
        ),
        (
            "cfa",
            Box::new(|i: &mut RawImage| i.meta.cfa.pattern = vec![2, 1, 1, 0]),
            "CFA pattern",
        ),
        (
            "camera",
            Box::new(|i: &mut RawImage| i.meta.model = Some("Other Phone".into())),
            "camera",
        ),
        (
            "black",
            Box::new(|i: &mut RawImage| i.meta.levels.black = vec![300.0]),
            "black",
        ),
        (
            "white",
            Box::new(|i: &mut RawImage| i.meta.levels.white = 4000.0),
            "white level",
        ),
    ];
    let mut want = vec![("one", "one frame".to_string())];
    for (name, f, reason) in cases {
        simple_scene(&root.join(name), &s);
        altered(
            &second,
            &root.join(name).join(second.file_name().unwrap()),
            f,
        );
        want.push((name, reason.to_string()));
    }
    // No low-ISO burst in the release layout.
    let rel = d.path().join("release");
    release_scene(&rel.join("good"), &s);
    release_scene(&rel.join("nolow"), &s);
    for k in 0..3 {
        std::fs::remove_file(rel.join(format!("nolow/RAW_0_000050_{k:04}.dng"))).unwrap();
    }
    let out = d.path().join("out");
    let o = real_pairs(&root, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    let recs = manifest(&out);
    assert_eq!(recs.len(), 7);
    for (name, reason) in &want {
        let r = recs.iter().find(|r| r["input"] == *name).unwrap();
        let e = r["error"].as_str().unwrap();
        assert_eq!(r["status"], "failed");
        assert!(
            e.starts_with(&format!("scene {name}: ")) && e.contains(reason.as_str()),
            "{name}: {e}"
        );
        assert!(err.contains(e), "{err}");
        assert!(r["outputs"].as_array().unwrap().is_empty());
        for sub in ["clean_raw", "target", "noisy_raw", "meta"] {
            let dir = out.join("real").join(sub);
            let left: Vec<_> = std::fs::read_dir(&dir)
                .map(|rd| {
                    rd.flatten()
                        .map(|e| e.file_name().to_string_lossy().into_owned())
                        .filter(|n| n.starts_with(name))
                        .collect()
                })
                .unwrap_or_default();
            assert!(left.is_empty(), "{name}: {left:?} left in {sub}");
        }
    }
    let good = recs.iter().find(|r| r["input"] == "good").unwrap();
    assert_eq!(good["status"], "ok");
    let o = real_pairs(&rel, &d.path().join("out_rel"), &[]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("scene nolow: ")
            && err.contains("no low-ISO burst: no frame named RAW_0_000050*"),
        "{err}"
    );
    assert!(err.contains("1 made"), "{err}");
}

#[test]
fn motion_is_caught() {
    let d = tempfile::tempdir().unwrap();
    let shaken = d.path().join("shaken");
    synth(&shaken, 4, &["--motion", "shake", "--shake-step", "3"]);
    let root = d.path().join("scenes");
    simple_scene(&root.join("hand"), &shaken);
    let o = real_pairs(&root, &d.path().join("out"), &[]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("scene hand: ") && err.contains("moved") && err.contains("--max-motion 1 px"),
        "{err}"
    );
    // Raised, the motion is recorded instead.
    let out = d.path().join("out_loose");
    ok(&real_pairs(&root, &out, &["--max-motion", "1000"]));
    let meta: Value =
        serde_json::from_slice(&std::fs::read(out.join("real/meta/hand.json")).unwrap()).unwrap();
    assert!(
        meta["checks"]["motion_max_measured_px"].as_f64().unwrap() > 2.0,
        "{meta}"
    );

    // A noisy input shifted by 4 columns against a still burst.
    let still = d.path().join("still");
    synth(&still, 3, &["--motion", "none"]);
    let root = d.path().join("scenes2");
    simple_scene(&root.join("shifted"), &still);
    let noisy = frames(&still, 1600)[0].clone();
    altered(
        &noisy,
        &root.join("shifted").join(noisy.file_name().unwrap()),
        |i| {
            let w = i.width;
            for row in i.data.chunks_mut(w) {
                row.rotate_right(4);
            }
        },
    );
    let o = real_pairs(&root, &d.path().join("out2"), &[]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("scene shifted: ") && err.contains("against the merged clean raw"),
        "{err}"
    );
}

#[test]
fn rerun_resumes_with_nothing_redone() {
    let d = tempfile::tempdir().unwrap();
    let (root, out) = two_simple_scenes(d.path(), 3, &["--jobs", "2"]);
    let before = std::fs::read(out.join("manifest.jsonl")).unwrap();
    let t = std::fs::metadata(out.join("real/clean_raw/a.dng"))
        .unwrap()
        .modified()
        .unwrap();
    let o = real_pairs(&root, &out, &["--json"]);
    ok(&o);
    let sum: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (
            sum["done"].as_u64(),
            sum["skipped"].as_u64(),
            sum["outputs_written"].as_u64()
        ),
        (Some(0), Some(2), Some(0)),
        "{sum}"
    );
    assert_eq!(std::fs::read(out.join("manifest.jsonl")).unwrap(), before);
    assert_eq!(
        std::fs::metadata(out.join("real/clean_raw/a.dng"))
            .unwrap()
            .modified()
            .unwrap(),
        t
    );
    // A changed frame remakes its scene only; --overwrite remakes all.
    let f = root
        .join("b")
        .join(frames(&d.path().join("synth"), 50)[2].file_name().unwrap());
    altered(&frames(&d.path().join("synth"), 50)[2].clone(), &f, |i| {
        i.data[1000] ^= 1
    });
    let o = real_pairs(&root, &out, &["--json"]);
    ok(&o);
    let sum: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (sum["done"].as_u64(), sum["skipped"].as_u64()),
        (Some(1), Some(1)),
        "{sum}"
    );
    assert_eq!(sum["recomputed"]["input changed"], 1);
    let o = real_pairs(&root, &out, &["--json", "--overwrite"]);
    let sum: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(sum["done"].as_u64(), Some(2), "{sum}");
}
