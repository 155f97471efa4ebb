//! Demosaic accuracy on scikit-image's sample photographs, mosaicked in all four Bayer
//! phases: CPSNR (all three channels, data range 1, an 8-pixel border excluded) per method.
//! The default run checks one photo in one phase; the slow test (ignored by default, run by
//! `scripts/test.sh --slow`) checks all of them and prints the markdown table of
//! docs/isp.md.
use crate::common;

use day2night::encode::read::read_image;
use day2night::isp::demosaic::{demosaic, mosaic, Demosaic};
use day2night::isp::RgbImage;
use day2night::raw::Bayer;

fn cpsnr(a: &RgbImage, b: &RgbImage, border: usize) -> f64 {
    let mut se = 0.0f64;
    let mut n = 0usize;
    for y in border..a.height - border {
        for x in border..a.width - border {
            for c in 0..3 {
                let i = 3 * (y * a.width + x) + c;
                let d = a.data[i] as f64 - b.data[i] as f64;
                se += d * d;
                n += 1;
            }
        }
    }
    10.0 * (1.0 / (se / n as f64)).log10()
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn demosaic_accuracy_on_one_sample_photo() {
    accuracy(false);
}

#[test]
#[ignore = "slow: every sample photo in every phase (scripts/test.sh --slow)"]
fn slow_demosaic_accuracy_on_every_sample_photo() {
    accuracy(true);
}

/// CPSNR per method on the first photo in RGGB, or (`slow`) on every photo in every phase.
fn accuracy(slow: bool) {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    let out = common::run_validator(&py, "isp_skimage_photos.py", &[dir.path().as_os_str()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let listing = String::from_utf8_lossy(&out.stdout).to_string();
    let names: Vec<&str> = listing
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(names.len() >= 4, "{listing}");
    let names = if slow { names } else { vec![names[0]] };
    let phases: Vec<Bayer> = if slow {
        Bayer::ALL.to_vec()
    } else {
        vec![Bayer::RGGB]
    };
    println!("| photo | size | bilinear | mhc | menon |");
    println!("|---|---|---|---|---|");
    let mut totals = [0.0f64; 3];
    for name in &names {
        let img = read_image(&dir.path().join(format!("{name}.png")))
            .unwrap()
            .image;
        let mut per = [0.0f64; 3];
        for &bayer in &phases {
            let m = mosaic(&img, bayer);
            for (k, method) in Demosaic::ALL.iter().enumerate() {
                let out = demosaic(&m, img.width, img.height, bayer, *method).unwrap();
                per[k] += cpsnr(&out, &img, 8) / phases.len() as f64;
            }
        }
        println!(
            "| {name} | {}x{} | {:.2} | {:.2} | {:.2} |",
            img.width, img.height, per[0], per[1], per[2]
        );
        for k in 0..3 {
            totals[k] += per[k] / names.len() as f64;
        }
        // the quality order the literature reports (bilinear < MHC < Menon), on every photo
        assert!(
            per[1] > per[0] + 0.5 && per[2] > per[1] + 0.5,
            "{name}: {per:?}"
        );
    }
    println!(
        "| mean | | {:.2} | {:.2} | {:.2} |",
        totals[0], totals[1], totals[2]
    );
}
