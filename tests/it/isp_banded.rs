//! The banded (fused) render equals the unfused whole-image reference bit for bit on the
//! committed fixtures and the real files of D2N_SHARED_DATA, for every demosaicer, every
//! orientation and with/without DefaultCrop; the PNG lookup quantizer equals the formula
//! on these renders.
use crate::common;

use crate::isp_opcodes_banded::whole;
use day2night::dng::read::read_dng;
use day2night::encode::png::{encode_u8, encode_u8_slow};
use day2night::isp::render::{render, Output, RenderOptions};
use day2night::isp::tone::DisplayTone;
use day2night::isp::{Demosaic, RgbImage};
use std::path::PathBuf;

fn bits(img: &RgbImage) -> (usize, usize, Vec<u32>) {
    (
        img.width,
        img.height,
        img.data.iter().map(|v| v.to_bits()).collect(),
    )
}

fn files() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(common::fixtures())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "dng"))
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no fixtures");
    // The real Canon file too, unless the real-camera files were absent at build time
    // (build.rs).
    if !cfg!(d2n_missing = "shared-data") {
        v.push(common::shared_file(
            "dng/canon_kissx4_magiclantern_rggb14_strips.dng",
        ));
    }
    v
}

#[test]
fn banded_render_equals_reference_on_real_files() {
    for f in files() {
        let img = read_dng(&f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let day = f.file_name().is_some_and(|n| n == "day.dng");
        for d in [Demosaic::Bilinear, Demosaic::Mhc] {
            // every orientation on day.dng, the file's own elsewhere (cost)
            let orients: Vec<Option<u16>> = if day {
                (1..=8).map(Some).collect()
            } else {
                vec![None]
            };
            for o in orients {
                let mut img = img.clone();
                if let Some(o) = o {
                    img.meta.orientation = o;
                }
                for crop in [true, false] {
                    let opts = RenderOptions {
                        demosaic: d,
                        crop,
                        ..RenderOptions::default()
                    };
                    let a = render(&img, &opts).unwrap();
                    let b = whole(&img, &opts).unwrap();
                    assert!(
                        bits(&a) == bits(&b),
                        "{} {d} orientation {o:?} crop {crop}: banded != reference",
                        f.display()
                    );
                    if crop && o.is_none_or(|o| o == 1 || o == 6) {
                        for t in [DisplayTone::Srgb, DisplayTone::Gamma22] {
                            assert_eq!(encode_u8(&a, t), encode_u8_slow(&a, t), "{t:?}");
                        }
                    }
                }
                let input = RenderOptions {
                    output: Output::Camera,
                    demosaic: d,
                    ..RenderOptions::default()
                };
                let a = render(&img, &input).unwrap();
                let b = whole(&img, &input).unwrap();
                assert!(bits(&a) == bits(&b), "{} {d} input", f.display());
            }
        }
    }
}
