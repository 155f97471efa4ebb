//! DNG opcodes applied by the ISP (docs/isp.md, "DNG opcodes"): a GainMap undoes a falloff
//! divided into the stored values; a WarpRectilinear moves bright dots where its formula
//! says; OpcodeList1 acts on stored values before linearization; `--opcodes ignore` gives
//! the plain render's bytes; unknown optional opcodes warn and mandatory ones fail; a
//! GainMap written by the Adobe DNG SDK (dngpy) renders as the gains say.
use crate::common;
use crate::dngbuild::Builder;

use day2night::dng::opcodes::{
    encode_list, AreaSpec, GainMap, Opcode, OpcodeKind, OpcodeList, WarpPlane, FLAG_OPTIONAL,
};
use day2night::dng::read_dng;
use day2night::isp::opcodes::{gain_map, warp, OpcodeMode, StageRect};
use day2night::isp::render::{render, RenderOptions};
use day2night::isp::RgbImage;
use day2night::raw::{Bayer, RawImage, RawMeta};

fn whole(w: u32, h: u32) -> AreaSpec {
    AreaSpec {
        top: 0,
        left: 0,
        bottom: h,
        right: w,
        plane: 0,
        planes: 1,
        row_pitch: 1,
        col_pitch: 1,
    }
}

/// A radial falloff map: gain 1 in the middle, `1 + k` in the corners.
fn falloff_map(w: u32, h: u32, pv: u32, ph: u32, k: f32) -> GainMap {
    let gains = (0..pv * ph)
        .map(|i| {
            let v = (i / ph) as f32 / (pv - 1) as f32 * 2.0 - 1.0;
            let u = (i % ph) as f32 / (ph - 1) as f32 * 2.0 - 1.0;
            1.0 + k * (v * v + u * u) / 2.0
        })
        .collect();
    GainMap {
        area: whole(w, h),
        points_v: pv,
        points_h: ph,
        spacing_v: 1.0 / (pv - 1) as f64,
        spacing_h: 1.0 / (ph - 1) as f64,
        origin_v: 0.0,
        origin_h: 0.0,
        map_planes: 1,
        gains,
    }
}

/// A smooth 16-bit RGGB scene (linear values 0.05 .. 0.3 of the range).
fn scene(w: usize, h: usize) -> RawImage {
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 16, 512.0, 65535.0);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
    let range = 65535.0 - 512.0;
    let data = (0..w * h)
        .map(|i| {
            let (r, c) = (i / w, i % w);
            let x = c as f64 / w as f64;
            let y = r as f64 / h as f64;
            let col = Bayer::RGGB.color_at(r, c) as usize;
            let base = [0.08, 0.15, 0.1][col];
            let v = base + 0.1 * (3.0 * x).sin().abs() * y + 0.05 * x;
            (512.0 + v * range).round() as u16
        })
        .collect();
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

fn with_lists(mut img: RawImage, lists: [Vec<Opcode>; 3]) -> RawImage {
    for (i, l) in lists.into_iter().enumerate() {
        img.meta.opcode_lists[i] = (!l.is_empty()).then(|| encode_list(&OpcodeList { opcodes: l }));
    }
    img
}

fn raw_opts(mode: OpcodeMode) -> RenderOptions {
    RenderOptions {
        crop: false,
        orient: false,
        opcodes: mode,
        ..RenderOptions::default()
    }
}

/// Relative errors of `a` against `b` over samples of `b` above 0.01, sorted.
fn rel_errors(a: &RgbImage, b: &RgbImage) -> Vec<f64> {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let mut e: Vec<f64> = a
        .data
        .iter()
        .zip(&b.data)
        .filter(|(_, &y)| y > 0.01)
        .map(|(&x, &y)| ((x - y) / y).abs() as f64)
        .collect();
    e.sort_by(|x, y| x.total_cmp(y));
    e
}

#[test]
fn gain_map_undoes_a_falloff_divided_into_the_stored_values() {
    let (w, h) = (96usize, 64usize);
    let flat = scene(w, h);
    let map = falloff_map(w as u32, h as u32, 9, 11, 1.6); // 2.6x in the corners
    let gm = gain_map::Prepared::new(&map, StageRect::of_size(w, h));
    // stored' = black + (stored - black) / gain
    let mut shaded = flat.clone();
    for r in 0..h {
        for c in 0..w {
            let x = flat.data[r * w + c] as f64 - 512.0;
            shaded.data[r * w + c] = (512.0 + x / gm.gain(r, c, 0) as f64).round() as u16;
        }
    }
    let shaded = with_lists(
        shaded,
        [
            vec![],
            vec![Opcode::new(OpcodeKind::GainMap(map), 0)],
            vec![],
        ],
    );
    let want = render(&flat, &raw_opts(OpcodeMode::Apply)).unwrap();
    let got = render(&shaded, &raw_opts(OpcodeMode::Apply)).unwrap();
    assert_eq!(got.count_non_finite(), 0);
    let e = rel_errors(&got, &want);
    let (med, max) = (e[e.len() / 2], e[e.len() - 1]);
    assert!(med < 0.002 && max < 0.01, "median {med}, max {max}");
    // ignored, the falloff stays: corners are far off
    let off = render(&shaded, &raw_opts(OpcodeMode::Ignore)).unwrap();
    let e = rel_errors(&off, &want);
    assert!(e[e.len() * 95 / 100] > 0.3, "p95 {}", e[e.len() * 95 / 100]);
}

#[test]
fn warp_rectilinear_moves_dots_where_the_formula_says() {
    let (w, h) = (160usize, 120usize);
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 16, 0.0, 65535.0);
    meta.as_shot_neutral = Some([1.0, 1.0, 1.0]);
    let bg = 0.05;
    let mut data = vec![(bg * 65535.0) as u16; w * h];
    let mut dots = vec![];
    for gy in 0..4 {
        for gx in 0..5 {
            let (py, px) = (24 + gy * 24, 24 + gx * 28);
            dots.push((py as f64, px as f64));
            for r in py - 2..=py + 2 {
                for c in px - 2..=px + 2 {
                    data[r * w + c] = (0.6 * 65535.0) as u16;
                }
            }
        }
    }
    let kr = [1.0, 0.2, 0.0, 0.0];
    let kt = [0.002, -0.001];
    let img = with_lists(
        RawImage {
            width: w,
            height: h,
            data,
            meta,
        },
        [
            vec![],
            vec![],
            vec![Opcode::new(
                OpcodeKind::WarpRectilinear {
                    planes: vec![WarpPlane { kr, kt }],
                    center: [0.5, 0.5],
                },
                0,
            )],
        ],
    );
    let out = render(&img, &raw_opts(OpcodeMode::Apply)).unwrap();
    assert_eq!((out.width, out.height), (w, h));
    let model = warp::Warp::new(
        vec![warp::Model::Rectilinear { kr, kt }],
        [0.5, 0.5],
        StageRect::of_size(w, h),
        3,
    )
    .unwrap();
    let luma = |x: usize, y: usize| out.pixel(x, y).map_or(0.0, |p| p.iter().sum::<f32>());
    let floor = luma(2, 2);
    let mut moved = 0.0f64;
    for &(py, px) in &dots {
        // destination d with source(d) = p, by fixed-point iteration
        let (mut dy, mut dx) = (py, px);
        for _ in 0..100 {
            let (sy, sx) = model.source(0, dy, dx);
            dy += py - sy;
            dx += px - sx;
        }
        let (cy, cx) = (dy.round() as i64, dx.round() as i64);
        let (mut sw, mut sy, mut sx) = (0.0f64, 0.0f64, 0.0f64);
        for y in cy - 6..=cy + 6 {
            for x in cx - 6..=cx + 6 {
                if x < 0 || y < 0 {
                    continue;
                }
                let v = (luma(x as usize, y as usize) - floor).max(0.0) as f64;
                sw += v;
                sy += v * y as f64;
                sx += v * x as f64;
            }
        }
        assert!(sw > 0.0, "dot at ({py},{px}) vanished");
        let (my, mx) = (sy / sw, sx / sw);
        assert!(
            (my - dy).abs() < 1.0 && (mx - dx).abs() < 1.0,
            "dot ({py},{px}): expected at ({dy:.2},{dx:.2}), centroid ({my:.2},{mx:.2})"
        );
        moved = moved.max((dy - py).abs().max((dx - px).abs()));
    }
    // the corner dots really moved (by more than the tolerance)
    assert!(moved > 2.0, "largest move {moved}");
}

#[test]
fn list1_acts_on_stored_values_before_the_black_level() {
    let (w, h) = (40usize, 30usize);
    let base = scene(w, h);
    // MapPolynomial y = 100 + 0.9 x on the stored values (list 1), and a ScalePerColumn
    // of 1.1 on every other column of the linear values (list 2)
    let poly = Opcode::new(
        OpcodeKind::MapPolynomial {
            area: whole(w as u32, h as u32),
            coefficients: vec![100.0, 0.9],
        },
        0,
    );
    let scale = Opcode::new(
        OpcodeKind::ScalePerColumn {
            area: AreaSpec {
                col_pitch: 2,
                ..whole(w as u32, h as u32)
            },
            scales: vec![1.1; w.div_ceil(2)],
        },
        0,
    );
    let with = with_lists(base.clone(), [vec![poly], vec![scale], vec![]]);
    let mut pre = base.clone();
    let black = 512.0;
    let range = 65535.0 - black;
    for r in 0..h {
        for c in 0..w {
            let x = (100.0 + 0.9 * base.data[r * w + c] as f64).round();
            let lin = ((x - black) / range).max(0.0);
            let lin = if c % 2 == 0 { lin * 1.1 } else { lin };
            pre.data[r * w + c] = (black + lin * range).round() as u16;
        }
    }
    let a = render(&with, &raw_opts(OpcodeMode::Apply)).unwrap();
    let b = render(&pre, &raw_opts(OpcodeMode::Apply)).unwrap();
    let e = rel_errors(&a, &b);
    assert!(e[e.len() - 1] < 2e-4, "max {}", e[e.len() - 1]);
}

#[test]
fn degenerate_maps_give_finite_renders() {
    let (w, h) = (12usize, 10usize);
    for gains in [vec![0.0f32], vec![1e30], vec![f32::NAN]] {
        let mut map = falloff_map(w as u32, h as u32, 2, 2, 0.0);
        map.points_v = 1;
        map.points_h = 1;
        map.gains = gains.clone();
        let img = with_lists(
            scene(w, h),
            [
                vec![],
                vec![Opcode::new(OpcodeKind::GainMap(map), 0)],
                vec![],
            ],
        );
        let out = match render(&img, &RenderOptions::default()) {
            Ok(o) => o,
            Err(e) => {
                // the parser refuses non-finite gains, naming them
                assert!(gains[0].is_nan() && e.to_string().contains("NaN"), "{e}");
                continue;
            }
        };
        assert_eq!(out.count_non_finite(), 0, "{gains:?}");
        if gains[0] == 0.0 {
            assert!(out.data.iter().all(|&v| v == 0.0));
        }
    }
}

#[test]
fn ignore_gives_the_plain_bytes_and_apply_changes_them() {
    let t = tempfile::tempdir().unwrap();
    let (w, h) = (32usize, 24usize);
    let map = falloff_map(w as u32, h as u32, 3, 3, 1.0);
    let list = OpcodeList {
        opcodes: vec![Opcode::new(OpcodeKind::GainMap(map), 0)],
    };
    let (da, db) = (t.path().join("a"), t.path().join("b"));
    std::fs::create_dir_all(&da).unwrap();
    std::fs::create_dir_all(&db).unwrap();
    let with = da.join("x.dng");
    let without = db.join("x.dng");
    std::fs::write(
        &with,
        Builder::new(w, h, 12)
            .opcode_list(2, encode_list(&list))
            .build(),
    )
    .unwrap();
    std::fs::write(&without, Builder::new(w, h, 12).build()).unwrap();
    for ext in ["exr", "png"] {
        let o1 = da.join(format!("ign.{ext}"));
        let o2 = db.join(format!("plain.{ext}"));
        let o3 = da.join(format!("app.{ext}"));
        for (i, o, x) in [
            (&with, &o1, vec!["--opcodes", "ignore"]),
            (&without, &o2, vec![]),
            (&with, &o3, vec![]),
        ] {
            let r = common::cli("render", i, o, &x);
            assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        }
        let (a, b, c) = (
            std::fs::read(&o1).unwrap(),
            std::fs::read(&o2).unwrap(),
            std::fs::read(&o3).unwrap(),
        );
        assert_eq!(a, b, "{ext}: --opcodes ignore = the file without lists");
        assert_ne!(a, c, "{ext}: the GainMap is applied by default");
    }
    let r = common::cli(
        "render",
        &with,
        &da.join("bad.exr"),
        &["--opcodes", "maybe"],
    );
    assert!(!r.status.success());
}

#[test]
fn unknown_optional_opcodes_warn_and_mandatory_ones_fail() {
    let t = tempfile::tempdir().unwrap();
    let unknown = |flags| Opcode {
        id: 99,
        dng_version: [1, 3, 0, 0],
        flags,
        kind: OpcodeKind::Unknown {
            params: vec![1, 2, 3, 4],
            len: 4,
        },
    };
    let f1 = t.path().join("opt.dng");
    let l = OpcodeList {
        opcodes: vec![unknown(FLAG_OPTIONAL)],
    };
    std::fs::write(
        &f1,
        Builder::new(16, 12, 12)
            .opcode_list(3, encode_list(&l))
            .build(),
    )
    .unwrap();
    let r = common::cli("render", &f1, &t.path().join("a.exr"), &[]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("warning") && err.contains("OpcodeList3: unknown (id 99)"),
        "{err}"
    );
    let f2 = t.path().join("mand.dng");
    let l = OpcodeList {
        opcodes: vec![unknown(0)],
    };
    std::fs::write(
        &f2,
        Builder::new(16, 12, 12)
            .opcode_list(2, encode_list(&l))
            .build(),
    )
    .unwrap();
    let out = t.path().join("b.exr");
    let r = common::cli("render", &f2, &out, &[]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        err.contains("mand.dng") && err.contains("OpcodeList2: unknown (id 99)"),
        "{err}"
    );
    assert!(!out.exists(), "no half-written output");
    // ignoring the lists renders it
    let r = common::cli("render", &f2, &out, &["--opcodes", "ignore"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // synth: the plan records the skipped one; a mandatory one fails a render unless
    // ignored (without a render it only warns: tests/it/isp_opcode_checks.rs)
    let o = t.path().join("s");
    let r = common::cli("synth", &f1, &o, &["--iso", "none", "--target", "none"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let sc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.join("opt.json")).unwrap()).unwrap();
    assert_eq!(sc["report"]["opcodes"]["skipped"][0]["list"], "OpcodeList3");
    assert_eq!(sc["report"]["opcodes"]["skipped"][0]["id"], 99);
    let r = common::bin()
        .arg("synth")
        .arg(&f2)
        .arg("-o")
        .arg(t.path().join("s2"))
        .args(["--iso", "none", "--target", "exr"])
        .output()
        .unwrap();
    assert!(!r.status.success());
    let r = common::bin()
        .arg("synth")
        .arg(&f2)
        .arg("-o")
        .arg(t.path().join("s3"))
        .args(["--iso", "none", "--target", "none", "--compat", "release"])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // info says what synth would do: ready with the skip as a warning, or not usable.
    let info = |f: &std::path::Path| {
        let r = common::bin().arg("info").arg(f).output().unwrap();
        String::from_utf8_lossy(&r.stdout).into_owned()
    };
    let i1 = info(&f1);
    assert!(
        i1.contains("ready, with warnings") && i1.contains("OpcodeList3: unknown (id 99)"),
        "{i1}"
    );
    let i2 = info(&f2);
    assert!(!i2.contains("ready"), "{i2}");
    assert!(i2.contains("OpcodeList2: unknown (id 99)"), "{i2}");
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn adobe_sdk_gain_map_renders_as_its_gains_say() {
    let py = common::python();
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let src = t.path().join("shaded.dng");
    let out = common::run_validator(
        &py,
        "make_gainmap_dng.py",
        &[
            "make".as_ref(),
            day.as_os_str(),
            src.as_os_str(),
            "--rows".as_ref(),
            "9".as_ref(),
            "--cols".as_ref(),
            "11".as_ref(),
        ],
    );
    assert!(
        out.status.success(),
        "make_gainmap_dng.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let plain = read_dng(&day).unwrap();
    let shaded = read_dng(&src).unwrap();
    assert_eq!(plain.data, shaded.data, "the SDK keeps the stored values");
    let [_, l2, _] = day2night::dng::opcodes::lists(&shaded.meta).unwrap();
    let OpcodeKind::GainMap(map) = &l2.opcodes[0].kind else {
        panic!("no GainMap")
    };
    let a = plain.active_area();
    let gm = gain_map::Prepared::new(map, StageRect::of_size(a.width(), a.height()));
    let p = render(&plain, &raw_opts(OpcodeMode::Apply)).unwrap();
    let s = render(&shaded, &raw_opts(OpcodeMode::Apply)).unwrap();
    // shaded render / plain render = the gain, where neither clips
    let mut e = vec![];
    for y in 0..p.height {
        for x in 0..p.width {
            let (pp, sp) = (p.pixel(x, y).unwrap(), s.pixel(x, y).unwrap());
            let g = gm.gain(y, x, 0) as f64;
            for k in 0..3 {
                if pp[k] > 0.02 && sp[k] < 0.98 && pp[k] * (g as f32) < 0.98 {
                    e.push(((sp[k] / pp[k]) as f64 / g - 1.0).abs());
                }
            }
        }
    }
    e.sort_by(|a, b| a.total_cmp(b));
    assert!(e.len() > 1000);
    let (med, p95) = (e[e.len() / 2], e[e.len() * 95 / 100]);
    assert!(med < 0.01 && p95 < 0.03, "median {med}, p95 {p95}");
}

#[test]
fn opcode_renders_are_identical_for_any_thread_count() {
    let (w, h) = (70usize, 50usize);
    let img = with_lists(
        scene(w, h),
        [
            vec![Opcode::new(
                OpcodeKind::FixBadPixelsList {
                    bayer_phase: 0,
                    points: vec![[5, 5], [20, 31]],
                    rects: vec![[10, 10, 12, 14]],
                },
                0,
            )],
            vec![Opcode::new(
                OpcodeKind::GainMap(falloff_map(w as u32, h as u32, 4, 5, 1.0)),
                0,
            )],
            vec![Opcode::new(
                OpcodeKind::WarpRectilinear {
                    planes: vec![WarpPlane {
                        kr: [1.0, -0.04, 0.0, 0.0],
                        kt: [0.0, 0.0],
                    }],
                    center: [0.4, 0.6],
                },
                0,
            )],
        ],
    );
    for d in day2night::isp::Demosaic::ALL {
        let opts = RenderOptions {
            demosaic: d,
            ..RenderOptions::default()
        };
        let a = render(&img, &opts).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| render(&img, &opts).unwrap());
        assert_eq!(a, b, "{d}");
        assert_eq!(a.count_non_finite(), 0);
    }
}
