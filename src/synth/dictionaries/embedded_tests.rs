use super::*;
use crate::synth::illuminant::{Covariance, Gaussian2};

// The constants the data files replaced (commit history), kept for the equality check.
const FIT_MEAN: [f64; 2] = [0.766125, 0.328891];
/// Unbiased (1/(M-1)) covariance of [`ILLUMINANTS`] (docs/synthesis.md, "4. Night illuminants").
const FIT_COV_UNBIASED: [[f64; 2]; 2] = [[0.0288803, -0.0109222], [-0.0109222, 0.00489429]];

/// The 45 night gray-card chromaticities [r/g, b/g] of the paper's phone.
const ILLUMINANTS: [[f64; 2]; 45] = [
    [0.854492, 0.30957],
    [0.766602, 0.316406],
    [0.674805, 0.333008],
    [0.628906, 0.37207],
    [0.832031, 0.303711],
    [0.557881, 0.443906],
    [1.082051, 0.205791],
    [0.72168, 0.333008],
    [0.630893, 0.392225],
    [0.87207, 0.293945],
    [0.666016, 0.356445],
    [0.583984, 0.381836],
    [0.553924, 0.420325],
    [0.761719, 0.329102],
    [0.899414, 0.311523],
    [0.821289, 0.295898],
    [0.701172, 0.328125],
    [0.610352, 0.368164],
    [1.080346, 0.20415],
    [0.560436, 0.470782],
    [1.085083, 0.202093],
    [0.770508, 0.288086],
    [0.769531, 0.303711],
    [0.803711, 0.289062],
    [0.87207, 0.321289],
    [0.623047, 0.353516],
    [0.869141, 0.326172],
    [0.630859, 0.366211],
    [0.782227, 0.290039],
    [0.583008, 0.413086],
    [0.849609, 0.326172],
    [1.213149, 0.202283],
    [0.554904, 0.467324],
    [0.743164, 0.288086],
    [0.714844, 0.321289],
    [0.553984, 0.467623],
    [1.144439, 0.183128],
    [0.704102, 0.319336],
    [0.727539, 0.332031],
    [0.924805, 0.291016],
    [0.712146, 0.339185],
    [0.575435, 0.426956],
    [0.668945, 0.333984],
    [0.733213, 0.342339],
    [1.006081, 0.236071],
];

/// Noise table of the paper's phone: (ISO, 2x2 position, beta1, beta2), DN, x incl. black.
const NOISE_TABLE_DN: [(u32, usize, f64, f64); 24] = [
    (100, 0, 0.1419234149084682, -8.890307111076448),
    (100, 1, 0.14010851348394535, -8.684474895126055),
    (100, 2, 0.13982037914173523, -8.685826036688809),
    (100, 3, 0.1418040808370286, -8.868374099147276),
    (200, 0, 0.28459846397296595, -17.99830279350811),
    (200, 1, 0.2842019999864774, -17.908969030282638),
    (200, 2, 0.28228803918683115, -17.791730955968337),
    (200, 3, 0.2840307985544278, -17.913387024217805),
    (400, 0, 0.5645075071356364, -35.755209362962496),
    (400, 1, 0.5623994898053915, -35.57701376873653),
    (400, 2, 0.5584229215509176, -35.23834418320569),
    (400, 3, 0.5631269260866636, -35.62237948220208),
    (800, 0, 1.1212485582585008, -69.87470804123991),
    (800, 1, 1.1213600816123324, -69.79704865646038),
    (800, 2, 1.1139926392926753, -69.33176850507408),
    (800, 3, 1.119083971640854, -69.49979993675758),
    (1600, 0, 2.2435579560800636, -134.13813652456366),
    (1600, 1, 2.2318542023898225, -132.79735744428996),
    (1600, 2, 2.212563286375087, -131.45865250865327),
    (1600, 3, 2.233160798965846, -132.7768160221999),
    (3200, 0, 4.292001197640824, -234.9049461133207),
    (3200, 1, 4.216130811900908, -228.34061839150064),
    (3200, 2, 4.185857471741983, -226.2369996301509),
    (3200, 3, 4.295593457145119, -235.7195457993698),
];
/// Black level of the noise table.
const NOISE_BLACK: f64 = 64.0;
/// White level of the noise table.
const NOISE_WHITE: f64 = 1023.0;

#[test]
fn the_data_files_decode_to_the_former_constants_bit_for_bit() {
    let c = paper();
    assert_eq!(c.illuminants.chromaticities, ILLUMINANTS.to_vec());
    assert!(c.illuminants.weights.is_empty());
    assert_eq!(
        c.illuminants.name,
        "embedded paper phone (S20 FE) night gray-card dictionary"
    );
    assert_eq!(
        c.illuminants.source,
        "CVPR 2022 day-to-night release, CC BY-NC 4.0"
    );
    let mut old = NoiseModel::from_dn_table(
        "embedded paper phone (S20 FE) table, CVPR 2022 day-to-night release, CC BY-NC 4.0",
        &NOISE_TABLE_DN,
        NOISE_BLACK,
        NOISE_WHITE,
    )
    .unwrap();
    for (a, b) in c.noise.isos.iter().zip(&old.isos) {
        for (pa, pb) in a.positions.iter().zip(&b.positions) {
            assert_eq!(pa.map(f64::to_bits), pb.map(f64::to_bits), "ISO {}", a.iso);
        }
    }
    old.camera = c.noise.camera.clone();
    assert_eq!(c.noise, old);
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
