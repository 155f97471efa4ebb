//! Tests of `synth::night` (its own file: night.rs stays under 900 lines).

use super::*;
use crate::isp::render::default_crop;
use crate::isp::render_crop::target_origin;
use crate::synth::{Calibration, Mode, PlanReport, Planner, SynthOptions};
use std::path::Path;

fn day() -> RawImage {
    let fix = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/day.dng");
    crate::dng::read_dng(&fix).unwrap()
}

fn planned(day: &RawImage, mode: Mode, isos: Vec<u32>) -> Plan {
    planned_with_report(day, mode, isos).0
}

fn planned_with_report(day: &RawImage, mode: Mode, isos: Vec<u32>) -> (Plan, PlanReport) {
    let opts = SynthOptions {
        mode,
        isos,
        ..SynthOptions::default()
    };
    let p = Planner::new(day, &opts)
        .name("day.dng")
        .seed(3)
        .variant(1)
        .plan()
        .unwrap();
    (p.plan, p.report)
}

/// Every sample of the crop raw `c` equals the same active-area site of `full`.
fn assert_region(c: &RawImage, full: &RawImage, crop: &Crop, what: &str) {
    let a = full.active_area();
    for r in 0..crop.height {
        for k in 0..crop.width {
            let want = full.get(
                a.top as usize + crop.top + r,
                a.left as usize + crop.left + k,
            );
            assert_eq!(c.get(r, k), want, "{what} {crop:?} ({r},{k})");
        }
    }
}

/// The crop's target `t` equals the frame target `ft` at `(oy, ox)`, pixel for pixel.
fn assert_target_region(
    t: &crate::isp::RgbImage,
    ft: &crate::isp::RgbImage,
    (oy, ox): (usize, usize),
    crop: &Crop,
    what: &str,
) {
    for r in 0..crop.height {
        for k in 0..crop.width {
            assert_eq!(
                t.pixel(k, r),
                ft.pixel(ox + k, oy + r),
                "{what} {crop:?} ({r},{k})"
            );
        }
    }
}

#[test]
fn crops_equal_the_whole_frame_region() {
    let day = day();
    let a = day.active_area();
    let (aw, ah) = (a.width(), a.height());
    for mode in [Mode::Local, Mode::Global, Mode::Dimmed, Mode::Day] {
        let p = planned(&day, mode, vec![1600]);
        let full = synthesize(
            &day,
            &p,
            &Request {
                target: true,
                ..Request::default()
            },
        )
        .unwrap();
        let (x0, y0, _, _) = default_crop(&full.clean.meta, aw, ah);
        // corners, edges and the middle, with and without the target
        let crops = [
            Crop {
                top: 0,
                left: 0,
                height: 6,
                width: 8,
            },
            Crop {
                top: ah - ah % 2 - 10,
                left: aw - aw % 2 - 12,
                height: 10,
                width: 12,
            },
            Crop {
                top: 2,
                left: 4,
                height: 7,
                width: 9,
            },
            Crop {
                top: 0,
                left: 0,
                height: ah,
                width: aw,
            },
        ];
        for crop in crops {
            let crop = Crop {
                height: crop.height.min(ah - crop.top),
                width: crop.width.min(aw - crop.left),
                ..crop
            };
            let c = synthesize(
                &day,
                &p,
                &Request {
                    target: true,
                    crop: Some(crop),
                    ..Request::default()
                },
            )
            .unwrap();
            assert_eq!((c.clean.width, c.clean.height), (crop.width, crop.height));
            assert_region(&c.clean, &full.clean, &crop, &format!("{mode:?} clean"));
            // The target of a crop inside the DefaultCrop equals the frame's region.
            let t = c.target.as_ref().unwrap();
            let ft = full.target.as_ref().unwrap();
            if let Some((oy, ox)) = target_origin(&full.clean.meta, aw, ah, &crop) {
                assert_eq!((oy, ox), (crop.top - y0, crop.left - x0));
                assert_target_region(t, ft, (oy, ox), &crop, &format!("{mode:?} target"));
            }
            assert_eq!(c.noisy.len(), 1);
            assert_eq!(c.noisy[0].1.data.len(), crop.width * crop.height);
            assert!(c.stages.iter().any(|s| s == "crop"));
            // Nothing was computed that the request did not ask for.
            let bare = synthesize(
                &day,
                &p,
                &Request {
                    crop: Some(crop),
                    ..Request::default()
                },
            )
            .unwrap();
            assert!(bare.target.is_none());
            assert_eq!(bare.clean.data, c.clean.data);
            assert_eq!(bare.noisy[0].1.data, c.noisy[0].1.data);
        }
    }
}

/// A GainMap over the active area (radial falloff 1 .. 2.6), for opcode tests.
fn shading(aw: u32, ah: u32) -> crate::dng::opcodes::Opcode {
    use crate::dng::opcodes::{AreaSpec, GainMap, Opcode, OpcodeKind};
    let (pv, ph) = (5u32, 7u32);
    let gains = (0..pv * ph)
        .map(|i| {
            let v = (i / ph) as f32 / (pv - 1) as f32 * 2.0 - 1.0;
            let h = (i % ph) as f32 / (ph - 1) as f32 * 2.0 - 1.0;
            1.0 + 0.8 * (v * v + h * h)
        })
        .collect();
    Opcode::new(
        OpcodeKind::GainMap(GainMap {
            area: AreaSpec {
                top: 0,
                left: 0,
                bottom: ah,
                right: aw,
                plane: 0,
                planes: 1,
                row_pitch: 1,
                col_pitch: 1,
            },
            points_v: pv,
            points_h: ph,
            spacing_v: 1.0 / (pv - 1) as f64,
            spacing_h: 1.0 / (ph - 1) as f64,
            origin_v: 0.0,
            origin_h: 0.0,
            map_planes: 1,
            gains,
        }),
        0,
    )
}

#[test]
fn crop_targets_equal_the_frame_region_with_opcodes() {
    use crate::dng::opcodes::{encode_list, Opcode, OpcodeKind, OpcodeList, WarpPlane};
    let mut day = day();
    let a = day.active_area();
    let (aw, ah) = (a.width(), a.height());
    let poly = Opcode::new(
        OpcodeKind::MapPolynomial {
            area: crate::dng::opcodes::AreaSpec {
                top: 0,
                left: 0,
                bottom: 0,
                right: 0,
                plane: 0,
                planes: 1,
                row_pitch: 1,
                col_pitch: 1,
            },
            coefficients: vec![3.0, 0.97, 1e-6],
        },
        0,
    );
    let warp = Opcode::new(
        OpcodeKind::WarpRectilinear {
            planes: vec![WarpPlane {
                kr: [1.0, -0.03, 0.0, 0.0],
                kt: [0.001, 0.0],
            }],
            center: [0.45, 0.55],
        },
        0,
    );
    let cases = [
        // pointwise: the crop path computes the crop only
        [
            vec![poly.clone()],
            vec![shading(aw as u32, ah as u32)],
            vec![],
        ],
        // a warp: the crop's target is cut from the frame render
        [vec![], vec![shading(aw as u32, ah as u32)], vec![warp]],
    ];
    for (ci, lists) in cases.into_iter().enumerate() {
        for (i, l) in lists.into_iter().enumerate() {
            day.meta.opcode_lists[i] =
                (!l.is_empty()).then(|| encode_list(&OpcodeList { opcodes: l }));
        }
        let (p, plan_report) = planned_with_report(&day, Mode::Local, vec![]);
        let report = plan_report.opcodes.as_ref().unwrap();
        assert_eq!(report.mode, crate::isp::opcodes::OpcodeMode::Apply);
        assert_eq!(p.opcodes, crate::isp::opcodes::OpcodeMode::Apply);
        assert!(!plan_report.stages.iter().any(|s| s == "apply_opcodes"));
        let full = synthesize(
            &day,
            &p,
            &Request {
                target: true,
                ..Request::default()
            },
        )
        .unwrap();
        assert!(!full.stages.iter().any(|s| s == "apply_opcodes"));
        let stages = plan_report.stages_with(&full.stages);
        assert!(stages.iter().any(|s| s == "apply_opcodes"), "{stages:?}");
        assert_eq!(full.clean.meta.opcode_lists, day.meta.opcode_lists);
        let ft = full.target.as_ref().unwrap();
        assert_eq!(ft.count_non_finite(), 0);
        for crop in [
            Crop {
                top: 0,
                left: 0,
                height: 6,
                width: 8,
            },
            Crop {
                top: 10,
                left: 20,
                height: 17,
                width: 23,
            },
            Crop {
                top: ah - ah % 2 - 10,
                left: aw - aw % 2 - 12,
                height: 10,
                width: 12,
            },
        ] {
            let c = synthesize(
                &day,
                &p,
                &Request {
                    target: true,
                    crop: Some(crop),
                    ..Request::default()
                },
            )
            .unwrap();
            let t = c.target.as_ref().unwrap();
            let Some((oy, ox)) = target_origin(&full.clean.meta, aw, ah, &crop) else {
                continue;
            };
            assert_target_region(t, ft, (oy, ox), &crop, &format!("case {ci}"));
        }
        // ignoring them gives the plain target
        let plain = {
            let mut d = day.clone();
            d.meta.opcode_lists = [None, None, None];
            let p = planned(&d, Mode::Local, vec![]);
            synthesize(
                &d,
                &p,
                &Request {
                    target: true,
                    ..Request::default()
                },
            )
            .unwrap()
            .target
            .unwrap()
        };
        assert_ne!(&plain, ft, "case {ci}: opcodes change the target");
    }
}

#[test]
fn crop_noise_is_deterministic_and_has_the_model_variance() {
    let day = day();
    let p = planned(&day, Mode::Dimmed, vec![3200]);
    let crop = Crop {
        top: 0,
        left: 0,
        height: day.active_area().height() & !1,
        width: day.active_area().width() & !1,
    };
    let req = Request {
        crop: Some(crop),
        ..Request::default()
    };
    let a = synthesize(&day, &p, &req).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| synthesize(&day, &p, &req).unwrap());
    assert_eq!(a.noisy[0].1.data, b.noisy[0].1.data);
    // Standardized residuals (noisy - clean) / sigma over unclipped sites: mean ~0, var ~1.
    let norm = crate::normalize::Normalizer::new(&a.clean).unwrap();
    let params = &p.noise[0].params;
    let (mut n, mut s1, mut s2) = (0f64, 0f64, 0f64);
    for r in 0..crop.height {
        for k in 0..crop.width {
            let x = a.clean.get(r, k) as f64;
            let y = (x - norm.black_at(r, k)) / norm.scale;
            let var =
                params.var_norm(crate::raw::Bayer::position(r, k), y) * norm.scale * norm.scale;
            let v = a.noisy[0].1.get(r, k) as f64;
            if var < 4.0 || v <= 0.0 || v >= norm.white {
                continue;
            }
            let z = (v - x) / var.sqrt();
            n += 1.0;
            s1 += z;
            s2 += z * z;
        }
    }
    assert!(n > 1000.0, "{n}");
    let mean = s1 / n;
    let var = s2 / n - mean * mean;
    assert!(mean.abs() < 0.05, "{mean}");
    assert!((var - 1.0).abs() < 0.1, "{var}");
}

#[test]
fn physics_noise_on_a_crop_equals_the_frame_region() {
    use crate::noise::physics::{PhysicsModel, PhysicsPoint};
    use crate::noise::NoiseModel;
    let day = day();
    let opts = SynthOptions {
        isos: vec![1200],
        ..SynthOptions::default()
    };
    let mut cal = Calibration::embedded(&opts).unwrap();
    let pt = |iso, k| PhysicsPoint {
        iso,
        k,
        sigma_read: 2.0 * k,
        lambda: 0.05,
        gaussian_read: false,
        sigma_row: 0.5 * k,
    };
    let (b, w) = (day.meta.levels.black_max(), day.meta.levels.white);
    let pm = PhysicsModel::new("t", b, w, vec![pt(800, 0.5), pt(1600, 1.0)]).unwrap();
    cal.noise = Some(NoiseModel::from_physics(pm).unwrap());
    let p = Planner::new(&day, &opts)
        .calibration(&cal)
        .name("day.dng")
        .seed(3)
        .plan()
        .map(|p| p.plan)
        .unwrap();
    assert!(p.noise[0].physics.is_some());
    let full = synthesize(&day, &p, &Request::default()).unwrap();
    let crop = Crop {
        top: 4,
        left: 6,
        height: 9,
        width: 11,
    };
    let c = synthesize(
        &day,
        &p,
        &Request {
            crop: Some(crop),
            ..Request::default()
        },
    )
    .unwrap();
    assert_region(&c.noisy[0].1, &full.noisy[0].1, &crop, "physics noisy");
}

#[test]
fn bad_crops_are_errors() {
    let day = day();
    let p = planned(&day, Mode::Local, vec![]);
    for crop in [
        Crop {
            top: 1,
            left: 0,
            height: 4,
            width: 4,
        },
        Crop {
            top: 0,
            left: 0,
            height: 0,
            width: 4,
        },
        Crop {
            top: 0,
            left: 0,
            height: 4,
            width: 100_000,
        },
    ] {
        let req = Request {
            crop: Some(crop),
            target: true,
            ..Request::default()
        };
        assert!(synthesize(&day, &p, &req).is_err(), "{crop:?}");
    }
    let req = Request {
        input: true,
        crop: Some(Crop {
            top: 0,
            left: 0,
            height: 4,
            width: 4,
        }),
        ..Request::default()
    };
    assert!(synthesize(&day, &p, &req).is_err());
}

/// A brightness-dictionary plan that carries its input's whole-frame mean
/// (`DayInput::with_frame_mean`) gives every crop the bytes of the plan without it, and a
/// memo made under another clean-pass key is not used.
#[test]
fn the_frame_mean_memo_changes_no_byte() {
    use crate::synth::day_input::DayInput;
    use crate::synth::dim::{DimPlan, FrameMean};
    let day = DayInput::new(day(), String::new(), "day.dng".into());
    let opts = SynthOptions {
        isos: vec![1600],
        ..SynthOptions::default()
    };
    let mut cal = Calibration::embedded(&opts).unwrap();
    cal.brightness = Some(crate::synth::dictionaries::BrightnessDict {
        name: "test".into(),
        mean: 0.05,
        std: 0.01,
        count: 3,
    });
    let p = Planner::new(&day.raw, &opts)
        .calibration(&cal)
        .name("day.dng")
        .seed(3)
        .plan()
        .unwrap()
        .plan;
    assert!(matches!(p.dim, DimPlan::TargetMean { .. }), "{:?}", p.dim);
    let memo = day.with_frame_mean(p.clone()).unwrap();
    let m = memo.frame_mean.get(memo.mean_key()).unwrap();
    assert!(m > 0.0 && m.is_finite());
    // the memo takes no part in comparing plans, and the second call reads the memo
    assert_eq!(memo, p);
    assert_eq!(day.frame_mean(&p).unwrap().to_bits(), m.to_bits());
    let crop = Crop {
        top: 4,
        left: 6,
        height: 9,
        width: 11,
    };
    let req = Request {
        target: true,
        crop: Some(crop),
        ..Request::default()
    };
    let plain = synthesize(&day.raw, &p, &req).unwrap();
    let fast = synthesize(&day.raw, &memo, &req).unwrap();
    assert_eq!(plain.clean.data, fast.clean.data);
    assert_eq!(plain.noisy[0].1.data, fast.noisy[0].1.data);
    assert_eq!(
        plain.report.dim_scale.to_bits(),
        fast.report.dim_scale.to_bits()
    );
    assert_eq!(
        plain.target.as_ref().unwrap().data,
        fast.target.as_ref().unwrap().data
    );
    // a wrong mean under the plan's key is used (the memo is trusted) ...
    let mut wrong = p.clone();
    wrong.frame_mean = FrameMean::new(p.mean_key(), m * 2.0);
    let w = synthesize(&day.raw, &wrong, &req).unwrap();
    assert_ne!(
        w.report.dim_scale.to_bits(),
        plain.report.dim_scale.to_bits()
    );
    // ... but not once the plan's day neutral is changed after the memo was made
    let mut stale = wrong.clone();
    stale.day_neutral[0] *= 1.5;
    let mut fresh = p.clone();
    fresh.day_neutral[0] *= 1.5;
    let s = synthesize(&day.raw, &stale, &req).unwrap();
    let f = synthesize(&day.raw, &fresh, &req).unwrap();
    assert_eq!(s.clean.data, f.clean.data);
    assert_eq!(s.report.dim_scale.to_bits(), f.report.dim_scale.to_bits());
}
