//! `day2night synth` end to end: output names, determinism across --jobs and reruns, replay,
//! every fixture (all Bayer phases, bit depths, black forms), unusable inputs, real camera
//! data, and the independent validators (rawpy, DNG SDK, tifffile) on the written DNGs.
use crate::common;

use day2night::dng::read_dng;
use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub(crate) fn synth(args: &[&str]) -> std::process::Output {
    common::bin().arg("synth").args(args).output().unwrap()
}

pub(crate) fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "synth failed: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

pub(crate) fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

/// Same names and bytes (without dumping megabytes on failure).
pub(crate) fn same(a: &BTreeMap<String, Vec<u8>>, b: &BTreeMap<String, Vec<u8>>, what: &str) {
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "{what}"
    );
    for (k, v) in a {
        assert!(v == &b[k], "{what}: {k} differs");
    }
}

fn day() -> PathBuf {
    common::fixtures().join("day.dng")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn validate(src: &Path, sidecar: &Path, dir: &Path) {
    let py = common::python();
    let out = common::run_validator(
        &py,
        "synth_check.py",
        &[src.as_os_str(), sidecar.as_os_str(), dir.as_os_str()],
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "validator failed on {}:\n{}\n{}",
        src.display(),
        text,
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn default_outputs_names_and_validators() {
    let t = tempfile::tempdir().unwrap();
    let o = t.path().join("night");
    let out = synth(&[s(&day()), "-o", s(&o)]);
    ok(&out);
    assert!(out.stdout.is_empty(), "nothing on stdout");
    let names: Vec<String> = files(&o).into_keys().collect();
    assert_eq!(
        names,
        vec![
            "day.json",
            "day_clean.dng",
            "day_iso1600.dng",
            "day_iso3200.dng",
            "day_target.exr"
        ]
    );
    validate(&day(), &o.join("day.json"), &o);
    let sc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.join("day.json")).unwrap()).unwrap();
    let stages: Vec<&str> = sc["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for st in [
        "normalize",
        "masks",
        "bulbs",
        "noise",
        "target_exr",
        "denormalize",
    ] {
        assert!(stages.contains(&st), "{st} missing from {stages:?}");
    }
    // The clean DNG read back carries the sidecar's neutral.
    let clean = read_dng(&o.join("day_clean.dng")).unwrap();
    let n = sc["plan"]["night_neutral"].as_array().unwrap();
    let got = clean.meta.as_shot_neutral.unwrap();
    for i in 0..3 {
        assert!((got[i] - n[i].as_f64().unwrap()).abs() < 1e-6);
    }
    // Refuses to overwrite without --overwrite.
    let again = synth(&[s(&day()), "-o", s(&o)]);
    assert_eq!(again.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--overwrite"));
}

#[test]
fn determinism_jobs_reruns_and_seeds() {
    let t = tempfile::tempdir().unwrap();
    let (a, b, c) = (t.path().join("a"), t.path().join("b"), t.path().join("c"));
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&a),
        "--jobs",
        "1",
        "--seed",
        "3",
        "--target",
        "both",
    ]));
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&b),
        "--jobs",
        "2",
        "--seed",
        "3",
        "--target",
        "both",
    ]));
    let fa = files(&a);
    assert!(fa.contains_key("day_target.png"));
    same(&fa, &files(&b), "--jobs 1 vs --jobs 2");
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&a),
        "--jobs",
        "2",
        "--seed",
        "3",
        "--target",
        "both",
        "--overwrite",
    ]));
    same(&fa, &files(&a), "rerun");
    ok(&synth(&[s(&day()), "-o", s(&c), "--seed", "4"]));
    let fc = files(&c);
    for k in ["day_clean.dng", "day_iso1600.dng", "day_target.exr"] {
        assert!(fa[k] != fc[k], "{k}: another seed gave the same bytes");
    }
}

#[test]
fn replay_reproduces_bytes_and_variants_names() {
    let t = tempfile::tempdir().unwrap();
    let (a, r) = (t.path().join("a"), t.path().join("r"));
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&a),
        "--variants",
        "2",
        "--iso",
        "800",
        "--target",
        "both",
        "--input-exr",
        "--compression",
        "ljpeg",
    ]));
    let fa = files(&a);
    for v in ["day_v1", "day_v2"] {
        for suf in [
            ".json",
            "_clean.dng",
            "_iso800.dng",
            "_target.exr",
            "_target.png",
            "_input.exr",
        ] {
            assert!(fa.contains_key(&format!("{v}{suf}")), "{v}{suf} missing");
        }
    }
    assert!(fa["day_v1_clean.dng"] != fa["day_v2_clean.dng"]);
    let out = synth(&[
        s(&day()),
        "-o",
        s(&r),
        "--replay",
        s(&a.join("day_v2.json")),
    ]);
    ok(&out);
    let fr = files(&r);
    assert!(!fr.is_empty());
    for (k, v) in &fr {
        assert!(Some(v) == fa.get(k), "{k}: replay differs");
    }
    assert_eq!(fr.len(), 6);
    // A replay on another input is refused.
    let other = common::fixtures().join("rggb_16bit_le_strips.dng");
    let out = synth(&[
        s(&other),
        "-o",
        s(&r),
        "--replay",
        s(&a.join("day_v2.json")),
        "--overwrite",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("sidecar"));
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn every_fixture_and_mode() {
    let t = tempfile::tempdir().unwrap();
    let mut n = 0;
    for e in std::fs::read_dir(common::fixtures()).unwrap() {
        let p = e.unwrap().path();
        if p.extension().and_then(|x| x.to_str()) != Some("dng") {
            continue;
        }
        let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
        let o = t.path().join(&stem);
        ok(&synth(&[
            s(&p),
            "-o",
            s(&o),
            "--iso",
            "3200",
            "--target",
            "none",
        ]));
        validate(&p, &o.join(format!("{stem}.json")), &o);
        n += 1;
    }
    assert!(n >= 10, "only {n} fixtures");
    for mode in ["day", "dimmed", "global"] {
        let o = t.path().join(format!("mode_{mode}"));
        ok(&synth(&[
            s(&day()),
            "-o",
            s(&o),
            "--mode",
            mode,
            "--iso",
            "none",
        ]));
        assert!(o.join("day_clean.dng").exists() && !o.join("day_iso1600.dng").exists());
    }
    // Day mode reproduces the input's pixels where the white-balance clip did not cut.
    let o = t.path().join("mode_day");
    let a = read_dng(&day()).unwrap();
    let b = read_dng(&o.join("day_clean.dng")).unwrap();
    let same = a.data.iter().zip(&b.data).filter(|(x, y)| x == y).count();
    assert!(
        same as f64 > 0.9 * a.data.len() as f64,
        "{same} of {}",
        a.data.len()
    );
    let o = t.path().join("paper");
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&o),
        "--relight-formula",
        "paper",
        "--target",
        "none",
    ]));
    validate(&day(), &o.join("day.json"), &o);
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn unusable_inputs_are_reported_and_others_processed() {
    let data = common::shared_data();
    let t = tempfile::tempdir().unwrap();
    let bad = data.join("dng-bad/lg_g4_linearraw_lossyjpeg_subifd.dng");
    let vc5 = data.join("dng-bad/gopro_hero7_vc5_compression9.gpr");
    let out = synth(&[
        s(&bad),
        s(&day()),
        s(&vc5),
        "-o",
        s(t.path()),
        "--iso",
        "none",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("lg_g4_linearraw"), "{err}");
    assert!(err.contains("gopro_hero7"), "{err}");
    assert!(
        err.contains("LinearRaw: already demosaiced; the night synthesis works on the CFA mosaic"),
        "{err}"
    );
    assert!(err.contains("2 of 3 inputs failed"), "{err}");
    assert!(t.path().join("day_clean.dng").exists());
    // No neutral: a clear error unless --day-neutral is given.
    let mut img = read_dng(&day()).unwrap();
    img.meta.as_shot_neutral = None;
    let p = t.path().join("noneutral.dng");
    std::fs::write(&p, encode_dng(&img, &WriteOptions::default()).unwrap()).unwrap();
    let out = synth(&[s(&p), "-o", s(t.path()), "--iso", "none"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--day-neutral"));
    ok(&synth(&[
        s(&p),
        "-o",
        s(t.path()),
        "--iso",
        "none",
        "--day-neutral",
        "0.5,1,0.7",
    ]));
    // Bad usage is exit code 2.
    let d = day();
    for args in [
        vec!["--iso", "abc"],
        vec!["--variants", "0"],
        vec!["--jobs", "0"],
        vec!["--mode", "x"],
    ] {
        let mut a = vec![s(&d), "-o", s(t.path())];
        a.extend(args.iter().copied());
        assert_eq!(synth(&a).status.code(), Some(2), "{args:?}");
    }
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
fn real_canon_file() {
    let data = common::shared_data();
    let p = data.join("dng/canon_kissx4_magiclantern_rggb14_strips.dng");
    let t = tempfile::tempdir().unwrap();
    ok(&synth(&[s(&p), "-o", s(t.path()), "--iso", "1600"]));
    let stem = "canon_kissx4_magiclantern_rggb14_strips";
    assert!(t.path().join(format!("{stem}_target.exr")).exists());
    validate(&p, &t.path().join(format!("{stem}.json")), t.path());
    // ISO unknown in the file -> clean ISO 50, embedded noise model.
    let sc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(t.path().join(format!("{stem}.json"))).unwrap())
            .unwrap();
    assert_eq!(sc["plan"]["clean_iso"], 50);
    assert!(sc["report"]["noise_model_source"]
        .as_str()
        .unwrap()
        .contains("embedded"));
}

/// Flat field written as a DNG, run through the CLI in day mode, read back: var(noisy - clean)
/// matches the NoiseProfile written into the noisy DNG within 2% per brightness band.
#[test]
fn flat_field_noise_matches_written_profile() {
    let (w, h) = (1024usize, 1024usize);
    let (black, white) = (512.0, 16383.0);
    let scale = white - black;
    let levels = [0.05, 0.2, 0.45, 0.7];
    let mut meta = RawMeta::new_bayer(Bayer::GRBG, 14, black, white);
    meta.as_shot_neutral = Some([1.0, 1.0, 1.0]);
    let mut data = vec![0u16; w * h];
    for r in 0..h {
        let x = (levels[r * 4 / h] * scale + black).round() as u16;
        data[r * w..(r + 1) * w].fill(x);
    }
    let img = RawImage {
        width: w,
        height: h,
        data,
        meta,
    };
    let t = tempfile::tempdir().unwrap();
    let p = t.path().join("flat.dng");
    std::fs::write(&p, encode_dng(&img, &WriteOptions::default()).unwrap()).unwrap();
    let o = t.path().join("o");
    ok(&synth(&[
        s(&p),
        "-o",
        s(&o),
        "--mode",
        "day",
        "--iso",
        "1600,6400",
        "--target",
        "none",
    ]));
    let clean = read_dng(&o.join("flat_clean.dng")).unwrap();
    assert_eq!(clean.data, img.data);
    for iso in [1600, 6400] {
        let noisy = read_dng(&o.join(format!("flat_iso{iso}.dng"))).unwrap();
        assert_eq!(noisy.meta.exif.iso, Some(iso));
        let prof = noisy.meta.noise_profile.clone().unwrap();
        for band in 0..4 {
            for colour in 0..3u8 {
                let (mut n, mut s1, mut s2, mut y) = (0.0, 0.0, 0.0, 0.0);
                for r in band * h / 4..(band + 1) * h / 4 {
                    for c in 0..w {
                        if Bayer::GRBG.color_at(r, c) != colour {
                            continue;
                        }
                        let d = (noisy.get(r, c) as f64 - clean.get(r, c) as f64) / scale;
                        y = (clean.get(r, c) as f64 - black) / scale;
                        n += 1.0;
                        s1 += d;
                        s2 += d * d;
                    }
                }
                let var = s2 / n - (s1 / n).powi(2);
                let (ps, po) = prof[colour as usize];
                // Rounding to integers adds 1/12 DN^2.
                let want = ps * y + po + 1.0 / 12.0 / (scale * scale);
                let rel = (var - want).abs() / want;
                assert!(
                    rel < 0.02,
                    "ISO {iso} band {band} colour {colour}: {var} vs {want}"
                );
            }
        }
    }
}

/// Calibration files on the command line: noise model, illuminant dictionary, brightness.
#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn calibration_files() {
    let t = tempfile::tempdir().unwrap();
    let nm = t.path().join("noise.json");
    std::fs::write(
        &nm,
        day2night::synth::dictionaries::embedded::noise_model().to_json(),
    )
    .unwrap();
    let il = t.path().join("ill.json");
    std::fs::write(&il, r#"{"illuminants_rgb_over_g": [[0.6, 1.0, 0.4]]}"#).unwrap();
    let br = t.path().join("bright.json");
    std::fs::write(&br, r#"{"values": [0.02, 0.03, 0.04]}"#).unwrap();
    let o = t.path().join("o");
    let out = synth(&[
        s(&day()),
        "-o",
        s(&o),
        "--noise-model",
        s(&nm),
        "--illuminants",
        s(&il),
        "--brightness",
        s(&br),
        "--iso",
        "1600,25",
        "--target",
        "none",
    ]);
    ok(&out);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning[noise-extrapolated]: day.dng: ISO 25"),
        "{err}"
    );
    assert!(!err.contains("ISO 1600"), "{err}");
    let sc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.join("day.json")).unwrap()).unwrap();
    let plan = &sc["plan"];
    assert!(sc["report"]["noise_model_source"]
        .as_str()
        .unwrap()
        .contains("embedded"));
    let nn: Vec<f64> = plan["night_neutral"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (a, b) in nn.iter().zip([0.6, 1.0, 0.4]) {
        assert!((a - b).abs() < 1e-12, "{nn:?}");
    }
    assert_eq!(plan["dim"]["kind"], "target_mean");
    let t_mean = plan["dim"]["target_mean"].as_f64().unwrap();
    let mean = sc["run"]["mean_white_balanced"].as_f64().unwrap();
    let s_used = sc["run"]["dim_scale"].as_f64().unwrap();
    assert!((s_used - t_mean / mean).abs() < 1e-12);
    validate(&day(), &o.join("day.json"), &o);
    // A malformed noise model is a clear error naming the file.
    std::fs::write(&nm, "{}").unwrap();
    let out = synth(&[
        s(&day()),
        "-o",
        s(&o),
        "--noise-model",
        s(&nm),
        "--overwrite",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("noise.json"));
}

#[test]
fn exr_compression_option_is_recorded_and_replayed() {
    let t = tempfile::tempdir().unwrap();
    let (z, p, r) = (t.path().join("z"), t.path().join("p"), t.path().join("r"));
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&z),
        "--iso",
        "none",
        "--target",
        "both",
    ]));
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&p),
        "--iso",
        "none",
        "--target",
        "both",
        "--exr-compression",
        "piz",
    ]));
    let (fz, fp) = (files(&z), files(&p));
    // The option is recorded, default or not.
    assert!(String::from_utf8_lossy(&fz["day.json"]).contains("\"exr_compression\": \"zip\""));
    assert!(String::from_utf8_lossy(&fp["day.json"]).contains("\"exr_compression\": \"piz\""));
    assert_eq!(fz["day_clean.dng"], fp["day_clean.dng"]);
    // zip renders band by band, piz from the whole image: the same PNG bytes
    assert_eq!(fz["day_target.png"], fp["day_target.png"]);
    assert_ne!(fz["day_target.exr"], fp["day_target.exr"]);
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&r),
        "--replay",
        s(&p.join("day.json")),
    ]));
    same(&fp, &files(&r), "replay of a piz run");
    let out = synth(&[s(&day()), "-o", s(&r), "--exr-compression", "gzip"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn exr_zip_level_is_recorded_replayed_and_checked() {
    let t = tempfile::tempdir().unwrap();
    let (z, n, r) = (t.path().join("z"), t.path().join("n"), t.path().join("r"));
    let d = day();
    let base = [s(&d), "--iso", "none", "--target", "exr"];
    ok(&synth(&[&base[..], &["-o", s(&z)]].concat()));
    ok(&synth(
        &[&base[..], &["-o", s(&n), "--exr-zip-level", "9"]].concat(),
    ));
    let (fz, fn_) = (files(&z), files(&n));
    assert!(String::from_utf8_lossy(&fz["day.json"]).contains("\"exr_zip_level\": 1"));
    assert!(String::from_utf8_lossy(&fn_["day.json"]).contains("\"exr_zip_level\": 9"));
    assert_eq!(fz["day_clean.dng"], fn_["day_clean.dng"]);
    // Level 9 is smaller than level 1 (lossless both: the pixels are compared by the
    // EXR validators elsewhere).
    assert!(fn_["day_target.exr"].len() < fz["day_target.exr"].len());
    ok(&synth(&[
        s(&day()),
        "-o",
        s(&r),
        "--replay",
        s(&n.join("day.json")),
    ]));
    same(&fn_, &files(&r), "replay of a level-9 run");
    for bad in ["0", "10", "x"] {
        let out = synth(&[s(&day()), "-o", s(&r), "--exr-zip-level", bad]);
        assert_eq!(out.status.code(), Some(2), "--exr-zip-level {bad}");
    }
}

/// A variant that fails part-way leaves none of its outputs behind: the files written before
/// the failure are synced but never renamed into place, and no temporary file remains.
#[test]
fn failed_variant_leaves_no_outputs() {
    let t = tempfile::tempdir().unwrap();
    let o = t.path().join("o");
    std::fs::create_dir_all(&o).unwrap();
    // The PNG target is refused when it is written (after the DNGs and the EXR).
    std::fs::write(o.join("day_target.png"), b"not ours").unwrap();
    let out = synth(&[s(&day()), "-o", s(&o), "--target", "both"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("day_target.png") && err.contains("--overwrite"),
        "{err}"
    );
    let mut names: Vec<String> = std::fs::read_dir(&o)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["day_target.png"], "left behind: {names:?}");
    assert_eq!(
        std::fs::read(o.join("day_target.png")).unwrap(),
        b"not ours"
    );
}
