//! Issue 26 point 7, "warps read only their source window": the warps of OpcodeList3 read
//! the image before them through a rolling window of strips (src/isp/opcodes/warp_window.rs).
//! The windowed render equals the whole-frame render bit for bit for each warp kind and for
//! several warps, any band (and strip) height, 1-3 threads, all eight orientations, with and
//! without DefaultCrop; on a tall (or, turned, wide) image it holds a small part of it; a
//! warp whose bands reach across the image falls back to the whole-image path and still
//! matches.

use crate::common;
use crate::dngbuild::Builder;
use crate::isp_opcodes_banded::{bits, frame, op, with_lists};
use crate::isp_opcodes_banded::{in_bands, whole};
use day2night::dng::opcodes::{
    encode_list, AreaSpec, Opcode, OpcodeKind, OpcodeList, WarpPlane, WarpPlane2,
};
use day2night::dng::read_dng;
use day2night::encode::exr::{standard_attributes, write_exr, ExrOptions};
use day2night::isp::render::{render, render_bands, resolve_neutral, RenderOptions};
use day2night::output::OutputPolicy;
use day2night::raw::RawImage;

fn area(planes: u32, bottom: u32, right: u32) -> AreaSpec {
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

fn rectilinear(kr: [f64; 4], kt: [f64; 2], center: [f64; 2]) -> OpcodeKind {
    OpcodeKind::WarpRectilinear {
        planes: vec![WarpPlane { kr, kt }],
        center,
    }
}

/// The list-3 cases: each warp kind (radial and tangential distortion, a zoom about an
/// off-centre point, a tangential shift; DNG warps have no rotation), and two warps with
/// in-place opcodes around them (on the 57 x 81 active area of `frame(61, 83)`).
fn cases() -> Vec<(&'static str, Vec<Opcode>)> {
    let mut kr = [0.0; 15];
    (kr[0], kr[1], kr[2], kr[5]) = (1.0, 0.02, -0.05, 0.01);
    let rect2 = OpcodeKind::WarpRectilinear2 {
        planes: vec![WarpPlane2 {
            kr,
            kt: [0.001, 0.0],
            valid: [0.1, 0.9],
        }],
        center: [0.5, 0.4],
        reciprocal: true,
    };
    let fish = OpcodeKind::WarpFisheye {
        planes: vec![
            [1.0, 0.05, 0.0, 0.0],
            [1.02, 0.05, 0.0, 0.0],
            [0.98, 0.05, 0.0, 0.0],
        ],
        center: [0.5, 0.5],
    };
    let poly = OpcodeKind::MapPolynomial {
        area: area(3, 0, 0),
        coefficients: vec![0.01, 0.9, 0.1],
    };
    let scale = OpcodeKind::ScalePerRow {
        area: area(3, 81, 57),
        scales: (0..81).map(|i| 0.9 + 0.001 * (i % 50) as f32).collect(),
    };
    vec![
        (
            "WarpRectilinear, radial and tangential",
            vec![op(rectilinear(
                [1.0, -0.08, 0.02, 0.0],
                [0.003, -0.002],
                [0.45, 0.6],
            ))],
        ),
        (
            "WarpRectilinear, a zoom about an off-centre point",
            vec![op(rectilinear(
                [1.06, 0.0, 0.0, 0.0],
                [0.0, 0.0],
                [0.2, 0.85],
            ))],
        ),
        (
            "WarpRectilinear, a strong tangential term (a shift that grows off the centre)",
            vec![op(rectilinear(
                [1.0, 0.0, 0.0, 0.0],
                [0.02, -0.03],
                [0.7, 0.3],
            ))],
        ),
        ("WarpRectilinear2, reciprocal", vec![op(rect2)]),
        ("WarpFisheye per plane", vec![op(poly.clone()), op(fish)]),
        (
            "two warps with in-place opcodes around them",
            vec![
                op(poly),
                op(rectilinear([1.0, 0.06, 0.0, 0.0], [0.0, 0.0], [0.3, 0.7])),
                op(scale),
                op(rectilinear(
                    [0.97, -0.04, 0.0, 0.0],
                    [0.0, 0.01],
                    [0.5, 0.5],
                )),
            ],
        ),
    ]
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

#[test]
fn windowed_warps_equal_the_whole_frame_render() {
    let (w, h) = (61usize, 83usize);
    let (aw, ah) = (w as f64 - 4.0, h as f64 - 2.0);
    for (name, list3) in cases() {
        let mut img = with_lists(frame(w, h), [vec![], vec![], list3]);
        for orientation in 1u16..=8 {
            img.meta.orientation = orientation;
            for crop in [false, true] {
                img.meta.default_crop_origin = crop.then_some([3.0, 1.0]);
                img.meta.default_crop_size = crop.then_some([aw - 5.0, ah - 6.0]);
                let opts = RenderOptions::default();
                let whole = whole(&img, &opts).unwrap();
                let what = format!("{name}, orientation {orientation}, crop {crop}");
                for band in [1, 4, 32, 33, 200] {
                    let (got, stats) = in_bands(&img, &opts, band, None)
                        .unwrap()
                        .unwrap_or_else(|| panic!("{what}: not banded"));
                    assert_eq!(bits(&got), bits(&whole), "{what}, bands of {band}");
                    assert!(!stats.fallback, "{what}, bands of {band}: {stats:?}");
                }
                for threads in 1..=3 {
                    let p = pool(threads);
                    let got = p.install(|| render(&img, &opts).unwrap());
                    assert_eq!(bits(&got), bits(&whole), "{what}, {threads} threads");
                    let bands = p
                        .install(|| {
                            render_bands(&img, &opts, |_, _| Ok(()), |_, _, rows| Ok(rows.to_vec()))
                        })
                        .unwrap()
                        .unwrap();
                    let rows: Vec<f32> = bands.bands.into_iter().flatten().collect();
                    assert_eq!(rows, whole.data, "{what}, streamed, {threads} threads");
                    // Bands of 3 lines: many strips shared and dropped across threads.
                    let (got, stats) = p
                        .install(|| in_bands(&img, &opts, 3, None))
                        .unwrap()
                        .unwrap();
                    assert_eq!(
                        bits(&got),
                        bits(&whole),
                        "{what}, bands of 3, {threads} threads"
                    );
                    assert!(!stats.fallback, "{what}, {threads} threads: {stats:?}");
                }
            }
        }
    }
}

/// A tall frame (or a wide one, turned: its bands are columns) with a usual distortion.
fn long(w: usize, h: usize, orientation: u16) -> RawImage {
    let warp = rectilinear([1.0, -0.05, 0.0, 0.0], [0.0005, 0.0], [0.5, 0.5]);
    let mut img = with_lists(frame(w, h), [vec![], vec![], vec![op(warp)]]);
    img.meta.orientation = orientation;
    img
}

#[test]
fn the_window_holds_a_small_part_of_a_long_image() {
    for (w, h, orientation) in [(40, 1200, 1), (40, 1200, 3), (1200, 40, 6), (1200, 40, 7)] {
        let img = long(w, h, orientation);
        let opts = RenderOptions::default();
        let whole = whole(&img, &opts).unwrap();
        // One thread makes the bands in order: the peak is the planned one.
        let (got, stats) = pool(1)
            .install(|| in_bands(&img, &opts, 8, None))
            .unwrap()
            .unwrap();
        assert_eq!(bits(&got), bits(&whole), "orientation {orientation}");
        assert!(!stats.fallback, "{stats:?}");
        assert!(stats.lines > 1000, "{stats:?}");
        assert!(stats.peak_lines <= stats.planned_lines, "{stats:?}");
        assert!(stats.planned_lines * 10 < stats.lines, "{stats:?}");
        assert!(stats.peak_lines > 0, "{stats:?}");
        // Three threads: a few bands more in flight, still a small part.
        let (got, stats) = pool(3)
            .install(|| in_bands(&img, &opts, 8, None))
            .unwrap()
            .unwrap();
        assert_eq!(bits(&got), bits(&whole));
        assert!(stats.peak_lines * 4 < stats.lines, "{stats:?}");
    }
}

#[test]
fn a_warp_reaching_across_the_image_falls_back_and_still_matches() {
    // A strong tangential term: the bands far from the centre read half the image.
    let (w, h) = (404, 602);
    let wild = rectilinear([1.0, 0.0, 0.0, 0.0], [0.0, 1.0], [0.5, 0.5]);
    let opts = RenderOptions::default();
    for orientation in [1u16, 3, 6, 8] {
        let mut img = with_lists(frame(w, h), [vec![], vec![], vec![op(wild.clone())]]);
        img.meta.orientation = orientation;
        let whole = whole(&img, &opts).unwrap();
        let (got, stats) = in_bands(&img, &opts, 32, None).unwrap().unwrap();
        assert!(stats.fallback, "orientation {orientation}: {stats:?}");
        assert!(stats.planned_lines > 256, "{stats:?}");
        assert_eq!(bits(&got), bits(&whole), "orientation {orientation}");
        let got = render(&img, &opts).unwrap();
        assert_eq!(
            bits(&got),
            bits(&whole),
            "orientation {orientation}, render"
        );
    }
    // More warps than the window path takes (8): the whole-image path, level by level.
    let nine: Vec<Opcode> = (0..9)
        .map(|i| {
            let k = 0.01 * (i as f64 - 4.0);
            op(rectilinear([1.0, k, 0.0, 0.0], [0.0, 0.0], [0.5, 0.5]))
        })
        .collect();
    for (n, fallback) in [(8, false), (9, true)] {
        let mut img = with_lists(frame(61, 83), [vec![], vec![], nine[..n].to_vec()]);
        img.meta.orientation = 6;
        let whole = whole(&img, &opts).unwrap();
        let (got, stats) = in_bands(&img, &opts, 7, None).unwrap().unwrap();
        assert_eq!(stats.fallback, fallback, "{n} warps: {stats:?}");
        assert_eq!(bits(&got), bits(&whole), "{n} warps");
    }
    // A usual warp over a window limit lowered to one line: the whole-image path, the same
    // pixels, every strip kept.
    for (name, list3) in cases() {
        for orientation in [1u16, 6] {
            let mut img = with_lists(frame(61, 83), [vec![], vec![], list3.clone()]);
            img.meta.orientation = orientation;
            let whole = whole(&img, &opts).unwrap();
            for threads in 1..=3 {
                let (got, stats) = pool(threads)
                    .install(|| in_bands(&img, &opts, 5, Some(1)))
                    .unwrap()
                    .unwrap();
                assert!(stats.fallback, "{name}: {stats:?}");
                assert!(stats.peak_lines >= stats.lines, "{name}: {stats:?}");
                assert_eq!(bits(&got), bits(&whole), "{name}, {orientation}, {threads}");
            }
        }
    }
}

/// `render` of a file with a warp, turned (Orientation 6), streams the EXR bytes of the
/// whole-frame render.
#[test]
fn render_of_a_turned_warp_writes_the_whole_frame_bytes() {
    let t = tempfile::tempdir().unwrap();
    let warp = rectilinear([1.0, -0.03, 0.0, 0.0], [0.0, 0.0], [0.5, 0.5]);
    let b = Builder::new(90, 70, 12)
        .opcode_list(
            3,
            encode_list(&OpcodeList {
                opcodes: vec![op(warp)],
            }),
        )
        .set(0x0112, day2night::tiff::value::Value::Short(vec![6]));
    let src = t.path().join("warp.dng");
    std::fs::write(&src, b.build()).unwrap();
    let img = read_dng(&src).unwrap();
    assert_eq!(img.meta.orientation, 6);
    let n = resolve_neutral(&img.meta, None).unwrap();
    let opts = RenderOptions {
        neutral: Some(n),
        ..RenderOptions::default()
    };
    let whole = whole(&img, &opts).unwrap();
    let got = t.path().join("got.exr");
    let o = common::cli("render", &src, &got, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut attrs = standard_attributes(&src, n);
    attrs.push(("day2night:demosaic".into(), "mhc".into()));
    attrs.push((
        "day2night:content".into(),
        "linear Rec.709/sRGB, D65".into(),
    ));
    let want = t.path().join("want.exr");
    let policy = OutputPolicy::default();
    write_exr(&whole, &want, &ExrOptions::default(), &attrs, &policy).unwrap();
    assert_eq!(std::fs::read(&got).unwrap(), std::fs::read(&want).unwrap());
}
