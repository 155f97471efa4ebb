//! Unit tests of the whole engine on small in-memory frames: per-stage hand-computed values in
//! all four Bayer phases, the numerical stability matrix, geometry ranges (proptest),
//! noise statistics and determinism.

#![allow(clippy::needless_range_loop)]

use super::dictionaries::IlluminantDict;
use super::dim::DimPlan;
use super::masks::{Light, LightKind, MaskEval, MASK_FLOOR};
use super::*;
use crate::normalize::Normalizer;
use crate::raw::meta::RawMeta;
use crate::raw::Bayer;
use proptest::prelude::*;

const BLACK: f64 = 64.0;
const WHITE: f64 = 1023.0;

/// Frame whose value depends only on the CFA colour (R, G, B values).
fn frame(bayer: Bayer, w: usize, h: usize, vals: [u16; 3]) -> RawImage {
    let mut data = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            data.push(vals[bayer.color_at(r, c) as usize]);
        }
    }
    let mut meta = RawMeta::new_bayer(bayer, 10, BLACK, WHITE);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.25]);
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

fn opts(mode: Mode) -> SynthOptions {
    SynthOptions {
        mode,
        isos: vec![],
        ..SynthOptions::default()
    }
}

fn plan_for(img: &RawImage, o: &SynthOptions) -> Plan {
    planned_for(img, o).plan
}

fn planned_for(img: &RawImage, o: &SynthOptions) -> Planned {
    let cal = Calibration::embedded(o).unwrap();
    Planner::new(img, o)
        .calibration(&cal)
        .name("t.dng")
        .seed(1)
        .plan()
        .unwrap()
}

fn with_dim(mut p: Plan, s: f64) -> Plan {
    p.dim = DimPlan::Uniform { s, range: [s, s] };
    p
}

/// Value at colour `col` of the clean output (all sites of a colour are equal here).
fn at_colour(img: &RawImage, bayer: Bayer, col: u8) -> u16 {
    for r in 0..2 {
        for c in 0..2 {
            if bayer.color_at(r, c) == col {
                return img.get(r, c);
            }
        }
    }
    unreachable!()
}

#[test]
fn dimmed_by_hand_all_phases() {
    // n = (0.5, 1, 0.25), s = 0.5, black 64, white 1023 (scale 959):
    // R 500: y_w = 872/959, y_r = 218/959 -> 282; G 700 -> 64 + 318 = 382;
    // B 300: y_w = 944/959 -> 64 + 118 = 182.
    for b in Bayer::ALL {
        let img = frame(b, 4, 4, [500, 700, 300]);
        let p = with_dim(plan_for(&img, &opts(Mode::Dimmed)), 0.5);
        let (out, rep) = run_clean(&img, &p).unwrap();
        assert_eq!(rep.dim_scale, 0.5);
        assert_eq!(at_colour(&out, b, 0), 282, "{b}");
        assert_eq!(at_colour(&out, b, 1), 382, "{b}");
        assert_eq!(at_colour(&out, b, 2), 182, "{b}");
        // Highlight: R 1000 -> y_w clipped to 1 -> y_r = 0.25 -> 64 + 239.75 -> 304 (303 truncated).
        let img = frame(b, 4, 4, [1000, 700, 300]);
        let p = with_dim(plan_for(&img, &opts(Mode::Dimmed)), 0.5);
        assert_eq!(at_colour(&run_clean(&img, &p).unwrap().0, b, 0), 304);
        let mut pt = p.clone();
        pt.truncate = true;
        assert_eq!(at_colour(&run_clean(&img, &pt).unwrap().0, b, 0), 303);
    }
}

#[test]
fn day_mode_is_identity_except_clipped_highlights() {
    for b in Bayer::ALL {
        let img = frame(b, 6, 4, [500, 700, 300]);
        let Planned { plan: p, report } = planned_for(&img, &opts(Mode::Day));
        assert_eq!(p.dim, DimPlan::None);
        assert!(!report.stages.contains(&"masks".to_string()));
        assert_eq!(p.night_neutral, [0.5, 1.0, 0.25]);
        let (out, _) = run_clean(&img, &p).unwrap();
        assert_eq!(out.data, img.data);
        // R 1000 with n_r = 0.5: y_w = 1 -> y_r = 0.5 -> 64 + 479.5 -> 544.
        let img = frame(b, 6, 4, [1000, 700, 300]);
        let (out, rep) = run_clean(&img, &plan_for(&img, &opts(Mode::Day))).unwrap();
        assert_eq!(at_colour(&out, b, 0), 544);
        assert_eq!(rep.saturated_sites, 0);
    }
}

#[test]
fn global_by_hand_all_phases() {
    // l = (0.8, 1, 0.4), s = 0.5: R 500 -> 64 + 436*0.8 = 412.8 -> 413; G 382;
    // B 300 -> 64 + 472*0.4 = 252.8 -> 253.
    for b in Bayer::ALL {
        let img = frame(b, 4, 6, [500, 700, 300]);
        let mut p = with_dim(plan_for(&img, &opts(Mode::Global)), 0.5);
        assert_eq!(p.lights.len(), 1);
        p.lights[0].illuminant = [0.8, 1.0, 0.4];
        let (out, _) = run_clean(&img, &p).unwrap();
        assert_eq!(at_colour(&out, b, 0), 413, "{b}");
        assert_eq!(at_colour(&out, b, 1), 382);
        assert_eq!(at_colour(&out, b, 2), 253);
    }
}

fn local(kind: LightKind, l: [f64; 3], gain: f64, center: [f64; 2], sigma: [f64; 2]) -> Light {
    Light {
        kind,
        illuminant: l,
        gain,
        weight: 1.0,
        center,
        window: Some([100.0, 100.0]),
        sigma,
        floor: MASK_FLOOR,
    }
}

#[test]
fn local_release_by_hand_all_phases() {
    for b in Bayer::ALL {
        let img = frame(b, 4, 4, [500, 700, 300]);
        let mut p = with_dim(plan_for(&img, &opts(Mode::Local)), 0.5);
        let amb = Light {
            kind: LightKind::Ambient,
            illuminant: [1.0, 1.0, 1.0],
            gain: 0.05,
            weight: 1.0,
            center: [0.0, 0.0],
            window: None,
            sigma: [0.0, 0.0],
            floor: 0.0,
        };
        let l1 = [0.8, 1.0, 0.4];
        p.lights = vec![
            amb,
            local(LightKind::Local, l1, 1.0, [0.0, 0.0], [1.0, 1.0]),
        ];
        let (out, _) = run_clean(&img, &p).unwrap();
        // y_e per colour (white balanced, dimmed by 0.5), in units of 1/959.
        let ye = [436.0, 318.0, 472.0];
        for r in 0..4 {
            for c in 0..4 {
                let col = b.color_at(r, c) as usize;
                let y = ye[col] / 959.0;
                let m = (-((r * r + c * c) as f64) / 2.0).exp().max(MASK_FLOOR);
                let r0 = (y * 0.05f64).min(1.0);
                let r1 = (y * l1[col]).min(1.0);
                let yr = (r0 + m * r1) / (1.0 + m);
                let want = (yr * 959.0 + 64.0).round() as u16;
                assert_eq!(out.get(r, c), want, "{b} ({r},{c})");
            }
        }
        // A bulb at (0,0) with gain 50 saturates its centre; far pixels keep their value.
        let before = out.get(3, 3);
        p.lights
            .push(local(LightKind::Bulb, l1, 50.0, [0.0, 0.0], [0.3, 0.3]));
        let (out, _) = run_clean(&img, &p).unwrap();
        assert_eq!(out.get(0, 0), 1023);
        let col = b.color_at(3, 3) as usize;
        let m = MASK_FLOOR; // exp(-9/0.18) underflows the floor
        let add = 50.0 * m * (ye[col] / 959.0 * l1[col]).min(1.0);
        assert!((out.get(3, 3) as f64 - before as f64).abs() <= (add * 959.0).ceil() + 1.0);
    }
}

#[test]
fn paper_formula_tiny_mask_sums_are_finite() {
    let img = frame(Bayer::GBRG, 7, 9, [500, 700, 300]);
    let mut o = opts(Mode::Local);
    o.formula = RelightFormula::Paper;
    let mut p = plan_for(&img, &o);
    assert!(p.lights.iter().all(|l| l.kind != LightKind::Bulb));
    let n = p.lights.len();
    assert!((5..=7).contains(&n), "{n}");
    for l in &mut p.lights {
        l.weight = 1e-38;
        l.sigma = [1e-3, 1e-3];
        l.center = [-100.0, -100.0];
    }
    let (out, _) = run_clean(&img, &p).unwrap();
    assert!(out.data.iter().all(|&v| v <= 1023));
    for l in &mut p.lights {
        l.weight = 0.0;
    }
    let (out, _) = run_clean(&img, &p).unwrap();
    assert!(
        out.data.iter().all(|&v| v == 64),
        "zero weights give black, not NaN"
    );
}

#[test]
fn stability_black_ge_white_is_an_error() {
    let mut img = frame(Bayer::RGGB, 4, 4, [500, 700, 300]);
    img.meta.levels.black = vec![1023.0];
    let cal = Calibration::embedded(&SynthOptions::default()).unwrap();
    let e = Planner::new(&img, &SynthOptions::default())
        .calibration(&cal)
        .name("x")
        .plan()
        .map(|p| p.plan)
        .unwrap_err();
    assert!(e.to_string().contains(">= white"), "{e}");
}

fn full_run(img: &RawImage) -> SynthOutput {
    let o = SynthOptions::default();
    let cal = Calibration::embedded(&o).unwrap();
    let p = Planner::new(img, &o)
        .calibration(&cal)
        .name("x.dng")
        .seed(3)
        .plan()
        .map(|p| p.plan)
        .unwrap();
    run(img, &p).unwrap()
}

#[test]
fn stability_all_black_frame() {
    let img = frame(Bayer::BGGR, 8, 8, [64, 64, 64]);
    let out = full_run(&img);
    assert!(out.clean.data.iter().all(|&v| v == 64));
    for (_, n) in &out.noisy {
        assert!(n.data.iter().all(|&v| v <= 1023));
    }
}

#[test]
fn stability_all_saturated_frame() {
    let img = frame(Bayer::GRBG, 8, 8, [1023, 1023, 1023]);
    let out = full_run(&img);
    assert_eq!(out.report.saturated_sites, 64);
    assert!(out.clean.data.iter().all(|&v| (64..=1023).contains(&v)));
    assert!(out.report.dim_scale.is_finite());
}

#[test]
fn stability_tiny_frames() {
    for (w, h) in [(1, 1), (2, 2), (7, 9), (9, 7), (1, 5)] {
        for b in Bayer::ALL {
            let img = frame(b, w, h, [500, 700, 300]);
            let out = full_run(&img);
            assert_eq!(out.clean.data.len(), w * h);
            assert_eq!(out.noisy.len(), 2);
        }
    }
}

#[test]
fn stability_tiny_or_zero_neutral_is_an_error() {
    for n in [
        [0.0, 1.0, 0.5],
        [1e-12, 1.0, 0.5],
        [0.5, 1.0, 0.0],
        [0.5, 0.0, 0.5],
    ] {
        let mut img = frame(Bayer::RGGB, 4, 4, [500, 700, 300]);
        img.meta.as_shot_neutral = Some(n);
        let cal = Calibration::embedded(&SynthOptions::default()).unwrap();
        let e = Planner::new(&img, &SynthOptions::default())
            .calibration(&cal)
            .name("x")
            .plan()
            .map(|p| p.plan)
            .unwrap_err();
        assert!(e.to_string().contains("AsShotNeutral"), "{e}");
    }
}

#[test]
fn stability_white_65535_no_overflow() {
    let mut img = frame(Bayer::RGGB, 8, 8, [65535, 65535, 40000]);
    img.meta.levels.black = vec![0.0];
    img.meta.levels.white = 65535.0;
    img.meta.bits_per_sample = 16;
    let mut o = opts(Mode::Day);
    o.isos = vec![3200];
    let cal = Calibration::embedded(&o).unwrap();
    let p = Planner::new(&img, &o)
        .calibration(&cal)
        .name("x")
        .plan()
        .map(|p| p.plan)
        .unwrap();
    let out = run(&img, &p).unwrap();
    // Day mode: G stays 65535, R 65535 with n = 0.5 -> y_w clipped -> 32768 (rounded).
    assert_eq!(at_colour(&out.clean, Bayer::RGGB, 1), 65535);
    assert_eq!(at_colour(&out.clean, Bayer::RGGB, 0), 32768);
    let full = full_run(&img);
    assert_eq!(full.clean.data.len(), 64);
}

#[test]
fn stability_iso_25_and_204800_extrapolate_finite() {
    let img = frame(Bayer::RGGB, 16, 16, [500, 700, 300]);
    let o = SynthOptions {
        isos: vec![25, 204800],
        ..SynthOptions::default()
    };
    let cal = Calibration::embedded(&o).unwrap();
    let Planned { plan: p, report } = Planner::new(&img, &o)
        .calibration(&cal)
        .name("x")
        .plan()
        .unwrap();
    // The frame has no ISO: the embedded table, said first, then one warning per ISO.
    let w = &report.warnings;
    assert_eq!(w.len(), 3, "{w:?}");
    assert!(w[0].message.contains("ISO is unknown"), "{}", w[0]);
    assert!(w[1].message.contains("extrapolated"));
    for np in &p.noise {
        assert!(np.extrapolated);
        for q in np.params.positions {
            assert!(q[0].is_finite() && q[1].is_finite() && q[0] >= 0.0 && q[1] >= 0.0);
        }
    }
    let out = run(&img, &p).unwrap();
    assert!(out.noisy[1].1.data.iter().all(|&v| v <= 1023));
    assert_eq!(out.noisy[1].1.meta.exif.iso, Some(204800));
}

#[test]
fn stability_single_illuminant_dictionary() {
    let img = frame(Bayer::RGGB, 16, 16, [500, 700, 300]);
    let o = SynthOptions::default();
    let d = IlluminantDict {
        name: "one".into(),
        source: String::new(),
        chromaticities: vec![[0.7, 0.35]],
        weights: Vec::new(),
    };
    let cal = Calibration {
        illuminants: IlluminantChoice::Gaussian(Gaussian2::fit(&d, o.covariance).unwrap(), None),
        brightness: None,
        noise: None,
    };
    let p = Planner::new(&img, &o)
        .calibration(&cal)
        .name("x")
        .plan()
        .map(|p| p.plan)
        .unwrap();
    assert!(p.lights.iter().all(|l| l.illuminant == [0.7, 1.0, 0.35]));
    assert_eq!(p.night_neutral, [0.7, 1.0, 0.35]);
    run(&img, &p).unwrap();
}

#[test]
fn no_nan_anywhere_in_plan_and_sidecar_values() {
    for mode in [Mode::Day, Mode::Dimmed, Mode::Global, Mode::Local] {
        let img = frame(Bayer::GBRG, 7, 9, [1023, 64, 0]);
        let o = SynthOptions {
            mode,
            isos: vec![25, 1600, 204800],
            ..SynthOptions::default()
        };
        let cal = Calibration::embedded(&o).unwrap();
        let p = Planner::new(&img, &o)
            .calibration(&cal)
            .name("x")
            .seed(9)
            .plan()
            .map(|p| p.plan)
            .unwrap();
        let j = serde_json::to_string(&p).unwrap();
        // serde_json writes non-finite floats as null: no null may appear except the
        // ambient/global light's absent window, the absent names of a camera, and the
        // absent physics model and burst.
        let v: serde_json::Value = serde_json::from_str(&j).unwrap();
        fn walk(v: &serde_json::Value, key: &str) {
            match v {
                serde_json::Value::Null => assert!(
                    [
                        "window",
                        "make",
                        "model",
                        "unique_camera_model",
                        "physics",
                        "burst"
                    ]
                    .contains(&key),
                    "null (NaN?) at {key}"
                ),
                serde_json::Value::Number(n) => assert!(n.as_f64().unwrap().is_finite()),
                serde_json::Value::Array(a) => a.iter().for_each(|x| walk(x, key)),
                serde_json::Value::Object(o) => o.iter().for_each(|(k, x)| walk(x, k)),
                _ => {}
            }
        }
        walk(&v, "");
        let out = run(&img, &p).unwrap();
        assert!(out.report.dim_scale.is_finite());
    }
}

#[test]
fn run_is_pure_and_deterministic_across_threads_and_seeds() {
    let img = frame(Bayer::RGGB, 64, 48, [500, 700, 300]);
    let o = SynthOptions::default();
    let cal = Calibration::embedded(&o).unwrap();
    let p = Planner::new(&img, &o)
        .calibration(&cal)
        .name("a.dng")
        .seed(5)
        .plan()
        .map(|p| p.plan)
        .unwrap();
    assert_eq!(
        p,
        Planner::new(&img, &o)
            .calibration(&cal)
            .name("a.dng")
            .seed(5)
            .plan()
            .map(|p| p.plan)
            .unwrap()
    );
    let a = run(&img, &p).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| run(&img, &p).unwrap());
    assert_eq!(a.clean.data, b.clean.data);
    for (x, y) in a.noisy.iter().zip(&b.noisy) {
        assert_eq!(x.1.data, y.1.data);
    }
    let q = Planner::new(&img, &o)
        .calibration(&cal)
        .name("a.dng")
        .seed(6)
        .plan()
        .map(|p| p.plan)
        .unwrap();
    assert_ne!(run(&img, &q).unwrap().clean.data, a.clean.data);
    let v = Planner::new(&img, &o)
        .calibration(&cal)
        .name("a.dng")
        .seed(5)
        .variant(1)
        .plan()
        .map(|p| p.plan)
        .unwrap();
    assert_ne!(v.lights, p.lights);
    // A plan round-trips through JSON exactly (replay).
    let j = serde_json::to_string(&p).unwrap();
    let p2: Plan = serde_json::from_str(&j).unwrap();
    assert_eq!(p2, p);
    assert_eq!(run(&img, &p2).unwrap().noisy[0].1.data, a.noisy[0].1.data);
}

#[test]
fn output_metadata() {
    let mut img = frame(Bayer::RGGB, 8, 8, [500, 700, 300]);
    img.meta.linearization_table = Some((0..1024u16).map(|v| v * 4).collect());
    img.meta.levels.black = vec![256.0];
    img.meta.levels.white = 4092.0;
    img.meta.bits_per_sample = 10;
    let out = full_run(&img);
    let m = &out.clean.meta;
    assert_eq!(m.linearization_table, None);
    assert_eq!(m.bits_per_sample, 12);
    assert_eq!(m.exif.iso, Some(50));
    assert_eq!(m.noise_profile.as_ref().unwrap().len(), 3);
    let n = m.as_shot_neutral.unwrap();
    assert_eq!(n[1], 1.0);
    assert_eq!(out.noisy[0].1.meta.exif.iso, Some(1600));
    assert_ne!(out.noisy[0].1.meta.noise_profile, m.noise_profile);
    // Linearized: a G sample of 700 -> 2800 -> y = 2544/3836; local relight keeps it < white.
    assert!(out.clean.data.iter().all(|&v| v <= 4092));
}

#[test]
fn masks_and_lights_skipped_in_modes_that_do_not_need_them() {
    let img = frame(Bayer::RGGB, 8, 8, [500, 700, 300]);
    let stages = |o: &SynthOptions| planned_for(&img, o).report.stages;
    let s = stages(&opts(Mode::Global));
    assert!(!s.iter().any(|s| s == "masks" || s == "noise"));
    let s = stages(&opts(Mode::Local));
    assert!(s.iter().any(|s| s == "masks") && s.iter().any(|s| s == "bulbs"));
    let mut o = opts(Mode::Local);
    o.bulbs = Some(0);
    assert!(!stages(&o).iter().any(|s| s == "bulbs"));
}

#[test]
fn noise_flat_field_matches_written_profile_per_band() {
    // 4 horizontal bands of flat levels on a 14-bit RGGB frame, day mode (clean = input).
    let (w, h) = (1024usize, 1024usize);
    let black = 512.0;
    let white = 16383.0;
    let scale = white - black;
    let levels = [0.05, 0.15, 0.35, 0.6];
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 14, black, white);
    meta.as_shot_neutral = Some([1.0, 1.0, 1.0]);
    let mut data = vec![0u16; w * h];
    for r in 0..h {
        let y = levels[r * levels.len() / h];
        let x = (y * scale + black).round() as u16;
        data[r * w..(r + 1) * w].fill(x);
    }
    let img = RawImage {
        width: w,
        height: h,
        data,
        meta,
    };
    let mut o = opts(Mode::Day);
    o.isos = vec![1600, 3200];
    let cal = Calibration::embedded(&o).unwrap();
    let p = Planner::new(&img, &o)
        .calibration(&cal)
        .name("flat.dng")
        .plan()
        .map(|p| p.plan)
        .unwrap();
    let out = run(&img, &p).unwrap();
    assert_eq!(out.clean.data, img.data);
    for (iso, noisy) in &out.noisy {
        let prof = noisy.meta.noise_profile.clone().unwrap();
        for (band, _) in levels.iter().enumerate() {
            for colour in 0..3u8 {
                let (mut n, mut s, mut s2) = (0.0, 0.0, 0.0);
                let mut y_clean = 0.0;
                for r in band * h / 4..(band + 1) * h / 4 {
                    for c in 0..w {
                        if Bayer::RGGB.color_at(r, c) != colour {
                            continue;
                        }
                        let d = (noisy.get(r, c) as f64 - out.clean.get(r, c) as f64) / scale;
                        y_clean = (out.clean.get(r, c) as f64 - black) / scale;
                        n += 1.0;
                        s += d;
                        s2 += d * d;
                    }
                }
                let var = s2 / n - (s / n).powi(2);
                let (ps, po) = prof[colour as usize];
                let want = ps * y_clean + po;
                let rel = (var - want).abs() / want;
                assert!(
                    rel < 0.02,
                    "ISO {iso} band {band} colour {colour}: {var} vs {want} ({rel})"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn geometry_stays_in_spec_ranges(seed in any::<u64>(), w in 1usize..3000, h in 1usize..3000, paper in any::<bool>()) {
        let img = frame(Bayer::RGGB, 1, 1, [500, 700, 300]);
        let mut img = img;
        // Geometry only: a w x h frame without pixels would fail validation, so fake sizes
        // through the active-area-free metadata by planning on a real small frame scaled up.
        img.width = w;
        img.height = h;
        img.data = vec![500; w * h];
        let mut o = SynthOptions::default();
        if paper {
            o.formula = RelightFormula::Paper;
        }
        let cal = Calibration::embedded(&o).unwrap();
        let p = Planner::new(&img, &o)
        .calibration(&cal)
        .name("g")
        .seed(seed)
        .plan()
        .map(|p| p.plan).unwrap();
        let (wf, hf) = (w as f64, h as f64);
        match p.dim {
            DimPlan::Uniform { s, .. } => prop_assert!((0.55..0.90).contains(&s)),
            _ => prop_assert!(false),
        }
        let amb = &p.lights[0];
        prop_assert_eq!(amb.kind, LightKind::Ambient);
        if paper {
            prop_assert!((0.05..0.10).contains(&amb.weight));
            prop_assert!((5..=7).contains(&p.lights.len()));
        } else {
            prop_assert_eq!(amb.gain, 0.05);
            prop_assert_eq!(p.lights.iter().filter(|l| l.kind == LightKind::Local).count(), 4);
            prop_assert_eq!(p.lights.iter().filter(|l| l.kind == LightKind::Bulb).count(), 5);
        }
        for l in &p.lights[1..] {
            prop_assert!(l.center[0] >= 0.1 * hf && l.center[0] < 0.9 * hf);
            prop_assert!(l.center[1] >= 0.1 * wf && l.center[1] < 0.9 * wf);
            prop_assert!(l.illuminant[0] > 0.0 && l.illuminant[2] > 0.0 && l.illuminant[1] == 1.0);
            match (paper, l.window) {
                (true, None) => {
                    prop_assert!(l.sigma[0] >= 0.5 * hf && l.sigma[0] < hf);
                    prop_assert!(l.sigma[1] >= 0.5 * wf && l.sigma[1] < wf);
                }
                (false, Some([wh, ww])) => {
                    prop_assert!(wh >= (0.5 * hf).max(1.0) && (wh < hf || h == 1));
                    prop_assert!(ww >= (0.5 * wf).max(1.0) && (ww < wf || w == 1));
                    let m = wh.max(ww);
                    let s = l.sigma[0].max(l.sigma[1]);
                    if l.kind == LightKind::Local {
                        prop_assert!((s - (0.3 * ((m - 1.0) / 2.0 - 1.0) + 0.8)).abs() < 1e-9);
                    } else {
                        let f = |k: f64| 0.3 * ((k - 1.0) / 2.0 - 1.0) + 0.8;
                        prop_assert!(s > f(m / 10.0) - 1e-9 && s <= f(m / 5.0) + 1e-9);
                        prop_assert!((50.0..100.0).contains(&l.gain));
                    }
                }
                _ => prop_assert!(false, "window mismatch"),
            }
        }
        let mean: Vec<f64> = (0..3).map(|i| {
            let used: Vec<&Light> = p.lights.iter().filter(|l| !paper || l.kind != LightKind::Bulb).collect();
            used.iter().map(|l| l.illuminant[i]).sum::<f64>() / used.len() as f64
        }).collect();
        for i in 0..3 {
            prop_assert!((p.night_neutral[i] - mean[i]).abs() < 1e-12);
        }
    }
}

#[test]
fn truncated_and_exact_masks_close_to_separable() {
    let img = frame(Bayer::RGGB, 64, 48, [500, 700, 300]);
    let p = plan_for(&img, &opts(Mode::Local));
    let base = run_clean(&img, &p).unwrap().0;
    // Bulbs have gains up to 100, so truncation must reach well past 4 sigma
    // (100 * exp(-k^2 / 2) < 0.5 DN / 959 needs k > 4.9).
    for eval in [MaskEval::Exact, MaskEval::Truncated { k: 6.0 }] {
        let mut q = p.clone();
        q.mask_eval = eval;
        let o = run_clean(&img, &q).unwrap().0;
        let maxd = base
            .data
            .iter()
            .zip(&o.data)
            .map(|(a, b)| (*a as i32 - *b as i32).abs())
            .max()
            .unwrap();
        assert!(maxd <= 2, "{eval:?}: {maxd}");
    }
}

#[test]
fn tampered_plans_are_refused_not_panicking() {
    let img = frame(Bayer::RGGB, 8, 8, [500, 700, 300]);
    let o = SynthOptions::default();
    let p = plan_for(&img, &o);
    let mut q = p.clone();
    q.dim = DimPlan::Uniform {
        s: f64::NAN,
        range: [0.0, 1.0],
    };
    assert!(run(&img, &q).is_err());
    let mut q = p.clone();
    q.noise[0].params.positions[0][0] = f64::INFINITY;
    assert!(run(&img, &q).is_err());
    let mut q = p.clone();
    q.lights[1].window = Some([f64::NAN, 3.0]);
    assert!(run(&img, &q).is_err());
    let mut q = p.clone();
    q.active_width = 9;
    assert!(run(&img, &q).is_err());
    // Extreme but finite geometry runs.
    let mut q = p.clone();
    for l in &mut q.lights {
        l.center = [1e300, -1e300];
        l.sigma = [0.0, 1e-300];
    }
    run(&img, &q).unwrap();
}

#[test]
fn non_bayer_cfa_is_a_clear_error() {
    let mut img = frame(Bayer::RGGB, 6, 6, [500, 700, 300]);
    img.meta.cfa.rows = 3;
    img.meta.cfa.cols = 3;
    img.meta.cfa.pattern = vec![0, 1, 2, 1, 2, 0, 2, 0, 1];
    let cal = Calibration::embedded(&SynthOptions::default()).unwrap();
    let e = Planner::new(&img, &SynthOptions::default())
        .calibration(&cal)
        .name("x")
        .plan()
        .map(|p| p.plan)
        .unwrap_err();
    assert!(e.to_string().contains("not a 2x2 Bayer"), "{e}");
    let mut img = frame(Bayer::RGGB, 6, 6, [500, 700, 300]);
    img.meta.cfa.plane_color = vec![0, 1, 3];
    assert!(Planner::new(&img, &SynthOptions::default())
        .calibration(&cal)
        .name("x")
        .plan()
        .map(|p| p.plan)
        .is_err());
}

/// The per-value tables of the clean pass (2x2-periodic black) give the bytes of the
/// per-sample formula: the same black levels written as a 2x4 repeat pattern (which is not
/// tabulated) must produce the same output, for every mode, dim plan and truncation, with
/// stored values below black, across the range, at and above white.
#[test]
fn clean_pass_tables_match_the_per_sample_formula() {
    for b in Bayer::ALL {
        let mut img = frame(b, 37, 23, [0, 0, 0]);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = ((i * 7919) % 1400) as u16;
        }
        img.meta.levels.black = vec![60.0, 64.5, 66.0, 70.0];
        img.meta.levels.black_repeat = (2, 2);
        let mut wide = img.clone();
        wide.meta.levels.black = vec![60.0, 64.5, 60.0, 64.5, 66.0, 70.0, 66.0, 70.0];
        wide.meta.levels.black_repeat = (2, 4);
        assert!(Normalizer::new(&img).unwrap().black_is_2x2_periodic());
        assert!(!Normalizer::new(&wide).unwrap().black_is_2x2_periodic());
        for mode in [Mode::Day, Mode::Dimmed, Mode::Global, Mode::Local] {
            for truncate in [false, true] {
                let mut p = plan_for(&img, &opts(mode));
                p.truncate = truncate;
                let (a, ra) = run_clean(&img, &p).unwrap();
                let (w, rw) = run_clean(&wide, &p).unwrap();
                assert_eq!(a.data, w.data, "{b} {mode:?} truncate {truncate}");
                assert_eq!(ra, rw, "{b} {mode:?}");
                let p = with_dim(p, 0.3);
                assert_eq!(
                    run_clean(&img, &p).unwrap().0.data,
                    run_clean(&wide, &p).unwrap().0.data
                );
            }
        }
    }
}

#[test]
fn physics_model_plan_carries_params_and_gaussian_plans_do_not() {
    use crate::noise::physics::{PhysicsModel, PhysicsPoint};
    let img = frame(Bayer::RGGB, 16, 12, [500, 700, 300]);
    let o = SynthOptions {
        isos: vec![800, 1200, 6400],
        ..SynthOptions::default()
    };
    let mut cal = Calibration::embedded(&o).unwrap();
    let gauss = Planner::new(&img, &o)
        .calibration(&cal)
        .name("x")
        .seed(3)
        .plan()
        .map(|p| p.plan)
        .unwrap();
    assert!(gauss.noise.iter().all(|n| n.physics.is_none()));
    let j = serde_json::to_string(&gauss).unwrap();
    assert!(!j.contains("\"physics\":{"), "{j}");
    let pt = |iso, k| PhysicsPoint {
        iso,
        k,
        sigma_read: 2.0 * k,
        lambda: 0.05,
        gaussian_read: false,
        sigma_row: 0.5 * k,
    };
    let pm = PhysicsModel::new("t", 512.0, 16383.0, vec![pt(800, 1.0), pt(1600, 2.0)]).unwrap();
    cal.noise = Some(NoiseModel::from_physics(pm.clone()).unwrap());
    let Planned { plan: p, report } = Planner::new(&img, &o)
        .calibration(&cal)
        .name("x")
        .seed(3)
        .plan()
        .unwrap();
    // Same random draws as the Gaussian plan (the seeds do not depend on the model).
    assert_eq!(p.lights, gauss.lights);
    let scale = WHITE - BLACK;
    for n in &p.noise {
        let ph = n.physics.unwrap();
        assert_eq!(ph, pm.at(n.iso).unwrap().params);
        assert_eq!(n.params, ph.to_noise_params(scale));
        assert_eq!(n.extrapolated, n.iso == 6400);
    }
    assert!(report
        .warnings
        .iter()
        .any(|w| w.message.contains("ISO 6400")));
    p.check_against(&img).unwrap();
    // The plan round-trips through JSON (the sidecar) with its physics parameters.
    let back: Plan = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
    assert_eq!(back, p);
    let out = run(&img, &p).unwrap();
    assert_eq!(out.noisy.len(), 3);
    assert_ne!(out.noisy[0].1.data, out.clean.data);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Anything the sampler produces passes the replay bounds (crate::bounds), whatever the
    /// input's neutral (within the metadata bound), levels, ISOs (within ISO_RANGE), mode,
    /// formula and seed: `synth` never writes a sidecar that `--replay` refuses.
    #[test]
    fn sampled_plans_pass_the_replay_bounds(
        seed in any::<u64>(),
        log_isos in proptest::collection::vec(0.0f64..=6.602, 0..4),
        log_r in -3.0f64..=3.0,
        log_b in -3.0f64..=3.0,
        bits in 8u16..=16,
        mode in 0usize..4,
        paper in any::<bool>(),
    ) {
        let white = ((1u32 << bits) - 1) as f64;
        let mut img = frame(Bayer::GRBG, 8, 6, [500, 700, 300]);
        img.meta.levels.white = white;
        img.meta.levels.black = vec![0.0];
        img.meta.bits_per_sample = bits;
        img.meta.as_shot_neutral = Some([10f64.powf(log_r), 1.0, 10f64.powf(log_b)]);
        crate::dng::check::check_meta(&mut img.meta).unwrap();
        let (lo, hi) = crate::bounds::ISO_RANGE;
        let mut o = SynthOptions {
            isos: log_isos
                .iter()
                .map(|l| (10f64.powf(*l).round() as u32).clamp(lo, hi))
                .collect(),
            mode: [Mode::Local, Mode::Day, Mode::Dimmed, Mode::Global][mode],
            ..SynthOptions::default()
        };
        o.isos.dedup();
        if paper {
            o.formula = RelightFormula::Paper;
        }
        let cal = Calibration::embedded(&o).unwrap();
        let p = Planner::new(&img, &o)
        .calibration(&cal)
        .name("b")
        .seed(seed)
        .plan()
        .map(|p| p.plan).unwrap();
        prop_assert!(p.validate_bounds().is_ok());
    }
}
