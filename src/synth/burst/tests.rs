//! Tests of the burst: the warp against an analytic scene, exact integer shifts, tiling and
//! thread independence, crops equal to the whole frames' regions.

use super::interp::Interp;
use super::motion::{invert, rigid, BurstOptions, Motion, Shake};
use super::warp::{CleanSource, WarpLevels, Warper};
use crate::normalize::Normalizer;
use crate::raw::crop::Crop;
use crate::raw::meta::RawMeta;
use crate::raw::{Bayer, RawImage};
use crate::synth::night::{synthesize, Request};
use crate::synth::{Calibration, Plan, Planner, SynthOptions};
use std::path::Path;

/// A smooth colour scene (normalized values in about [0.1, 0.9]) at (x, y).
fn scene(x: f64, y: f64) -> [f64; 3] {
    let t = 0.5 + 0.2 * (x * 0.21).sin() * (y * 0.17).cos() + 0.1 * (y * 0.11 + x * 0.05).sin();
    [0.8 * t + 0.05, t, 0.6 * t + 0.1]
}

/// A `w x h` raw (no masked border, black 64, white 16383) holding `scene`'s mosaic.
fn scene_raw(w: usize, h: usize) -> RawImage {
    let (black, white) = (64.0, 16383.0);
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 14, black, white);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.7]);
    let data = (0..w * h)
        .map(|i| {
            let (y, x) = (i / w, i % w);
            let v = scene(x as f64, y as f64)[Bayer::RGGB.color_at(y, x) as usize];
            (v * (white - black) + black).round() as u16
        })
        .collect();
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

fn warp_all(img: &RawImage, aff: &[[f64; 3]; 2], interp: Interp) -> Vec<u16> {
    let norm = Normalizer::new(img).unwrap();
    let levels = WarpLevels {
        norm: &norm,
        bayer: Bayer::RGGB,
        neutral: [0.5, 1.0, 0.7],
        active: (img.width, img.height),
        keep_negative: false,
        truncate: false,
    };
    let src = CleanSource {
        data: &img.data,
        stride: img.width,
        offset: 0,
        rows: 0..img.height,
        cols: 0..img.width,
    };
    let w = Warper::new(src, &levels, invert(aff), interp);
    let mut out = vec![0u16; img.data.len()];
    w.fill(0..img.height, 0..img.width, &mut out, (img.width, 0));
    out
}

/// RMS error (DN) of a warped frame against the analytic scene moved by `aff`, over the
/// frame's interior (8 samples from the edges).
fn warp_error(img: &RawImage, aff: &[[f64; 3]; 2], interp: Interp) -> f64 {
    let out = warp_all(img, aff, interp);
    let inv = invert(aff);
    let (mut se, mut n) = (0.0, 0.0);
    for y in 8..img.height - 8 {
        for x in 8..img.width - 8 {
            let (sx, sy) = super::motion::apply(&inv, x as f64, y as f64);
            let want = scene(sx, sy)[Bayer::RGGB.color_at(y, x) as usize] * (16383.0 - 64.0) + 64.0;
            se += (out[y * img.width + x] as f64 - want).powi(2);
            n += 1.0;
        }
    }
    (se / n).sqrt()
}

#[test]
fn the_warp_follows_the_scene() {
    let img = scene_raw(96, 80);
    // The scene spans about 16000 DN. Integer shifts are exact up to the 0.29 DN of
    // rounding the scene; fractional ones carry the demosaicer's error at the interpolated
    // sites (docs/synthesis.md, "Bursts": the interpolants compared).
    for (dx, dy, th, tol) in [
        (2.0, 0.0, 0.0, 0.3),
        (0.5, 0.0, 0.0, 30.0),
        (0.5, 0.5, 0.0, 30.0),
        (1.37, -0.61, 0.4, 30.0),
    ] {
        let aff = rigid([47.5, 39.5], dx, dy, th);
        for k in Interp::ALL {
            let e = warp_error(&img, &aff, k);
            assert!(e < tol, "{k} ({dx}, {dy}, {th}): RMS {e} DN");
        }
    }
}

#[test]
fn even_integer_shifts_copy_samples_exactly() {
    let img = scene_raw(64, 48);
    let aff = rigid([31.5, 23.5], 2.0, -4.0, 0.0);
    for interp in Interp::ALL {
        let out = warp_all(&img, &aff, interp);
        for y in 4..44 {
            for x in 0..62 {
                assert_eq!(out[y * 64 + x + 2], img.data[(y + 4) * 64 + x], "{interp}");
            }
        }
    }
}

#[test]
fn tiles_and_row_chunks_do_not_change_samples() {
    let img = scene_raw(300, 270);
    let aff = rigid([149.5, 134.5], -3.3, 2.7, 1.1);
    let whole = warp_all(&img, &aff, Interp::CatmullRom);
    let norm = Normalizer::new(&img).unwrap();
    let levels = WarpLevels {
        norm: &norm,
        bayer: Bayer::RGGB,
        neutral: [0.5, 1.0, 0.7],
        active: (300, 270),
        keep_negative: false,
        truncate: false,
    };
    let src = CleanSource {
        data: &img.data,
        stride: 300,
        offset: 0,
        rows: 0..270,
        cols: 0..300,
    };
    let w = Warper::new(src, &levels, invert(&aff), Interp::CatmullRom);
    let mut out = vec![0u16; 300 * 270];
    let mut y = 0;
    for step in [1usize, 7, 130, 3, 129].iter().cycle() {
        if y >= 270 {
            break;
        }
        let y1 = (y + step).min(270);
        w.fill(y..y1, 0..300, &mut out[y * 300..], (300, 0));
        y = y1;
    }
    assert_eq!(out, whole);
}

fn fixture() -> RawImage {
    let fix = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/day.dng");
    crate::dng::read_dng(&fix).unwrap()
}

fn burst_plan(day: &RawImage, motion: Motion, physics: bool) -> Plan {
    let opts = SynthOptions {
        isos: vec![1600],
        burst: BurstOptions {
            frames: 4,
            motion,
            shake: Shake {
                step_px: 3.0,
                roll_deg: 0.3,
            },
            ..crate::synth::options::burst_defaults()
        },
        ..SynthOptions::default()
    };
    let mut cal = Calibration::embedded(&opts).unwrap();
    if physics {
        use crate::noise::physics::{PhysicsModel, PhysicsPoint};
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
        cal.noise = Some(crate::noise::NoiseModel::from_physics(pm).unwrap());
    }
    Planner::new(day, &opts)
        .calibration(&cal)
        .name("day.dng")
        .seed(5)
        .plan()
        .map(|p| p.plan)
        .unwrap()
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

#[test]
fn frame_crops_equal_the_whole_frames_regions_for_any_thread_count() {
    let day = fixture();
    // physics noise draws per site, so a crop's noisy frame is the frame's region
    let p = burst_plan(&day, Motion::Shake, true);
    let b = p.burst.as_ref().unwrap();
    assert!(b.transforms[1..].iter().all(|t| !t.is_identity()));
    let full = synthesize(&day, &p, &Request::default()).unwrap();
    assert_eq!(full.frames.len(), 3);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| synthesize(&day, &p, &Request::default()).unwrap());
    for (a, b) in full.frames.iter().zip(&one.frames) {
        assert_eq!(a.2.data, b.2.data, "frame {} with one thread", a.1);
    }
    let a = day.active_area();
    let (aw, ah) = (a.width(), a.height());
    for crop in [
        Crop {
            top: 0,
            left: 0,
            height: 30,
            width: 40,
        },
        Crop {
            top: 100,
            left: 202,
            height: 77,
            width: 91,
        },
        Crop {
            top: ah - 40,
            left: aw - 50,
            height: 40,
            width: 50,
        },
    ] {
        let c = synthesize(
            &day,
            &p,
            &Request {
                crop: Some(crop),
                ..Request::default()
            },
        )
        .unwrap();
        assert_region(&c.noisy[0].1, &full.noisy[0].1, &crop, "frame 0");
        assert_eq!(c.frames.len(), 3);
        for ((iso, k, img), (_, _, f)) in c.frames.iter().zip(&full.frames) {
            assert_eq!(*iso, 1600);
            assert_region(img, f, &crop, &format!("frame {k}"));
        }
    }
}

#[test]
fn still_frames_are_the_clean_raw_plus_independent_noise() {
    let day = fixture();
    let p = burst_plan(&day, Motion::None, false);
    let n = synthesize(&day, &p, &Request::default()).unwrap();
    // frame 00 is the single-frame noisy raw
    let single = {
        let mut q = p.clone();
        q.burst = None;
        synthesize(&day, &q, &Request::default()).unwrap()
    };
    assert_eq!(n.noisy[0].1.data, single.noisy[0].1.data);
    assert!(single.frames.is_empty());
    let a = day.active_area();
    let clean = &n.clean;
    let mut prev: Vec<&[u16]> = vec![&n.noisy[0].1.data];
    for (_, k, f) in &n.frames {
        // same masked border, different noise draws
        for r in 0..a.top as usize {
            assert_eq!(
                f.data[r * f.width..(r + 1) * f.width],
                clean.data[r * f.width..(r + 1) * f.width]
            );
        }
        for q in &prev {
            assert_ne!(&f.data[..], *q, "frame {k}");
        }
        prev.push(&f.data);
    }
}
