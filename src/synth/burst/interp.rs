//! The interpolants of the burst warp: separable kernels evaluated at a frame-00 position.
//! The choice and its measured error are in docs/synthesis.md ("Bursts").

use serde::{Deserialize, Serialize};

/// A separable interpolation kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Interp {
    /// Bilinear (2 taps per axis): blurs, no overshoot.
    Bilinear,
    /// Catmull-Rom cubic convolution (Keys 1981, a = -0.5; 4 taps per axis): interpolating,
    /// third-order accurate.
    CatmullRom,
    /// Lanczos with 3 lobes (6 taps per axis), weights normalized to sum 1.
    Lanczos3,
}

impl Interp {
    /// All interpolants.
    pub const ALL: [Interp; 3] = [Interp::Bilinear, Interp::CatmullRom, Interp::Lanczos3];

    /// Taps on each side of the position: the kernel reads samples
    /// `floor(x) - radius + 1 ..= floor(x) + radius`.
    pub fn radius(self) -> usize {
        match self {
            Interp::Bilinear => 1,
            Interp::CatmullRom => 2,
            Interp::Lanczos3 => 3,
        }
    }

    /// The weights of the `2 * radius` taps for fractional offset `f` in [0, 1) (tap `j`
    /// at distance `j - (radius - 1) - f` from the position). They sum to 1.
    #[inline]
    pub fn weights(self, f: f64, out: &mut [f64; 6]) {
        match self {
            Interp::Bilinear => {
                out[0] = 1.0 - f;
                out[1] = f;
            }
            Interp::CatmullRom => {
                // Keys' cubic with a = -0.5 at distances 1 + f, f, 1 - f, 2 - f
                let f2 = f * f;
                let f3 = f2 * f;
                out[0] = -0.5 * f3 + f2 - 0.5 * f;
                out[1] = 1.5 * f3 - 2.5 * f2 + 1.0;
                out[2] = -1.5 * f3 + 2.0 * f2 + 0.5 * f;
                out[3] = 0.5 * f3 - 0.5 * f2;
            }
            Interp::Lanczos3 => {
                let mut sum = 0.0;
                for (j, o) in out.iter_mut().enumerate() {
                    let d = j as f64 - 2.0 - f;
                    *o = lanczos3(d);
                    sum += *o;
                }
                for o in out.iter_mut() {
                    *o /= sum;
                }
            }
        }
    }
}

crate::choices! {
    Interp, ignore_case: false,
    unknown: |s| crate::error::Error::invalid(format!(
        "interpolant {s:?} (use {})",
        crate::choice::listed::<Interp>(", ", " or ")
    )),
    CatmullRom => "catmull-rom" | "cubic": "Catmull-Rom cubic (4 taps per axis): interpolating, sharp",
    Lanczos3 => "lanczos3" | "lanczos": "Lanczos, 3 lobes (6 taps per axis)",
    Bilinear => "bilinear": "Bilinear (2 taps per axis): blurs",
}

fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-12 {
        1.0
    } else {
        let p = std::f64::consts::PI * x;
        p.sin() / p
    }
}

fn lanczos3(d: f64) -> f64 {
    if d.abs() >= 3.0 {
        0.0
    } else {
        sinc(d) * sinc(d / 3.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_interpolate_and_reproduce_lines() {
        for k in Interp::ALL {
            let r = k.radius();
            let mut w = [0.0; 6];
            for i in 0..=20 {
                let f = i as f64 / 20.0 * 0.999;
                k.weights(f, &mut w);
                let s: f64 = w[..2 * r].iter().sum();
                assert!((s - 1.0).abs() < 1e-12, "{k} {f}");
                // a linear ramp sampled at integers is reproduced at x = f
                let v: f64 = (0..2 * r).map(|j| w[j] * (j as f64 - (r - 1) as f64)).sum();
                // Lanczos-3 reproduces lines only approximately (its normalized weights)
                let tol = if k == Interp::Lanczos3 { 2e-2 } else { 1e-12 };
                assert!((v - f).abs() < tol, "{k} {f}: {v}");
            }
            // at f = 0 the sample itself (interpolating kernels)
            k.weights(0.0, &mut w);
            assert!((w[r - 1] - 1.0).abs() < 1e-12, "{k}");
        }
        assert_eq!("catmull-rom".parse::<Interp>().unwrap(), Interp::CatmullRom);
        assert!("nearest".parse::<Interp>().is_err());
    }

    #[test]
    fn every_name_and_alias_parses_back() {
        use crate::choice::Choice;
        for (n, k) in Interp::NAMES.iter().zip(Interp::VALUES) {
            for s in std::iter::once(n.name).chain(n.aliases.iter().copied()) {
                assert_eq!(s.parse::<Interp>().unwrap(), *k, "{s}");
            }
        }
    }
}
