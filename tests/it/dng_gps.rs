//! The GPS IFD of a capture is carried into every DNG day2night writes (`convert` and the
//! night raws of `synth`), checked by tifffile and exiftool (tests/validators/dng_gps.py) and
//! by the Adobe DNG SDK / rawpy / OpenImageIO checks of tests/validators/dng_check.py.
use crate::common;

use day2night::dng::read::read_dng;
use day2night::dng::write::{write_dng, WriteOptions};
use day2night::output::OutputPolicy;
use day2night::tiff::value::{Entry, Value};
use std::path::Path;

/// 48 deg 51' 29.40" N, 2 deg 17' 40.20" E, 35.5 m.
const LAT: f64 = 48.0 + 51.0 / 60.0 + 29.4 / 3600.0;
const LON: f64 = 2.0 + 17.0 / 60.0 + 40.2 / 3600.0;
const ALT: f64 = 35.5;

fn gps_entries() -> Vec<Entry> {
    let e = |tag, value| Entry { tag, value };
    vec![
        e(0, Value::Byte(vec![2, 3, 0, 0])),
        e(1, Value::Ascii(b"N\0".to_vec())),
        e(2, Value::Rational(vec![(48, 1), (51, 1), (2940, 100)])),
        e(3, Value::Ascii(b"E\0".to_vec())),
        e(4, Value::Rational(vec![(2, 1), (17, 1), (4020, 100)])),
        e(5, Value::Byte(vec![0])),
        e(6, Value::Rational(vec![(71, 2)])),
        e(29, Value::Ascii(b"2026:11:22\0".to_vec())),
    ]
}

fn validate(src: &Path, files: &[&Path]) {
    let py = common::python();
    for f in files {
        let o = std::process::Command::new(&py)
            .arg(common::root().join("tests/validators/dng_gps.py"))
            .arg(f)
            .args([LAT.to_string(), LON.to_string(), ALT.to_string()])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "dng_gps.py {}:\n{text}{}",
            f.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        eprint!("{text}");
    }
    let o = std::process::Command::new(&py)
        .arg(common::root().join("tests/validators/dng_check.py"))
        .arg(src)
        .args(files)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "dng_check.py:\n{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
#[cfg_attr(
    d2n_missing = "exiftool",
    ignore = "needs exiftool (D2N_ALLOW_MISSING)"
)]
fn gps_ifd_is_carried_by_convert_and_synth() {
    let et = common::exiftool();
    let t = tempfile::tempdir().unwrap();
    let mut img = read_dng(&common::fixtures().join("day.dng")).unwrap();
    assert!(img.meta.gps.is_empty(), "the fixture has no GPS IFD");
    img.meta.gps = gps_entries();
    let with_gps = t.path().join("gps.dng");
    write_dng(
        &img,
        &with_gps,
        &WriteOptions::default(),
        &OutputPolicy::default(),
    )
    .unwrap();
    let back = read_dng(&with_gps).unwrap();
    assert_eq!(back.meta.gps, gps_entries());

    // `info` reports it (text and JSON); a file without GPS has no GPS line
    let o = common::bin().arg("info").arg(&with_gps).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stdout).contains("GPS:           8 entries"));
    let o = common::bin()
        .args(["info", "--json"])
        .arg(&with_gps)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["raw"]["meta"]["gps_entries"], 8, "{v}");
    let o = common::bin()
        .arg("info")
        .arg(common::fixtures().join("day.dng"))
        .output()
        .unwrap();
    assert!(!String::from_utf8_lossy(&o.stdout).contains("GPS"));

    // convert and synth keep it
    let conv = t.path().join("conv.dng");
    let o = common::bin()
        .args(["convert"])
        .arg(&with_gps)
        .arg(&conv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = t.path().join("night");
    let o = common::bin()
        .arg("synth")
        .arg(&with_gps)
        .arg("-o")
        .arg(&out)
        .args(["--iso", "1600", "--target", "none"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (clean, noisy) = (out.join("gps_clean.dng"), out.join("gps_iso1600.dng"));
    for f in [&conv, &clean, &noisy] {
        assert_eq!(
            read_dng(f).unwrap().meta.gps,
            gps_entries(),
            "{}",
            f.display()
        );
    }
    validate(&with_gps, &[&with_gps, &conv]);
    validate(&with_gps, &[]);
    // the night raws: GPS checked (their pixels differ from the source by design)
    let py = common::python();
    for f in [&clean, &noisy] {
        let o = std::process::Command::new(&py)
            .arg(common::root().join("tests/validators/dng_gps.py"))
            .arg(f)
            .args([LAT.to_string(), LON.to_string(), ALT.to_string()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    }

    // A file without GPS gets no GPS IFD (and the same bytes as before: fixtures test).
    let plain = t.path().join("plain.dng");
    let img = read_dng(&common::fixtures().join("day.dng")).unwrap();
    write_dng(
        &img,
        &plain,
        &WriteOptions::default(),
        &OutputPolicy::default(),
    )
    .unwrap();
    assert!(read_dng(&plain).unwrap().meta.gps.is_empty());

    // exiftool -validate: the GPS IFD adds no warning
    {
        let warnings = |f: &Path| -> Vec<String> {
            let o = std::process::Command::new(&et)
                .args(["-validate", "-warning", "-a", "-s3"])
                .arg(f)
                .output()
                .unwrap();
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .map(str::to_string)
                .filter(|l| !l.is_empty())
                .collect()
        };
        let base = warnings(&plain);
        for f in [&with_gps, &clean] {
            let extra: Vec<_> = warnings(f)
                .into_iter()
                .filter(|w| !base.contains(w))
                .collect();
            assert!(extra.is_empty(), "{}: {extra:?}", f.display());
        }
    }
}
