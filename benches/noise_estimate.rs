//! Cost and accuracy of the single-image noise estimate (`noise::estimate`) on a 12 MP
//! (4000 x 3000) frame: the `texture` content of examples/noise_estimate_accuracy.rs
//! (a real photograph enlarged to the frame), 14-bit RGGB, with known noise
//! `var(y) = a y + b` (a = 4e-5, b = 4e-7, a DSLR-like base ISO). Before timing, prints the
//! error of every subsample step against the truth, for docs/noise.md and
//! docs/benchmarks.md ("error against run time").
//!
//! Run: `cargo bench --bench noise_estimate` (D2N_BENCH_QUICK=1 for a shorter run).
use criterion::{criterion_group, criterion_main, Criterion};
use day2night::noise::estimate::{estimate, EstimateOptions};
use day2night::raw::Bayer;
use std::hint::black_box;

#[path = "../examples/noise_estimate_accuracy.rs"]
mod accuracy;

use accuracy::{errors, synthetic_frame, Content, Grey};

const STEPS: [usize; 4] = [1, 2, 4, 8];

fn bench(c: &mut Criterion) {
    let (a, b) = (4e-5, 4e-7);
    let grey = Grey::astronaut().halved();
    let img = synthetic_frame(
        Content::Texture,
        &grey,
        Bayer::RGGB,
        14,
        4000,
        3000,
        a,
        b,
        1,
    );
    println!("12 MP texture frame, 14-bit, a = {a:e}, b = {b:e}");
    println!("| step | max abs(S/a - 1) | max abs(O - b) | max abs(O/b - 1) | trusted |");
    for step in STEPS {
        let e = estimate(&img, &EstimateOptions { step: Some(step) }).unwrap();
        let er = errors(&e, a, b);
        println!(
            "| {step} | {:.4} | {:.2e} | {:.3} | {} |",
            er.s_rel,
            er.o_abs,
            er.o_rel,
            er.untrusted.as_deref().unwrap_or("yes")
        );
    }
    let mut g = c.benchmark_group("noise_estimate_12mp");
    if std::env::var_os("D2N_BENCH_QUICK").is_some() {
        g.sample_size(10);
    }
    for step in STEPS {
        g.bench_function(format!("step {step}"), |bch| {
            bch.iter(|| estimate(black_box(&img), &EstimateOptions { step: Some(step) }).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
