//! `--compat release` and its pieces (docs/synthesis.md, "Release compatibility"): the
//! preset end to end (sidecar, replay, thread counts), the day neutral as stored on a real
//! file whose AsShotNeutral has green 2.477, and `--mode day` returning every unclipped
//! sample exactly on the fixtures and the real camera files, rounding and truncating; the
//! release's per-site range with a 2x2 black level and bulbs on every CFA phase, against an
//! independent numpy reference of the release's arithmetic.
use crate::common;
use crate::dngbuild;

use day2night::dng::read_dng;
use day2night::normalize::Normalizer;
use day2night::raw::RawImage;
use day2night::synth::sidecar::Sidecar;
use day2night::synth::{
    self, run_clean, Calibration, Compat, MaskEval, Mode, SynthOptions, NO_MAHALANOBIS_CUT,
};
use std::path::{Path, PathBuf};

// The synth CLI helpers are shared with synth_cli (same test binary).
use crate::synth_cli::{files, ok, same, synth};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn canon() -> PathBuf {
    common::shared_file("dng/canon_kissx4_magiclantern_rggb14_strips.dng")
}

#[test]
fn preset_is_recorded_replayed_and_thread_count_free() {
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let (a, b, c) = (t.path().join("a"), t.path().join("b"), t.path().join("c"));
    let args = |o: &Path, jobs: &str| {
        vec![
            s(&day).to_string(),
            "-o".into(),
            s(o).to_string(),
            "--compat".into(),
            "release".into(),
            "--seed".into(),
            "5".into(),
            "--jobs".into(),
            jobs.into(),
        ]
    };
    let run = |v: Vec<String>| synth(&v.iter().map(|x| x.as_str()).collect::<Vec<_>>());
    ok(&run(args(&a, "1")));
    ok(&run(args(&b, "2")));
    same(&files(&a), &files(&b), "--jobs 1 vs 2");
    let sc = Sidecar::read(&a.join("day.json")).unwrap();
    assert!(sc.options.truncate && sc.plan.truncate && sc.plan.truncate_noise);
    assert_eq!(sc.options.compat, Compat::RELEASE);
    assert_eq!(sc.options.mask_eval, MaskEval::Release);
    assert_eq!(sc.options.sampler.max_mahalanobis, NO_MAHALANOBIS_CUT);
    assert!(sc.report.day_neutral_source.contains("as stored"));
    // replay reproduces every byte
    ok(&synth(&[
        s(&day),
        "-o",
        s(&c),
        "--replay",
        s(&a.join("day.json")),
    ]));
    same(&files(&a), &files(&c), "replay");
    // the preset differs from the default run of the same seed
    let d = t.path().join("d");
    ok(&synth(&[s(&day), "-o", s(&d), "--seed", "5"]));
    assert_ne!(files(&a)["day_clean.dng"], files(&d)["day_clean.dng"]);
    let text = std::fs::read_to_string(d.join("day.json")).unwrap();
    assert!(!text.contains("compat") && text.contains("\"truncate_noise\": false"));
}

#[test]
fn preset_refuses_conflicting_flags() {
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    for extra in [
        ["--relight-formula", "paper"],
        ["--covariance", "ml"],
        ["--mask-eval", "exact"],
    ] {
        let mut v = vec![s(&day), "-o", s(t.path()), "--compat", "release"];
        v.extend(extra);
        let out = synth(&v);
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--compat release"), "{err}");
    }
    // --mask-eval release alone is a plain option
    ok(&synth(&[
        s(&day),
        "-o",
        s(&t.path().join("m")),
        "--mask-eval",
        "release",
        "--iso",
        "none",
        "--target",
        "none",
    ]));
}

/// The black levels of the per-site test inputs (BlackLevelRepeatDim 2x2), white 1023.
const SITE_BLACKS: [u32; 4] = [250, 256, 260, 254];

/// A big-endian 10-bit DNG of 384x256 with CFA pattern `cfa` and [`SITE_BLACKS`]: smooth
/// ramps, a band below black and a saturated patch (1023).
fn per_site_black_dng(cfa: [u8; 4]) -> Vec<u8> {
    use day2night::tiff::value::Value;
    let (w, h) = (384usize, 256usize);
    let mut b = dngbuild::Builder::new(w, h, 10);
    b.big_endian = true;
    b.layout = dngbuild::Pixels::Strips { rows: 32 };
    b.pixels = (0..w * h)
        .map(|i| {
            let (r, c) = (i / w, i % w);
            if (100..130).contains(&r) && (50..120).contains(&c) {
                return 1023;
            }
            if r < 6 {
                return 240 + (c % 20) as u16;
            }
            let (y, x) = (r as f64 / h as f64, c as f64 / w as f64);
            (262.0 + 480.0 * y + 250.0 * x + 30.0 * (9.0 * x).sin()).min(1023.0) as u16
        })
        .collect();
    b.set(33422, Value::Byte(cfa.to_vec()))
        .set(50713, Value::Short(vec![2, 2]))
        .set(50714, Value::Long(SITE_BLACKS.to_vec()))
        .set(50717, Value::Long(vec![1023]))
        .build()
}

/// `tests/validators/release_relight.py` on (day, sidecar, clean): its JSON report.
fn release_reference(py: &Path, day: &Path, sidecar: &Path, clean: &Path) -> serde_json::Value {
    let blacks = SITE_BLACKS.map(|b| b.to_string()).join(",");
    let o = common::run_validator(
        py,
        "release_relight.py",
        &[
            day.as_os_str(),
            sidecar.as_os_str(),
            clean.as_os_str(),
            "--black".as_ref(),
            blacks.as_ref(),
            "--white".as_ref(),
            "1023".as_ref(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// With `D2N_RELEASE_INPUTS=DIR` the inputs and outputs are kept in DIR, to run the
/// authors' release on them outside the repository (docs/synthesis.md, "Release
/// compatibility", per-site black levels).
#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn release_bulbs_with_per_site_black_match_the_release_on_every_cfa_phase() {
    let py = common::python();
    let tmp = tempfile::tempdir().unwrap();
    let keep = std::env::var_os("D2N_RELEASE_INPUTS").map(PathBuf::from);
    if let Some(k) = &keep {
        std::fs::create_dir_all(k).unwrap();
    }
    let t = keep.as_deref().unwrap_or(tmp.path());
    for (name, cfa) in [
        ("rggb", [0u8, 1, 1, 2]),
        ("grbg", [1, 0, 2, 1]),
        ("gbrg", [1, 2, 0, 1]),
        ("bggr", [2, 1, 1, 0]),
    ] {
        let day = t.join(format!("{name}.dng"));
        std::fs::write(&day, per_site_black_dng(cfa)).unwrap();
        let out = t.join(name);
        ok(&synth(&[
            s(&day),
            "-o",
            s(&out),
            "--overwrite",
            "--compat",
            "release",
            "--iso",
            "none",
            "--target",
            "none",
            "--seed",
            "7",
        ]));
        let sidecar = out.join(format!("{name}.json"));
        let clean = out.join(format!("{name}_clean.dng"));
        let sc = Sidecar::read(&sidecar).unwrap();
        assert!(sc.plan.range_per_site && sc.options.compat.range_per_site);
        let r = release_reference(&py, &day, &sidecar, &clean);
        eprintln!("{name}: preset vs the release's arithmetic: {r}");
        // the bulbs and the saturated patch put many sites at 1 (the path under test)
        assert!(r["saturated"].as_u64().unwrap() > 1000, "{name}: {r}");
        assert!(r["bulb_lit"].as_u64().unwrap() > 1000, "{name}: {r}");
        assert!(r["max_abs_diff"].as_u64().unwrap() <= 1, "{name}: {r}");
        // Control: the same plan with white - black_max as every site's range (the preset
        // before the fix, and what a sidecar without the switch replays) is caught.
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&sidecar).unwrap()).unwrap();
        v["options"]["compat"]["range_per_site"] = false.into();
        v["plan"]["range_per_site"] = false.into();
        let old = t.join(format!("{name}-old.json"));
        std::fs::write(&old, serde_json::to_string(&v).unwrap()).unwrap();
        let out_old = t.join(format!("{name}-old"));
        ok(&synth(&[
            s(&day),
            "-o",
            s(&out_old),
            "--overwrite",
            "--replay",
            s(&old),
        ]));
        let r_old = release_reference(
            &py,
            &day,
            &sidecar,
            &out_old.join(format!("{name}_clean.dng")),
        );
        eprintln!("{name}: with white - black_max: {r_old}");
        assert!(
            r_old["max_abs_diff"].as_u64().unwrap() >= 4,
            "{name}: {r_old}"
        );
    }
}

/// Clean night raw of `img` with `opts` (seed 3).
fn clean(img: &RawImage, opts: &SynthOptions) -> (RawImage, synth::Plan) {
    let cal = Calibration::embedded(opts).unwrap();
    let p = synth::Planner::new(img, opts)
        .calibration(&cal)
        .name("x.dng")
        .seed(3)
        .plan()
        .map(|p| p.plan)
        .unwrap();
    (run_clean(img, &p).unwrap().0, p)
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn stored_neutral_makes_the_canon_file_2_48x_darker() {
    let path = canon();
    let img = read_dng(&path).unwrap();
    // The file stores "1 2.477 1.462"; the DNG reader normalizes it to green = 1 and keeps
    // the stored entry (RawMeta::stored), which the preset divides by.
    let n = img.meta.as_shot_neutral.unwrap();
    assert!((n[0] - 1.0 / 2.477).abs() < 1e-12 && n[1] == 1.0);
    let base = SynthOptions {
        mode: Mode::Global,
        isos: vec![],
        ..SynthOptions::default()
    };
    let stored = SynthOptions {
        compat: Compat {
            neutral_as_stored: true,
            ..Compat::default()
        },
        ..base.clone()
    };
    let (a, pa) = clean(&img, &base);
    let (b, pb) = clean(&img, &stored);
    assert_eq!(pa.lights, pb.lights);
    assert!(
        (pb.day_neutral[1] - 2.477).abs() < 1e-3,
        "{:?}",
        pb.day_neutral
    );
    let norm = Normalizer::new(&img).unwrap();
    let area = img.active_area();
    // green sites (RGGB in the active area: row + col odd), unclipped in both
    let (mut sa, mut sb) = (0.0, 0.0);
    for r in area.top as usize..area.bottom as usize {
        for c in area.left as usize..area.right as usize {
            if (r - area.top as usize + c - area.left as usize).is_multiple_of(2) {
                continue;
            }
            let (x, y) = (a.get(r, c) as f64, b.get(r, c) as f64);
            if x < norm.white * 0.9 && x > 2056.0 + 200.0 {
                sa += x - 2056.0;
                sb += y - 2056.0;
            }
        }
    }
    let ratio = sa / sb;
    eprintln!("default / as stored: {ratio:.4}");
    assert!((ratio - 2.477).abs() < 0.01, "{ratio}");
}

/// `--mode day`: every sample that no clip changed is the linearized input itself.
fn check_day_identity(img: &RawImage, what: &str) {
    let norm = Normalizer::new(img).unwrap();
    let area = img.active_area();
    let (top, left) = (area.top as usize, area.left as usize);
    for truncate in [false, true] {
        let opts = SynthOptions {
            mode: Mode::Day,
            isos: vec![],
            truncate,
            ..SynthOptions::default()
        };
        let (out, p) = clean(img, &opts);
        let (mut n, mut cut, mut old_off) = (0u64, 0u64, 0u64);
        for r in 0..area.height() {
            for c in 0..area.width() {
                let x = img.get(r + top, c + left);
                let lin = norm.linearize(x);
                let y = norm.normalize_with_black(x, norm.black_at(r, c));
                let v = y / p.day_neutral[p.bayer.color_at(r, c) as usize];
                if y < 0.0 || v > 1.0 || lin > norm.white {
                    cut += 1;
                    continue;
                }
                n += 1;
                // the f32 round trip of the clean pass before the fix (y_w as f32, times
                // the neutral as f32, denormalized): how many samples it moved
                let nc = p.day_neutral[p.bayer.color_at(r, c) as usize];
                let old = norm.denormalize_with_black(
                    ((v as f32) * (nc as f32)) as f64,
                    norm.black_at(r, c),
                    truncate,
                );
                old_off += (old as f64 != lin) as u64;
                assert_eq!(
                    out.get(r + top, c + left) as f64,
                    lin,
                    "{what} truncate {truncate} ({r},{c})"
                );
            }
        }
        eprintln!(
            "{what}: truncate {truncate}: {n} samples exact, {cut} clipped; the f32 round trip \
             moved {old_off} ({:.1} %)",
            100.0 * old_off as f64 / n as f64
        );
        assert!(n > 0, "{what}");
    }
}

#[test]
fn day_mode_returns_the_input_on_fixtures() {
    let mut checked = 0;
    for e in std::fs::read_dir(common::fixtures()).unwrap() {
        let p = e.unwrap().path();
        if p.extension().and_then(|x| x.to_str()) != Some("dng") {
            continue;
        }
        let img = read_dng(&p).unwrap();
        // fixtures without a neutral or with a non-Bayer layout are not day inputs
        let ok = img.bayer().is_ok()
            && synth::neutral::day_neutral(&img.meta, None).is_ok()
            && Normalizer::new(&img).is_ok();
        if ok {
            check_day_identity(&img, &p.display().to_string());
            checked += 1;
        }
    }
    assert!(checked >= 5, "{checked}");
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn day_mode_returns_the_input_on_the_real_canon_file() {
    check_day_identity(&read_dng(&canon()).unwrap(), "canon");
}

/// Measurement for docs/synthesis.md (run with `--ignored --nocapture`): mask and clean-raw
/// differences between the analytic masks (default) and the release's resized kernels on
/// 10-bit frames (black 64, white 1023) of 512x512 and 4000x3000, several seeds.
#[test]
#[ignore = "measurement for docs/synthesis.md: run with --ignored --nocapture"]
fn measure_release_masks() {
    use day2night::raw::meta::RawMeta;
    use day2night::raw::Bayer;
    use day2night::synth::masks::{LightKind, PreparedMask};
    for (w, h, seeds, snap) in [
        (512usize, 512usize, 20u64, false),
        (512, 512, 20, true),
        (4000, 3000, 4, false),
        (4000, 3000, 4, true),
    ] {
        let mut meta = RawMeta::new_bayer(Bayer::RGGB, 10, 64.0, 1023.0);
        meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
        // a smooth scene: mid-grey with gentle gradients
        let data = (0..w * h)
            .map(|i| {
                let (r, c) = ((i / w) as f64 / h as f64, (i % w) as f64 / w as f64);
                (200.0 + 500.0 * r * c + 150.0 * (6.0 * c).sin().abs()) as u16
            })
            .collect();
        let img = RawImage {
            width: w,
            height: h,
            data,
            meta,
        };
        let (mut bulb_max, mut bulb_sum, mut bulb_n) = (0f32, 0f64, 0f64);
        let (mut loc_max, mut loc_sum, mut loc_n) = (0f32, 0f64, 0f64);
        let (mut dn_max, mut dn_sum, mut dn_diff, mut dn_n) = (0i32, 0f64, 0f64, 0f64);
        for seed in 0..seeds {
            let base = SynthOptions {
                isos: vec![],
                ..SynthOptions::default()
            };
            let cal = Calibration::embedded(&base).unwrap();
            let mut pa = synth::Planner::new(&img, &base)
                .calibration(&cal)
                .name("m.dng")
                .seed(seed)
                .plan()
                .map(|p| p.plan)
                .unwrap();
            if snap {
                // centres on the release's grid (its integer location ty is the window's
                // first row + h // 2): only the kernel's shape differs, not its placement
                for l in pa.lights.iter_mut() {
                    if let Some(win) = l.window {
                        for (c, n) in l.center.iter_mut().zip(win) {
                            let n = n.round();
                            let first = (*c - n / 2.0).floor() + 1.0;
                            *c = first + (n - 1.0) / 2.0;
                        }
                    }
                }
            }
            let mut pb = pa.clone();
            pb.mask_eval = MaskEval::Release;
            for l in pa.lights.iter().filter(|l| l.kind != LightKind::Ambient) {
                let a = PreparedMask::new(l, w, h, MaskEval::Separable);
                let b = PreparedMask::new(l, w, h, MaskEval::Release);
                let rows = a.rows.0.min(b.rows.0)..a.rows.1.max(b.rows.1);
                let (mut m, mut sum, mut n) = (0f32, 0f64, 0f64);
                let row_of = |pm: &PreparedMask, r: usize| {
                    let mut full = vec![0f32; w];
                    if pm.on_row(r) {
                        let (c0, c1) = pm.cols;
                        pm.fill_row(r, &mut full[c0..c1]);
                    }
                    full
                };
                for r in rows {
                    let (ra, rb) = (row_of(&a, r), row_of(&b, r));
                    for (&va, &vb) in ra.iter().zip(&rb) {
                        let d = (va - vb).abs();
                        m = m.max(d);
                        // mean over the lit part (either mask >= 1 %), not the floor
                        if va.max(vb) >= 0.01 {
                            sum += d as f64;
                            n += 1.0;
                        }
                    }
                }
                if l.kind == LightKind::Bulb {
                    bulb_max = bulb_max.max(m);
                    (bulb_sum, bulb_n) = (bulb_sum + sum, bulb_n + n);
                } else {
                    loc_max = loc_max.max(m);
                    (loc_sum, loc_n) = (loc_sum + sum, loc_n + n);
                }
            }
            let (ca, _) = run_clean(&img, &pa).unwrap();
            let (cb, _) = run_clean(&img, &pb).unwrap();
            for (&x, &y) in ca.data.iter().zip(&cb.data) {
                let d = (x as i32 - y as i32).abs();
                dn_max = dn_max.max(d);
                dn_sum += d as f64;
                dn_diff += (d != 0) as u32 as f64;
                dn_n += 1.0;
            }
        }
        eprintln!(
            "{w}x{h}, {seeds} plans, centres on the release grid {snap}: bulbs mask |diff| max {:.4} mean {:.2e} (where >= 0.01); \
             local lights max {:.4} mean {:.2e}; clean raw |diff| max {dn_max} DN, mean {:.4} DN, \
             {:.3} % of samples differ",
            bulb_max,
            bulb_sum / bulb_n,
            loc_max,
            loc_sum / loc_n,
            dn_sum / dn_n,
            100.0 * dn_diff / dn_n
        );
    }
}
