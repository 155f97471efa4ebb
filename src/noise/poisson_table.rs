//! Exact Poisson draws from tables (issue 20), for the physics sampler's shot noise: one
//! table per (black level, stored value) pair, built on first use.
//!
//! [`PoissonTable`] holds `Poisson(e)` over `[lo, hi]`, the counts whose probabilities
//! exceed [`PMF_FLOOR`] (2^-64; the mass left out is below 1e-17), as integer weights in
//! units of 2^-64 that sum to exactly 2^64 (each probability rounded to the nearest unit,
//! the rounding remainder, about 1e-16 of the total, given to the mode), laid out for
//! Walker's alias method (Vose's construction, in exact integer arithmetic): `2^g >= hi -
//! lo + 1` buckets of `2^(64-g)` units each; bucket `j` gives `threshold(j)` units to count
//! `lo + j` and the rest to `lo + alias(j)`. A draw splits 64 random bits into the bucket
//! (top `g` bits) and a position in it (the other `64 - g`): one table read and one
//! comparison, no loop, no branch on the data. Every count gets exactly its weight, so the
//! draws follow the Poisson distribution up to the 2^-64 rounding of each probability and
//! the f64 rounding of the probabilities themselves (about 1e-15; unit test against sums
//! of the pmf evaluated one by one).
//!
//! (An inverse-CDF table with a guide table was tried first: as exact, but a draw reads a
//! guide entry and a CDF entry at two random places of two arrays, two cache misses once
//! the tables of a frame outgrow the L2 cache; the noise stage was 1.25x slower than with
//! the alias tables. docs/noise.md.)
//!
//! The probabilities come from the mode `floor(e)`, `ln p(m) = m ln e - e - ln m!`, and the
//! recurrences `p(k + 1) = p(k) e / (k + 1)`, `p(k - 1) = p(k) k / e`; the normalization
//! removes the common error of `ln m!`.

use super::tukey::ln_gamma;
use std::sync::OnceLock;

/// Counts with a smaller probability are left out of a table.
pub const PMF_FLOOR: f64 = 1.0 / 18_446_744_073_709_551_616.0;

/// `2^64`, the total weight of a table.
const TOTAL: u128 = 1 << 64;

/// One Poisson distribution as an alias table.
#[derive(Debug, Clone)]
pub struct PoissonTable {
    lo: u32,
    /// `g`: `2^g` buckets, `1 <= g <= 16`.
    g: u32,
    /// Per bucket `(threshold << g) | alias`, `threshold < 2^(64-g)` (a bucket that keeps all
    /// its units has threshold 0 and itself as alias).
    cells: Box<[u64]>,
}

impl PoissonTable {
    /// The table of `Poisson(e)`, `e` finite, `0 < e <= MAX_TABLE_MEAN`.
    pub fn new(e: f64) -> PoissonTable {
        debug_assert!(e > 0.0 && e <= MAX_TABLE_MEAN);
        let (lo, pmf, mode) = pmf(e);
        let n = pmf.len();
        let g = n.next_power_of_two().trailing_zeros().max(1);
        let buckets = 1usize << g;
        if n == 1 {
            // one count holds all the mass: every bucket keeps it
            return PoissonTable {
                lo,
                g,
                cells: vec![0; buckets].into(),
            };
        }
        let cap: u64 = 1 << (64 - g);
        // integer weights summing to exactly 2^64 (each at least one unit: p >= 2^-64)
        let scale = TOTAL as f64 / pmf.iter().sum::<f64>();
        let mut w: Vec<u64> = Vec::with_capacity(buckets);
        let mut sum: u128 = 0;
        for p in &pmf {
            let x = (p * scale).round() as u64;
            sum += x as u128;
            w.push(x);
        }
        // the remainder is about 1e-16 of the total, far below the mode's weight
        let fixed = w[mode] as i128 + (TOTAL as i128 - sum as i128);
        w[mode] = fixed.clamp(0, u64::MAX as i128) as u64;
        w.resize(buckets, 0);
        // Vose's alias construction, exact in integers; a bucket not split keeps its units
        // (threshold 0, alias itself)
        let mut cells: Vec<u64> = (0..buckets as u64).collect();
        let mut small = Vec::with_capacity(buckets);
        let mut large = Vec::with_capacity(buckets);
        for (j, &x) in w.iter().enumerate() {
            if x < cap {
                small.push(j);
            } else {
                large.push(j);
            }
        }
        while let (Some(&l), Some(s)) = (large.last(), small.pop()) {
            // w[s] < cap = 2^(64-g): the shift keeps every bit
            cells[s] = (w[s] << g) | l as u64;
            w[l] -= cap - w[s];
            if w[l] < cap {
                large.pop();
                small.push(l);
            }
        }
        // what is left holds exactly `cap` (the weights sum to buckets * cap)
        PoissonTable {
            lo,
            g,
            cells: cells.into(),
        }
    }

    /// The count that the 64 random bits `v` select, as f64.
    #[inline]
    pub fn sample(&self, v: u64) -> f64 {
        let j = (v >> (64 - self.g)) as usize;
        let r = (v << self.g) >> self.g;
        let cell = self.cells[j];
        let k = if r < cell >> self.g {
            j as u64
        } else {
            cell & ((1 << self.g) - 1)
        };
        // lo + k < 2^32: a signed conversion (one instruction)
        (self.lo as i64 + k as i64) as f64
    }

    /// The weight of each count `lo + i` in units of 2^-64 (they sum to 2^64).
    pub fn weights(&self) -> (u32, Vec<u128>) {
        let cap: u128 = TOTAL >> self.g;
        let mut w = vec![0u128; self.cells.len()];
        for (j, &c) in self.cells.iter().enumerate() {
            let t = (c >> self.g) as u128;
            let a = (c & ((1 << self.g) - 1)) as usize;
            w[j] += t;
            w[a] += cap - t;
        }
        while w.len() > 1 && w[w.len() - 1] == 0 {
            w.pop();
        }
        (self.lo, w)
    }

    /// Buckets held.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Never true (a table holds at least two buckets).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }
}

/// The probabilities of `Poisson(e)` above [`PMF_FLOOR`]: the first count, the
/// probabilities from it on, the index of the mode.
fn pmf(e: f64) -> (u32, Vec<f64>, usize) {
    let mode = e.floor();
    let pm = (mode * e.ln() - e - ln_gamma(mode + 1.0)).exp();
    // downwards from the mode
    let mut down = vec![];
    let mut p = pm;
    let mut k = mode;
    while k > 0.0 {
        p *= k / e;
        k -= 1.0;
        if p < PMF_FLOOR {
            break;
        }
        down.push(p);
    }
    let lo = mode as u32 - down.len() as u32;
    let at = down.len();
    let mut pmf: Vec<f64> = down.into_iter().rev().collect();
    pmf.push(pm);
    let mut p = pm;
    let mut k = mode;
    loop {
        k += 1.0;
        p *= e / k;
        if p < PMF_FLOOR {
            break;
        }
        pmf.push(p);
    }
    (lo, pmf, at)
}

/// Largest mean tabulated: a table of mean `e` holds about `17 sqrt(e)` entries.
pub const MAX_TABLE_MEAN: f64 = 1e6;
/// Budget of table entries over all tables of one sampler (a table of `n` counts holds
/// fewer than `2 n` buckets of 8 bytes, so at most about 32 MB if every tabulated value
/// occurs): values whose tables would pass it are drawn without a table.
pub const ENTRY_BUDGET: f64 = 2.0e6;

/// An upper bound of the entries of the table of mean `e`.
fn entries_bound(e: f64) -> f64 {
    let sd = e.sqrt();
    e.min(12.0 * sd) + 12.0 * sd + 40.0
}

/// Tables of `Poisson((x - black) / K)` for the stored values `x` of one black level.
#[derive(Debug)]
pub struct LevelTables {
    k: f64,
    /// First tabulated value: the smallest `x > black`.
    x0: usize,
    black: f64,
    tables: Vec<OnceLock<PoissonTable>>,
}

impl LevelTables {
    /// The black level of these tables.
    #[inline]
    pub fn black(&self) -> f64 {
        self.black
    }

    /// The table of stored value `x`, when tabulated (built on first use).
    #[inline]
    pub fn get(&self, x: u16) -> Option<&PoissonTable> {
        let i = (x as usize).checked_sub(self.x0)?;
        let cell = self.tables.get(i)?;
        Some(cell.get_or_init(|| PoissonTable::new((x as f64 - self.black) / self.k)))
    }
}

/// The shot-noise tables of one sampler: per 2x2 position, the tables of its black level
/// (positions with equal black levels share them), for every stored value `x` whose mean
/// `(x - black) / K` is in `(0, max_mean]`; `max_mean` is `poisson_max_electrons` lowered
/// to [`MAX_TABLE_MEAN`] and to the [`ENTRY_BUDGET`] (a choice that depends on the
/// parameters and levels only, so crops and thread counts see the same tables). Tables
/// are built on first use.
#[derive(Debug)]
pub struct ShotTables {
    k: f64,
    level_of: [usize; 4],
    levels: Vec<LevelTables>,
}

impl ShotTables {
    /// Tables for gain `k` and the black levels of the four 2x2 positions; values up to
    /// `x_max` (the white level) are considered.
    pub fn new(k: f64, poisson_max: f64, blacks: [f64; 4], x_max: usize) -> ShotTables {
        let mut distinct: Vec<f64> = vec![];
        let level_of = blacks.map(|b| {
            if let Some(i) = distinct.iter().position(|&d| d.to_bits() == b.to_bits()) {
                i
            } else {
                distinct.push(b);
                distinct.len() - 1
            }
        });
        let cap = poisson_max.min(MAX_TABLE_MEAN);
        // x0 and the last value per level within the cap, then lowered to the budget: the
        // levels grow together in steps of one stored value.
        let x0: Vec<usize> = distinct
            .iter()
            .map(|&b| (b.max(-1.0).floor() + 1.0) as usize)
            .collect();
        let mut count = vec![0usize; distinct.len()];
        let mut spent = 0.0;
        let x_max = x_max.min(u16::MAX as usize);
        'grow: for step in 0.. {
            let mut grew = false;
            for (l, &b) in distinct.iter().enumerate() {
                let x = x0[l] + step;
                if x > x_max {
                    continue;
                }
                let e = (x as f64 - b) / k;
                if !(e > 0.0 && e <= cap) {
                    continue;
                }
                spent += entries_bound(e);
                if spent > ENTRY_BUDGET {
                    break 'grow;
                }
                count[l] = step + 1;
                grew = true;
            }
            if !grew {
                break;
            }
        }
        let levels = distinct
            .iter()
            .enumerate()
            .map(|(l, &black)| LevelTables {
                k,
                x0: x0[l],
                black,
                tables: (0..count[l]).map(|_| OnceLock::new()).collect(),
            })
            .collect();
        ShotTables {
            k,
            level_of,
            levels,
        }
    }

    /// The tables of 2x2 position `pos`.
    #[inline]
    pub fn level(&self, pos: usize) -> &LevelTables {
        &self.levels[self.level_of[pos]]
    }

    /// The table of stored value `x` at 2x2 position `pos`, when tabulated.
    #[inline]
    pub fn get(&self, pos: usize, x: u16) -> Option<&PoissonTable> {
        self.level(pos).get(x)
    }

    /// The largest tabulated mean (0 when nothing is tabulated).
    pub fn max_mean(&self) -> f64 {
        self.levels
            .iter()
            .filter(|l| !l.tables.is_empty())
            .map(|l| ((l.x0 + l.tables.len() - 1) as f64 - l.black) / self.k)
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `F(k)` summed from pmf values evaluated one by one (no recurrence).
    fn direct_cdf(e: f64, k: u32) -> f64 {
        (0..=k)
            .map(|i| {
                let i = i as f64;
                (i * e.ln() - e - ln_gamma(i + 1.0)).exp()
            })
            .sum()
    }

    #[test]
    fn weights_match_direct_sums() {
        for e in [1e-25, 1e-9, 0.3, 1.0, 3.0, 11.99, 12.5, 100.0, 428.1, 999.7] {
            let t = PoissonTable::new(e);
            let (lo, w) = t.weights();
            assert_eq!(w.iter().sum::<u128>(), TOTAL, "e {e}");
            let mut worst = 0.0f64;
            let mut acc = 0u128;
            for k in 0..lo + w.len() as u32 + 3 {
                if k >= lo {
                    acc += w.get((k - lo) as usize).copied().unwrap_or(0);
                }
                let f = acc as f64 / TOTAL as f64;
                worst = worst.max((f - direct_cdf(e, k)).abs());
            }
            // the reference's own error: ln k! holds about 1e-16 * ln k! (~ e ln e) absolute
            eprintln!("e {e}: max |F - direct| {worst:.2e}");
            assert!(worst < 1e-15 * (20.0 + e * e.ln()), "e {e}: {worst:e}");
        }
    }

    #[test]
    fn draws_follow_the_weights() {
        // every (bucket, position) pair: exhaustively over the buckets, 64 positions each
        let t = PoissonTable::new(7.3);
        let (lo, w) = t.weights();
        let g = t.g;
        let mut hits = vec![0u128; w.len() + 40];
        for j in 0..(1u64 << g) {
            for r in 0..64u64 {
                // positions spread over the bucket
                let pos = r << (64 - g - 6);
                let k = t.sample((j << (64 - g)) | pos) as u32;
                hits[(k - lo) as usize] += 1;
            }
        }
        // each count's share of the sampled grid is within one grid step of its weight
        let step = TOTAL >> (g + 6);
        for (i, &wi) in w.iter().enumerate() {
            let got = hits[i] * step;
            let tol = step * (1 << g);
            assert!(
                got.abs_diff(wi) <= tol,
                "count {}: {got} vs {wi}",
                lo as usize + i
            );
        }
        assert_eq!(t.sample(0), lo as f64);
        assert!(t.sample(u64::MAX) < (lo as usize + w.len()) as f64);
    }

    #[test]
    fn sample_moments() {
        for e in [0.05, 2.0, 40.0, 600.0] {
            let t = PoissonTable::new(e);
            let mut s = 99u64;
            let n = 200_000;
            let (mut m1, mut m2) = (0.0, 0.0);
            for _ in 0..n {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let k = t.sample(s ^ (s >> 29));
                m1 += k;
                m2 += k * k;
            }
            let mean = m1 / n as f64;
            let var = m2 / n as f64 - mean * mean;
            let se = (e / n as f64).sqrt();
            assert!((mean - e).abs() < 5.0 * se, "{e} {mean}");
            assert!(
                (var / e - 1.0).abs() < 0.02 + 5.0 / (e * n as f64).sqrt(),
                "{e} {var}"
            );
        }
    }

    #[test]
    fn tables_share_levels_and_respect_the_budget() {
        let t = ShotTables::new(1.0, 1000.0, [512.0, 512.0, 512.0, 512.0], 16383);
        assert_eq!(t.levels.len(), 1);
        assert_eq!(t.max_mean(), 1000.0);
        assert!(t.get(0, 512).is_none());
        assert!(t.get(0, 1512).is_some());
        assert!(t.get(3, 1513).is_none());
        let t = ShotTables::new(1.0, 1000.0, [64.5, 64.0, 64.0, 70.0], 1023);
        assert_eq!(t.levels.len(), 3);
        assert_eq!(t.level_of, [0, 1, 1, 2]);
        assert!(t.get(0, 64).is_none() && t.get(0, 65).is_some());
        assert!(t.get(3, 70).is_none() && t.get(3, 71).is_some());
        // a huge budget demand (tiny K, exact everywhere) stops at the budget
        let t = ShotTables::new(1e-6, 1e12, [0.0; 4], 65535);
        let spent: f64 = t.levels[0]
            .tables
            .iter()
            .enumerate()
            .map(|(i, _)| entries_bound((i + 1) as f64 / 1e-6))
            .sum();
        assert!(spent <= ENTRY_BUDGET && !t.levels[0].tables.is_empty());
        assert!(t.max_mean() <= MAX_TABLE_MEAN);
        // the largest mean tabulated has fewer than 2^16 counts
        assert!(PoissonTable::new(MAX_TABLE_MEAN).g <= 16);
        // K huge: fractions of an electron; 65535 small tables pass the budget, the values
        // past it are drawn without a table
        let t = ShotTables::new(1e6, 1000.0, [0.0; 4], 65535);
        let n = t.levels[0].tables.len();
        assert!(n > 30_000 && n < 65535, "{n}");
        assert_eq!(t.get(0, 600).unwrap().lo, 0);
        assert!(t.get(0, 65535).is_none());
    }
}
