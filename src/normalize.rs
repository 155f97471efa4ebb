//! Normalization of stored raw values to [0, 1] and back (DNG chapter 5; docs/synthesis.md, "1. Normalize", "6. Denormalize").
//! The one code path shared by synthesis, the ISP, calibration and merging.
//!
//! `y = (lin(x) - black(site)) / (white - black_max)`, where `lin` is the LinearizationTable
//! (values past its end map to its last entry), `black(site)` is BlackLevel (repeat pattern
//! relative to the ActiveArea origin) plus BlackLevelDeltaH\[col\] plus BlackLevelDeltaV\[row\],
//! and `black_max` is the largest black over the plane.
//!
//! [`Normalizer::with_range_per_site`] divides by each site's own range instead,
//! `y = (lin(x) - black(site)) / (white - black(site))` (and denormalizes with it): what the
//! authors' release does with a 2x2 BlackLevel (`--compat release`, docs/synthesis.md).

use crate::error::Result;
use crate::raw::RawImage;

/// Normalized active-area plane: `width * height` f32 samples, row-major, active-area
/// coordinates (so the Bayer pattern applies directly).
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    /// Active-area width.
    pub width: usize,
    /// Active-area height.
    pub height: usize,
    /// Normalized samples.
    pub data: Vec<f32>,
}

/// Options of [`normalize`].
#[derive(Debug, Clone, Copy)]
pub struct NormalizeOptions {
    /// Clip below at 0 (default true; false keeps negative values).
    pub clip_negative: bool,
}

impl Default for NormalizeOptions {
    fn default() -> Self {
        NormalizeOptions {
            clip_negative: true,
        }
    }
}

/// Precomputed per-image normalization constants.
#[derive(Debug, Clone)]
pub struct Normalizer {
    lut: Option<Vec<u16>>,
    /// `white - black_max`: the scale of normalized units in DN.
    pub scale: f64,
    /// White level.
    pub white: f64,
    black_repeat: (usize, usize),
    black: Vec<f64>,
    delta_h: Vec<f64>,
    delta_v: Vec<f64>,
    /// Divide by `white - black(site)` instead of `scale`.
    range_per_site: bool,
}

impl Normalizer {
    /// Constants for `img`; errors on inconsistent geometry or black >= white.
    pub fn new(img: &RawImage) -> Result<Normalizer> {
        if img.meta.linear_raw.is_some() {
            return Err(crate::error::Error::unsupported(
                crate::raw::meta::LINEAR_RAW_NOT_CFA,
            ));
        }
        img.validate()?;
        let l = &img.meta.levels;
        Ok(Normalizer {
            lut: img
                .meta
                .linearization_table
                .clone()
                .filter(|t| !t.is_empty()),
            scale: l.white - l.black_max(),
            white: l.white,
            black_repeat: l.black_repeat,
            black: l.black.clone(),
            delta_h: l.black_delta_h.clone(),
            delta_v: l.black_delta_v.clone(),
            range_per_site: false,
        })
    }
    /// The same levels with each site's own range `white - black(site)` as the unit of
    /// normalized values, instead of `white - black_max` (the authors' release; a site whose
    /// stored value is white then normalizes to exactly 1 whatever its black level).
    pub fn with_range_per_site(mut self) -> Normalizer {
        self.range_per_site = true;
        self
    }
    /// The DN per normalized unit at a site whose black level is `black`: `scale`, or
    /// `white - black` with [`with_range_per_site`](Self::with_range_per_site).
    #[inline]
    pub fn range_at_black(&self, black: f64) -> f64 {
        if self.range_per_site {
            self.white - black
        } else {
            self.scale
        }
    }
    /// The same levels for linear samples: any LinearizationTable dropped (what a clean
    /// night raw made from this image holds).
    pub fn without_linearization(mut self) -> Normalizer {
        self.lut = None;
        self
    }
    /// True when there is no LinearizationTable: [`linearize`](Self::linearize) is `x as f64`.
    pub fn is_identity(&self) -> bool {
        self.lut.is_none()
    }
    /// Linearized value of a stored sample.
    #[inline]
    pub fn linearize(&self, x: u16) -> f64 {
        match &self.lut {
            Some(t) => t[(x as usize).min(t.len() - 1)] as f64,
            None => x as f64,
        }
    }
    /// Black level at active-area (row, col).
    #[inline]
    pub fn black_at(&self, row: usize, col: usize) -> f64 {
        let (rr, rc) = self.black_repeat;
        let mut b = self.black[(row % rr) * rc + (col % rc)];
        if let Some(d) = self.delta_h.get(col) {
            b += d;
        }
        if let Some(d) = self.delta_v.get(row) {
            b += d;
        }
        b
    }
    /// True when the black level depends only on the site's 2x2 position: BlackLevel repeat
    /// dimensions 1 or 2 and no non-zero BlackLevelDeltaH/V. Then
    /// `black_at(row, col) == black_at(row & 1, col & 1)` exactly.
    pub fn black_is_2x2_periodic(&self) -> bool {
        let (rr, rc) = self.black_repeat;
        matches!(rr, 1 | 2)
            && matches!(rc, 1 | 2)
            && self.delta_h.iter().all(|&d| d == 0.0)
            && self.delta_v.iter().all(|&d| d == 0.0)
    }
    /// Normalize one stored sample at active-area (row, col).
    #[inline]
    pub fn normalize(&self, x: u16, row: usize, col: usize) -> f64 {
        self.normalize_with_black(x, self.black_at(row, col))
    }
    /// Denormalize (docs/synthesis.md, "6. Denormalize"): `y * scale + black(site)`, rounded (or truncated),
    /// clipped to [0, white], as a linear (post-LinearizationTable) value.
    #[inline]
    pub fn denormalize(&self, y: f64, row: usize, col: usize, truncate: bool) -> u16 {
        let b = self.black_at(row, col);
        let v = y * self.range_at_black(b) + b;
        let v = if truncate { v.trunc() } else { v.round() };
        let v = if v.is_nan() { 0.0 } else { v };
        v.clamp(0.0, self.white.min(u16::MAX as f64)) as u16
    }
    /// Fill `out[c]` with [`black_at`](Self::black_at)`(row, c)` for `c in 0..out.len()`
    /// (same values, bit for bit, without a division per sample).
    pub fn black_row(&self, row: usize, out: &mut [f64]) {
        let (rr, rc) = self.black_repeat;
        let base = &self.black[(row % rr) * rc..][..rc];
        let dv = self.delta_v.get(row).copied();
        let mut k = 0;
        for (col, o) in out.iter_mut().enumerate() {
            let mut b = base[k];
            k += 1;
            if k == rc {
                k = 0;
            }
            if let Some(d) = self.delta_h.get(col) {
                b += d;
            }
            if let Some(d) = dv {
                b += d;
            }
            *o = b;
        }
    }
    /// [`normalize`](Self::normalize) with the site's black level given (from [`black_row`](Self::black_row)).
    #[inline]
    pub fn normalize_with_black(&self, x: u16, black: f64) -> f64 {
        (self.linearize(x) - black) / self.range_at_black(black)
    }
    /// [`denormalize`](Self::denormalize) with the site's black level given.
    #[inline]
    pub fn denormalize_with_black(&self, y: f64, black: f64, truncate: bool) -> u16 {
        let v = y * self.range_at_black(black) + black;
        let white = self.white.min(u16::MAX as f64);
        if !truncate {
            return round_clamp(v, white);
        }
        let v = v.trunc();
        let v = if v.is_nan() { 0.0 } else { v };
        v.clamp(0.0, white) as u16
    }
}

/// [`round_clamp`] to a fixed white level, in operations the compiler keeps in whole
/// registers: the saturating float-to-integer `as` casts are converted one sample at a time
/// on x86-64, which kept the loops that quantize every sample (the clean row, the noise
/// rows) from vectorizing. The same value as `round_clamp(v, white)` for every `v` and
/// `white` (tested against it in noise::apply).
#[derive(Debug, Clone, Copy)]
pub struct RoundClamp {
    /// `white as u32`, the largest result.
    top: f64,
}

impl RoundClamp {
    /// 2^52: adding it to a non-negative float below 2^52 rounds it to an integer.
    const SHIFT: f64 = 4_503_599_627_370_496.0;

    /// The rounding to `white`.
    pub fn new(white: f64) -> RoundClamp {
        RoundClamp {
            top: (white as u32) as f64,
        }
    }

    /// `round_clamp(v, white)`: below 0.5 (or NaN) 0; else `floor(min(v + 0.5, top))`,
    /// which is `min(floor(v + 0.5), top)` (the saturating cast's value). The floor of
    /// `x` in `[0, 2^32]`: adding 2^52 rounds it to the nearest integer `r` (exactly, in
    /// that binade), the low bits of the sum are `r`, and `r - 1` where `r` rounded up.
    #[inline(always)]
    pub fn apply(self, v: f64) -> u16 {
        let x = (v + 0.5).min(self.top);
        let t = x + Self::SHIFT;
        let r = (t.to_bits() as i64).wrapping_sub(Self::SHIFT.to_bits() as i64)
            - i64::from(t - Self::SHIFT > x);
        if v >= 0.5 {
            r as u16
        } else {
            0
        }
    }
}

/// A table of a function of (2x2 position, stored value) for every stored value up to the
/// white level, built only when the black level depends on the 2x2 position alone
/// ([`Normalizer::black_is_2x2_periodic`]): then a per-sample expression of the site's
/// black level and stored value can be looked up instead of computed, with the same bits.
/// Values above white are not tabulated (callers compute them).
#[derive(Debug, Clone)]
pub struct SiteTable<T> {
    tab: [Vec<T>; 4],
}

impl<T: Copy> SiteTable<T> {
    /// `f(row & 1, col & 1, x)` for every position and `x` in `0..=white`; `None` unless the
    /// black level is 2x2-periodic.
    pub fn new(norm: &Normalizer, f: impl Fn(usize, usize, u16) -> T) -> Option<SiteTable<T>> {
        if !norm.black_is_2x2_periodic() {
            return None;
        }
        let len = (norm.white.clamp(0.0, u16::MAX as f64) as usize) + 1;
        Some(SiteTable {
            tab: std::array::from_fn(|pos| {
                (0..len).map(|x| f(pos >> 1, pos & 1, x as u16)).collect()
            }),
        })
    }
    /// The table of `g` applied to every entry.
    pub fn map<U>(&self, g: impl Fn(T) -> U) -> SiteTable<U> {
        SiteTable {
            tab: std::array::from_fn(|pos| self.tab[pos].iter().map(|&v| g(v)).collect()),
        }
    }
    /// The tables of the even and odd columns of active-area row `r`.
    #[inline]
    pub fn row(&self, r: usize) -> (&[T], &[T]) {
        let p = (r & 1) << 1;
        (&self.tab[p], &self.tab[p | 1])
    }
    /// The entry of stored value `x` at active-area (r, c), `None` above white.
    #[inline]
    pub fn get(&self, r: usize, c: usize, x: u16) -> Option<T> {
        self.tab[((r & 1) << 1) | (c & 1)].get(x as usize).copied()
    }
}

/// `clamp(round(v), 0, white) as u16` with NaN -> 0 (round half away from zero), without
/// calling `f64::round` (a libm call on baseline x86-64). Same result as the plain
/// expression for every input, fractional whites included (tested in noise::apply).
#[inline]
pub fn round_clamp(v: f64, white: f64) -> u16 {
    // 0.5 <= v < white <= 65535: floor(v + 0.5) is round half up, and the rounded sum has
    // the same floor as the exact one (it is exact within v's binade; crossing into the
    // next binade it stays within [2^k, 2^k + 0.5]). A fractional white caps the rounded
    // value at floor(white), and so does v >= white (the saturating cast gives at least
    // floor(white), +inf included). NaN casts to 0. Below 0.5 the sum v + 0.5 could round
    // up to 1, so those are 0, by a select rather than a branch: the values of the three
    // branches this replaced, in fewer instructions per sample.
    let r = ((v + 0.5) as u32).min(white as u32) as u16;
    if v < 0.5 {
        0
    } else {
        r
    }
}

/// Normalize the active area of `img` into a [`Plane`].
pub fn normalize(img: &RawImage, opts: NormalizeOptions) -> Result<Plane> {
    let n = Normalizer::new(img)?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let mut data = Vec::with_capacity(w * h);
    for r in 0..h {
        let row = &img.data[(r + a.top as usize) * img.width + a.left as usize..][..w];
        for (c, &x) in row.iter().enumerate() {
            let mut y = n.normalize(x, r, c);
            if opts.clip_negative && y < 0.0 {
                y = 0.0;
            }
            data.push(y as f32);
        }
    }
    Ok(Plane {
        width: w,
        height: h,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::{Bayer, Rect};

    fn img(w: usize, h: usize, data: Vec<u16>) -> RawImage {
        RawImage {
            width: w,
            height: h,
            data,
            meta: RawMeta::new_bayer(Bayer::RGGB, 12, 64.0, 4095.0),
        }
    }

    #[test]
    fn per_site_black_with_deltas_and_active_area() {
        let mut i = img(4, 3, (0..12).map(|v| 1000 + v).collect());
        i.meta.active_area = Some(Rect {
            top: 1,
            left: 1,
            bottom: 3,
            right: 4,
        });
        i.meta.levels.black_repeat = (1, 2);
        i.meta.levels.black = vec![60.0, 70.0];
        i.meta.levels.black_delta_h = vec![0.0, 1.0, 2.0];
        i.meta.levels.black_delta_v = vec![0.5, 0.0];
        let p = normalize(&i, NormalizeOptions::default()).unwrap();
        assert_eq!((p.width, p.height), (3, 2));
        // black_max = 70 + 2 + 0.5; scale = 4095 - 72.5
        let scale = 4095.0 - 72.5;
        // active (0,0) = stored (1,1) = 1005; black = 60 + 0 + 0.5
        assert!((p.data[0] as f64 - (1005.0 - 60.5) / scale).abs() < 1e-6);
        // active (1,2) = stored (2,3) = 1011; black = 60 + 2 + 0
        assert!((p.data[5] as f64 - (1011.0 - 62.0) / scale).abs() < 1e-6);
    }

    #[test]
    fn linearization_table_clamps_past_end() {
        let mut i = img(2, 1, vec![1, 10]);
        i.meta.levels.black = vec![0.0];
        i.meta.levels.white = 1000.0;
        i.meta.linearization_table = Some(vec![0, 100, 400]);
        let p = normalize(&i, NormalizeOptions::default()).unwrap();
        assert_eq!(p.data, vec![0.1, 0.4]);
    }

    #[test]
    fn black_at_or_above_white_is_an_error() {
        let mut i = img(2, 2, vec![0; 4]);
        i.meta.levels.black = vec![4095.0];
        let e = normalize(&i, NormalizeOptions::default()).unwrap_err();
        assert!(e.to_string().contains(">= white"), "{e}");
    }

    #[test]
    fn black_row_and_with_black_variants_match() {
        let mut i = img(5, 4, (0..20).map(|v| 900 + 37 * v).collect());
        i.meta.levels.black_repeat = (2, 2);
        i.meta.levels.black = vec![60.0, 61.5, 62.25, 63.0];
        i.meta.levels.black_delta_h = vec![0.1, 0.2, 0.3, 0.4, 0.5];
        i.meta.levels.black_delta_v = vec![0.7, 0.0, 1.3, 0.9];
        let n = Normalizer::new(&i).unwrap();
        let mut row = vec![0.0; 5];
        for r in 0..4 {
            n.black_row(r, &mut row);
            for (c, &b) in row.iter().enumerate() {
                assert_eq!(b.to_bits(), n.black_at(r, c).to_bits());
                let x = i.get(r, c);
                assert_eq!(n.normalize_with_black(x, b), n.normalize(x, r, c));
                for y in [-0.1, 0.3, 0.77, 1.5, f64::NAN] {
                    for t in [false, true] {
                        assert_eq!(n.denormalize_with_black(y, b, t), n.denormalize(y, r, c, t));
                    }
                }
            }
        }
    }

    #[test]
    fn denormalize_round_trip_and_clip() {
        let i = img(2, 2, vec![0; 4]);
        let n = Normalizer::new(&i).unwrap();
        for x in [64u16, 65, 1000, 4095] {
            let y = n.normalize(x, 0, 0);
            assert_eq!(n.denormalize(y, 0, 0, false), x);
        }
        assert_eq!(n.denormalize(2.0, 0, 0, false), 4095);
        assert_eq!(n.denormalize(-1.0, 0, 0, false), 0);
        assert_eq!(n.denormalize(f64::NAN, 0, 0, false), 0);
        assert_eq!(n.denormalize(0.49 / n.scale, 0, 0, true), 64);
    }

    #[test]
    fn range_per_site_maps_white_to_one_on_every_site() {
        let mut i = img(2, 2, vec![4095; 4]);
        i.meta.levels.black_repeat = (2, 2);
        i.meta.levels.black = vec![250.0, 256.0, 260.0, 254.0];
        let max = Normalizer::new(&i).unwrap();
        let own = max.clone().with_range_per_site();
        for (r, c) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let b = own.black_at(r, c);
            assert_eq!(own.range_at_black(b), 4095.0 - b);
            assert_eq!(max.range_at_black(b), 4095.0 - 260.0);
            assert_eq!(own.normalize(4095, r, c), 1.0);
            assert_eq!(own.denormalize(1.0, r, c, true), 4095);
            // white - black_max as the unit: 1 falls short of white by black_max - black
            assert_eq!(
                max.denormalize(1.0, r, c, true) as f64,
                4095.0 - (260.0 - b)
            );
            for x in [250u16, 700, 3000] {
                let y = own.normalize(x, r, c);
                assert_eq!(y, (x as f64 - b) / (4095.0 - b));
                assert_eq!(own.denormalize(y, r, c, false), x);
            }
        }
    }
}
