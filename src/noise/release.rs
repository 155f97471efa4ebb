//! The release's noise on a clean raw (the experiment's `--noise release`): the authors'
//! `prepare_data.py` adds noise to every synthetic clean night raw with its S20 FE table
//! (`noise_profiler/h-gauss-s20-v1`), whatever the camera, in DN with the black level
//! included, then clips to [0, 1023] and truncates:
//!
//! ```text
//! var   = beta1[p] * x + beta2[p]     (float32; negative -> 0; p: the 2x2 position)
//! noisy = uint16(clip(float32(x + sqrt(var) * z), 0, 1023)),  z ~ N(0, 1) (float64)
//! ```
//!
//! The draws `z` are `numpy.random.RandomState.normal`'s, row-major over the plane
//! ([`LegacyState`]): the numbers are NumPy's own, bit for bit. The table is the embedded
//! paper phone's `dn_table` (`synth::dictionaries::embedded::paper_dn_table`, the one copy
//! of its figures), passed in by the caller (noise sits below synth).

use super::numpy_legacy::LegacyState;
use crate::error::{Error, Result};

/// The release clips every noisy raw at 1023 (its phone's 10-bit white level), whatever
/// the camera.
pub const RELEASE_CLIP_MAX: f32 = 1023.0;

/// A noise table in DN: `var = beta1 * x + beta2` per ISO and 2x2 position.
#[derive(Debug, Clone, PartialEq)]
pub struct DnTable {
    /// The table's black level.
    pub black: f64,
    /// The table's white level.
    pub white: f64,
    /// (ISO, position 0..4 row-major, beta1, beta2).
    pub rows: Vec<(u32, usize, f64, f64)>,
}

impl DnTable {
    /// The ISOs the table holds, ascending.
    pub fn isos(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.rows.iter().map(|r| r.0).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The four (beta1, beta2) of `iso`, by position; an error naming the table's ISOs.
    pub fn betas(&self, iso: u32) -> Result<[(f64, f64); 4]> {
        let mut out = [None; 4];
        for &(i, p, b1, b2) in &self.rows {
            if i == iso && p < 4 {
                out[p] = Some((b1, b2));
            }
        }
        match out {
            [Some(a), Some(b), Some(c), Some(d)] => Ok([a, b, c, d]),
            _ => {
                let isos: Vec<String> = self.isos().iter().map(u32::to_string).collect();
                Err(Error::invalid(format!(
                    "ISO {iso}: the release's S20 FE table has {}",
                    isos.join(", ")
                )))
            }
        }
    }
}

/// The release's noisy raw of the clean `plane` (`width` x `height`, row-major, DN as
/// float32; its 2x2 positions are `table`'s) at `iso`, drawing from `rng` (which
/// advances as `RandomState.normal(size=plane.shape)` advances it).
pub fn release_noise(
    plane: &[f32],
    width: usize,
    iso: u32,
    table: &DnTable,
    rng: &mut LegacyState,
) -> Result<Vec<u16>> {
    let betas = table.betas(iso)?;
    if width == 0 && !plane.is_empty() || width > 0 && !plane.len().is_multiple_of(width) {
        return Err(Error::invalid(format!(
            "release noise: {} samples are not rows of {width}",
            plane.len()
        )));
    }
    let betas = betas.map(|(b1, b2)| (b1 as f32, b2 as f32));
    let mut out = crate::limits::try_with_capacity(plane.len(), "release noise")?;
    for (i, &x) in plane.iter().enumerate() {
        let (r, c) = (i / width, i % width);
        let (b1, b2) = betas[(r % 2) * 2 + c % 2];
        // float32 product and sum, widened, as NumPy computes the release's variance
        let var = f64::from(x * b1 + b2).max(0.0);
        let noisy = (f64::from(x) + rng.gauss() * var.sqrt()) as f32;
        // clip in float32, then truncate toward zero (astype(uint16))
        out.push(noisy.clamp(0.0, RELEASE_CLIP_MAX) as u16);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::dictionaries::embedded::paper_dn_table;

    #[test]
    fn the_table_has_the_releases_isos() {
        let t = paper_dn_table();
        assert_eq!(t.isos(), [100, 200, 400, 800, 1600, 3200]);
        assert_eq!((t.black, t.white), (64.0, 1023.0));
        let e = t.betas(6400).unwrap_err().to_string();
        assert!(
            e.contains("ISO 6400: the release's S20 FE table has 100, 200"),
            "{e}"
        );
    }

    #[test]
    fn clipped_truncated_and_deterministic() {
        let plane = vec![4000.0f32; 16];
        let out = release_noise(
            &plane,
            4,
            3200,
            paper_dn_table(),
            &mut LegacyState::from_seed(1),
        )
        .unwrap();
        assert!(out.iter().all(|&v| v == 1023));
        let plane: Vec<f32> = (0..64).map(|i| 300.0 + i as f32).collect();
        let a = release_noise(
            &plane,
            8,
            1600,
            paper_dn_table(),
            &mut LegacyState::from_seed(7),
        )
        .unwrap();
        let b = release_noise(
            &plane,
            8,
            1600,
            paper_dn_table(),
            &mut LegacyState::from_seed(7),
        )
        .unwrap();
        assert_eq!(a, b);
        assert!(a.iter().zip(&plane).any(|(&n, &x)| f32::from(n) != x));
        assert!(release_noise(
            &plane,
            7,
            1600,
            paper_dn_table(),
            &mut LegacyState::from_seed(7)
        )
        .is_err());
    }

    /// A negative variance (dark samples: beta2 < 0) is 0: the sample stays, truncated.
    #[test]
    fn negative_variance_is_zero() {
        let plane = vec![10.5f32; 4];
        let out = release_noise(
            &plane,
            2,
            100,
            paper_dn_table(),
            &mut LegacyState::from_seed(3),
        )
        .unwrap();
        assert_eq!(out, [10; 4]);
    }
}
