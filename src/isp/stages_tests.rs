//! The stage list drives every execution: `Stage::Probe`, a test-only sample stage (one
//! entry in `stages!` and one function, `probe`), runs in every execution of a render with
//! no other edit, and `Plan::finish` (a debug assertion every render makes) fails any
//! execution that leaves a stage of `STAGES` out.
use super::*;
use crate::dng::opcodes::{encode_list, AreaSpec, Opcode, OpcodeKind, OpcodeList};
use crate::isp::render::{
    render, render_bands, render_crop, render_with, CropSamples, Execution, RenderOptions,
};
use crate::isp::render_crop::CROP_MARGIN;
use crate::raw::crop::Crop;
use crate::raw::meta::LinearRaw;
use crate::raw::{Bayer, Levels, RawMeta, Rect};

#[test]
fn a_plan_names_the_stages_an_execution_left_out() {
    let img = RawImage {
        width: 4,
        height: 4,
        data: vec![100; 16],
        meta: RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0),
    };
    let opts = RenderOptions::default();
    let plan = Plan::new(&img, &opts).unwrap();
    assert_eq!(plan.missing(), STAGES.to_vec());
    plan.rows();
    assert_eq!(plan.ran(), vec![Stage::Colour]);
    plan.cfa(true).unwrap();
    assert!(plan.ran().contains(&Stage::Normalize));
    assert!(plan.ran().contains(&Stage::WhiteBalance));
    assert!(plan.ran().contains(&Stage::Probe));
    assert!(plan.missing().contains(&Stage::Demosaic));
    plan.opcodes();
    plan.demosaic();
    plan.geometry();
    assert!(plan.missing().is_empty());
    assert_eq!(plan.ran(), STAGES.to_vec());
    let names: std::collections::HashSet<&str> = STAGES.iter().map(|s| s.name()).collect();
    assert_eq!(names.len(), STAGES.len());
}

#[test]
fn the_sample_stages_run_in_list_order_between_two_stages() {
    let s = Samples::new([0.5, 1.0, 0.25]);
    // white balance (x 2 for red, x 4 for blue), then the clip
    assert_eq!(s.between(Stage::Normalize, Stage::Demosaic, 0.3f64, 0), 0.6);
    assert_eq!(s.between(Stage::Normalize, Stage::Demosaic, 0.3f64, 2), 1.0);
    assert_eq!(s.between(Stage::Opcodes2, Stage::Demosaic, 0.2f32, 1), 0.2);
    // nothing between the normalization and OpcodeList2, nor after the demosaic
    assert_eq!(s.between(Stage::Normalize, Stage::Opcodes2, 7.0f64, 0), 7.0);
    assert_eq!(
        s.between(Stage::Demosaic, Stage::Orientation, 7.0f32, 0),
        7.0
    );
    assert!(matches!(Stage::Probe.kind(), Kind::Sample(..)));
    let probe = STAGES.iter().position(|&s| s == Stage::Probe).unwrap();
    let demosaic = STAGES.iter().position(|&s| s == Stage::Demosaic).unwrap();
    assert!(probe < demosaic, "the probe runs before the demosaic");
}

fn area(bottom: u32, right: u32, planes: u32) -> AreaSpec {
    AreaSpec {
        top: 0,
        left: 0,
        bottom,
        right,
        plane: 0,
        planes,
        row_pitch: 1,
        col_pitch: 1,
    }
}

/// A `w x h` RGGB frame of hash noise with an inset active area, a DefaultCrop and a
/// turning orientation.
fn frame(w: usize, h: usize) -> RawImage {
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 16, 512.0, 65535.0);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
    meta.active_area = Some(Rect {
        top: 2,
        left: 3,
        bottom: h as u32,
        right: w as u32 - 1,
    });
    meta.orientation = 6;
    meta.default_crop_origin = Some([2.0, 1.0]);
    meta.default_crop_size = Some([w as f64 - 9.0, h as f64 - 6.0]);
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let data = (0..w * h)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (600 + s % 60000) as u16
        })
        .collect();
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

fn with_list(mut img: RawImage, list: usize, ops: Vec<OpcodeKind>) -> RawImage {
    let opcodes = ops.into_iter().map(|k| Opcode::new(k, 0)).collect();
    img.meta.opcode_lists[list] = Some(encode_list(&OpcodeList { opcodes }));
    img
}

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
        white: 65535.0,
    };
    m.linear_raw = Some(LinearRaw {
        samples_per_pixel: 3,
        black: vec![10.0, 20.0, 30.0],
        white: vec![65535.0; 3],
    });
    img.data = (0..w * h * 3).map(|i| (i * 7919 % 65536) as u16).collect();
    img
}

#[test]
fn a_stage_added_to_the_list_runs_in_every_execution() {
    let (w, h) = (40usize, 33usize);
    let (aw, ah) = (w as u32 - 4, h as u32 - 2);
    let scale = |a: AreaSpec| OpcodeKind::MapPolynomial {
        area: a,
        coefficients: vec![0.01, 0.9, 0.1],
    };
    let images = [
        ("plain", frame(w, h)),
        // OpcodeList2: the opcode paths around the stage-2 image
        (
            "list 2",
            with_list(frame(w, h), 1, vec![scale(area(ah, aw, 1))]),
        ),
        // OpcodeList3: the list-3 path (white balance taken out and put back)
        (
            "list 3",
            with_list(frame(w, h), 2, vec![scale(area(ah, aw, 3))]),
        ),
        ("LinearRaw", linear_raw(w, h)),
    ];
    for (name, img) in &images {
        for demosaic in [Demosaic::Mhc, Demosaic::Menon] {
            let opts = RenderOptions {
                demosaic,
                ..RenderOptions::default()
            };
            let want = render_with(img, &opts, Execution::WholeFrame)
                .unwrap()
                .unwrap();
            let bands = Execution::Bands {
                rows: 5,
                limit: None,
            };
            for how in Execution::ALL.into_iter().chain([bands]) {
                if let Some(got) = render_with(img, &opts, how).unwrap() {
                    assert!(got.stages.contains(&Stage::Probe), "{name} {how:?}");
                    assert_eq!(got.stages, STAGES.to_vec(), "{name} {how:?}");
                    assert_eq!(got.image, want.image, "{name} {how:?}");
                }
            }
            assert_eq!(render(img, &opts).unwrap(), want.image, "{name}");
            // band-wise and crop executions: `Plan::finish` asserts every stage ran
            let f = |_: usize, _: usize, rows: &[f32]| Ok(rows.to_vec());
            if let Some(b) = render_bands(img, &opts, |_, _| Ok(()), f).unwrap() {
                assert_eq!(b.bands.concat(), want.image.data, "{name}: bands");
            }
            let flat = RenderOptions {
                crop: false,
                orient: false,
                ..opts
            };
            let c = Crop {
                top: 6,
                left: 4,
                width: 12,
                height: 9,
            };
            let frame_crop = render_crop(img, &flat, &c, CropSamples::Frame).unwrap();
            assert_eq!((frame_crop.width, frame_crop.height), (12, 9), "{name}");
            if demosaic == Demosaic::Mhc && img.meta.linear_raw.is_none() {
                let outer = c.grown(CROP_MARGIN, aw as usize, ah as usize);
                let a = img.active_area();
                let mut plane = Vec::new();
                for r in outer.rows() {
                    let i = (r + a.top as usize) * img.width + a.left as usize + outer.left;
                    plane.extend_from_slice(&img.data[i..][..outer.width]);
                }
                let samples = CropSamples::Stored {
                    outer: &outer,
                    plane: &plane,
                };
                let stored = render_crop(img, &flat, &c, samples).unwrap();
                assert_eq!(stored, frame_crop, "{name}: stored crop");
            }
        }
    }
}
