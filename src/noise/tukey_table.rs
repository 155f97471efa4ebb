//! Tabulated Tukey-lambda quantile for the physics sampler's read noise (issue 20): the
//! closed form [`super::tukey::quantile`] costs two logarithms and two `expm1` per site;
//! this table costs a few integer operations, one 32-byte load and a cubic.
//!
//! The distribution is symmetric, `Q(1 - p) = -Q(p)`, so a draw is a sign bit and
//! `p = (m + 1/2) 2^-53` with `m` a 52-bit integer (`p` in `[2^-54, 1/2)`): the same grid of
//! 2^53 uniforms as `Q(((v >> 11) + 1/2) 2^-53)`. Two tables of intervals, on each of which
//! `Q` is the cubic Hermite interpolant of its exact values and derivatives
//! `Q'(p) = p^(lambda-1) + (1-p)^(lambda-1)` at both ends:
//!
//! - `p >= 1/16` (7 draws in 8): [`UNI`] equal intervals of width 2^-10 over `[0, 1/2)`,
//!   located by the top bits of `m` (interval width / p at most 1/64);
//! - `p < 1/16`: `p` is located by its floating-point bits: 53 octaves
//!   `[2^-(o+2), 2^-(o+1))`, each cut into [`SUB`] equal intervals by the top mantissa bits,
//!   so intervals stay narrow where `Q` is steep (interval width / p at most 1/SUB).
//!
//! The error is measured in the unit tests and docs/noise.md (about 1e-9 of `Q`'s size, far
//! below the 1 DN quantization the sum goes through).

use super::tukey;

/// Mantissa bits selecting the interval within an octave.
const SUB_BITS: u32 = 6;
/// Intervals per octave.
pub const SUB: usize = 1 << SUB_BITS;
/// Octaves: `p` in `[2^-54, 2^-1)`.
const OCTAVES: usize = 53;
/// Biased exponent of `p` in `[1/4, 1/2)`.
const TOP_EXP: u64 = 1021;
/// Equal intervals over `[0, 1/2)` (width 2^-10), used from `p = 1/16` on.
pub const UNI: usize = 512;
/// `m >> UNI_SHIFT` is the equal interval of `p = (m + 1/2) 2^-53`.
const UNI_SHIFT: u32 = 43;
/// First equal interval used (`p >= 1/16`).
const UNI_FIRST: usize = UNI / 8;

/// The cubic-Hermite table of one shape `lambda`, scaled by a constant.
#[derive(Debug, Clone)]
pub struct TukeyTable {
    /// Per octave interval: `c0 + t (c1 + t (c2 + t c3))`, `t` in [0, 1).
    coef: Vec<[f64; 4]>,
    /// Per equal interval (the first [`UNI_FIRST`] unused), the same.
    uni: Box<[[f64; 4]; UNI]>,
}

/// `Q(p)` and `Q'(p)` of the standard distribution.
fn value_and_slope(p: f64, lambda: f64) -> (f64, f64) {
    let (lp, lq) = (p.ln(), (-p).ln_1p());
    let d = ((lambda - 1.0) * lp).exp() + ((lambda - 1.0) * lq).exp();
    (tukey::quantile(p, lambda), d)
}

/// `(p0, p1)`, the ends of interval `i`.
fn interval(i: usize) -> (f64, f64) {
    let (o, j) = (i / SUB, i % SUB);
    let base = f64::from_bits((TOP_EXP - o as u64) << 52);
    let step = base / SUB as f64;
    (base + j as f64 * step, base + (j + 1) as f64 * step)
}

/// The cubic Hermite coefficients of `scale * Q` on `[p0, p1]`.
fn hermite(p0: f64, p1: f64, lambda: f64, scale: f64) -> [f64; 4] {
    let h = p1 - p0;
    let (y0, s0) = value_and_slope(p0, lambda);
    let (y1, s1) = value_and_slope(p1, lambda);
    let (d0, d1) = (h * s0, h * s1);
    [
        scale * y0,
        scale * d0,
        scale * (3.0 * (y1 - y0) - 2.0 * d0 - d1),
        scale * (2.0 * (y0 - y1) + d0 + d1),
    ]
}

impl TukeyTable {
    /// The table of `scale * Q_lambda`.
    pub fn new(lambda: f64, scale: f64) -> TukeyTable {
        let coef = (0..OCTAVES * SUB)
            .map(|i| {
                let (p0, p1) = interval(i);
                hermite(p0, p1, lambda, scale)
            })
            .collect();
        let mut uni = Box::new([[0.0; 4]; UNI]);
        let w = 0.5 / UNI as f64;
        for (j, c) in uni.iter_mut().enumerate().skip(UNI_FIRST) {
            *c = hermite(j as f64 * w, (j + 1) as f64 * w, lambda, scale);
        }
        TukeyTable { coef, uni }
    }

    /// `scale * Q(u)` for the uniform `u` that the 64 random bits `v` select (bit 63: the
    /// half, bits 11..63: `m`).
    #[inline]
    pub fn sample(&self, v: u64) -> f64 {
        // bits 11..63 of v
        let m = (v << 1) >> 12;
        let q = if m >> (UNI_SHIFT + 6) != 0 {
            // p >= 1/16: equal interval j, position t (p = (j + t) 2^-10 exactly)
            let j = (m >> UNI_SHIFT) as usize & (UNI - 1);
            let f = (m & ((1 << UNI_SHIFT) - 1)) as i64;
            let t = (f as f64 + 0.5) * (1.0 / (1u64 << UNI_SHIFT) as f64);
            let c = &self.uni[j];
            c[0] + t * (c[1] + t * (c[2] + t * c[3]))
        } else {
            // m < 2^52: exact, and a signed conversion is one instruction
            self.at_lower_half(((m as i64) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64))
        };
        // the sign bit of v flips the sign of Q
        f64::from_bits(q.to_bits() ^ (v & (1 << 63)))
    }

    /// `scale * Q(p)` for `p` in `[2^-54, 1/2)`.
    #[inline]
    pub fn at_lower_half(&self, p: f64) -> f64 {
        let bits = p.to_bits();
        // p in [2^-54, 1/2): o in [0, 52] (the index is checked anyway)
        let o = TOP_EXP.saturating_sub(bits >> 52) as usize;
        let frac_bits = 52 - SUB_BITS;
        let j = ((bits >> frac_bits) as usize) & (SUB - 1);
        let t =
            ((bits & ((1 << frac_bits) - 1)) as i64) as f64 * (1.0 / (1u64 << frac_bits) as f64);
        let c = &self.coef[o * SUB + j];
        c[0] + t * (c[1] + t * (c[2] + t * c[3]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest |table - exact| over interval quarter points and random points on the whole
    /// lower half: absolute, and relative to max(|Q|, 1) (1 = about half a standard
    /// deviation; Q reaches 0 at p = 1/2).
    pub(crate) fn max_error(lambda: f64) -> (f64, f64) {
        let t = TukeyTable::new(lambda, 1.0);
        let (mut abs, mut rel) = (0.0f64, 0.0f64);
        // through sample(): v with sign bit 0 and bits 11..63 = m
        let mut check = |m: u64| {
            let p = (m as f64 + 0.5) * (1.0 / (1u64 << 53) as f64);
            let exact = tukey::quantile(p, lambda);
            let e = (t.sample(m << 11) - exact).abs();
            abs = abs.max(e);
            rel = rel.max(e / exact.abs().max(1.0));
        };
        let m_of = |p: f64| ((p * (1u64 << 53) as f64) as u64).min((1 << 52) - 1);
        for i in 0..OCTAVES * SUB {
            let (p0, p1) = interval(i);
            for f in [0.0, 0.25, 0.5, 0.75, 0.999] {
                check(m_of(p0 + f * (p1 - p0)));
            }
        }
        for j in 0..UNI * 8 {
            check(m_of(j as f64 / (16 * UNI) as f64));
        }
        let mut s = 7u64;
        for _ in 0..200_000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            check((s >> 12) & ((1 << 52) - 1));
        }
        for m in [0, 1, (1 << 49) - 1, 1 << 49, (1 << 52) - 1] {
            check(m);
        }
        (abs, rel)
    }

    #[test]
    fn table_matches_the_closed_form() {
        for l in [
            tukey::LAMBDA_MIN,
            -0.1,
            -1e-4,
            0.0,
            1e-12,
            0.05,
            tukey::LAMBDA_NORMAL,
            0.5,
            tukey::LAMBDA_MAX,
        ] {
            let (abs, rel) = max_error(l);
            eprintln!("lambda {l}: max abs error {abs:.2e}, max error / max(|Q|, 1) {rel:.2e}");
            // abs: the tails reach |Q| ~ 3e4 at lambda = -0.24
            assert!(
                rel < 1e-8 && abs < 1e-4,
                "lambda {l}: abs {abs:e} rel {rel:e}"
            );
        }
    }

    #[test]
    fn symmetric_draws_cover_the_uniform_grid() {
        let t = TukeyTable::new(0.1, 2.0);
        // extreme bit patterns: smallest and largest p on both halves
        for v in [0u64, (1 << 63) - 1, 1 << 63, u64::MAX] {
            let q = t.sample(v);
            assert!(q.is_finite());
            let m = (v >> 11) & ((1 << 52) - 1);
            let p = (m as f64 + 0.5) / (1u64 << 53) as f64;
            let want = 2.0 * tukey::quantile(p, 0.1);
            let want = if v >> 63 == 0 { want } else { -want };
            assert!(
                (q - want).abs() < 1e-8 * want.abs().max(1.0),
                "{v:x} {q} {want}"
            );
        }
        // the half bit flips the sign only
        assert_eq!(t.sample(12345 << 11), -t.sample((12345 << 11) | (1 << 63)));
    }
}
