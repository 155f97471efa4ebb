//! The stage list drives every execution: `Stage::Probe` (a sample stage before the
//! demosaic) and `Stage::ProbeRgb` (a sample stage after it), test-only, each one entry in
//! `stages!` and one function (`probe`, `probe_rgb`), run in every execution of a render
//! with no other edit; every public render goes through the driver (`drive`), whose log shows the
//! walk and the stages it ran; the driver refuses a list its walks cannot run in order.
use super::*;
use crate::dng::opcodes::{encode_list, AreaSpec, Opcode, OpcodeKind, OpcodeList, WarpPlane};
use crate::isp::demosaic::Demosaic;
use crate::isp::drive::{check_order, DRIVEN};
use crate::isp::render::{
    render, render_bands, render_crop, render_with, CropSamples, Execution, RenderOptions,
};
use crate::isp::render_crop::CROP_MARGIN;
use crate::isp::rgb::RgbImage;
use crate::raw::crop::Crop;
use crate::raw::meta::LinearRaw;
use crate::raw::{Bayer, Levels, RawImage, RawMeta, Rect};

#[test]
fn the_list_is_one_every_walk_runs_in_order() {
    check_order(STAGES).unwrap();
    let names: std::collections::HashSet<&str> = STAGES.iter().map(|s| s.name()).collect();
    assert_eq!(names.len(), STAGES.len());
    use Stage::*;
    let walked = [Opcodes1, Normalize, Opcodes2, Demosaic, Opcodes3];
    let geometry = [DefaultCrop, Orientation];
    let list = |middle: &[Stage]| -> Vec<Stage> {
        walked
            .iter()
            .chain(middle)
            .chain(&geometry)
            .copied()
            .collect()
    };
    check_order(&list(&[Colour, ProbeRgb])).unwrap();
    // a sample stage between the demosaic and OpcodeList3, a row stage before OpcodeList3,
    // a sample stage on the stored values: no walk can run them in that order
    let mut before3 = list(&[Colour]);
    before3.insert(4, Probe);
    let mut colour_early = list(&[]);
    colour_early.insert(3, Colour);
    let mut stored = list(&[Colour]);
    stored.insert(0, Probe);
    for bad in [before3, colour_early, stored] {
        let e = check_order(&bad).unwrap_err().to_string();
        assert!(e.contains("where no execution can run it"), "{bad:?}: {e}");
    }
    // a walked stage out of order or missing
    let mut swapped = list(&[Colour]);
    swapped.swap(6, 7);
    assert!(check_order(&swapped).is_err());
    let mut missing = list(&[Colour]);
    missing.retain(|&s| s != Demosaic);
    assert!(check_order(&missing).is_err());
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
    let at = |x: Stage| STAGES.iter().position(|&s| s == x).unwrap();
    assert!(at(Stage::Probe) < at(Stage::Demosaic));
    assert!(at(Stage::ProbeRgb) > at(Stage::Colour));
}

/// Sets the test stages' factors for this thread while alive (1 again when dropped).
struct Factor;

impl Factor {
    fn set(f: [f64; 2]) -> Factor {
        PROBE.with(|p| p.set(f));
        Factor
    }
}

impl Drop for Factor {
    fn drop(&mut self) {
        PROBE.with(|p| p.set([1.0; 2]));
    }
}

/// `f()`, and the renders it drove: the walks' names (each ran every stage of the list).
fn driven<T>(f: impl FnOnce() -> T) -> (T, Vec<&'static str>) {
    DRIVEN.with(|d| d.borrow_mut().clear());
    let out = f();
    let log = DRIVEN.with(|d| std::mem::take(&mut *d.borrow_mut()));
    for (walk, stages) in &log {
        assert_eq!(stages, &STAGES.to_vec(), "{walk}");
    }
    (out, log.into_iter().map(|(w, _)| w).collect())
}

#[test]
fn rows_run_a_sample_stage_listed_after_the_demosaic() {
    let _f = Factor::set([1.0, 0.5]);
    let rows = Rows::new(Colour::Clip, Samples::new([1.0; 3]));
    let mut row = [0.5f32, 2.0, -1.0, 0.25, 0.75, 1.0];
    rows.run(&mut row);
    // clipped to [0, 1] by the colour stage, then halved by `ProbeRgb`
    assert_eq!(row, [0.25, 0.5, 0.0, 0.125, 0.375, 0.5]);
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

fn bits(img: &RgbImage) -> Vec<u32> {
    img.data.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn a_stage_added_to_the_list_runs_in_every_execution() {
    let (w, h) = (40usize, 33usize);
    let (aw, ah) = (w as u32 - 4, h as u32 - 2);
    let scale = |a: AreaSpec| OpcodeKind::MapPolynomial {
        area: a,
        coefficients: vec![0.01, 0.9, 0.1],
    };
    let warp = OpcodeKind::WarpRectilinear {
        planes: vec![WarpPlane {
            kr: [1.0, -0.08, 0.02, 0.0],
            kt: [0.003, -0.002],
        }],
        center: [0.45, 0.6],
    };
    let bad_pixels = OpcodeKind::FixBadPixelsList {
        bayer_phase: 0,
        points: vec![[5, 5], [20, 31]],
        rects: vec![[10, 10, 12, 14]],
    };
    // (name, image, whether a crop renders from its own samples: pointwise opcodes only)
    let images = [
        ("plain", frame(w, h), true),
        // OpcodeList1 and OpcodeList2: the opcode paths around the stage-2 image
        (
            "list 1",
            with_list(frame(w, h), 0, vec![scale(area(h as u32, w as u32, 1))]),
            true,
        ),
        (
            "list 2",
            with_list(frame(w, h), 1, vec![scale(area(ah, aw, 1))]),
            true,
        ),
        (
            "bad pixels",
            with_list(frame(w, h), 1, vec![bad_pixels]),
            false,
        ),
        // OpcodeList3: the list-3 path (white balance taken out and put back), and a warp
        // (its rolling window in bands)
        (
            "list 3",
            with_list(frame(w, h), 2, vec![scale(area(ah, aw, 3))]),
            true,
        ),
        ("warp", with_list(frame(w, h), 2, vec![warp]), false),
        ("LinearRaw", linear_raw(w, h), false),
    ];
    for (name, img, stored) in &images {
        for demosaic in [Demosaic::Mhc, Demosaic::Menon] {
            let opts = RenderOptions {
                demosaic,
                ..RenderOptions::default()
            };
            let whole = || {
                render_with(img, &opts, Execution::WholeFrame)
                    .unwrap()
                    .unwrap()
            };
            let plain = whole();
            for factors in [[0.5, 1.0], [1.0, 0.5]] {
                let _f = Factor::set(factors);
                every_execution(name, img, &opts, &plain.image, *stored);
            }
        }
    }
}

/// `img` rendered through every execution with the factors set (a crop from its samples if
/// `stored`): each drove every stage and made the whole frame's pixels, which the probes
/// changed from `plain`.
fn every_execution(
    name: &str,
    img: &RawImage,
    opts: &RenderOptions,
    plain: &RgbImage,
    stored: bool,
) {
    let (w, h) = (img.width, img.height);
    let (aw, ah) = (w - 4, h - 2);
    let bands = Execution::Bands {
        rows: 5,
        limit: None,
    };
    let demosaic = opts.demosaic;
    let name = &format!("{name} {demosaic} {:?}", PROBE.with(|p| p.get()));
    let whole = || {
        render_with(img, opts, Execution::WholeFrame)
            .unwrap()
            .unwrap()
    };
    let (want, walks) = driven(whole);
    assert_eq!(walks, ["whole frame"], "{name}");
    // the probe halves the samples before the demosaic, or the output after it
    assert!(bits(&want.image) != bits(plain), "{name}: the probe ran");
    for how in Execution::ALL.into_iter().chain([bands]) {
        let (got, walks) = driven(|| render_with(img, opts, how).unwrap());
        assert_eq!(walks.len(), 1, "{name} {how:?}");
        if let Some(got) = got {
            assert_eq!(got.stages, STAGES.to_vec(), "{name} {how:?}");
            assert!(bits(&got.image) == bits(&want.image), "{name} {how:?}");
        }
    }
    let (auto, walks) = driven(|| render(img, opts).unwrap());
    assert!(bits(&auto) == bits(&want.image), "{name}: automatic");
    assert_eq!(walks, ["automatic"], "{name}");
    let f = |_: usize, _: usize, rows: &[f32]| Ok(rows.to_vec());
    let (b, walks) = driven(|| render_bands(img, opts, |_, _| Ok(()), f).unwrap());
    if let Some(b) = b {
        assert_eq!(walks, ["band-wise"], "{name}");
        assert!(b.bands.concat() == want.image.data, "{name}: bands");
    }
    let flat = RenderOptions {
        crop: false,
        orient: false,
        ..opts.clone()
    };
    let c = Crop {
        top: 6,
        left: 4,
        width: 12,
        height: 9,
    };
    let (frame_crop, walks) = driven(|| render_crop(img, &flat, &c, CropSamples::Frame).unwrap());
    assert_eq!(walks, ["frame crop"], "{name}");
    let whole_flat = render_with(img, &flat, Execution::WholeFrame)
        .unwrap()
        .unwrap()
        .image;
    let mut region = Vec::new();
    for r in c.rows() {
        let i = 3 * (r * whole_flat.width + c.left);
        region.extend_from_slice(&whole_flat.data[i..][..3 * c.width]);
    }
    assert!(frame_crop.data == region, "{name}: frame crop");
    if demosaic == Demosaic::Mhc && stored {
        let outer = c.grown(CROP_MARGIN, aw, ah);
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
        let (stored, walks) = driven(|| render_crop(img, &flat, &c, samples).unwrap());
        assert_eq!(walks, ["stored crop"], "{name}");
        assert!(stored == frame_crop, "{name}: stored crop");
    }
}
