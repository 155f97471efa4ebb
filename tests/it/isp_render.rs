//! Software ISP: renders of the committed fixtures and the real Canon DNG, EXR outputs
//! checked by OpenEXR and OpenImageIO, and the linear render compared with LibRaw (rawpy).
use crate::common;

use day2night::dng::read::read_dng;
use day2night::isp::render::{default_crop, render, Output, RenderOptions};
use day2night::isp::Demosaic;
use std::path::{Path, PathBuf};

fn fixtures() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(common::fixtures())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "dng"))
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no fixtures");
    v
}

fn canon() -> PathBuf {
    common::shared_file("dng/canon_kissx4_magiclantern_rggb14_strips.dng")
}

#[test]
fn every_fixture_renders_with_every_method() {
    for f in fixtures() {
        let img = read_dng(&f).unwrap();
        let a = img.active_area();
        let (_, _, cw, ch) = default_crop(&img.meta, a.width(), a.height());
        for d in Demosaic::ALL {
            let opts = RenderOptions {
                demosaic: d,
                ..RenderOptions::default()
            };
            let out = render(&img, &opts).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
            assert_eq!((out.width, out.height), (cw, ch), "{}", f.display());
            assert!(
                out.data.iter().all(|v| (0.0..=1.0).contains(v)),
                "{}",
                f.display()
            );
            let input = RenderOptions {
                output: Output::Camera,
                demosaic: d,
                ..RenderOptions::default()
            };
            let inp = render(&img, &input).unwrap();
            assert_eq!((inp.width, inp.height), (cw, ch));
        }
    }
}

fn run_ok(args: &[&std::ffi::OsStr]) -> std::process::Output {
    let out = common::bin().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{:?}: {}",
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty(), "render printed on stdout");
    out
}

fn validator(script: &str, args: &[&std::ffi::OsStr]) -> String {
    let py = common::python();
    let out = common::run_validator(&py, script, args);
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{script} failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!("{script}: {stdout}");
    stdout
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn exr_outputs_pass_openexr_and_openimageio() {
    let dir = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let img = read_dng(&day).unwrap();
    let a = img.active_area();
    let (_, _, w, h) = default_crop(&img.meta, a.width(), a.height());
    let n = img.meta.as_shot_neutral.unwrap();
    for (kind, flag, comp) in [
        ("half", "--half", "zip"),
        ("float", "--float", "piz"),
        ("half", "--half", "b44"),
    ] {
        let out = dir.path().join(format!("day_{kind}_{comp}.exr"));
        run_ok(&[
            "render".as_ref(),
            day.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            flag.as_ref(),
            "--exr-compression".as_ref(),
            comp.as_ref(),
        ]);
        let attrs = [
            "day2night:source=day.dng".to_string(),
            format!("day2night:neutral={} {} {}", n[0], n[1], n[2]),
            format!("day2night:version={}", day2night::VERSION),
            "day2night:demosaic=mhc".to_string(),
        ];
        let mut args: Vec<std::ffi::OsString> = vec![
            out.clone().into(),
            kind.into(),
            w.to_string().into(),
            h.to_string().into(),
        ];
        args.extend(attrs.iter().map(|s| s.into()));
        let refs: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
        validator("isp_exr.py", &refs);
    }
}

fn compare_with_libraw(dng: &Path, dir: &Path, orient: bool, min_psnr: f64) {
    let img = read_dng(dng).unwrap();
    let a = img.active_area();
    let out = dir.join(format!(
        "{}_{}.exr",
        dng.file_stem().unwrap().to_string_lossy(),
        orient
    ));
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "render".as_ref(),
        dng.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--float".as_ref(),
        "--no-crop".as_ref(),
        "--demosaic".as_ref(),
        "menon".as_ref(),
    ];
    if !orient {
        args.push("--no-orient".as_ref());
    }
    run_ok(&args);
    let top = a.top.to_string();
    let left = a.left.to_string();
    let o = if orient { "1" } else { "0" };
    let m = min_psnr.to_string();
    validator(
        "isp_rawpy.py",
        &[
            dng.as_os_str(),
            out.as_os_str(),
            top.as_ref(),
            left.as_ref(),
            o.as_ref(),
            m.as_ref(),
        ],
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
fn linear_render_agrees_with_libraw_on_the_real_canon_dng() {
    let c = canon();
    let dir = tempfile::tempdir().unwrap();
    compare_with_libraw(&c, dir.path(), false, 30.0);
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn linear_render_agrees_with_libraw_on_fixtures_including_orientation() {
    let dir = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    compare_with_libraw(&day, dir.path(), false, 30.0);
    compare_with_libraw(
        &common::fixtures().join("grbg_12bit_packed_be_strips.dng"),
        dir.path(),
        false,
        30.0,
    );
    // The same raw with Orientation 6 (rotate 90 clockwise): both sides rotate.
    let mut img = read_dng(&day).unwrap();
    img.meta.orientation = 6;
    let rotated = dir.path().join("day_orient6.dng");
    day2night::dng::write::write_dng(&img, &rotated, &Default::default(), &Default::default())
        .unwrap();
    compare_with_libraw(&rotated, dir.path(), true, 30.0);
}

#[test]
fn render_cli_errors_and_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let png = dir.path().join("d.png");
    run_ok(&[
        "render".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        png.as_os_str(),
    ]);
    let i = image::open(&png).unwrap();
    assert!(matches!(i, image::DynamicImage::ImageRgb8(_)));
    // existing output refused without --overwrite, accepted with it
    let again = common::bin()
        .args([
            "render".as_ref(),
            day.as_os_str(),
            "-o".as_ref(),
            png.as_os_str(),
        ])
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--overwrite"));
    run_ok(&[
        "render".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        png.as_os_str(),
        "--overwrite".as_ref(),
        "--bits".as_ref(),
        "16".as_ref(),
        "--tone".as_ref(),
        "release".as_ref(),
    ]);
    assert!(matches!(
        image::open(&png).unwrap(),
        image::DynamicImage::ImageRgb16(_)
    ));
    let tif = dir.path().join("d.tif");
    run_ok(&[
        "render".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        tif.as_os_str(),
    ]);
    assert!(matches!(
        image::open(&tif).unwrap(),
        image::DynamicImage::ImageRgb16(_)
    ));
    // the network input
    let inp = dir.path().join("in.exr");
    run_ok(&[
        "render".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        inp.as_os_str(),
        "--camera-rgb".as_ref(),
        "--neutral".as_ref(),
        "0.5,1,0.7".as_ref(),
    ]);
    // usage errors: exit 2
    for bad in [
        vec!["--demosaic", "ahd"],
        vec!["--neutral", "1,2"],
        vec!["--exr-compression", "dwaa"],
    ] {
        let o = dir.path().join("u.exr");
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "render".as_ref(),
            day.as_os_str(),
            "-o".as_ref(),
            o.as_os_str(),
        ];
        args.extend(bad.iter().map(|s| std::ffi::OsStr::new(*s)));
        let r = common::bin().args(&args).output().unwrap();
        assert_eq!(r.status.code(), Some(2), "{bad:?}");
        let err = String::from_utf8_lossy(&r.stderr);
        // --neutral is checked by the command; a choice by clap, from the enum's names
        if bad[0] == "--neutral" {
            assert!(err.starts_with("day2night: "), "{err}");
        } else {
            assert!(err.contains(bad[0]) && err.contains(bad[1]), "{err}");
        }
        assert!(!o.exists());
    }
}

/// Bad input: exit 1, names the file.
#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn render_of_an_unsupported_real_file_exits_1_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let gpr = common::shared_file("dng-bad/gopro_hero7_vc5_compression9.gpr");
    let o = dir.path().join("g.exr");
    let r = common::bin()
        .args([
            "render".as_ref(),
            gpr.as_os_str(),
            "-o".as_ref(),
            o.as_os_str(),
        ])
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(1));
    let e = String::from_utf8_lossy(&r.stderr);
    assert!(e.contains("gopro_hero7") && !o.exists(), "{e}");
}

#[test]
fn outputs_are_byte_identical_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    for ext in ["exr", "png"] {
        let mut outs = vec![];
        for threads in ["1", "2", "3"] {
            let o = dir.path().join(format!("t{threads}.{ext}"));
            let r = common::bin()
                .env("RAYON_NUM_THREADS", threads)
                .args([
                    "render".as_ref(),
                    day.as_os_str(),
                    "-o".as_ref(),
                    o.as_os_str(),
                    "--demosaic".as_ref(),
                    "menon".as_ref(),
                ])
                .output()
                .unwrap();
            assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
            outs.push(std::fs::read(&o).unwrap());
        }
        assert!(
            outs.windows(2).all(|w| w[0] == w[1]),
            "{ext} differs across thread counts"
        );
    }
}
