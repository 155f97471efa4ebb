//! Hostile and unsupported DNGs: the real files in ../shared/data/dng-bad and deliberately
//! malformed files built here all get a clear error naming the reason (never a panic), and
//! `info` exits 1 for them, except for well-formed files of a kind synthesis cannot use
//! (LinearRaw, non-Bayer CFA), which `info` describes with the reason.
use crate::common;
use crate::dngbuild;

use day2night::dng::read::{inspect_bytes, read_dng, read_dng_bytes};
use day2night::tiff::value::Value;
use dngbuild::Builder;
use std::path::PathBuf;

fn expect_err(bytes: &[u8], want: &str) {
    let e = read_dng_bytes(bytes).expect_err(want).to_string();
    assert!(e.contains(want), "error {e:?} does not say {want:?}");
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn shared_bad_files_are_refused_with_reasons() {
    let d = common::shared_data();
    let cases = [
        (
            "gopro_hero7_vc5_compression9.gpr",
            "compression 9 (VC-5) is not supported",
            1,
        ),
        ("fuzz_subifd_empty_offsets.bin", "runs past the end", 1),
        ("fuzz_entry_count_oom.bin", "runs past the end", 1),
    ];
    for (name, want, info_code) in cases {
        let p = d.join("dng-bad").join(name);
        let e = read_dng(&p).expect_err(name).to_string();
        assert!(e.contains(want) && e.contains(name), "{name}: {e}");
        let out = common::bin().arg("info").arg(&p).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(info_code), "{name}: {err}");
        if info_code == 1 {
            assert!(
                err.contains(&format!("day2night: {}: ", p.display())) && err.contains(want),
                "{err}"
            );
        } else {
            let text = String::from_utf8_lossy(&out.stdout);
            assert!(text.contains(want) && text.contains("LG-H815"), "{text}");
            assert!(err.is_empty(), "{err}");
        }
    }
}

/// The real LinearRaw file (lossy JPEG tiles in a SubIFD, Adobe lossy DNG): read, described
/// in full and rendered; synthesis refuses it with the reason.
#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn shared_linear_raw_file_is_read_described_and_refused_for_synthesis() {
    let d = common::shared_data();
    let reason = "LinearRaw: already demosaiced; the night synthesis works on the CFA mosaic";
    let p = d.join("dng-bad/lg_g4_linearraw_lossyjpeg_subifd.dng");
    let img = read_dng(&p).unwrap();
    assert_eq!((img.width, img.height), (600, 338));
    let l = img.meta.linear_raw.as_ref().unwrap();
    assert_eq!((l.samples_per_pixel, l.white.clone()), (3, vec![255.0; 3]));
    assert!(img.bayer().unwrap_err().to_string().contains(reason));
    let out = common::bin().arg("info").arg(&p).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    for want in [
        "LG-H815",
        "lossy JPEG",
        "tiles 304x352",
        "per sample:",
        reason,
    ] {
        assert!(text.contains(want), "{want}: {text}");
    }
    assert!(out.stderr.is_empty());
    // JSON: described in full, not synth-ready, reason given, no error.
    let out = common::bin()
        .args(["info", "--json"])
        .arg(&p)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v[0]["synth_ready"], false);
    assert_eq!(v[0]["raw_ifd"], "IFD0/SubIFD0");
    assert!(v[0]["reason"].as_str().unwrap().contains(reason));
    assert!(v[0]["error"].is_null());
    assert_eq!(v[0]["raw"]["meta"]["linear_raw"]["samples_per_pixel"], 3);
    // Rendered: a daylight scene, neither black nor clipped, about neutral on average
    // (its OpcodeList2 MapPolynomial curves are what make the 8-bit samples linear).
    let t = tempfile::tempdir().unwrap();
    let png = t.path().join("lg.png");
    let out = common::cli("render", &p, &png, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rgb = image::open(&png).unwrap().to_rgb8();
    assert_eq!(rgb.dimensions(), (600, 338));
    let mut mean = [0f64; 3];
    for px in rgb.pixels() {
        for c in 0..3 {
            mean[c] += f64::from(px[c]) / (600.0 * 338.0);
        }
    }
    assert!(mean.iter().all(|&m| (60.0..200.0).contains(&m)), "{mean:?}");
    let (lo, hi) = (
        mean.iter().cloned().fold(255.0, f64::min),
        mean.iter().cloned().fold(0.0, f64::max),
    );
    assert!(hi / lo < 1.3, "colour cast: {mean:?}");
    // --opcodes ignore leaves the curves out (shared opcode stage): washed out, colour cast.
    let png2 = t.path().join("lg_ignore.png");
    let out = common::cli("render", &p, &png2, &["--opcodes", "ignore"]);
    assert!(out.status.success() && out.stderr.is_empty());
    let raw = image::open(&png2).unwrap().to_rgb8();
    let mut mean2 = [0f64; 3];
    for px in raw.pixels() {
        for c in 0..3 {
            mean2[c] += f64::from(px[c]) / (600.0 * 338.0);
        }
    }
    assert!(
        (0..3).all(|c| mean2[c] > mean[c] + 40.0),
        "{mean2:?} {mean:?}"
    );
    // synth refuses it with the reason, writing nothing.
    let out = common::bin()
        .arg("synth")
        .arg(&p)
        .arg("-o")
        .arg(t.path().join("night"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(reason) && err.contains("lg_g4_linearraw"),
        "{err}"
    );
}

/// Deliberately malformed files: (name, bytes, expected reason).
fn malformed() -> Vec<(&'static str, Vec<u8>, &'static str)> {
    let ok = Builder::new(64, 48, 12);
    let full = ok.build();
    let mut v = vec![
        ("truncated_header", full[..6].to_vec(), "too short"),
        (
            "truncated_half",
            full[..full.len() / 2].to_vec(),
            "past the end",
        ),
        (
            "bad_strip_counts",
            ok.clone().set(279, Value::Long(vec![10])).build(),
            "StripByteCounts",
        ),
        (
            "short_strip",
            ok.clone().set(279, Value::Long(vec![10; 16])).build(),
            "truncated",
        ),
        (
            "black_ge_white",
            ok.clone()
                .set(50714, Value::Long(vec![5000]))
                .set(50717, Value::Long(vec![4095]))
                .build(),
            "black level 5000 >= white level 4095",
        ),
        (
            "neutral_zero",
            ok.clone()
                .set(50728, Value::Rational(vec![(1, 2), (0, 1), (1, 2)]))
                .build(),
            "AsShotNeutral component 0 is not positive",
        ),
        (
            "noise_profile_3",
            ok.clone()
                .set(51041, Value::Double(vec![1e-4, 1e-6, 2e-4]))
                .build(),
            "NoiseProfile has 3 values",
        ),
        (
            "zero_width",
            ok.clone().set(256, Value::Long(vec![0])).build(),
            "zero size",
        ),
        (
            "huge_dims",
            ok.clone()
                .set(256, Value::Long(vec![60000]))
                .set(257, Value::Long(vec![60000]))
                .build(),
            "exceeds the limit",
        ),
        (
            "huge_width",
            ok.clone()
                .set(256, Value::Long(vec![4_000_000_000]))
                .build(),
            "exceeds the limit",
        ),
        (
            "cfa_value_3",
            ok.clone().set(33422, Value::Byte(vec![0, 1, 3, 2])).build(),
            "CFAPattern value 3 is not a colour plane",
        ),
        (
            // Uncompressed samples labelled JPEG XL: the decoder says what is wrong.
            "jpeg_xl",
            ok.clone().set(259, Value::Short(vec![52546])).build(),
            "JPEG XL strip 0: cannot decode",
        ),
        (
            "deflate",
            ok.clone().set(259, Value::Short(vec![8])).build(),
            "compression 8 (deflate) is not supported",
        ),
        (
            "lossy_jpeg",
            ok.clone().set(259, Value::Short(vec![34892])).build(),
            "lossy JPEG (34892) with 12-bit samples",
        ),
        (
            "no_dng_version",
            ok.clone().without(50706).build(),
            "no DNGVersion",
        ),
        (
            "cfa_count",
            ok.clone().set(33422, Value::Byte(vec![0, 1, 1])).build(),
            "CFAPattern has 3 values",
        ),
        (
            "active_area_outside",
            ok.clone()
                .set(50829, Value::Long(vec![0, 0, 49, 64]))
                .build(),
            "ActiveArea",
        ),
        (
            "matrix_size",
            ok.clone()
                .set(50721, Value::SRational(vec![(1, 1); 6]))
                .build(),
            "ColorMatrix1 has 6 values",
        ),
        (
            "float_samples",
            ok.clone().set(339, Value::Short(vec![3])).build(),
            "SampleFormat 3",
        ),
        (
            "bits_32",
            ok.clone().set(258, Value::Short(vec![32])).build(),
            "32-bit samples",
        ),
    ];
    let mut lj = Builder::new(64, 48, 14);
    lj.layout = dngbuild::Pixels::LjpegTiles {
        w: 32,
        h: 16,
        two_components: true,
    };
    let ljb = lj.build();
    // Corrupt the entropy-coded data of the first tile: cut it short via its byte count.
    let mut short = lj.clone();
    short.overrides.push((325, Value::Long(vec![40; 6])));
    v.push(("ljpeg_short_tile", short.build(), "lossless JPEG"));
    v.push((
        "ljpeg_truncated_file",
        ljb[..ljb.len() / 3].to_vec(),
        "past the end",
    ));
    v
}

#[test]
fn generated_malformed_files_get_clear_errors() {
    for (name, bytes, want) in malformed() {
        let e = read_dng_bytes(&bytes).expect_err(name).to_string();
        assert!(
            e.contains(want),
            "{name}: error {e:?} does not say {want:?}"
        );
    }
}

#[test]
fn info_reports_each_bad_file_and_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let mut paths: Vec<PathBuf> = Vec::new();
    let good = dir.path().join("good.dng");
    std::fs::write(&good, Builder::new(16, 16, 12).build()).unwrap();
    paths.push(good.clone());
    let cases = malformed();
    for (name, bytes, _) in &cases {
        let p = dir.path().join(format!("{name}.dng"));
        std::fs::write(&p, bytes).unwrap();
        paths.push(p);
    }
    let out = common::bin().arg("info").args(&paths).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    for (name, _, want) in &cases {
        let p = dir.path().join(format!("{name}.dng"));
        let line = err
            .lines()
            .find(|l| l.starts_with(&format!("day2night: {}: ", p.display())))
            .unwrap_or_else(|| panic!("no error line for {name} in:\n{err}"));
        assert!(line.contains(want), "{line}");
    }
    // The good file is still described on stdout.
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(&good.display().to_string()) && text.contains("synthesis:     ready"));
    // A missing file is an error too, and usage errors exit 2.
    let out = common::bin()
        .args(["info", "/nonexistent/x.dng"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let out = common::bin().arg("info").output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn non_bayer_cfa_reads_but_is_not_synth_ready() {
    let b = Builder::new(16, 16, 12)
        .set(33421, Value::Short(vec![3, 3]))
        .set(33422, Value::Byte(vec![0, 1, 2, 1, 2, 0, 2, 0, 1]));
    let bytes = b.build();
    let img = read_dng_bytes(&bytes).unwrap();
    let e = img.bayer().unwrap_err().to_string();
    assert!(
        e.contains("3x3 CFA pattern is not a 2x2 Bayer mosaic"),
        "{e}"
    );
    let info = inspect_bytes(&bytes).unwrap();
    assert!(!info.synth_ready && info.error.is_none());
    // Two greens side by side: 2x2 but not Bayer.
    let b = Builder::new(16, 16, 12).set(33422, Value::Byte(vec![1, 1, 0, 2]));
    let e = read_dng_bytes(&b.build())
        .unwrap()
        .bayer()
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a Bayer pattern"), "{e}");
    expect_err(
        &Builder::new(4, 4, 12)
            .set(50713, Value::Short(vec![0, 2]))
            .build(),
        "BlackLevelRepeatDim",
    );
}
