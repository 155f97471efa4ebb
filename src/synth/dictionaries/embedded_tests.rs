use super::*;
use crate::synth::illuminant::{Covariance, Gaussian2};

// The paper's fitted figures (docs/synthesis.md, "4. Night illuminants").
const FIT_MEAN: [f64; 2] = [0.766125, 0.328891];
const FIT_COV_UNBIASED: [[f64; 2]; 2] = [[0.0288803, -0.0109222], [-0.0109222, 0.00489429]];

/// The noise file's `dn_table`, converted as docs/noise.md says, is its `isos` bit for bit
/// (the data files replaced Rust constants: commit 1b5aace checked them equal bit for bit).
#[test]
fn the_noise_file_isos_are_its_dn_table_converted() {
    let v: serde_json::Value = serde_json::from_str(PAPER_PHONE.noise_json).unwrap();
    let t = &v["dn_table"];
    let rows: Vec<(u32, usize, f64, f64)> = serde_json::from_value(t["rows"].clone()).unwrap();
    assert_eq!(rows.len(), 24);
    let (black, white) = (t["black"].as_f64().unwrap(), t["white"].as_f64().unwrap());
    assert_eq!((black, white), (64.0, 1023.0));
    let dn = paper_dn_table();
    assert_eq!((dn.black, dn.white, &dn.rows), (black, white, &rows));
    let c = paper();
    let mut from_dn =
        NoiseModel::from_dn_table(c.noise.source.clone(), &rows, black, white).unwrap();
    for (a, b) in c.noise.isos.iter().zip(&from_dn.isos) {
        for (pa, pb) in a.positions.iter().zip(&b.positions) {
            assert_eq!(pa.map(f64::to_bits), pb.map(f64::to_bits), "ISO {}", a.iso);
        }
    }
    from_dn.camera = c.noise.camera.clone();
    assert_eq!(c.noise, from_dn);
    assert_eq!(
        c.noise.source,
        "embedded paper phone (S20 FE) table, CVPR 2022 day-to-night release, CC BY-NC 4.0"
    );
}

#[test]
fn the_illuminant_file_reads_as_before() {
    let d = &paper().illuminants;
    assert_eq!(d.chromaticities.len(), 45);
    assert_eq!(d.chromaticities[0], [0.854492, 0.30957]);
    assert_eq!(d.chromaticities[44], [1.006081, 0.236071]);
    assert!(d.weights.is_empty());
    assert_eq!(
        d.name,
        "embedded paper phone (S20 FE) night gray-card dictionary"
    );
    assert_eq!(
        attribution(),
        "CVPR 2022 day-to-night release, CC BY-NC 4.0"
    );
}

#[test]
fn the_lookup_finds_the_phone_by_make_and_model_prefix() {
    let id = |make: &str, model: &str| CameraId::new(Some(make.into()), Some(model.into()), None);
    for (make, model) in [
        ("samsung", "SM-G780F"),
        ("SAMSUNG", "sm-g781b"),
        (" Samsung ", "SM-G781U1"),
    ] {
        assert_eq!(
            for_camera(&id(make, model)).map(|c| c.key),
            Some("samsung-s20fe")
        );
    }
    for (make, model) in [
        ("samsung", "SM-G991B"),
        ("Google", "SM-G780F"),
        ("samsung", "G780"),
    ] {
        assert!(for_camera(&id(make, model)).is_none(), "{make} {model}");
    }
    // Each embedded file names a camera the lookup recognizes.
    for c in all() {
        assert_eq!(
            for_camera(&c.illuminants_camera).map(|f| f.key),
            Some(c.key)
        );
        let noise_camera = c.noise.camera.as_ref().unwrap();
        assert_eq!(for_camera(noise_camera).map(|f| f.key), Some(c.key));
    }
}

#[test]
#[allow(clippy::needless_range_loop)]
fn fit_matches_spec_figures() {
    let g = Gaussian2::fit(&illuminants(), Covariance::Unbiased).unwrap();
    for i in 0..2 {
        assert!((g.mean[i] - FIT_MEAN[i]).abs() < 1e-6, "{:?}", g.mean);
        for j in 0..2 {
            assert!(
                (g.cov[i][j] - FIT_COV_UNBIASED[i][j]).abs() < 1e-7,
                "{:?}",
                g.cov
            );
        }
    }
    let ml = Gaussian2::fit(&illuminants(), Covariance::MaximumLikelihood).unwrap();
    assert!((ml.cov[0][0] * 45.0 / 44.0 - g.cov[0][0]).abs() < 1e-12);
}

#[test]
fn noise_table_loads() {
    let m = noise_model();
    assert_eq!(m.iso_range(), (100, 3200));
    assert_eq!(m.isos.len(), 6);
}
