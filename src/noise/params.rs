//! The parameters both noise models share: `(S, O)` per 2x2 CFA position
//! ([`NoiseParams`], the DNG NoiseProfile form on normalized data, `var(y) = S * y + O`) and
//! one calibrated ISO of a model ([`IsoPoint`]). The heteroscedastic Gaussian model
//! ([`super::model`]) and the physics model ([`super::physics`]) both use them.

use crate::error::{Error, Result};
use crate::raw::Bayer;
use serde::{Deserialize, Serialize};

/// `(S, O)` for each 2x2 CFA position (row-major, relative to the ActiveArea origin).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseParams {
    /// `[[S, O]; 4]` per position.
    pub positions: [[f64; 2]; 4],
}

impl NoiseParams {
    /// The same `(S, O)` at every position.
    pub fn uniform(s: f64, o: f64) -> NoiseParams {
        NoiseParams {
            positions: [[s, o]; 4],
        }
    }
    /// The model with its standard deviation multiplied by `gain` (`S` and `O` by
    /// `gain^2`); itself, bit for bit, for a gain of 1.
    pub fn with_gain(self, gain: f64) -> NoiseParams {
        if gain == 1.0 {
            return self;
        }
        let g2 = gain * gain;
        NoiseParams {
            positions: self.positions.map(|[s, o]| [s * g2, o * g2]),
        }
    }
    /// Variance of normalized `y` at 2x2 position `pos`: `max(0, S*y + O)` (0 for NaN).
    #[inline]
    pub fn var_norm(&self, pos: usize, y: f64) -> f64 {
        let [s, o] = self.positions[pos & 3];
        let v = s * y + o;
        if v > 0.0 {
            v
        } else {
            0.0
        }
    }
    /// DNG NoiseProfile pairs, one per colour plane R, G, B: the mean `(S, O)` of the
    /// positions of that colour in `bayer` (the two greens are averaged).
    pub fn to_dng_profile(&self, bayer: Bayer) -> Vec<(f64, f64)> {
        (0u8..3)
            .map(|colour| {
                let (mut s, mut o, mut n) = (0.0, 0.0, 0.0);
                for (pos, &c) in bayer.0.iter().enumerate() {
                    if c == colour {
                        s += self.positions[pos][0];
                        o += self.positions[pos][1];
                        n += 1.0;
                    }
                }
                (s / n, o / n)
            })
            .collect()
    }
    /// From a DNG NoiseProfile (one pair for all planes, or one per plane R, G, B).
    pub fn from_dng_profile(profile: &[(f64, f64)], bayer: Bayer) -> Result<NoiseParams> {
        let mut positions = [[0.0; 2]; 4];
        for (pos, p) in positions.iter_mut().enumerate() {
            let (s, o) = match profile.len() {
                1 => profile[0],
                3 => profile[bayer.0[pos] as usize],
                n => {
                    return Err(Error::unsupported(format!(
                        "NoiseProfile with {} pairs (expected 1 or 3)",
                        n
                    )))
                }
            };
            *p = [s, o];
        }
        let np = NoiseParams { positions };
        np.check("NoiseProfile")?;
        Ok(np)
    }
    /// Refuse non-finite parameters or a negative `S` (`what` names them in the error).
    pub(crate) fn check(&self, what: &str) -> Result<()> {
        for p in &self.positions {
            if !p[0].is_finite() || !p[1].is_finite() || p[0] < 0.0 {
                return Err(Error::invalid(format!(
                    "{}: noise parameters S={} O={} are not finite with S >= 0",
                    what, p[0], p[1]
                )));
            }
        }
        Ok(())
    }
    /// `S` and `O` clamped at 0, so that no variance is negative.
    pub(crate) fn clamped(mut self) -> NoiseParams {
        for p in &mut self.positions {
            p[0] = p[0].max(0.0);
            p[1] = p[1].max(0.0);
        }
        self
    }
}

/// One calibrated ISO.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IsoPoint {
    /// ISO.
    pub iso: u32,
    /// `[[S, O]; 4]` per 2x2 position.
    pub positions: [[f64; 2]; 4],
}
