//! The three calibration files drive `synth` through its CLI: it accepts them, echoes the
//! fitted illuminant Gaussian and brightness in the sidecar, and writes the calibrated noise
//! model into the noisy DNG's NoiseProfile.
use crate::args;
use crate::calibrate_support;
use crate::common;

use calibrate_support::*;
use day2night::raw::Bayer;
use serde_json::Value;
use std::ffi::OsString;

#[test]
fn synth_accepts_calibrated_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Gray cards: three flat cards under known lights.
    let mut a = args!["calibrate", "illuminants"];
    for (i, (rg, bg)) in [(0.85, 0.31), (0.56, 0.44), (1.08, 0.21)]
        .iter()
        .enumerate()
    {
        let data: Vec<u16> = (0..64 * 64)
            .map(|k| {
                let c = Bayer::RGGB.color_at(k / 64, k % 64);
                (256.0 + 1500.0 * [*rg, 1.0, *bg][c as usize]) as u16
            })
            .collect();
        a.push(
            write(
                d,
                &format!("card{i}.dng"),
                &frame(64, 64, data, 256.0, 4095.0, 100),
            )
            .into(),
        );
    }
    let ill = d.join("ill.json");
    a.extend(args!["-o", &ill]);
    assert_eq!(run_os(&a).0, 0);
    // Brightness: two night frames.
    let mut a = args!["calibrate", "brightness"];
    for (i, v) in [300u16, 400].iter().enumerate() {
        a.push(
            write(
                d,
                &format!("n{i}.dng"),
                &frame(64, 64, vec![*v; 4096], 256.0, 4095.0, 3200),
            )
            .into(),
        );
    }
    let br = d.join("b.json");
    a.extend(args!["-o", &br]);
    assert_eq!(run_os(&a).0, 0);
    // Noise: one small burst at ISO 1600.
    let mut a = args!["calibrate", "noise", "--burst"];
    a.extend(
        burst(
            d,
            "b",
            4,
            (256, 128),
            (64.0, 1023.0),
            (2.4e-3, 1.03e-5),
            1600,
            3,
        )
        .into_iter()
        .map(OsString::from),
    );
    let nm = d.join("noise.json");
    a.extend(args!["-o", &nm]);
    let (code, _, err) = run_os(&a);
    assert_eq!(code, 0, "{err}");

    let day = common::fixtures().join("day.dng");
    let out = d.join("out");
    let (code, _, err) = run_os(&args![
        "synth",
        &day,
        "-o",
        &out,
        "--illuminants",
        &ill,
        "--brightness",
        &br,
        "--noise-model",
        &nm,
        "--iso",
        "1600",
        "--target",
        "none"
    ]);
    assert_eq!(code, 0, "{err}");
    let side: Value =
        serde_json::from_slice(&std::fs::read(out.join("day.json")).unwrap()).unwrap();
    let ill_doc: Value = serde_json::from_slice(&std::fs::read(&ill).unwrap()).unwrap();
    let br_doc: Value = serde_json::from_slice(&std::fs::read(&br).unwrap()).unwrap();
    let cal = &side["calibration"];
    // The cards are another camera's (day2night Synthetic, not the fixture's): their xy go
    // through the fixture's matrices (docs/calibration.md).
    assert_eq!(cal["provenance"]["illuminants"]["source"], "file_xy");
    assert_eq!(cal["illuminants"]["count"], ill_doc["count"]);
    // Recorded as the fixture's own camera, the file's fit is what synth samples.
    let mut own = ill_doc.clone();
    own["camera"] = serde_json::json!({"make": "day2night", "model": "Fixture Camera",
        "unique_camera_model": "day2night Fixture Camera"});
    let own_path = d.join("own.json");
    std::fs::write(&own_path, own.to_string()).unwrap();
    let out2 = d.join("out2");
    let (code, _, err) = run_os(&args![
        "synth",
        &day,
        "-o",
        &out2,
        "--illuminants",
        &own_path,
        "--iso",
        "none",
        "--target",
        "none"
    ]);
    assert_eq!(code, 0, "{err}");
    let side2: Value =
        serde_json::from_slice(&std::fs::read(out2.join("day.json")).unwrap()).unwrap();
    let cal2 = &side2["calibration"];
    assert_eq!(
        cal2["provenance"]["illuminants"]["source"],
        "file_camera_rgb"
    );
    assert_eq!(cal2["illuminants"]["mean"], ill_doc["fit"]["mean"]);
    assert_eq!(cal2["illuminants"]["cov"], ill_doc["fit"]["covariance"]);
    assert_eq!(cal["brightness"]["mean"], br_doc["fit"]["mean"]);
    assert_eq!(cal["brightness"]["std"], br_doc["fit"]["std"]);
    // The noisy DNG's NoiseProfile is the calibrated model (per colour plane).
    let noisy = day2night::dng::read_dng(&out.join("day_iso1600.dng")).unwrap();
    let model = day2night::noise::model::NoiseModel::from_file(&nm).unwrap();
    let want = model
        .at(1600)
        .unwrap()
        .params
        .to_dng_profile(noisy.bayer().unwrap());
    let got = noisy.meta.noise_profile.clone().unwrap();
    for (g, w) in got.iter().zip(&want) {
        assert!(
            (g.0 / w.0 - 1.0).abs() < 1e-9 && (g.1 / w.1 - 1.0).abs() < 1e-9,
            "{got:?} vs {want:?}"
        );
    }
}
