//! Night illuminants (docs/synthesis.md, "4. Night illuminants"): a 2-D Gaussian fitted to a dictionary of gray-card
//! chromaticities `[r/g, b/g]`, and sampling with rejection.
//!
//! The covariance is the unbiased `1/(M-1)` estimate by default (released code), the
//! maximum-likelihood `1/M` one (the paper's equation 2) as an option. A dictionary with a
//! single illuminant has a zero covariance: every draw is that illuminant. Sampling uses the
//! eigen decomposition `Sigma = V diag(lambda) V^T` (negative eigenvalues from rounding are
//! clamped to 0), so singular and near-singular covariances work without jitter: a draw is
//! `mu + V diag(sqrt(lambda)) z` with `z ~ N(0, I)`, and its Mahalanobis distance is `|z|`.
//! A draw farther than the Mahalanobis radius, or with a component `<=` the floor, is redrawn;
//! after `max_tries` rejections the error names the dictionary.

use super::dictionaries::{IlluminantDict, IlluminantSource};
use super::rng::SynthRng;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Covariance estimator of the fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Covariance {
    /// `1/(M-1)` (released code; default).
    #[default]
    Unbiased,
    /// `1/M` (the paper's equation 2).
    MaximumLikelihood,
}

/// A fitted 2-D Gaussian over `[r/g, b/g]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Gaussian2 {
    /// Dictionary name.
    pub name: String,
    /// Mean `[r/g, b/g]`.
    pub mean: [f64; 2],
    /// Covariance.
    pub cov: [[f64; 2]; 2],
    /// Number of chromaticities fitted (0 when the file gave the Gaussian).
    pub count: usize,
    /// Estimator used.
    pub estimator: Covariance,
}

/// Rejection rules of the sampler.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SamplerRules {
    /// A component `<=` this is redrawn.
    pub floor: f64,
    /// A draw farther than this Mahalanobis distance is redrawn.
    pub max_mahalanobis: f64,
    /// Tries before giving up with an error.
    pub max_tries: u32,
}

impl Default for SamplerRules {
    fn default() -> Self {
        SamplerRules {
            floor: 1e-3,
            max_mahalanobis: 3.0,
            max_tries: 1000,
        }
    }
}

impl Gaussian2 {
    /// Fit a dictionary (weighted when it has weights: [`Gaussian2::fit_weighted`]).
    pub fn fit(dict: &IlluminantDict, est: Covariance) -> Result<Gaussian2> {
        if !dict.weights.is_empty() {
            return Gaussian2::fit_weighted(dict, est);
        }
        let m = dict.chromaticities.len();
        if m == 0 {
            return Err(Error::invalid(format!(
                "illuminant dictionary {} is empty",
                dict.name
            )));
        }
        if dict
            .chromaticities
            .iter()
            .any(|c| !c[0].is_finite() || !c[1].is_finite())
        {
            return Err(Error::invalid(format!(
                "illuminant dictionary {} holds a non-finite value",
                dict.name
            )));
        }
        let n = m as f64;
        let mut mean = [0.0; 2];
        for c in &dict.chromaticities {
            mean[0] += c[0];
            mean[1] += c[1];
        }
        mean[0] /= n;
        mean[1] /= n;
        let mut cov = [[0.0; 2]; 2];
        for c in &dict.chromaticities {
            let d = [c[0] - mean[0], c[1] - mean[1]];
            for i in 0..2 {
                for j in 0..2 {
                    cov[i][j] += d[i] * d[j];
                }
            }
        }
        let div = match est {
            Covariance::Unbiased if m > 1 => n - 1.0,
            Covariance::Unbiased => 1.0, // one sample: zero covariance
            Covariance::MaximumLikelihood => n,
        };
        for row in &mut cov {
            for v in row.iter_mut() {
                *v /= div;
            }
        }
        Ok(Gaussian2 {
            name: dict.name.clone(),
            mean,
            cov,
            count: m,
            estimator: est,
        })
    }

    /// Fit a weighted dictionary: each weight is a count of gray cards (frequency weights).
    /// Mean `sum(w c) / W`, covariance `sum(w d d^T) / (W - 1)` (unbiased) or `/ W`
    /// (maximum likelihood), `W = sum(w)`; weight 1 each gives [`Gaussian2::fit`]'s figures.
    /// Errors unless there is one finite weight >= 0 per chromaticity, `W > 0`, and `W > 1`
    /// for the unbiased estimator.
    pub fn fit_weighted(dict: &IlluminantDict, est: Covariance) -> Result<Gaussian2> {
        let name = &dict.name;
        let (c, w) = (&dict.chromaticities, &dict.weights);
        if c.is_empty() {
            return Err(Error::invalid(format!(
                "illuminant dictionary {name} is empty"
            )));
        }
        if w.len() != c.len() {
            return Err(Error::invalid(format!(
                "illuminant dictionary {name}: {} weights for {} chromaticities",
                w.len(),
                c.len()
            )));
        }
        if c.iter().flatten().chain(w).any(|v| !v.is_finite()) || w.iter().any(|&v| v < 0.0) {
            return Err(Error::invalid(format!(
                "illuminant dictionary {name} holds a non-finite value or a negative weight"
            )));
        }
        let total: f64 = w.iter().sum();
        let div = match est {
            Covariance::Unbiased => total - 1.0,
            Covariance::MaximumLikelihood => total,
        };
        if !(total > 0.0 && div > 0.0) {
            return Err(Error::invalid(format!(
                "illuminant dictionary {name}: weights sum to {} (the unbiased covariance needs \
                 more than 1: weights count gray cards)",
                crate::bounds::short(total)
            )));
        }
        let mut mean = [0.0; 2];
        for (ci, wi) in c.iter().zip(w) {
            mean[0] += wi * ci[0];
            mean[1] += wi * ci[1];
        }
        mean = mean.map(|v| v / total);
        let mut cov = [[0.0; 2]; 2];
        for (ci, wi) in c.iter().zip(w) {
            let d = [ci[0] - mean[0], ci[1] - mean[1]];
            for i in 0..2 {
                for j in 0..2 {
                    cov[i][j] += wi * d[i] * d[j];
                }
            }
        }
        Ok(Gaussian2 {
            name: name.clone(),
            mean,
            cov: cov.map(|r| r.map(|v| v / div)),
            count: c.len(),
            estimator: est,
        })
    }

    /// From a file's illuminant source (fit or given Gaussian).
    pub fn from_source(src: &IlluminantSource, est: Covariance) -> Result<Gaussian2> {
        match src {
            IlluminantSource::Dict(d) => Gaussian2::fit(d, est),
            IlluminantSource::Gaussian(name, mean, cov) => {
                let sym = (cov[0][1] - cov[1][0]).abs() <= 1e-12 * (1.0 + cov[0][1].abs());
                if !sym || cov[0][0] < 0.0 || cov[1][1] < 0.0 {
                    return Err(Error::invalid(format!(
                        "illuminant dictionary {}: covariance is not symmetric positive semi-definite",
                        name
                    )));
                }
                Ok(Gaussian2 {
                    name: name.clone(),
                    mean: *mean,
                    cov: *cov,
                    count: 0,
                    estimator: est,
                })
            }
        }
    }

    /// `A` with `A A^T = Sigma` from the eigen decomposition (PSD part).
    pub fn sqrt_cov(&self) -> [[f64; 2]; 2] {
        let [[a, b], [_, d]] = self.cov;
        let tr = a + d;
        let det = a * d - b * b;
        let disc = ((tr * tr / 4.0 - det).max(0.0)).sqrt();
        let l1 = (tr / 2.0 + disc).max(0.0);
        let l2 = (tr / 2.0 - disc).max(0.0);
        // Eigenvector of l1.
        let (vx, vy) = if b.abs() > 1e-300 {
            (l1 - d, b)
        } else if a >= d {
            (1.0, 0.0)
        } else {
            (0.0, 1.0)
        };
        let nrm = (vx * vx + vy * vy).sqrt();
        let (ux, uy) = if nrm > 0.0 {
            (vx / nrm, vy / nrm)
        } else {
            (1.0, 0.0)
        };
        // Second eigenvector: orthogonal.
        let (wx, wy) = (-uy, ux);
        let (s1, s2) = (l1.sqrt(), l2.sqrt());
        [[ux * s1, wx * s2], [uy * s1, wy * s2]]
    }

    /// Draw one illuminant `(r/g, 1, b/g)` under `rules`.
    pub fn sample(&self, rng: &mut SynthRng, rules: &SamplerRules) -> Result<[f64; 3]> {
        let a = self.sqrt_cov();
        for _ in 0..rules.max_tries.max(1) {
            let z = [rng.normal(), rng.normal()];
            let r = self.mean[0] + a[0][0] * z[0] + a[0][1] * z[1];
            let b = self.mean[1] + a[1][0] * z[0] + a[1][1] * z[1];
            let dist = (z[0] * z[0] + z[1] * z[1]).sqrt();
            if dist <= rules.max_mahalanobis
                && r > rules.floor
                && b > rules.floor
                && r.is_finite()
                && b.is_finite()
            {
                return Ok([r, 1.0, b]);
            }
        }
        Err(Error::invalid(format!(
            "could not draw a night illuminant from dictionary {} in {} tries (floor {}, \
             Mahalanobis radius {}): its mean [{}, {}] is too close to zero or the rules too tight",
            self.name,
            rules.max_tries,
            rules.floor,
            rules.max_mahalanobis,
            self.mean[0],
            self.mean[1]
        )))
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use crate::synth::dictionaries::embedded;

    fn dict(c: Vec<[f64; 2]>) -> IlluminantDict {
        IlluminantDict {
            name: "test".into(),
            source: String::new(),
            chromaticities: c,
            weights: Vec::new(),
        }
    }

    #[test]
    fn sqrt_cov_reproduces_cov() {
        let g = Gaussian2::fit(&embedded::illuminants(), Covariance::Unbiased).unwrap();
        let a = g.sqrt_cov();
        for i in 0..2 {
            for j in 0..2 {
                let v = a[i][0] * a[j][0] + a[i][1] * a[j][1];
                assert!((v - g.cov[i][j]).abs() < 1e-12, "{i}{j} {v}");
            }
        }
    }

    #[test]
    fn sampled_mean_and_cov_match_fit() {
        // Statistical test: with a generous Mahalanobis radius (no truncation in practice)
        // the sample moments match the fit within sampling error.
        let g = Gaussian2::fit(&embedded::illuminants(), Covariance::Unbiased).unwrap();
        let rules = SamplerRules {
            floor: -1e9,
            max_mahalanobis: 1e9,
            max_tries: 10,
        };
        let mut rng = SynthRng::new(11, "stat", 0);
        let n = 100_000usize;
        let xs: Vec<[f64; 3]> = (0..n)
            .map(|_| g.sample(&mut rng, &rules).unwrap())
            .collect();
        let m0 = xs.iter().map(|x| x[0]).sum::<f64>() / n as f64;
        let m1 = xs.iter().map(|x| x[2]).sum::<f64>() / n as f64;
        let nf = n as f64;
        // Standard error of the mean: sqrt(var / n); allow 4 standard errors.
        assert!((m0 - g.mean[0]).abs() < 4.0 * (g.cov[0][0] / nf).sqrt());
        assert!((m1 - g.mean[1]).abs() < 4.0 * (g.cov[1][1] / nf).sqrt());
        let mut c = [[0.0; 2]; 2];
        for x in &xs {
            let d = [x[0] - m0, x[2] - m1];
            for i in 0..2 {
                for j in 0..2 {
                    c[i][j] += d[i] * d[j] / (nf - 1.0);
                }
            }
        }
        // Standard error of a covariance entry: sqrt((s_ii s_jj + s_ij^2) / n).
        for i in 0..2 {
            for j in 0..2 {
                let se = ((g.cov[i][i] * g.cov[j][j] + g.cov[i][j].powi(2)) / nf).sqrt();
                assert!((c[i][j] - g.cov[i][j]).abs() < 4.0 * se, "{i}{j} {:?}", c);
            }
        }
    }

    /// Covariance of `n` draws under `rules`, divided entry-wise by the fit's (trace ratio).
    fn cov_ratio(rules: &SamplerRules, n: usize) -> f64 {
        let g = Gaussian2::fit(&embedded::illuminants(), Covariance::Unbiased).unwrap();
        let mut rng = SynthRng::new(3, "cov", 0);
        let xs: Vec<[f64; 3]> = (0..n).map(|_| g.sample(&mut rng, rules).unwrap()).collect();
        let nf = n as f64;
        let m = [0, 2].map(|i| xs.iter().map(|x| x[i]).sum::<f64>() / nf);
        let var =
            |i: usize, k: usize| xs.iter().map(|x| (x[i] - m[k]).powi(2)).sum::<f64>() / (nf - 1.0);
        (var(0, 0) + var(2, 1)) / (g.cov[0][0] + g.cov[1][1])
    }

    #[test]
    fn the_radius_cut_shrinks_the_covariance_and_no_cut_keeps_it() {
        // A 2-D standard normal cut at |z| <= 3 keeps E[z_i^2] = 1 - 4.5 e^-4.5 / (1 - e^-4.5)
        // = 0.9494; without a cut (the release) the draws have the dictionary's covariance.
        let exact = 1.0 - 4.5 * (-4.5f64).exp() / (1.0 - (-4.5f64).exp());
        let n = 200_000;
        let cut = cov_ratio(&SamplerRules::default(), n);
        let free = cov_ratio(
            &SamplerRules {
                max_mahalanobis: crate::synth::NO_MAHALANOBIS_CUT,
                ..SamplerRules::default()
            },
            n,
        );
        // standard error of a variance ratio ~ sqrt(2/n) = 0.0032
        assert!((cut - exact).abs() < 0.013, "cut {cut} vs {exact}");
        assert!((free - 1.0).abs() < 0.013, "no cut {free}");
        eprintln!(
            "covariance / dictionary's: radius 3 {cut:.4} (exact {exact:.4}), no cut {free:.4}"
        );
    }

    #[test]
    fn default_rules_respect_floor_and_radius() {
        let g = Gaussian2::fit(&embedded::illuminants(), Covariance::Unbiased).unwrap();
        let rules = SamplerRules::default();
        let mut rng = SynthRng::new(5, "r", 0);
        for _ in 0..5000 {
            let l = g.sample(&mut rng, &rules).unwrap();
            assert!(l[0] > rules.floor && l[2] > rules.floor && l[1] == 1.0);
        }
    }

    #[test]
    fn single_illuminant_dictionary_is_singular_and_works() {
        let d = dict(vec![[0.8, 0.3]]);
        for est in [Covariance::Unbiased, Covariance::MaximumLikelihood] {
            let g = Gaussian2::fit(&d, est).unwrap();
            assert_eq!(g.cov, [[0.0; 2]; 2]);
            let mut rng = SynthRng::new(1, "s", 0);
            let l = g.sample(&mut rng, &SamplerRules::default()).unwrap();
            assert_eq!(l, [0.8, 1.0, 0.3]);
        }
        // Two identical-direction points: rank-1 covariance, draws on the line.
        let d = dict(vec![[0.6, 0.3], [0.8, 0.4]]);
        let g = Gaussian2::fit(&d, Covariance::Unbiased).unwrap();
        let mut rng = SynthRng::new(2, "s", 0);
        for _ in 0..100 {
            let l = g.sample(&mut rng, &SamplerRules::default()).unwrap();
            assert!((l[2] - 0.35 - 0.5 * (l[0] - 0.7)).abs() < 1e-9, "{l:?}");
        }
    }

    #[test]
    fn weights_are_counts_of_gray_cards() {
        // [a, a, b] unweighted == [a x2, b x1] weighted, both estimators.
        let (a, b) = ([0.6, 0.4], [0.9, 0.25]);
        for est in [Covariance::Unbiased, Covariance::MaximumLikelihood] {
            let plain = Gaussian2::fit(&dict(vec![a, a, b]), est).unwrap();
            let mut d = dict(vec![a, b]);
            d.weights = vec![2.0, 1.0];
            let w = Gaussian2::fit(&d, est).unwrap();
            for i in 0..2 {
                assert!((plain.mean[i] - w.mean[i]).abs() < 1e-15);
                for j in 0..2 {
                    assert!((plain.cov[i][j] - w.cov[i][j]).abs() < 1e-15, "{est:?}");
                }
            }
            assert_eq!(w.count, 2);
        }
        // weight 0 drops a point; weight 1 each is the plain fit
        let mut d = dict(vec![a, b, [5.0, 5.0]]);
        d.weights = vec![1.0, 1.0, 0.0];
        let g = Gaussian2::fit(&d, Covariance::Unbiased).unwrap();
        let p = Gaussian2::fit(&dict(vec![a, b]), Covariance::Unbiased).unwrap();
        assert!((g.mean[0] - p.mean[0]).abs() < 1e-15 && (g.cov[0][0] - p.cov[0][0]).abs() < 1e-15);
        // bad weights
        for (w, what) in [
            (vec![1.0], "1 weights"),
            (vec![1.0, -1.0, 1.0], "negative"),
            (vec![0.5, 0.25, 0.0], "sum to 0.75"),
            (vec![0.0, 0.0, 0.0], "sum to 0"),
            (vec![1.0, f64::NAN, 1.0], "non-finite"),
        ] {
            d.weights = w;
            let e = Gaussian2::fit(&d, Covariance::Unbiased)
                .unwrap_err()
                .to_string();
            assert!(e.contains(what) && e.contains("test"), "{e}");
        }
        d.weights = vec![0.5, 0.25, 0.0];
        assert!(Gaussian2::fit(&d, Covariance::MaximumLikelihood).is_ok());
    }

    #[test]
    fn impossible_dictionary_errors_with_its_name() {
        let d = dict(vec![[-0.5, 0.3], [-0.6, 0.35]]);
        let g = Gaussian2::fit(&d, Covariance::Unbiased).unwrap();
        let mut rng = SynthRng::new(1, "s", 0);
        let e = g.sample(&mut rng, &SamplerRules::default()).unwrap_err();
        assert!(e.to_string().contains("test"), "{e}");
        assert!(Gaussian2::fit(&dict(vec![]), Covariance::Unbiased).is_err());
        assert!(Gaussian2::fit(&dict(vec![[f64::NAN, 1.0]]), Covariance::Unbiased).is_err());
    }
}
