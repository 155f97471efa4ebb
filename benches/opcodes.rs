//! Cost of each DNG opcode in the render of a generated 12 MP (4000x3000) RGGB frame: the
//! default render (MHC) with one opcode at a time against the plain render and against the
//! opcode path with a near no-op (ScalePerRow of 1.0001 on one row: a scale of exactly 1 is
//! dropped before the render since issue 26, which then takes the plain path), runs
//! interleaved, median of
//! `D2N_BENCH_RUNS` (default 5) wall times. Run: `cargo bench --bench opcodes`.
use day2night::dng::opcodes::{
    encode_list, AreaSpec, GainMap, Opcode, OpcodeKind, OpcodeList, WarpPlane, WarpPlane2,
};
use day2night::isp::render::{render, RenderOptions};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use std::hint::black_box;
use std::time::Instant;

const W: usize = 4000;
const H: usize = 3000;

fn frame() -> RawImage {
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 12, 64.0, 4095.0);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
    let data = (0..W * H)
        .map(|i| {
            let (y, x) = (i / W, i % W);
            let (fx, fy) = (x as f64 / W as f64, y as f64 / H as f64);
            let v = 0.3 + 0.2 * (fx * 9.0).sin() * (fy * 7.0).cos();
            let gain = [0.5, 1.0, 0.6][Bayer::RGGB.color_at(y, x) as usize];
            (64.0 + (v * gain).clamp(0.0, 1.0) * 4031.0) as u16
        })
        .collect();
    RawImage {
        width: W,
        height: H,
        data,
        meta,
    }
}

fn area(planes: u32) -> AreaSpec {
    AreaSpec {
        top: 0,
        left: 0,
        bottom: H as u32,
        right: W as u32,
        plane: 0,
        planes,
        row_pitch: 1,
        col_pitch: 1,
    }
}

fn gain_map(planes: u32) -> OpcodeKind {
    let (pv, ph) = (13u32, 17u32);
    OpcodeKind::GainMap(GainMap {
        area: area(planes),
        points_v: pv,
        points_h: ph,
        spacing_v: 1.0 / (pv - 1) as f64,
        spacing_h: 1.0 / (ph - 1) as f64,
        origin_v: 0.0,
        origin_h: 0.0,
        map_planes: 1,
        gains: (0..pv * ph).map(|i| 1.0 + (i % 7) as f32 * 0.1).collect(),
    })
}

fn with(img: &RawImage, list: usize, kind: OpcodeKind) -> RawImage {
    let mut img = img.clone();
    img.meta.opcode_lists[list] = Some(encode_list(&OpcodeList {
        opcodes: vec![Opcode::new(kind, 0)],
    }));
    img
}

fn main() {
    let runs: usize = std::env::var("D2N_BENCH_RUNS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let base = frame();
    let warp = |kt| OpcodeKind::WarpRectilinear {
        planes: vec![WarpPlane {
            kr: [1.0, -0.05, 0.01, 0.0],
            kt,
        }],
        center: [0.5, 0.5],
    };
    let cases: Vec<(&str, RawImage)> = vec![
        ("plain render (no opcodes)", base.clone()),
        (
            "opcode path, near no-op (ScalePerRow 1.0001, one row)",
            with(
                &base,
                1,
                OpcodeKind::ScalePerRow {
                    area: AreaSpec {
                        bottom: 1,
                        ..area(1)
                    },
                    scales: vec![1.0001],
                },
            ),
        ),
        (
            "OpcodeList1 MapTable (4096 entries)",
            with(
                &base,
                0,
                OpcodeKind::MapTable {
                    area: area(1),
                    table: (0..4096u16).map(|v| v / 2 + 32).collect(),
                },
            ),
        ),
        (
            "OpcodeList1 DeltaPerRow",
            with(
                &base,
                0,
                OpcodeKind::DeltaPerRow {
                    area: area(1),
                    deltas: vec![1.5; H],
                },
            ),
        ),
        (
            "OpcodeList1 FixBadPixelsConstant",
            with(
                &base,
                0,
                OpcodeKind::FixBadPixelsConstant {
                    constant: 0,
                    bayer_phase: 0,
                },
            ),
        ),
        (
            "OpcodeList1 FixBadPixelsList (1000 points)",
            with(
                &base,
                0,
                OpcodeKind::FixBadPixelsList {
                    bayer_phase: 0,
                    points: (0..1000u32)
                        .map(|i| [(i * 7) % H as u32, (i * 13) % W as u32])
                        .collect(),
                    rects: vec![],
                },
            ),
        ),
        ("OpcodeList2 GainMap 13x17", with(&base, 1, gain_map(1))),
        (
            "OpcodeList2 MapPolynomial (degree 3)",
            with(
                &base,
                1,
                OpcodeKind::MapPolynomial {
                    area: area(1),
                    coefficients: vec![0.0, 1.1, -0.1, 0.01],
                },
            ),
        ),
        (
            "OpcodeList2 ScalePerColumn",
            with(
                &base,
                1,
                OpcodeKind::ScalePerColumn {
                    area: area(1),
                    scales: vec![1.01; W],
                },
            ),
        ),
        (
            "OpcodeList2 FixVignetteRadial",
            with(
                &base,
                1,
                OpcodeKind::FixVignetteRadial {
                    k: [0.3, 0.1, 0.0, 0.0, 0.0],
                    center: [0.5, 0.5],
                },
            ),
        ),
        (
            "OpcodeList3 GainMap 13x17, 3 planes",
            with(&base, 2, gain_map(3)),
        ),
        (
            "OpcodeList3 WarpRectilinear (radial)",
            with(&base, 2, warp([0.0, 0.0])),
        ),
        (
            "OpcodeList3 WarpRectilinear (radial + tangential)",
            with(&base, 2, warp([0.001, 0.0005])),
        ),
        (
            "OpcodeList3 WarpFisheye",
            with(
                &base,
                2,
                OpcodeKind::WarpFisheye {
                    planes: vec![[1.0, -0.05, 0.0, 0.0]],
                    center: [0.5, 0.5],
                },
            ),
        ),
        (
            "OpcodeList3 WarpRectilinear2 (radial, reciprocal)",
            with(&base, 2, {
                let mut kr = [0.0; 15];
                (kr[0], kr[2], kr[4]) = (1.0, 0.05, -0.01);
                OpcodeKind::WarpRectilinear2 {
                    planes: vec![WarpPlane2 {
                        kr,
                        kt: [0.0, 0.0],
                        valid: [0.0, 1.0],
                    }],
                    center: [0.5, 0.5],
                    reciprocal: true,
                }
            }),
        ),
        (
            "OpcodeList3 TrimBounds (8 px each side)",
            with(
                &base,
                2,
                OpcodeKind::TrimBounds {
                    bounds: [8, 8, H as u32 - 8, W as u32 - 8],
                },
            ),
        ),
    ];
    let opts = RenderOptions::default();
    let mut times: Vec<Vec<f64>> = vec![vec![]; cases.len()];
    for _ in 0..runs {
        for (i, (_, img)) in cases.iter().enumerate() {
            let t = Instant::now();
            black_box(render(img, &opts).unwrap());
            times[i].push(t.elapsed().as_secs_f64());
        }
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    let meds: Vec<f64> = times.iter_mut().map(med).collect();
    println!(
        "{} runs each, interleaved; loadavg {}",
        runs,
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    println!("| case | median render (s) | cost over the no-op opcode path (s) |");
    println!("|---|---|---|");
    for (i, (name, _)) in cases.iter().enumerate() {
        let over = if i >= 2 {
            format!("{:+.3}", meds[i] - meds[1])
        } else {
            "".into()
        };
        println!("| {name} | {:.3} | {over} |", meds[i]);
    }
}
