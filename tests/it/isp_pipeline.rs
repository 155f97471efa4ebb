//! One render pipeline (docs/isp.md, "The pipeline"): every execution of a render (the
//! whole frame, bands of any height, the band-wise consumer, a crop from its own samples or
//! from the frame's) runs every stage of `STAGES` and makes the pixels of the whole-frame
//! execution, bit for bit, on a plain CFA image, one with each case of opcodes and a
//! LinearRaw image, for the linear render and the network input.
use crate::isp_opcodes_banded::{bits, cases, frame, with_lists};
use day2night::isp::render::{
    render_bands, render_crop, render_with, CropSamples, Execution, Output, RenderOptions, STAGES,
};
use day2night::isp::render_crop::CROP_MARGIN;
use day2night::isp::{Demosaic, RgbImage};
use day2night::raw::crop::Crop;
use day2night::raw::meta::LinearRaw;
use day2night::raw::{Levels, RawImage};

/// A LinearRaw image of `w x h` (three samples per pixel) with a DefaultCrop and a
/// turning orientation.
fn linear_raw(w: usize, h: usize) -> RawImage {
    let mut img = frame(w, h);
    let m = &mut img.meta;
    m.cfa.rows = 0;
    m.cfa.cols = 0;
    m.cfa.pattern.clear();
    m.levels = Levels {
        black_repeat: (1, 1),
        black: vec![10.0],
        black_delta_h: vec![],
        black_delta_v: vec![],
        white: 4095.0,
    };
    m.linear_raw = Some(LinearRaw {
        samples_per_pixel: 3,
        black: vec![10.0, 20.0, 30.0],
        white: vec![4095.0; 3],
    });
    img.data = (0..w * h * 3).map(|i| (i * 7919 % 4096) as u16).collect();
    img
}

fn images() -> Vec<(String, RawImage)> {
    let (w, h) = (45usize, 38usize);
    // frame(): the active area is inset by 3 columns and 2 rows, one column off the right
    let (aw, ah) = (w as u32 - 4, h as u32 - 2);
    let mut v = vec![("plain".to_string(), frame(w, h))];
    for (name, lists) in cases(aw, ah) {
        v.push((name.to_string(), with_lists(frame(w, h), lists)));
    }
    v.push(("LinearRaw".to_string(), linear_raw(w, h)));
    for (_, img) in &mut v {
        img.meta.orientation = 6;
        img.meta.default_crop_origin = Some([2.0, 1.0]);
        img.meta.default_crop_size = Some([f64::from(aw) - 5.0, f64::from(ah) - 4.0]);
    }
    v
}

#[test]
fn every_execution_runs_every_stage_and_makes_the_same_pixels() {
    // Execution::ALL holds every kind of execution (a new variant fails to compile here).
    let kind = |how: Execution| match how {
        Execution::Auto => "auto",
        Execution::WholeFrame => "whole frame",
        Execution::Bands { .. } => "bands",
    };
    let kinds: std::collections::HashSet<&str> = Execution::ALL.into_iter().map(kind).collect();
    assert_eq!(kinds.len(), 3);
    let odd = Execution::Bands {
        rows: 7,
        limit: Some(3),
    };
    for (name, img) in images() {
        for output in [Output::Linear, Output::Camera] {
            for demosaic in [Demosaic::Mhc, Demosaic::Menon] {
                let what = format!("{name}, {output:?}, {demosaic}");
                let opts = RenderOptions {
                    output,
                    demosaic,
                    ..RenderOptions::default()
                };
                let want = render_with(&img, &opts, Execution::WholeFrame)
                    .unwrap()
                    .unwrap();
                assert_eq!(want.stages, STAGES.to_vec(), "{what}: whole frame");
                assert_eq!(want.image.count_non_finite(), 0, "{what}");
                let mut made = 0;
                for how in Execution::ALL.into_iter().chain([odd]) {
                    match render_with(&img, &opts, how).unwrap() {
                        Some(got) => {
                            assert_eq!(got.stages, STAGES.to_vec(), "{what}: {how:?}");
                            assert_eq!(bits(&got.image), bits(&want.image), "{what}: {how:?}");
                            made += 1;
                        }
                        // Bands are not possible with Menon, a TrimBounds or a LinearRaw image.
                        None => assert!(matches!(how, Execution::Bands { .. }), "{what}: {how:?}"),
                    }
                }
                let banded = demosaic == Demosaic::Mhc && name != "LinearRaw";
                assert_eq!(made, if banded { 4 } else { 2 }, "{what}");
                let f = |_: usize, _: usize, rows: &[f32]| Ok(rows.to_vec());
                match render_bands(&img, &opts, |_, _| Ok(()), f).unwrap() {
                    Some(b) => assert_eq!(b.bands.concat(), want.image.data, "{what}: bands"),
                    None => assert!(!banded, "{what}: not band-wise"),
                }
            }
        }
    }
}

/// The rectangle `c` of `img`.
fn region(img: &RgbImage, c: &Crop) -> Vec<u32> {
    let mut v = Vec::new();
    for y in c.rows() {
        let row = &img.data[3 * (y * img.width + c.left)..][..3 * c.width];
        v.extend(row.iter().map(|x| x.to_bits()));
    }
    v
}

#[test]
fn a_crop_is_the_region_of_the_whole_frame() {
    // even offsets: a crop keeps the CFA phase
    let crop = Crop {
        top: 4,
        left: 6,
        height: 13,
        width: 20,
    };
    for (name, img) in images() {
        for output in [Output::Linear, Output::Camera] {
            let what = format!("{name}, {output:?}");
            let opts = RenderOptions {
                output,
                crop: false,
                orient: false,
                ..RenderOptions::default()
            };
            let whole = render_with(&img, &opts, Execution::WholeFrame)
                .unwrap()
                .unwrap();
            let want = region(&whole.image, &crop);
            let got = render_crop(&img, &opts, &crop, CropSamples::Frame).unwrap();
            assert_eq!((got.width, got.height), (crop.width, crop.height), "{what}");
            assert_eq!(bits(&got).2, want, "{what}: from the frame");
            if name == "LinearRaw" {
                continue;
            }
            // From the crop's own samples (and the demosaicer's margin).
            let a = img.active_area();
            let (aw, ah) = (a.width(), a.height());
            let outer = crop.grown(CROP_MARGIN, aw, ah);
            let plane: Vec<u16> = outer
                .rows()
                .flat_map(|r| {
                    let i = (r + a.top as usize) * img.width + a.left as usize;
                    img.data[i + outer.left..i + outer.left + outer.width].to_vec()
                })
                .collect();
            let stored = CropSamples::Stored {
                outer: &outer,
                plane: &plane,
            };
            match render_crop(&img, &opts, &crop, stored) {
                Ok(got) => assert_eq!(bits(&got).2, want, "{what}: from its samples"),
                Err(e) => assert!(
                    e.to_string().contains("need the whole frame"),
                    "{what}: {e}"
                ),
            }
        }
        // A crop is made before DefaultCrop and orientation.
        let on = RenderOptions::default();
        let e = render_crop(&img, &on, &crop, CropSamples::Frame).unwrap_err();
        assert!(
            e.to_string().contains("turn crop and orient off"),
            "{name}: {e}"
        );
    }
}
