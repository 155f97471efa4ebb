//! Issue 14 point 5: cost of the physics noise model's shot term against its accuracy.
//!
//! 1. Error of the normal approximation `N(e, e)` of `Poisson(e)`: Kolmogorov distance
//!    between the Poisson CDF and the continuity-corrected normal CDF, and the skewness the
//!    approximation drops (`1/sqrt(e)`), for electron counts e.
//! 2. Time to add physics noise to a 12 MP (4000x3000) 14-bit frame, median of 5 runs, for
//!    exact-Poisson thresholds N (exact at or below N electrons, normal above), on a ramp
//!    scene (signal uniform over the range) and a night scene (exponential signal, mean 2 %
//!    of the range); the Gaussian model (`apply_noise`) for reference.
//!
//! Run: `cargo run --release --example physics_noise_cost` (prints Markdown tables).
use day2night::noise::tukey::ln_gamma;
use day2night::noise::{apply_noise, apply_physics_noise_image, NoiseParams, PhysicsParams};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use std::time::Instant;

/// erfc (Numerical Recipes' Chebyshev fit, relative error < 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// Kolmogorov distance between Poisson(e) and N(e, e) evaluated at k + 1/2.
fn ks(e: f64) -> f64 {
    let sd = e.sqrt();
    let hi = (e + 40.0 * sd + 50.0) as u64;
    let lo = (e - 40.0 * sd).max(0.0) as u64;
    let mut cdf = 0.0;
    let mut worst: f64 = 0.0;
    // mass below lo is negligible (< 1e-300)
    for k in lo..=hi {
        let kf = k as f64;
        cdf += (kf * e.ln() - e - ln_gamma(kf + 1.0)).exp();
        worst = worst.max((cdf - normal_cdf((kf + 0.5 - e) / sd)).abs());
    }
    worst
}

fn scene(w: usize, h: usize, night: bool, black: f64, white: f64) -> RawImage {
    let mut s = 0x1234_5678_u64;
    let mut data = vec![0u16; w * h];
    for (i, v) in data.iter_mut().enumerate() {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let u = ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
        let y = if night {
            -0.02 * u.ln()
        } else {
            (i % w) as f64 / w as f64
        };
        *v = (black + y.min(1.0) * (white - black)).round() as u16;
    }
    RawImage {
        width: w,
        height: h,
        data,
        meta: RawMeta::new_bayer(Bayer::RGGB, 14, black, white),
    }
}

fn median_secs(mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..5)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[2]
}

fn main() {
    println!("| electrons e | KS distance Poisson vs N(e, e) | skewness dropped 1/sqrt(e) |");
    println!("|---:|---:|---:|");
    for e in [3.0, 10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0, 10000.0] {
        println!("| {e} | {:.2e} | {:.4} |", ks(e), 1.0 / e.sqrt());
    }
    let (black, white) = (512.0, 16383.0);
    let threads = rayon::current_num_threads();
    println!();
    println!("12 MP (4000x3000), K = 1 DN/e- (0..15871 e-), read 3 DN lambda 0.05, row 1 DN; median of 5; {threads} rayon threads");
    println!();
    println!("| shot term | ramp scene (s) | night scene (s) |");
    println!("|---|---:|---:|");
    let imgs = [
        scene(4000, 3000, false, black, white),
        scene(4000, 3000, true, black, white),
    ];
    let g = NoiseParams::uniform(1.0 / (white - black), 10.0 / (white - black).powi(2));
    let t: Vec<f64> = imgs
        .iter()
        .map(|img| {
            median_secs(|| {
                std::hint::black_box(apply_noise(img, &g, 1).unwrap());
            })
        })
        .collect();
    println!(
        "| Gaussian model (apply_noise), reference | {:.3} | {:.3} |",
        t[0], t[1]
    );
    for n in [0.0, 100.0, 1000.0, 10000.0, 1e12] {
        let p = PhysicsParams {
            k: 1.0,
            sigma_read: 3.0,
            lambda: 0.05,
            gaussian_read: false,
            sigma_row: 1.0,
            poisson_max_electrons: n,
        };
        let t: Vec<f64> = imgs
            .iter()
            .map(|img| {
                median_secs(|| {
                    std::hint::black_box(apply_physics_noise_image(img, &p, 1).unwrap());
                })
            })
            .collect();
        let label = if n == 0.0 {
            "normal approximation everywhere (N = 0)".to_string()
        } else if n >= 1e12 {
            "exact Poisson everywhere (N = 1e12)".to_string()
        } else {
            format!("exact up to N = {n} e-, normal above")
        };
        println!("| {label} | {:.3} | {:.3} |", t[0], t[1]);
    }
}
