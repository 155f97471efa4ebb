//! `real-pairs` under bad input and interrupts (issue 36): colliding scene ids, unchecked
//! targets, featureless frames, a second signal in the middle of a scene, the blame and the
//! advice of errors, stale outputs of a scene that turns failed, and the smaller defects.
//! Scenes are made as in tests/it/real_pairs.rs (`synth --burst` of the fixture).
use crate::real_pairs::{
    altered, frames, manifest, ok, processed_scene, real_pairs, release_scene, simple_scene, synth,
    two_simple_scenes,
};
use day2night::raw::RawImage;
use day2night::realpairs::{self, Checkpoint, PairOptions, RunOptions};
use serde_json::Value;
use std::path::Path;

/// Every file under `dir` (relative paths, sorted); none when it does not exist.
fn files_under(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.push(rel);
            }
        }
    }
    out.sort();
    out
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn meta(out: &Path, id: &str) -> Value {
    let p = out.join(format!("real/meta/{id}.json"));
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

fn record<'a>(recs: &'a [Value], input: &str) -> &'a Value {
    recs.iter()
        .find(|r| r["input"] == input)
        .unwrap_or_else(|| panic!("no record of {input}: {recs:?}"))
}

#[test]
fn colliding_scene_ids_are_refused_before_anything_is_written() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "none"]);
    for (layout, make) in [
        ("simple", simple_scene as fn(&Path, &Path)),
        ("release", release_scene as fn(&Path, &Path)),
    ] {
        let root = d.path().join(format!("scenes_{layout}"));
        make(&root.join("a/b"), &s);
        make(&root.join("a__b"), &s);
        let out = d.path().join(format!("out_{layout}"));
        let o = real_pairs(&root, &out, &[]);
        let err = stderr(&o);
        assert!(!o.status.success(), "{layout}: {err}");
        assert!(
            err.contains("\"a/b\"") && err.contains("\"a__b\"") && err.contains("output id"),
            "{layout}: {err}"
        );
        assert!(!out.exists(), "{layout}: {:?}", files_under(&out));
        // Ids that differ only in letter case collide on a case-insensitive file system.
        let root = d.path().join(format!("case_{layout}"));
        make(&root.join("Night"), &s);
        make(&root.join("night"), &s);
        let o = real_pairs(&root, &d.path().join(format!("out_case_{layout}")), &[]);
        let err = stderr(&o);
        assert!(
            !o.status.success() && err.contains("letter case"),
            "{layout}: {err}"
        );
    }
}

/// A processed tree of scene 007 with its target replaced by `bytes`: the scene fails,
/// naming clean/007.png and `reason`, and writes nothing.
fn bad_target(d: &Path, s: &Path, name: &str, bytes: &[u8], reason: &str) {
    let root = d.join(name);
    processed_scene(&root, "007", s);
    std::fs::write(root.join("clean/007.png"), bytes).unwrap();
    let out = d.join(format!("out_{name}"));
    let o = real_pairs(&root, &out, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{name}: {err}");
    let recs = manifest(&out);
    let e = record(&recs, "007")["error"].as_str().unwrap();
    assert!(
        e.contains("clean/007.png") && e.contains(reason),
        "{name}: {e}"
    );
    assert!(files_under(&out.join("real")).is_empty(), "{name}");
}

#[test]
fn the_release_target_is_checked_before_it_is_copied() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "none"]);
    bad_target(
        d.path(),
        &s,
        "text",
        b"not a png at all\n",
        "not a readable PNG",
    );
    let mut small = Vec::new();
    image::RgbImage::new(30, 10)
        .write_to(
            &mut std::io::Cursor::new(&mut small),
            image::ImageFormat::Png,
        )
        .unwrap();
    bad_target(d.path(), &s, "small", &small, "30x10, not the scene's size");
    // Right size, wrong kind: a 16-bit grey PNG.
    let good = d.path().join("good");
    processed_scene(&good, "007", &s);
    let (w, h) = image::image_dimensions(good.join("clean/007.png")).unwrap();
    let mut grey = Vec::new();
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(w, h)
        .write_to(
            &mut std::io::Cursor::new(&mut grey),
            image::ImageFormat::Png,
        )
        .unwrap();
    bad_target(d.path(), &s, "grey", &grey, "8-bit RGB");
    // The release's own target, of the scene's size, is accepted and copied.
    let out = d.path().join("out_good");
    ok(&real_pairs(&good, &out, &[]));
    assert_eq!(
        std::fs::read(out.join("real/target/007.png")).unwrap(),
        std::fs::read(good.join("clean/007.png")).unwrap()
    );
}

#[test]
fn processed_tree_missing_iso_is_an_error_and_unused_files_are_listed() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "none"]);
    let root = d.path().join("night_real");
    processed_scene(&root, "007", &s);
    processed_scene(&root, "008", &s);
    std::fs::remove_file(root.join("dng/iso_3200/008.dng")).unwrap();
    for sub in ["dng/iso_abc", "dng/iso_800"] {
        std::fs::create_dir_all(root.join(sub)).unwrap();
        std::fs::copy(
            root.join("dng/iso_1600/007.dng"),
            root.join(sub).join("007.dng"),
        )
        .unwrap();
    }
    // An orphan: an input with neither clean raw nor metadata frame.
    std::fs::copy(
        root.join("dng/iso_1600/007.dng"),
        root.join("dng/iso_1600/009.dng"),
    )
    .unwrap();
    let out = d.path().join("out");
    let o = real_pairs(&root, &out, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let recs = manifest(&out);
    assert_eq!(recs.len(), 3, "{recs:?}");
    assert_eq!(record(&recs, "007")["status"], "ok");
    let e8 = record(&recs, "008")["error"].as_str().unwrap();
    assert!(
        e8.contains("no dng/iso_3200/008.dng") && e8.contains("--iso"),
        "{e8}"
    );
    let e9 = record(&recs, "009")["error"].as_str().unwrap();
    assert!(e9.contains("no clean_raw/009.png"), "{e9}");
    assert_eq!(
        meta(&out, "007")["ignored"],
        serde_json::json!(["dng/iso_800/007.dng", "dng/iso_abc/007.dng"])
    );
    // --iso names what is expected, as in the release layout.
    let out = d.path().join("out_1600");
    let o = real_pairs(&root, &out, &["--iso", "1600"]);
    let recs = manifest(&out);
    assert_eq!(record(&recs, "008")["status"], "ok", "{}", stderr(&o));
}

/// Every sample of the frame at its black level: a frame with nothing above black.
fn black(i: &mut RawImage) {
    let b = i.meta.levels.black[0] as u16;
    i.data.iter_mut().for_each(|v| *v = b);
}

#[test]
fn featureless_frames_are_reported_not_given_a_shift() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 3, &["--motion", "none"]);
    // Three byte-identical flat frames (every sample at black), nothing else.
    let root = d.path().join("scenes");
    let flat = root.join("flat");
    std::fs::create_dir_all(&flat).unwrap();
    let first = frames(&d.path().join("synth"), 50)[0].clone();
    altered(&first, &flat.join("f0.dng"), black);
    for k in 1..3 {
        std::fs::copy(flat.join("f0.dng"), flat.join(format!("f{k}.dng"))).unwrap();
    }
    // A textured burst with an all-zero noisy frame.
    let zero = root.join("zero");
    simple_scene(&zero, &s);
    let n = frames(&s, 1600)[0].clone();
    altered(&n, &zero.join(n.file_name().unwrap()), |i| i.data.fill(0));
    let out = d.path().join("out");
    let o = real_pairs(&root, &out, &[]);
    let err = stderr(&o);
    ok(&o);
    assert!(
        err.contains("warning[real-motion-unmeasured]") && !err.contains("moved"),
        "{err}"
    );
    for (id, unmeasured) in [("flat", 2), ("zero", 1)] {
        let m = meta(&out, id);
        let fr = m["frames"].as_array().unwrap();
        let un: Vec<&Value> = fr.iter().filter(|f| f["motion"].is_null()).collect();
        assert_eq!(un.len(), unmeasured, "{id}: {m}");
        for f in un {
            assert!(f["motion_px"].is_null(), "{f}");
            assert!(f["motion_unmeasured"].as_str().unwrap().len() > 10, "{f}");
        }
        let warned = m["checks"]["warnings"].as_array().unwrap();
        assert!(
            warned
                .iter()
                .filter(|w| w["code"] == "real-motion-unmeasured")
                .count()
                == unmeasured,
            "{id}: {m}"
        );
    }
    let z = meta(&out, "zero");
    let noisy = z["frames"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["iso"] == 1600)
        .unwrap()
        .clone();
    assert!(noisy["motion"].is_null(), "{noisy}");
}

/// Patch a little-endian DNG's IFD entry `tag` (type `ty`, count `n`): `f` gets the file and
/// the offset of the entry's value (inline, or where it points).
fn patch_entry(path: &Path, tag: u16, ty: u16, n: u32, f: impl Fn(&mut Vec<u8>, usize)) {
    let mut b = std::fs::read(path).unwrap();
    assert_eq!(&b[..2], b"II");
    let mut key = tag.to_le_bytes().to_vec();
    key.extend(ty.to_le_bytes());
    key.extend(n.to_le_bytes());
    let at = b.windows(8).position(|w| w == key).expect("entry") + 8;
    let size = [0, 1, 1, 2, 4, 8][ty as usize] * n as usize;
    let off = if size <= 4 {
        at
    } else {
        u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize
    };
    f(&mut b, off);
    std::fs::write(path, b).unwrap();
}

#[test]
fn errors_blame_the_real_cause_and_advise_what_exists() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "none"]);
    let root = d.path().join("scenes");
    let second = frames(&d.path().join("synth"), 50)[1].clone();
    let first = frames(&d.path().join("synth"), 50)[0].clone();
    // WhiteLevel below BlackLevel (a LONG 4000 made 100).
    simple_scene(&root.join("white"), &s);
    let p = root.join("white").join(second.file_name().unwrap());
    altered(&second, &p, |i| i.meta.levels.white = 4000.0);
    patch_entry(&p, 50717, 4, 1, |b, o| {
        b[o..o + 4].copy_from_slice(&100u32.to_le_bytes())
    });
    // An all-zero AsShotNeutral (three RATIONALs, numerators made 0).
    simple_scene(&root.join("zero_neutral"), &s);
    let p = root.join("zero_neutral").join(second.file_name().unwrap());
    patch_entry(&p, 50728, 5, 3, |b, o| {
        for k in 0..3 {
            b[o + 8 * k..o + 8 * k + 4].fill(0);
        }
    });
    // No AsShotNeutral in the burst's first frame.
    simple_scene(&root.join("no_neutral"), &s);
    altered(
        &first,
        &root.join("no_neutral").join(first.file_name().unwrap()),
        |i| {
            i.meta.as_shot_neutral = None;
            i.meta.as_shot_white_xy = None;
        },
    );
    let out = d.path().join("out");
    let o = real_pairs(&root, &out, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let recs = manifest(&out);
    for (name, src, want) in [
        ("white", &second, "white level"),
        ("zero_neutral", &second, "AsShotNeutral"),
        ("no_neutral", &first, "AsShotNeutral"),
    ] {
        let e = record(&recs, name)["error"].as_str().unwrap();
        let file = src.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            e.contains(&file) && e.contains(want) && !e.contains("no ISO"),
            "{name}: {e}"
        );
        assert!(!e.contains("--neutral"), "{name}: {e}");
    }
}

#[test]
fn a_scene_that_turns_failed_loses_its_old_files() {
    let d = tempfile::tempdir().unwrap();
    let (root, out) = two_simple_scenes(d.path(), 3, &[]);
    assert_eq!(files_under(&out.join("real")).len(), 10);
    for f in &frames(&d.path().join("synth"), 50)[1..] {
        std::fs::remove_file(root.join("a").join(f.file_name().unwrap())).unwrap();
    }
    let o = real_pairs(&root, &out, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let left = files_under(&out.join("real"));
    assert!(
        left.iter()
            .all(|f| !f.contains("/a.") && !f.contains("/a_")),
        "{left:?}"
    );
    assert_eq!(left.len(), 5, "{left:?}");
    let recs = manifest(&out);
    assert_eq!(record(&recs, "a")["status"], "failed");
    assert_eq!(record(&recs, "b")["status"], "ok");
}

#[test]
fn small_defects_of_the_command_line() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "shake", "--shake-step", "3"]);
    let root = d.path().join("scenes");
    simple_scene(&root.join("a"), &s);
    // A tiny --max-motion prints a short number.
    let o = real_pairs(&root, &d.path().join("out"), &["--max-motion", "1e-300"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--max-motion 1e-300 px"), "{err}");
    assert!(err.lines().all(|l| l.len() < 400), "{err}");
    // OUT equal to SCENES is named as such.
    let o = real_pairs(&root, &root, &[]);
    let err = stderr(&o);
    assert!(
        !o.status.success() && err.contains("the output folder is the scenes folder"),
        "{err}"
    );
}

/// The environment variable that makes [`interrupt_child`] run (read by the test only).
const CHILD: &str = "D2N_TEST_REAL_PAIRS_INTERRUPT";

/// What the second signal does (src/cli/interrupt.rs): the first asked to stop, the second
/// removes every temporary file and exits at once. Called at the checkpoint the parent
/// chose, which makes the test deterministic.
fn second_signal_at(_scene: &str, at: Checkpoint) {
    let want = std::env::var(CHILD).unwrap_or_default();
    let point = want.lines().nth(2).unwrap_or_default();
    if format!("{at:?}") == point {
        day2night::output::request_stop(2);
        day2night::output::remove_temp_files_and_close();
        std::process::exit(130);
    }
}

#[test]
#[ignore = "the child process of a_second_signal_leaves_a_whole_scene_or_none (run by it)"]
fn interrupt_child() {
    let Ok(spec) = std::env::var(CHILD) else {
        return;
    };
    let mut l = spec.lines();
    let (scenes, out) = (l.next().unwrap(), l.next().unwrap());
    let opts = RunOptions {
        scenes_dir: scenes.into(),
        out_dir: out.into(),
        jobs: 1,
        overwrite: false,
        on_scene: None,
        checkpoint: Some(second_signal_at),
    };
    let r = realpairs::run(&opts, &PairOptions::default());
    panic!("not interrupted: {r:?}");
}

#[test]
fn a_second_signal_leaves_a_whole_scene_or_none() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "none"]);
    let root = d.path().join("scenes");
    simple_scene(&root.join("a"), &s);
    let reference = d.path().join("reference");
    ok(&real_pairs(&root, &reference, &[]));
    let whole = files_under(&reference.join("real"));
    assert_eq!(whole.len(), 5, "{whole:?}");
    for (point, left) in [("Staged", vec![]), ("Committed", whole.clone())] {
        let out = d.path().join(format!("out_{point}"));
        let o = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--exact", "real_pairs_bad::interrupt_child", "--ignored"])
            .args(["--nocapture", "--test-threads", "1"])
            .env(
                CHILD,
                format!("{}\n{}\n{point}", root.display(), out.display()),
            )
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(130), "{point}: {}", stderr(&o));
        // Every file of the scene or none, and no temporary or lock file.
        assert_eq!(files_under(&out.join("real")), left, "{point}");
        let hidden: Vec<String> = files_under(&out)
            .into_iter()
            .filter(|f| f.contains("/.") || f.starts_with('.'))
            .collect();
        assert!(hidden.is_empty(), "{point}: {hidden:?}");
        // The rerun repairs: the scene recorded, its files those of an uninterrupted run.
        ok(&real_pairs(&root, &out, &[]));
        assert_eq!(manifest(&out), manifest(&reference), "{point}");
        for f in &whole {
            assert_eq!(
                std::fs::read(out.join("real").join(f)).unwrap(),
                std::fs::read(reference.join("real").join(f)).unwrap(),
                "{point}: {f}"
            );
        }
    }
}

#[test]
fn saturated_sites_are_white_counted_and_documented() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 3, &["--motion", "none"]);
    let root = d.path().join("scenes");
    simple_scene(&root.join("a"), &s);
    // Three sites clipped in one frame of the burst only.
    let f = frames(&d.path().join("synth"), 50)[1].clone();
    let img = day2night::dng::read_dng(&f).unwrap();
    let a = img.active_area();
    let sites: Vec<usize> = (0..3)
        .map(|k| (a.top as usize + 40 + 2 * k) * img.width + a.left as usize + 40)
        .collect();
    let white = img.meta.levels.white as u16;
    let clipped = sites.clone();
    altered(&f, &root.join("a").join(f.file_name().unwrap()), move |i| {
        for &k in &clipped {
            i.data[k] = white;
        }
    });
    let out = d.path().join("out");
    ok(&real_pairs(&root, &out, &[]));
    let merged = day2night::dng::read_dng(&out.join("real/clean_raw/a.dng")).unwrap();
    let m = meta(&out, "a");
    let count = m["merge"]["saturated_sites"].as_u64().unwrap();
    assert!(count >= 3, "{m}");
    for &k in &sites {
        // White, not the mean of one clipped and two unclipped samples.
        assert_eq!(merged.data[k] as f64, merged.meta.levels.white, "site {k}");
    }
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/real-pairs.md"))
            .unwrap();
    assert!(
        doc.contains("**Saturated sites.**") && doc.contains("`merge.saturated_sites`"),
        "docs/real-pairs.md does not say what happens at saturated sites"
    );
}

#[test]
fn a_scene_gone_from_scenes_is_listed_with_its_files_left() {
    let d = tempfile::tempdir().unwrap();
    let (root, out) = two_simple_scenes(d.path(), 2, &[]);
    std::fs::remove_dir_all(root.join("b")).unwrap();
    let o = real_pairs(&root, &out, &["--json"]);
    let err = ok(&o);
    assert!(
        err.contains("dropped the manifest records of 1 scenes no longer in SCENES")
            && err.contains(": b"),
        "{err}"
    );
    let sum: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(sum["dropped"], serde_json::json!(["b"]));
    let recs = manifest(&out);
    assert_eq!(recs.len(), 1);
    assert!(out.join("real/clean_raw/b.dng").is_file());
}

/// The release's own renders (shared data `release-isp/`, Orientation 3 and 6, a second
/// crop by the ActiveArea) are targets of the scene's size: a processed tree of each, with
/// the frame's visible raw as its clean raw, is accepted and its target copied.
#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs ../shared/data (release-isp/): the release's own renders"
)]
fn the_release_renders_are_targets_of_the_scenes_size() {
    let d = tempfile::tempdir().unwrap();
    let root = d.path().join("night_real");
    let refs = crate::common::shared_data().join("release-isp");
    for (nnn, o) in [("003", 3), ("006", 6)] {
        let dng = refs.join(format!("day_orient{o}.dng"));
        let img = day2night::dng::read_dng(&dng).unwrap();
        let a = img.active_area();
        let mut vis = Vec::new();
        for r in a.top as usize..a.bottom as usize {
            vis.extend_from_slice(&img.data[r * img.width + a.left as usize..][..a.width()]);
        }
        let png: image::ImageBuffer<image::Luma<u16>, Vec<u16>> =
            image::ImageBuffer::from_raw(a.width() as u32, a.height() as u32, vis).unwrap();
        for sub in [
            "clean_raw",
            "clean",
            "dng/iso_50",
            "dng/iso_1600",
            "dng/iso_3200",
        ] {
            std::fs::create_dir_all(root.join(sub)).unwrap();
        }
        png.save(root.join(format!("clean_raw/{nnn}.png"))).unwrap();
        let target = refs.join(format!("day_orient{o}_release.png"));
        std::fs::copy(&target, root.join(format!("clean/{nnn}.png"))).unwrap();
        for iso in [50, 1600, 3200] {
            std::fs::copy(&dng, root.join(format!("dng/iso_{iso}/{nnn}.dng"))).unwrap();
        }
    }
    let out = d.path().join("out");
    ok(&real_pairs(&root, &out, &[]));
    for (nnn, o) in [("003", 3), ("006", 6)] {
        assert_eq!(
            std::fs::read(out.join(format!("real/target/{nnn}.png"))).unwrap(),
            std::fs::read(refs.join(format!("day_orient{o}_release.png"))).unwrap()
        );
    }
}

/// A scene id longer than its file names allow (issue 47): a 225-byte folder name is refused
/// before anything is written (exit 2, one line naming the folder and the fix); 224 bytes,
/// the longest ([`realpairs::discover::ID_MAX_BYTES`]), are made, temporary names included.
#[test]
fn a_scene_id_too_long_for_its_file_names_is_refused_before_anything_is_written() {
    assert_eq!(realpairs::discover::ID_MAX_BYTES, 224);
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "none"]);
    let long = "n".repeat(225);
    let root = d.path().join("long");
    simple_scene(&root.join(&long), &s);
    let out = d.path().join("out_long");
    let o = real_pairs(&root, &out, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("225 bytes") && err.contains("224") && err.contains("rename"),
        "{err}"
    );
    assert!(!out.exists(), "{:?}", files_under(&out));
    let fits = "n".repeat(224);
    let root = d.path().join("fits");
    simple_scene(&root.join(&fits), &s);
    let out = d.path().join("out_fits");
    let o = real_pairs(&root, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(meta(&out, &fits)["scene"], fits.as_str());
    assert_eq!(manifest(&out).len(), 1);
    assert!(out
        .join(format!("real/noisy_raw/{fits}_iso3200.dng"))
        .is_file());
}
