//! NumPy's legacy generator, `numpy.random.RandomState`: MT19937 and its polar Box-Muller
//! normal (`legacy_gauss`, one cached draw), bit for bit, so the release's noise
//! ([`super::release`]) draws what `RandomState(key).normal(0, 1, shape)` draws.
//!
//! The state is the one `RandomState.get_state()` gives and `set_state` takes: 624 key
//! words, a position, whether a normal draw is cached and that draw. NumPy's C sources
//! (`numpy/random/src/mt19937/mt19937.c`, `numpy/random/src/legacy/legacy-distributions.c`)
//! are the reference; `log` is the platform's, as NumPy's.

use crate::error::{Error, Result};

/// Words of MT19937's state.
pub const MT_WORDS: usize = 624;
const MT_SHIFT: usize = 397;
const MATRIX_A: u32 = 0x9908_b0df;
const UPPER: u32 = 0x8000_0000;
const LOWER: u32 = 0x7fff_ffff;

/// `RandomState`'s state: MT19937 plus the cached normal draw.
#[derive(Debug, Clone, PartialEq)]
pub struct LegacyState {
    /// The 624 key words.
    pub key: Vec<u32>,
    /// Next word to temper (624: the key is regenerated first).
    pub pos: usize,
    /// Whether `gauss` holds the second draw of the last polar pair.
    pub has_gauss: bool,
    /// The cached draw.
    pub gauss: f64,
}

impl LegacyState {
    /// A state as `get_state()` spells it, checked: 624 words and a position of at most 624.
    pub fn new(key: Vec<u32>, pos: usize, has_gauss: bool, gauss: f64) -> Result<LegacyState> {
        if key.len() != MT_WORDS || pos > MT_WORDS {
            return Err(Error::invalid(format!(
                "MT19937 state: {MT_WORDS} key words and a position up to {MT_WORDS} expected, \
                 got {} words, position {pos}",
                key.len()
            )));
        }
        Ok(LegacyState {
            key,
            pos,
            has_gauss,
            gauss,
        })
    }

    /// `init_genrand(seed)`: MT19937's reference seeding (`RandomState(seed)` for an int
    /// below 2^32 seeds this way).
    pub fn from_seed(seed: u32) -> LegacyState {
        let mut key = vec![0u32; MT_WORDS];
        key[0] = seed;
        for i in 1..MT_WORDS {
            let prev = key[i - 1];
            key[i] = 1_812_433_253u32
                .wrapping_mul(prev ^ (prev >> 30))
                .wrapping_add(i as u32);
        }
        LegacyState {
            key,
            pos: MT_WORDS,
            has_gauss: false,
            gauss: 0.0,
        }
    }

    fn regenerate(&mut self) {
        let k = &mut self.key;
        let twist = |a: u32, b: u32, m: u32| {
            let y = (a & UPPER) | (b & LOWER);
            m ^ (y >> 1) ^ (0u32.wrapping_sub(y & 1) & MATRIX_A)
        };
        for i in 0..MT_WORDS {
            let next = k[(i + 1) % MT_WORDS];
            k[i] = twist(k[i], next, k[(i + MT_SHIFT) % MT_WORDS]);
        }
        self.pos = 0;
    }

    /// `mt19937_next32`: the next tempered word.
    pub fn next_u32(&mut self) -> u32 {
        if self.pos >= MT_WORDS {
            self.regenerate();
        }
        let mut y = self.key[self.pos];
        self.pos += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^ (y >> 18)
    }

    /// `legacy_double`: a double in [0, 1) from two words (53 bits).
    pub fn next_double(&mut self) -> f64 {
        let a = f64::from(self.next_u32() >> 5);
        let b = f64::from(self.next_u32() >> 6);
        (a * 67_108_864.0 + b) / 9_007_199_254_740_992.0
    }

    /// `legacy_gauss`: a standard normal draw (the polar method; every second draw is the
    /// cached one).
    pub fn gauss(&mut self) -> f64 {
        if self.has_gauss {
            let g = self.gauss;
            self.has_gauss = false;
            self.gauss = 0.0;
            return g;
        }
        loop {
            let x1 = 2.0 * self.next_double() - 1.0;
            let x2 = 2.0 * self.next_double() - 1.0;
            let r2 = x1 * x1 + x2 * x2;
            if r2 < 1.0 && r2 != 0.0 {
                let f = (-2.0 * r2.ln() / r2).sqrt();
                self.gauss = f * x1;
                self.has_gauss = true;
                return f * x2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// MT19937's reference output for seed 5489 (the 10000th word is 4123659995).
    #[test]
    fn reference_words() {
        let mut s = LegacyState::from_seed(5489);
        assert_eq!(s.next_u32(), 3_499_211_612);
        let last = (1..10_000).map(|_| s.next_u32()).last();
        assert_eq!(last, Some(4_123_659_995));
    }

    /// `RandomState(0)`: `random_sample()` then `standard_normal(3)`, as NumPy prints them.
    #[test]
    fn numpy_randomstate_zero() {
        let mut s = LegacyState::from_seed(0);
        assert_eq!(s.next_double(), 0.5488135039273248);
        let g: Vec<f64> = (0..3).map(|_| s.gauss()).collect();
        assert_eq!(g, NUMPY_SEED0_NORMALS_AFTER_ONE_DOUBLE);
    }

    /// `r = RandomState(0); r.random_sample(); r.standard_normal(3)`.
    const NUMPY_SEED0_NORMALS_AFTER_ONE_DOUBLE: [f64; 3] =
        [0.7415917408091613, 1.5529137219128164, -2.268328201180374];

    #[test]
    fn a_short_key_is_refused() {
        assert!(LegacyState::new(vec![0; 3], 0, false, 0.0).is_err());
        assert!(LegacyState::new(vec![0; MT_WORDS], MT_WORDS + 1, false, 0.0).is_err());
    }
}
