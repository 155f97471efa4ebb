//! Synthesis stages on a 12 MP (4000 x 3000) RGGB 14-bit frame generated here:
//! normalize, the fused clean pass in `day` mode (normalize + denormalize only),
//! relight local (release formula, 4 lights + 5 bulbs, each mask evaluation), and noise
//! (one ISO: the Gaussian model, and the physics model of issue 14 with a bench model of
//! the same total variance at that ISO). Before timing, prints the error of each mask evaluation against the exact one
//! (max and mean absolute difference in DN over the frame) for docs/benchmarks.md.
//!
//! Run: `cargo bench --bench synth` (D2N_BENCH_QUICK=1 for a shorter run;
//! D2N_BENCH_NO_ACCURACY=1 skips the accuracy table; `-- noise` times the noise stages only).
use criterion::{criterion_group, criterion_main, Criterion};
use day2night::noise::physics::{PhysicsModel, PhysicsPoint};
use day2night::noise::NoiseModel;
use day2night::normalize::{normalize, NormalizeOptions};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use day2night::synth::{self, Calibration, MaskEval, Mode, SynthOptions};
use std::hint::black_box;
use std::time::Instant;

fn frame() -> RawImage {
    let (w, h) = (4000usize, 3000usize);
    let mut data = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            // Smooth gradients plus a texture, 14-bit, black 512.
            let v = 512.0
                + 6000.0 * (r as f64 / h as f64)
                + 5000.0 * (c as f64 / w as f64)
                + 800.0 * ((r * 7 + c * 13) % 97) as f64 / 97.0;
            data.push(v as u16);
        }
    }
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 14, 512.0, 16383.0);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
    meta.exif.iso = Some(100);
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

fn plan_for(img: &RawImage, mode: Mode, eval: MaskEval) -> synth::Plan {
    plan_with(img, mode, eval, false)
}

/// The plan, with the physics noise model of [`physics_model`] when `physics`.
fn plan_with(img: &RawImage, mode: Mode, eval: MaskEval, physics: bool) -> synth::Plan {
    let o = SynthOptions {
        mode,
        mask_eval: eval,
        isos: vec![3200],
        ..SynthOptions::default()
    };
    let mut cal = Calibration::embedded(&o).unwrap();
    if physics {
        cal.noise = Some(NoiseModel::from_physics(physics_model()).unwrap());
    }
    synth::Planner::new(img, &o)
        .calibration(&cal)
        .name("bench.dng")
        .seed(1)
        .plan()
        .map(|p| p.plan)
        .unwrap()
}

/// A physics model for the bench frame's levels (14-bit, black 512): at ISO 3200 K = 4
/// DN/e-, Tukey read noise lambda 0.05 of 6 DN, row noise 1.5 DN.
fn physics_model() -> PhysicsModel {
    let pt = |iso, k: f64| PhysicsPoint {
        iso,
        k,
        sigma_read: 1.5 * k,
        lambda: 0.05,
        gaussian_read: false,
        sigma_row: 0.375 * k,
    };
    PhysicsModel::new("bench", 512.0, 16383.0, vec![pt(1600, 2.0), pt(3200, 4.0)]).unwrap()
}

fn accuracy(img: &RawImage) {
    let exact = synth::run_clean(img, &plan_for(img, Mode::Local, MaskEval::Exact))
        .unwrap()
        .0;
    for eval in [
        MaskEval::Separable,
        MaskEval::Truncated { k: 3.0 },
        MaskEval::Truncated { k: 4.0 },
        MaskEval::Truncated { k: 5.0 },
        MaskEval::Truncated { k: 6.0 },
    ] {
        let p = plan_for(img, Mode::Local, eval);
        let t = Instant::now();
        let out = synth::run_clean(img, &p).unwrap().0;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let (mut max, mut sum, mut n_diff) = (0i32, 0u64, 0u64);
        for (a, b) in exact.data.iter().zip(&out.data) {
            let d = (*a as i32 - *b as i32).abs();
            max = max.max(d);
            sum += d as u64;
            n_diff += (d != 0) as u64;
        }
        eprintln!(
            "accuracy {:?}: max {} DN, mean {:.6} DN, {} of {} samples differ from exact; one run {:.0} ms",
            eval,
            max,
            sum as f64 / exact.data.len() as f64,
            n_diff,
            exact.data.len(),
            ms
        );
    }
}

fn bench(c: &mut Criterion) {
    let img = frame();
    if std::env::var_os("D2N_BENCH_NO_ACCURACY").is_none() {
        accuracy(&img);
    }
    let mut g = c.benchmark_group("synth_12mp");
    g.sample_size(10);
    if std::env::var_os("D2N_BENCH_QUICK").is_some() {
        g.measurement_time(std::time::Duration::from_secs(3));
        g.warm_up_time(std::time::Duration::from_millis(500));
    }
    g.bench_function("normalize", |b| {
        b.iter(|| black_box(normalize(&img, NormalizeOptions::default()).unwrap()))
    });
    let day = plan_for(&img, Mode::Day, MaskEval::Separable);
    g.bench_function("clean_pass_day_mode", |b| {
        b.iter(|| black_box(synth::run_clean(&img, &day).unwrap()))
    });
    for (name, eval) in [
        ("relight_local_separable", MaskEval::Separable),
        ("relight_local_exact", MaskEval::Exact),
        (
            "relight_local_truncated_6sigma",
            MaskEval::Truncated { k: 6.0 },
        ),
    ] {
        let p = plan_for(&img, Mode::Local, eval);
        g.bench_function(name, |b| {
            b.iter(|| black_box(synth::run_clean(&img, &p).unwrap()))
        });
    }
    let p = plan_for(&img, Mode::Local, MaskEval::Separable);
    let (clean, _) = synth::run_clean(&img, &p).unwrap();
    g.bench_function("noise_one_iso", |b| {
        b.iter(|| black_box(synth::run_noise(&clean, &p, 0).unwrap()))
    });
    let pp = plan_with(&img, Mode::Local, MaskEval::Separable, true);
    g.bench_function("noise_one_iso_physics", |b| {
        b.iter(|| black_box(synth::run_noise(&clean, &pp, 0).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
