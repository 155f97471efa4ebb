//! `merge`: the output equals the frames' mean within rounding (exact sums when they fit in
//! 16 bits), rawpy and the Adobe DNG SDK accept it, and mismatched bursts are clear errors.
use crate::args;
use crate::calibrate_support;
use crate::common;

use calibrate_support::*;
use day2night::dng::read_dng;
use day2night::normalize::{normalize, NormalizeOptions};
use std::ffi::OsString;
use std::path::PathBuf;

fn validate(merged: &std::path::Path, frames: &[PathBuf]) {
    let py = common::python();
    let mut a: Vec<&std::ffi::OsStr> = vec![merged.as_os_str()];
    a.extend(frames.iter().map(|p| p.as_os_str()));
    let o = common::run_validator(&py, "calibrate_merge_check.py", &a);
    let msg = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    eprintln!("{msg}");
    assert!(o.status.success(), "{msg}");
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn exact_sums_for_a_10_bit_burst() {
    let dir = tempfile::tempdir().unwrap();
    let lv = (64.0, 1023.0);
    let mut frames = burst(dir.path(), "f", 8, (128, 96), lv, (2.4e-3, 1e-5), 50, 1);
    // Give the frames a NoiseProfile and one saturated site in one frame.
    let mut imgs: Vec<_> = frames.iter().map(|p| read_dng(p).unwrap()).collect();
    for (k, img) in imgs.iter_mut().enumerate() {
        img.meta.noise_profile = Some(vec![(2.4e-3, 1e-5)]);
        if k == 3 {
            img.data[500] = 1023;
        }
        frames[k] = write(dir.path(), &format!("g{k}.dng"), img);
    }
    let out = dir.path().join("merged.dng");
    let mut a = args!["merge"];
    a.extend(frames.iter().map(OsString::from));
    a.extend(args!["-o", &out, "--json"]);
    let (code, stdout, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("merged 8 frames") && err.contains("exact sums"),
        "{err}"
    );
    let rep: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(rep["scale_factor"], 8);
    let m = read_dng(&out).unwrap();
    assert_eq!(m.meta.levels.black, vec![512.0]);
    assert_eq!(m.meta.levels.white, 8184.0);
    assert_eq!(m.meta.exif.iso, Some(50));
    assert_eq!(m.meta.noise_profile, Some(vec![(3e-4, 1.25e-6)]));
    for i in 0..m.data.len() {
        let sum: u32 = imgs.iter().map(|f| f.data[i] as u32).sum();
        if imgs.iter().any(|f| f.data[i] >= 1023) {
            assert_eq!(m.data[i], 8184, "saturated site stays saturated");
        } else {
            assert_eq!(m.data[i] as u32, sum, "site {i}");
        }
    }
    assert_eq!(m.data[500], 8184);
    // Normalized: the mean of the frames' normalized values.
    let opts = NormalizeOptions {
        clip_negative: false,
    };
    let p = normalize(&m, opts).unwrap();
    let fs: Vec<_> = imgs.iter().map(|f| normalize(f, opts).unwrap()).collect();
    for i in (0..p.data.len()).step_by(97) {
        if m.data[i] < 8184 {
            let mean = fs.iter().map(|f| f.data[i] as f64).sum::<f64>() / 8.0;
            assert!((p.data[i] as f64 - mean).abs() < 1e-6, "site {i}");
        }
    }
    validate(&out, &frames);
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn rounded_mean_for_a_14_bit_burst() {
    let dir = tempfile::tempdir().unwrap();
    // 8 x 15000 > 65535: K = 4, the output is round(sum * 4 / 8).
    let lv = (2048.0, 15000.0);
    let frames = burst(dir.path(), "f", 8, (64, 64), lv, (1e-3, 1e-6), 100, 2);
    let out = dir.path().join("merged.dng");
    let mut a = args!["merge"];
    a.extend(frames.iter().map(OsString::from));
    a.extend(args!["-o", &out, "--compression", "ljpeg"]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("rounded mean") && err.contains("levels x4"),
        "{err}"
    );
    let m = read_dng(&out).unwrap();
    assert_eq!(m.meta.levels.white, 60000.0);
    let imgs: Vec<_> = frames.iter().map(|p| read_dng(p).unwrap()).collect();
    for i in 0..m.data.len() {
        let mean: f64 = imgs.iter().map(|f| f.data[i] as f64).sum::<f64>() / 8.0;
        assert!(
            (m.data[i] as f64 / 4.0 - mean).abs() <= 0.125 + 1e-9,
            "site {i}"
        );
    }
    validate(&out, &frames);
}

#[test]
fn mismatched_bursts_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let lv = (64.0, 1023.0);
    let b = burst(dir.path(), "b", 2, (32, 32), lv, (1e-3, 1e-5), 50, 1);
    let out = dir.path().join("m.dng");
    let other_iso = write(
        dir.path(),
        "iso100.dng",
        &frame(32, 32, vec![100; 1024], 64.0, 1023.0, 100),
    );
    let other_size = write(
        dir.path(),
        "wide.dng",
        &frame(64, 32, vec![100; 2048], 64.0, 1023.0, 50),
    );
    let mut bggr = frame(32, 32, vec![100; 1024], 64.0, 1023.0, 50);
    bggr.meta.cfa.pattern = vec![2, 1, 1, 0];
    let other_cfa = write(dir.path(), "bggr.dng", &bggr);
    let other_white = write(
        dir.path(),
        "white.dng",
        &frame(32, 32, vec![100; 1024], 64.0, 4095.0, 50),
    );
    for (p, what) in [
        (&other_iso, "ISO 100 differs from the first frame's ISO 50"),
        (&other_size, "size 64x32 differs"),
        (
            &other_cfa,
            "CFA pattern BGGR differs from the first frame's RGGB",
        ),
        (&other_white, "white level 4095 differs"),
    ] {
        let (code, _, err) = run_os(&args!["merge", &b[0], &b[1], p, "-o", &out]);
        assert_eq!(code, 1, "{err}");
        assert!(
            err.contains(&*p.file_name().unwrap().to_string_lossy()) && err.contains(what),
            "{err}"
        );
    }
    let (code, _, err) = run_os(&args!["merge", &b[0], "-o", &out]);
    assert_eq!(code, 1);
    assert!(err.contains("at least 2 frames"), "{err}");
    // Never overwrite an input, nor an existing output without --overwrite.
    let (code, _, err) = run_os(&args!["merge", &b[0], &b[1], "-o", &b[1], "--overwrite"]);
    assert_eq!(code, 1);
    assert!(err.contains("input"), "{err}");
    std::fs::write(&out, b"x").unwrap();
    let (code, _, err) = run_os(&args!["merge", &b[0], &b[1], "-o", &out]);
    assert_eq!(code, 1);
    assert!(err.contains("--overwrite"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"x");
}

/// The same frame given twice (as the same path, or another path to the same file) is bad
/// usage, as Python's `merge` refuses it: one line naming the file, exit 2, nothing written.
#[test]
fn a_frame_given_twice_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let b = burst(
        dir.path(),
        "b",
        2,
        (32, 32),
        (64.0, 1023.0),
        (1e-3, 1e-5),
        50,
        1,
    );
    let out = dir.path().join("m.dng");
    let name = b[0].file_name().unwrap().to_os_string();
    let again = dir.path().join(".").join(&name);
    for twice in [&b[0], &again] {
        let (code, _, err) = run_os(&args!["merge", &b[0], &b[1], twice, "-o", &out]);
        assert_eq!(code, 2, "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(
            err.contains(&*name.to_string_lossy()) && err.contains("merge got this frame twice"),
            "{err}"
        );
        assert!(!out.exists());
    }
}

/// Real data: two copies of the shared Canon capture (14-bit in 16, ActiveArea, black 2056,
/// white 15000, ISO unknown) merge to exact sums (K = 2) that rawpy and the DNG SDK read as
/// the same image; brightness and a gray-card measurement run on it.
#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn real_canon_capture() {
    let data = common::shared_data();
    let src = data.join("dng/canon_kissx4_magiclantern_rggb14_strips.dng");
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.dng"), dir.path().join("b.dng"));
    std::fs::copy(&src, &a).unwrap();
    std::fs::copy(&src, &b).unwrap();
    let out = dir.path().join("merged.dng");
    let (code, _, err) = run_os(&args!["merge", &a, &b, "-o", &out]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("exact sums, levels x2"), "{err}");
    let (m, f) = (read_dng(&out).unwrap(), read_dng(&src).unwrap());
    assert_eq!(m.active_area(), f.active_area());
    assert!(m.data.iter().zip(&f.data).all(|(&x, &y)| {
        if y as f64 >= f.meta.levels.white {
            x as f64 == m.meta.levels.white
        } else {
            x == 2 * y
        }
    }));
    validate(&out, &[a.clone(), b.clone()]);
    let (code, _, err) = run_os(&args![
        "calibrate",
        "brightness",
        &src,
        "-o",
        dir.path().join("b.json")
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run_os(&args![
        "calibrate",
        "illuminants",
        &src,
        &out,
        "-o",
        dir.path().join("i.json")
    ]);
    assert_eq!(code, 0, "{err}");
    // The merged file measures the same chromaticity as the original.
    let d: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("i.json")).unwrap()).unwrap();
    let (c0, c1) = (
        &d["illuminants_rgb_over_g"][0],
        &d["illuminants_rgb_over_g"][1],
    );
    for k in [0, 2] {
        assert!(
            (c0[k].as_f64().unwrap() - c1[k].as_f64().unwrap()).abs() < 1e-6,
            "{d}"
        );
    }
}
