//! The bounded opcode path (issue 26 points 6 and 7): the banded opcode render equals the
//! whole-frame render bit for bit (any band height, orientation, crop, 1-3 threads); opcodes
//! that change nothing are dropped and cost nothing; opcode work over the budget is refused
//! at planning, naming the list; `render` writes its EXR/PNG band by band with the bytes of
//! the whole-image writers; WarpRectilinear2 is parsed as the Adobe DNG SDK parses it.

use crate::common;
use crate::dngbuild::Builder;
use day2night::dng::opcodes::{
    encode_list, AreaSpec, GainMap, Opcode, OpcodeKind, OpcodeList, WarpPlane, WarpPlane2,
};
use day2night::dng::read_dng;
use day2night::encode::exr::{standard_attributes, write_exr, ExrOptions};
use day2night::encode::png::{write_png, PngOptions};
use day2night::isp::opcodes::warp_window::WindowStats;
use day2night::isp::opcodes::{prepare, OpcodeMode};
use day2night::isp::render::{
    render, render_bands, render_with, resolve_neutral, Execution, Output, RenderOptions, STAGES,
};
use day2night::isp::RgbImage;
use day2night::output::OutputPolicy;
use day2night::raw::{Bayer, RawImage, RawMeta, Rect};
use std::path::Path;

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

pub(crate) fn op(kind: OpcodeKind) -> Opcode {
    Opcode::new(kind, 0)
}

/// A `w x h` RGGB frame of hash noise with an inset active area; samples equal to 4000
/// (a FixBadPixelsConstant marker) sprinkled in, a clump of them too.
pub(crate) fn frame(w: usize, h: usize) -> RawImage {
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 16, 512.0, 65535.0);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
    meta.active_area = Some(Rect {
        top: 2,
        left: 3,
        bottom: h as u32,
        right: w as u32 - 1,
    });
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let data = (0..w * h)
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let (r, c) = (i / w, i % w);
            if s.is_multiple_of(61) || ((9..14).contains(&r) && (20..27).contains(&c)) {
                4000
            } else {
                (600 + (r * 97 + c * 31) % 9000 + (s % 3000) as usize) as u16
            }
        })
        .collect();
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

pub(crate) fn with_lists(mut img: RawImage, lists: [Vec<Opcode>; 3]) -> RawImage {
    for (i, l) in lists.into_iter().enumerate() {
        img.meta.opcode_lists[i] = (!l.is_empty()).then(|| encode_list(&OpcodeList { opcodes: l }));
    }
    img
}

fn gain_map(planes: u32) -> GainMap {
    let (pv, ph) = (4, 5);
    GainMap {
        area: area(0, 0, planes),
        points_v: pv,
        points_h: ph,
        spacing_v: 1.0 / (pv - 1) as f64,
        spacing_h: 1.0 / (ph - 1) as f64,
        origin_v: 0.0,
        origin_h: 0.0,
        map_planes: 1,
        gains: (0..pv * ph).map(|i| 1.0 + 0.05 * (i % 7) as f32).collect(),
    }
}

pub(crate) fn bits(img: &RgbImage) -> (usize, usize, Vec<u32>) {
    (
        img.width,
        img.height,
        img.data.iter().map(|v| v.to_bits()).collect(),
    )
}

/// The whole-frame execution's image (the reference every execution equals), which ran
/// every stage of the pipeline.
pub(crate) fn whole(img: &RawImage, opts: &RenderOptions) -> day2night::Result<RgbImage> {
    let r = render_with(img, opts, Execution::WholeFrame)?
        .ok_or_else(|| day2night::Error::invalid("the whole frame is always rendered"))?;
    assert_eq!(r.stages, STAGES.to_vec());
    Ok(r.image)
}

/// The execution in bands of `rows` output rows, a warp's window holding at most `limit`
/// lines: the image and what the window did; `None` when the render is not banded.
pub(crate) fn in_bands(
    img: &RawImage,
    opts: &RenderOptions,
    rows: usize,
    limit: Option<usize>,
) -> day2night::Result<Option<(RgbImage, WindowStats)>> {
    let r = render_with(img, opts, Execution::Bands { rows, limit })?;
    Ok(r.map(|r| {
        assert_eq!(r.stages, STAGES.to_vec());
        (r.image, r.window)
    }))
}

/// The lists of every case: local opcodes in lists 1-2, in-place list 3, and each warp.
pub(crate) fn cases(w: u32, h: u32) -> Vec<(&'static str, [Vec<Opcode>; 3])> {
    let bad_list = OpcodeKind::FixBadPixelsList {
        bayer_phase: 0,
        points: vec![[5, 5], [20, 31], [0, 0]],
        rects: vec![[10, 10, 12, 14], [h - 3, w - 6, h, w]],
    };
    let constant = OpcodeKind::FixBadPixelsConstant {
        constant: 4000,
        bayer_phase: 0,
    };
    let table = OpcodeKind::MapTable {
        area: area(0, 0, 1),
        table: (0..65536u32).map(|i| (i * 9 / 10) as u16).collect(),
    };
    let poly = OpcodeKind::MapPolynomial {
        area: area(h, w, 3),
        coefficients: vec![0.01, 0.9, 0.1],
    };
    let delta = OpcodeKind::DeltaPerRow {
        area: area(h, w, 3),
        deltas: (0..h).map(|i| (i % 5) as f32 * 30.0).collect(),
    };
    let vignette = OpcodeKind::FixVignetteRadial {
        k: [0.3, -0.1, 0.0, 0.0, 0.0],
        center: [0.4, 0.55],
    };
    let rect = OpcodeKind::WarpRectilinear {
        planes: vec![WarpPlane {
            kr: [1.0, -0.08, 0.02, 0.0],
            kt: [0.003, -0.002],
        }],
        center: [0.45, 0.6],
    };
    let fish = OpcodeKind::WarpFisheye {
        planes: vec![
            [1.0, 0.05, 0.0, 0.0],
            [1.02, 0.05, 0.0, 0.0],
            [0.98, 0.05, 0.0, 0.0],
        ],
        center: [0.5, 0.5],
    };
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
    vec![
        (
            "local opcodes in lists 1 and 2, in-place list 3",
            [
                vec![op(bad_list.clone()), op(constant.clone()), op(table)],
                vec![
                    op(OpcodeKind::GainMap(gain_map(1))),
                    op(bad_list),
                    op(vignette.clone()),
                ],
                vec![op(poly.clone()), op(OpcodeKind::GainMap(gain_map(3)))],
            ],
        ),
        (
            "repeated constant fixes (whole-stage lists)",
            [
                vec![
                    op(constant.clone()),
                    op(constant.clone()),
                    op(constant.clone()),
                ],
                vec![op(constant.clone()), op(constant)],
                vec![],
            ],
        ),
        (
            "WarpRectilinear between in-place opcodes",
            [
                vec![],
                vec![op(vignette)],
                vec![op(poly.clone()), op(rect), op(delta)],
            ],
        ),
        ("WarpFisheye per plane", [vec![], vec![], vec![op(fish)]]),
        (
            "WarpRectilinear2, reciprocal",
            [vec![], vec![], vec![op(poly), op(rect2)]],
        ),
    ]
}

#[test]
fn banded_opcode_render_equals_the_whole_frame_render() {
    let (w, h) = (67usize, 75usize);
    let (aw, ah) = (w as u32 - 4, h as u32 - 2);
    for (name, lists) in cases(aw, ah) {
        let mut img = with_lists(frame(w, h), lists);
        for orientation in [1u16, 3, 6, 8] {
            img.meta.orientation = orientation;
            for crop in [false, true] {
                img.meta.default_crop_origin = crop.then_some([3.0, 1.0]);
                img.meta.default_crop_size = crop.then_some([aw as f64 - 5.0, ah as f64 - 6.0]);
                let opts = RenderOptions::default();
                let whole = whole(&img, &opts).unwrap();
                assert_eq!(whole.count_non_finite(), 0);
                let what = format!("{name}, orientation {orientation}, crop {crop}");
                for band in [1, 5, 32, 33, 200] {
                    let got = in_bands(&img, &opts, band, None)
                        .unwrap()
                        .map(|(rgb, _)| rgb);
                    let got = got.unwrap_or_else(|| panic!("{what}: not banded"));
                    assert_eq!(bits(&got), bits(&whole), "{what}, bands of {band} rows");
                }
                for threads in 1..=3 {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    let got = pool.install(|| render(&img, &opts).unwrap());
                    assert_eq!(bits(&got), bits(&whole), "{what}, {threads} threads");
                    // the band-wise consumer (synth's targets, `render`) sees the same rows
                    let bands = pool
                        .install(|| {
                            render_bands(&img, &opts, |_, _| Ok(()), |_, _, rows| Ok(rows.to_vec()))
                        })
                        .unwrap()
                        .unwrap();
                    let rows: Vec<f32> = bands.bands.into_iter().flatten().collect();
                    assert_eq!(rows, whole.data, "{what}, bands, {threads} threads");
                }
            }
        }
    }
}

#[test]
fn no_op_opcodes_are_dropped_and_cost_nothing() {
    let identity = OpcodeKind::WarpRectilinear {
        planes: vec![WarpPlane {
            kr: [1.0, 0.0, 0.0, 0.0],
            kt: [0.0, 0.0],
        }],
        center: [0.5, 0.5],
    };
    let ones = OpcodeKind::ScalePerColumn {
        area: area(30, 8, 1),
        scales: vec![1.0; 8],
    };
    let img = with_lists(
        frame(40, 30),
        [vec![op(ones)], vec![], vec![op(identity); 4096]],
    );
    let p = prepare(&img.meta, OpcodeMode::Apply).unwrap().unwrap();
    assert!(p.is_noop(), "nothing left to apply");
    assert!(p.report.applied.is_empty());
    assert_eq!(p.report.dropped.len(), 4097);
    assert!(p.report.dropped[1]
        .reason
        .as_deref()
        .unwrap()
        .contains("identity warp"));
    assert!(p.costs((40, 30), (36, 28)).is_empty());
    // the render is the plain one, byte for byte
    let ignore = RenderOptions {
        opcodes: OpcodeMode::Ignore,
        ..RenderOptions::default()
    };
    let a = render(&img, &RenderOptions::default()).unwrap();
    let b = render(&img, &ignore).unwrap();
    assert_eq!(bits(&a), bits(&b));
    // a repeated FixBadPixelsList is dropped (a second pass writes the same means)
    let list = OpcodeKind::FixBadPixelsList {
        bayer_phase: 0,
        points: vec![[3, 3]],
        rects: vec![],
    };
    let img2 = with_lists(
        frame(40, 30),
        [vec![op(list.clone()), op(list)], vec![], vec![]],
    );
    let p = prepare(&img2.meta, OpcodeMode::Apply).unwrap().unwrap();
    assert_eq!(
        (
            p.list(day2night::dng::opcodes::ListId::List1).len(),
            p.report.dropped.len()
        ),
        (1, 1)
    );
}

fn write(dir: &Path, name: &str, b: &Builder) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, b.build()).unwrap();
    p
}

fn warps(n: usize, k1: f64) -> Vec<u8> {
    let w = OpcodeKind::WarpRectilinear {
        planes: vec![WarpPlane {
            kr: [1.0, k1, 0.0, 0.0],
            kt: [0.0, 0.0],
        }],
        center: [0.5, 0.5],
    };
    encode_list(&OpcodeList {
        opcodes: vec![op(w); n],
    })
}

#[test]
fn opcode_work_over_the_budget_is_refused_naming_the_list() {
    let t = tempfile::tempdir().unwrap();
    // The file: 4096 identity warps on 2048 x 1536 cost nothing and render like
    // the file without them; 4096 real warps are refused before any pixel work.
    let big = |list| Builder::new(2048, 1536, 12).opcode_list(3, list);
    let identity = write(t.path(), "identity.dng", &big(warps(4096, 0.0)));
    let real = write(t.path(), "real.dng", &big(warps(4096, 0.01)));
    let (a, b) = (t.path().join("a.exr"), t.path().join("b.exr"));
    let o = common::cli("render", &identity, &a, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = common::cli("render", &identity, &b, &["--opcodes", "ignore"]);
    assert!(o.status.success());
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let out = t.path().join("real.exr");
    for cmd in ["render", "synth"] {
        let o = common::cli(cmd, &real, &out, &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{cmd}: {err}");
        assert!(
            err.contains("real.dng")
                && err.contains("limit exceeded: OpcodeList3: its 4096 opcodes"),
            "{cmd}: {err}"
        );
        assert!(!out.exists());
    }
    // One opcode alone over a (lowered) budget is named with its position.
    let one = write(
        t.path(),
        "one.dng",
        &Builder::new(64, 48, 12).opcode_list(3, warps(1, 0.01)),
    );
    let o = common::bin()
        .args([
            "render".as_ref(),
            one.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .env("D2N_OPCODE_BUDGET", "1000")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("OpcodeList3: WarpRectilinear (opcode 1 of 1) alone costs"),
        "{err}"
    );
    // 4096 FixBadPixelsConstant on 512 x 384: within the budget, merged into one pass
    let fix = OpcodeKind::FixBadPixelsConstant {
        constant: 0,
        bayer_phase: 0,
    };
    let many = encode_list(&OpcodeList {
        opcodes: vec![op(fix); 4096],
    });
    let f = write(
        t.path(),
        "fix.dng",
        &Builder::new(512, 384, 12).opcode_list(1, many),
    );
    let o = common::cli("render", &f, &t.path().join("fix.exr"), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn render_streams_the_bytes_of_the_whole_image_writers() {
    let t = tempfile::tempdir().unwrap();
    let gm = OpcodeKind::GainMap(gain_map(1));
    let plain = Builder::new(70, 45, 12);
    let with_op = Builder::new(70, 45, 12).opcode_list(
        2,
        encode_list(&OpcodeList {
            opcodes: vec![op(gm)],
        }),
    );
    let policy = OutputPolicy::default();
    for (name, b) in [("plain", plain), ("gainmap", with_op)] {
        let src = write(t.path(), &format!("{name}.dng"), &b);
        let img = read_dng(&src).unwrap();
        let n = resolve_neutral(&img.meta, None).unwrap();
        for camera in [false, true] {
            let opts = RenderOptions {
                neutral: Some(n),
                ..RenderOptions::default()
            };
            let rgb = if camera {
                let camera = RenderOptions {
                    output: Output::Camera,
                    ..opts.clone()
                };
                render(&img, &camera).unwrap()
            } else {
                render(&img, &opts).unwrap()
            };
            let extra: &[&str] = if camera { &["--camera-rgb"] } else { &[] };
            // EXR
            let got = t.path().join(format!("{name}{camera}.exr"));
            let o = common::cli("render", &src, &got, extra);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let mut attrs = standard_attributes(&src, n);
            attrs.push(("day2night:demosaic".into(), "mhc".into()));
            let content = if camera {
                "white-balanced camera RGB (network input)"
            } else {
                "linear Rec.709/sRGB, D65"
            };
            attrs.push(("day2night:content".into(), content.into()));
            let want = t.path().join(format!("{name}{camera}-want.exr"));
            write_exr(&rgb, &want, &ExrOptions::default(), &attrs, &policy).unwrap();
            assert_eq!(
                std::fs::read(&got).unwrap(),
                std::fs::read(&want).unwrap(),
                "{name} {camera}"
            );
            // 8-bit PNG with a tone
            let got = t.path().join(format!("{name}{camera}.png"));
            let mut args = extra.to_vec();
            args.extend(["--tone", "gamma22"]);
            let o = common::cli("render", &src, &got, &args);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let want = t.path().join(format!("{name}{camera}-want.png"));
            let png = PngOptions {
                sixteen_bit: false,
                tone: "gamma22".parse().unwrap(),
            };
            write_png(&rgb, &want, &png, &policy).unwrap();
            assert_eq!(
                std::fs::read(&got).unwrap(),
                std::fs::read(&want).unwrap(),
                "{name} {camera} png"
            );
        }
    }
}

/// A WarpRectilinear2 as day2night writes it is read by the Adobe DNG SDK (whose parser
/// checks the parameter byte count and the valid radius range); one with a valid range the
/// SDK refuses is refused by day2night's parser too, naming the field.
#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn warp_rectilinear2_is_parsed_as_the_adobe_sdk_parses_it() {
    let t = tempfile::tempdir().unwrap();
    let mut kr = [0.0; 15];
    (kr[0], kr[3]) = (1.0, -0.02);
    let w2 = |valid: [f64; 2]| {
        encode_list(&OpcodeList {
            opcodes: vec![op(OpcodeKind::WarpRectilinear2 {
                planes: vec![WarpPlane2 {
                    kr,
                    kt: [0.0005, 0.0],
                    valid,
                }],
                center: [0.5, 0.5],
                reciprocal: false,
            })],
        })
    };
    let good = write(
        t.path(),
        "good.dng",
        &Builder::new(64, 48, 12).opcode_list(3, w2([0.0, 1.0])),
    );
    let bad = write(
        t.path(),
        "bad.dng",
        &Builder::new(64, 48, 12).opcode_list(3, w2([0.5, 0.4])),
    );
    let img = read_dng(&good).unwrap();
    let p = prepare(&img.meta, OpcodeMode::Apply).unwrap().unwrap();
    assert_eq!(p.report.applied[0].name, "WarpRectilinear2");
    let out = t.path().join("good.exr");
    let o = common::cli("render", &good, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = common::bin()
        .args(["info".as_ref(), good.as_os_str()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("WarpRectilinear2 (id 14") && text.contains("valid r 0..1"),
        "{text}"
    );
    let e = read_dng(&bad)
        .and_then(|i| prepare(&i.meta, OpcodeMode::Apply))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("OpcodeList3: WarpRectilinear2 (opcode 1 of 1)") && e.contains("valid radius"),
        "{e}"
    );
    let py = common::python();
    let o = common::run_validator(&py, "sdk_accepts.py", &[good.as_os_str(), bad.as_os_str()]);
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2, "{}", String::from_utf8_lossy(&o.stderr));
    // The SDK's "Too little padding" warnings are about the tiny frame's borders.
    let complaints = |v: &serde_json::Value| -> Vec<String> {
        v["messages"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m.as_str().unwrap().to_string())
            .filter(|m| !m.contains("Too little padding"))
            .collect()
    };
    assert!(
        complaints(&lines[0]).is_empty(),
        "the SDK refused our WarpRectilinear2: {}",
        lines[0]
    );
    assert!(
        !complaints(&lines[1]).is_empty(),
        "the SDK accepted a bad valid range: {}",
        lines[1]
    );
}
