//! The Tukey-lambda distribution (read noise of the physics-based noise model, Wei et al.
//! CVPR 2020): quantile `Q(p) = (p^lambda - (1-p)^lambda) / lambda`, whose `lambda -> 0`
//! limit is the logistic `ln(p / (1-p))`; `lambda ~= 0.14` is close to a normal
//! distribution, `lambda < 0.14` has heavier tails. Here the distribution is used with unit
//! variance ([`std_dev`] divides it out) so that `sigma_read` is a standard deviation in DN.
//!
//! Moments (`lambda > -1/4` for a finite kurtosis), with `B` the beta function:
//! `m2 = (2/lambda^2) (1/(1+2 lambda) - B(1+lambda, 1+lambda))`,
//! `m4 = (1/lambda^4) (2/(1+4 lambda) - 8 B(1+3 lambda, 1+lambda) + 6 B(1+2 lambda, 1+2 lambda))`.
//! Near `lambda = 0` these differences cancel, so small `|lambda|` use a quadratic through
//! the logistic values (`m2 = pi^2/3`, kurtosis 4.2) and the closed form at `+-eps`.

/// Smallest accepted shape: the kurtosis is finite for `lambda > -1/4`.
pub const LAMBDA_MIN: f64 = -0.24;
/// Largest accepted shape (`lambda = 1` is the uniform distribution on [-1, 1]).
pub const LAMBDA_MAX: f64 = 1.0;
/// Shape closest to the normal distribution.
pub const LAMBDA_NORMAL: f64 = 0.1349;

/// `ln Gamma(x)` for `x > 0` (Lanczos, g = 7, 9 terms; relative error about 1e-15).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Recurrence Gamma(x) = Gamma(x + 1) / x keeps x > 0 on the positive side.
        return ln_gamma(x + 1.0) - x.ln();
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

fn beta(a: f64, b: f64) -> f64 {
    (ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b)).exp()
}

/// Quantile of the standard (scale 1) Tukey-lambda distribution; `p` in (0, 1).
#[inline]
pub fn quantile(p: f64, lambda: f64) -> f64 {
    let (lp, lq) = (p.ln(), (-p).ln_1p());
    if lambda == 0.0 {
        lp - lq
    } else {
        ((lambda * lp).exp_m1() - (lambda * lq).exp_m1()) / lambda
    }
}

/// `f(lambda)`, with a quadratic through `f(-eps)`, `at0`, `f(eps)` for `|lambda| < eps`.
fn smoothed(lambda: f64, eps: f64, at0: f64, f: impl Fn(f64) -> f64) -> f64 {
    if lambda.abs() >= eps {
        return f(lambda);
    }
    let (fm, fp) = (f(-eps), f(eps));
    let t = lambda / eps;
    at0 + t * (fp - fm) / 2.0 + t * t * ((fp + fm) / 2.0 - at0)
}

/// Variance of the standard Tukey-lambda distribution (`lambda > -1/2`).
pub fn variance(lambda: f64) -> f64 {
    let pi2_3 = std::f64::consts::PI.powi(2) / 3.0;
    smoothed(lambda, 1e-3, pi2_3, |l| {
        2.0 / (l * l) * (1.0 / (1.0 + 2.0 * l) - beta(1.0 + l, 1.0 + l))
    })
}

/// Standard deviation of the standard Tukey-lambda distribution.
pub fn std_dev(lambda: f64) -> f64 {
    variance(lambda).sqrt()
}

/// Excess kurtosis (`m4 / m2^2 - 3`) of the Tukey-lambda distribution (`lambda > -1/4`).
pub fn excess_kurtosis(lambda: f64) -> f64 {
    smoothed(lambda, 0.005, 1.2, |l| {
        let m4 = (2.0 / (1.0 + 4.0 * l) - 8.0 * beta(1.0 + 3.0 * l, 1.0 + l)
            + 6.0 * beta(1.0 + 2.0 * l, 1.0 + 2.0 * l))
            / l.powi(4);
        m4 / variance(l).powi(2) - 3.0
    })
}

/// Probability-plot correlation of sorted samples `sorted` with the Tukey-lambda quantiles
/// at Filliben's uniform order-statistic medians (at most `max_points` evenly spaced
/// order statistics are used).
pub fn ppcc(sorted: &[f64], lambda: f64, max_points: usize) -> f64 {
    let n = sorted.len();
    if n < 3 {
        return f64::NAN;
    }
    let m = n.min(max_points.max(3));
    let nf = n as f64;
    let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for j in 0..m {
        // order statistic i (1-based) spread over 1..=n
        let i = if m == n {
            j + 1
        } else {
            1 + ((j as f64) * (nf - 1.0) / (m as f64 - 1.0)).round() as usize
        };
        let med = if i == n {
            0.5f64.powf(1.0 / nf)
        } else if i == 1 {
            1.0 - 0.5f64.powf(1.0 / nf)
        } else {
            (i as f64 - 0.3175) / (nf + 0.365)
        };
        let x = quantile(med, lambda);
        let y = sorted[i - 1];
        sx += x;
        sy += y;
        sxx += x * x;
        syy += y * y;
        sxy += x * y;
    }
    let mf = m as f64;
    let cxy = sxy - sx * sy / mf;
    let cxx = sxx - sx * sx / mf;
    let cyy = syy - sy * sy / mf;
    cxy / (cxx * cyy).sqrt()
}

/// The shape maximizing [`ppcc`] over [`LAMBDA_MIN`]..=[`LAMBDA_MAX`]: a grid of step 0.01,
/// then golden-section refinement around the best grid point. Returns (lambda, ppcc).
pub fn fit_lambda_ppcc(sorted: &[f64], max_points: usize) -> (f64, f64) {
    let f = |l: f64| ppcc(sorted, l, max_points);
    let steps = ((LAMBDA_MAX - LAMBDA_MIN) / 0.01).round() as usize;
    let mut best = (LAMBDA_MIN, f64::NEG_INFINITY);
    for k in 0..=steps {
        let l = LAMBDA_MIN + 0.01 * k as f64;
        let r = f(l);
        if r > best.1 {
            best = (l, r);
        }
    }
    let (mut a, mut b) = (
        (best.0 - 0.01).max(LAMBDA_MIN),
        (best.0 + 0.01).min(LAMBDA_MAX),
    );
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..30 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    let l = (a + b) / 2.0;
    let r = f(l);
    if r >= best.1 {
        (l, r)
    } else {
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_known_values() {
        let pi = std::f64::consts::PI;
        assert!((ln_gamma(1.0)).abs() < 1e-14);
        assert!((ln_gamma(2.0)).abs() < 1e-14);
        assert!((ln_gamma(0.5) - pi.sqrt().ln()).abs() < 1e-14);
        assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(0.1) - 2.252_712_651_734_206).abs() < 1e-12);
    }

    #[test]
    fn logistic_limit_and_continuity() {
        let pi2_3 = std::f64::consts::PI.powi(2) / 3.0;
        assert!((variance(0.0) - pi2_3).abs() < 1e-12);
        assert!((excess_kurtosis(0.0) - 1.2).abs() < 1e-12);
        for l in [1e-9, -1e-9, 5e-4, -5e-4] {
            assert!((variance(l) - pi2_3).abs() < 0.01, "{l}");
            assert!((excess_kurtosis(l) - 1.2).abs() < 0.02, "{l}");
            let q = quantile(0.9, l);
            assert!((q - 9f64.ln()).abs() < 0.01, "{l} {q}");
        }
        // continuity across the switch points
        for eps in [1e-3, 0.005] {
            let (a, b) = (variance(eps * 0.999_999), variance(eps * 1.000_001));
            assert!((a - b).abs() < 1e-6, "{a} {b}");
            let (a, b) = (
                excess_kurtosis(eps * 0.999_999),
                excess_kurtosis(eps * 1.000_001),
            );
            assert!((a - b).abs() < 1e-5, "{a} {b}");
        }
    }

    #[test]
    fn matches_scipy_reference_values() {
        // scipy.stats.tukeylambda(l).stats(moments='vk'), scipy 1.x.
        let reference = [
            (-0.2, 7.485121693687224, 19.212645820411698),
            (-0.1, 4.780502178742506, 3.7855952034608613),
            (-0.05, 3.936722678907758, 2.131297930577237),
            (0.0001, 3.2887296137124586, 1.1985547700319745),
            (0.019, 3.083082361285201, 0.947124876313352),
            (0.05, 2.7828105340546427, 0.6116040438868936),
            (0.14, 2.1102970222144966, -0.027083773532802446),
            (1.0, 1.0 / 3.0, -1.2),
        ];
        for (l, v, k) in reference {
            assert!((variance(l) / v - 1.0).abs() < 1e-6, "{l} {}", variance(l));
            assert!(
                (excess_kurtosis(l) - k).abs() < 1e-4,
                "{l} {}",
                excess_kurtosis(l)
            );
        }
    }

    #[test]
    fn known_shapes() {
        // lambda = 1: uniform on [-1, 1]: variance 1/3, excess kurtosis -1.2.
        assert!((variance(1.0) - 1.0 / 3.0).abs() < 1e-12);
        assert!((excess_kurtosis(1.0) + 1.2).abs() < 1e-9);
        // lambda = 0.14: nearly normal (excess kurtosis about 0).
        assert!(excess_kurtosis(LAMBDA_NORMAL).abs() < 0.01);
        // heavier tails below
        assert!(excess_kurtosis(-0.1) > 2.0);
        for l in [LAMBDA_MIN, -0.1, 0.0, 0.1, 0.5, LAMBDA_MAX] {
            assert!(variance(l).is_finite() && variance(l) > 0.0);
            assert!(excess_kurtosis(l).is_finite());
        }
    }

    #[test]
    fn moments_match_numerical_integration() {
        for l in [-0.05, 0.03, 0.14, 0.4] {
            let n = 2_000_000;
            let (mut m2, mut m4) = (0.0, 0.0);
            for i in 0..n {
                let q = quantile((i as f64 + 0.5) / n as f64, l);
                m2 += q * q;
                m4 += q.powi(4);
            }
            m2 /= n as f64;
            m4 /= n as f64;
            assert!((m2 / variance(l) - 1.0).abs() < 2e-3, "{l}");
            let k = m4 / (m2 * m2) - 3.0;
            assert!(
                (k - excess_kurtosis(l)).abs() < 0.05 * (1.0 + k.abs()),
                "{l} {k}"
            );
        }
    }

    #[test]
    fn ppcc_recovers_shape_of_exact_quantiles() {
        for l in [-0.15, 0.0, 0.14, 0.3] {
            let n = 5000;
            let xs: Vec<f64> = (1..=n)
                .map(|i| 3.0 * quantile((i as f64 - 0.3175) / (n as f64 + 0.365), l))
                .collect();
            let (fit, r) = fit_lambda_ppcc(&xs, 2000);
            assert!((fit - l).abs() < 0.01, "{l} {fit}");
            assert!(r > 0.999);
        }
    }
}
