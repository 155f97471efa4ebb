//! Display-referred PNG (and 16-bit TIFF) renders: linear RGB encoded with a
//! [`DisplayTone`] (sRGB OETF by default), quantized to 8 bits (default) or 16 bits.

use crate::error::{Error, Result};
use crate::isp::tone::DisplayTone;
use crate::isp::RgbImage;
use crate::output::{write_atomic, OutputPolicy};
use image::ImageEncoder;
use rayon::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Options of [`write_png`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PngOptions {
    /// 16-bit samples instead of 8.
    pub sixteen_bit: bool,
    /// Display encoding.
    pub tone: DisplayTone,
}

impl Default for PngOptions {
    fn default() -> Self {
        PngOptions {
            sixteen_bit: false,
            tone: DisplayTone::Srgb,
        }
    }
}

/// The 8-bit quantizer: `(tone.encode(v) * 255 + 0.5) as u8`. The reference for the
/// lookup in [`encode_u8`] (which returns exactly these bytes for every `f32`).
#[inline]
pub fn quantize_u8_slow(tone: DisplayTone, v: f32) -> u8 {
    (tone.encode(v) * 255.0 + 0.5) as u8
}

/// Display-encoded 8-bit samples, by the direct formula for every sample (the reference
/// implementation of [`encode_u8`]; kept for tests and benchmarks).
pub fn encode_u8_slow(img: &RgbImage, tone: DisplayTone) -> Vec<u8> {
    img.data
        .par_iter()
        .map(|&v| quantize_u8_slow(tone, v))
        .collect()
}

/// Display-encoded 8-bit samples: byte for byte [`quantize_u8_slow`] of each sample, by
/// a per-tone lookup (see [`Lut8`]), or the direct formula if the lookup could not be
/// built for the tone.
pub fn encode_u8(img: &RgbImage, tone: DisplayTone) -> Vec<u8> {
    match Lut8::cached(tone) {
        Some(lut) => {
            let mut out = vec![0u8; img.data.len()];
            out.par_chunks_mut(1 << 16)
                .zip(img.data.par_chunks(1 << 16))
                .for_each(|(o, i)| lut_into(lut, i, o));
            out
        }
        None => encode_u8_slow(img, tone),
    }
}

/// `out[i] = lut.get(src[i])`, compiled twice like [`encode_u8_slice`] (the same bits).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn lut_into(lut: &Lut8, src: &[f32], out: &mut [u8]) {
    for (o, &v) in out.iter_mut().zip(src) {
        *o = lut.get(v);
    }
}

/// [`encode_u8`] of a slice of samples, on the calling thread (for band-wise encoding:
/// the same bytes as the whole-image call gives for these samples).
///
/// Compiled twice, the second time for AVX2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub fn encode_u8_slice(src: &[f32], tone: DisplayTone) -> Vec<u8> {
    match Lut8::cached(tone) {
        Some(lut) => src.iter().map(|&v| lut.get(v)).collect(),
        None => src.iter().map(|&v| quantize_u8_slow(tone, v)).collect(),
    }
}

/// Bit pattern of 1.0f32: every key is clamped to `[0, ONE]`.
const ONE_BITS: u32 = 0x3f80_0000;
/// Bucket size of [`Lut8`]: keys `>> LUT_SHIFT` index the bucket table (16 256 buckets, each
/// 2^16 consecutive `f32` bit patterns, i.e. 1/128 to 1/256 of an octave).
const LUT_SHIFT: u32 = 16;
/// Length of the bucket table: a power of two above `ONE_BITS >> LUT_SHIFT`.
const BUCKETS: usize = 1 << 14;
/// Thresholds a sample is compared with after the bucket lookup; tables whose buckets
/// hold more are not built.
const MAX_STEPS: usize = 2;

/// Exact table-driven 8-bit quantizer of one [`DisplayTone`].
///
/// `q(v) = quantize_u8_slow(tone, v)` depends on `v` only through the clamped input of
/// `DisplayTone::encode`: NaN and everything `<= 0` (sign bit set) give `q(0)`, everything
/// `>= 1` (and +inf) gives `q(1)`. For non-negative `f32` the bit patterns are ordered like
/// the values, and `q` is non-decreasing on `[0, 1]` for sRGB and gamma 2.2 (proved by
/// the exhaustive test over all 2^32 bit patterns, run by `scripts/test.sh --slow`; not
/// for the release tone, see [`Lut8::cached`]), so `q(v) = max{k : thr[k] <= key(v)}`
/// where `thr[k]` is the smallest key with `q >= k`, found by bisection over the bit
/// patterns with `quantize_u8_slow` itself. A
/// bucket table gives `q` at the start of each 2^16-pattern bucket; the few thresholds
/// inside a bucket (at most [`Lut8::max_steps`], 1 for sRGB) are then compared.
#[derive(Debug, Clone)]
pub struct Lut8 {
    /// `thr[k]` for k in 1..=255: smallest key in `[0, ONE]` with `q(key) >= k`
    /// (`ONE + 1` if none); `thr[0] = 0`, `thr[256] = u32::MAX` (sentinels).
    /// `thr[257]` is a second sentinel so that `thr[base + 2]` exists for `base = 255`.
    thr: Box<[u32; 258]>,
    /// `q` at key `i << LUT_SHIFT`, for i in `0..=ONE >> LUT_SHIFT` (the rest unused; the
    /// power-of-two length lets the index be masked instead of bounds-checked).
    base: Box<[u8; BUCKETS]>,
    /// `[thr[base[i] + 1], thr[base[i] + 2]]`: the next two thresholds after the bucket's
    /// start, so that a lookup's loads do not depend on each other.
    next: Box<[[u32; 2]; BUCKETS]>,
}

impl Lut8 {
    /// The cached table of `tone` (built on first use), `None` if a consistency check of
    /// the construction failed (then callers use the direct formula).
    ///
    /// Only sRGB and gamma 2.2 have a table: the exhaustive test proves their quantizers
    /// non-decreasing. The release tone is not: `3y^2 - 2y^3` is evaluated as
    /// `y * y * (3 - 2y)`, a rising factor times a falling one, and the rounded product
    /// steps back across a code boundary for some inputs (e.g. bit pattern 0x3f432c46 gives
    /// 245 while a smaller input gives 246), so it keeps the direct formula.
    pub fn cached(tone: DisplayTone) -> Option<&'static Lut8> {
        static LUTS: [OnceLock<Option<Lut8>>; 2] = [OnceLock::new(), OnceLock::new()];
        let i = match tone {
            DisplayTone::Srgb => 0,
            DisplayTone::Gamma22 => 1,
            DisplayTone::Release => return None,
        };
        LUTS.get(i)?.get_or_init(|| Lut8::build(tone)).as_ref()
    }

    /// The key of `v`: its bit pattern clamped to `[0, ONE]`, 0 for NaN and negatives.
    #[inline(always)]
    fn key(v: f32) -> u32 {
        let b = v.to_bits();
        if b > 0x7f80_0000 {
            // negative (sign bit, including -0.0 and -inf) or NaN
            0
        } else {
            b.min(ONE_BITS)
        }
    }

    /// Build the table of `tone`; `None` if the thresholds are not consistent with a
    /// non-decreasing quantizer or the special values do not map as the keys assume.
    pub fn build(tone: DisplayTone) -> Option<Lut8> {
        let q = |k: u32| quantize_u8_slow(tone, f32::from_bits(k));
        let mut thr = Box::new([0u32; 258]);
        for (k, t) in thr.iter_mut().enumerate().take(256).skip(1) {
            let k = k as u8;
            *t = if q(0) >= k {
                0
            } else if q(ONE_BITS) < k {
                ONE_BITS + 1
            } else {
                // q(lo) < k <= q(hi)
                let (mut lo, mut hi) = (0u32, ONE_BITS);
                while hi - lo > 1 {
                    let mid = lo + (hi - lo) / 2;
                    if q(mid) >= k {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                hi
            };
        }
        thr[256] = u32::MAX;
        thr[257] = u32::MAX;
        // Consistency: thresholds non-decreasing, and each is a step of q.
        if thr.windows(2).any(|w| w[0] > w[1]) {
            return None;
        }
        for k in 1..=255u32 {
            let t = thr[k as usize];
            if t <= ONE_BITS && (u32::from(q(t)) < k || (t > 0 && u32::from(q(t - 1)) >= k)) {
                return None;
            }
        }
        // A cheap guard against a non-monotone quantizer (the exhaustive test is the
        // proof): q steps exactly once, at the threshold, within WINDOW patterns of it.
        const WINDOW: u32 = 64;
        for k in 1..=255u32 {
            let t = thr[k as usize];
            if t > ONE_BITS {
                continue;
            }
            let lo = t.saturating_sub(WINDOW);
            let hi = t.saturating_add(WINDOW).min(ONE_BITS);
            if (lo..=hi).any(|b| (u32::from(q(b)) >= k) != (b >= t)) {
                return None;
            }
        }
        // The keys' assumptions about special values.
        let q0 = quantize_u8_slow(tone, 0.0);
        let q1 = quantize_u8_slow(tone, 1.0);
        let specials_ok = [
            -0.0,
            -1.0,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            -f32::MIN_POSITIVE,
        ]
        .iter()
        .all(|&v| quantize_u8_slow(tone, v) == q0)
            && [1.5, f32::MAX, f32::INFINITY]
                .iter()
                .all(|&v| quantize_u8_slow(tone, v) == q1);
        if !specials_ok {
            return None;
        }
        let count = |key: u32| thr[1..=255].iter().filter(|&&t| t <= key).count() as u8;
        let mut base = Box::new([255u8; BUCKETS]);
        for (i, b) in base
            .iter_mut()
            .enumerate()
            .take((ONE_BITS >> LUT_SHIFT) as usize + 1)
        {
            *b = count((i as u32) << LUT_SHIFT);
        }
        let mut next = Box::new([[u32::MAX; 2]; BUCKETS]);
        for (n, &b) in next.iter_mut().zip(base.iter()) {
            let b = usize::from(b);
            *n = [thr[b + 1], thr[b + 2]];
        }
        let lut = Lut8 { thr, base, next };
        (lut.max_steps() <= MAX_STEPS).then_some(lut)
    }

    /// `quantize_u8_slow(tone, v)` by table.
    #[inline(always)]
    pub fn get(&self, v: f32) -> u8 {
        let k = Lut8::key(v);
        let i = (k >> LUT_SHIFT) as usize & (BUCKETS - 1);
        // Branch-free: at most MAX_STEPS (2) thresholds lie inside a bucket, so the third
        // one after its start is beyond every key of the bucket; q never passes 255
        // (thr[256] = u32::MAX exceeds every key).
        let [t1, t2] = self.next[i];
        self.base[i] + u8::from(k >= t1) + u8::from(k >= t2)
    }

    /// The thresholds for codes 1..=255: element `k - 1` is the smallest bit pattern in
    /// `[0, 1]` whose code is `>= k` (`0x3f80_0001` if code `k` is never reached).
    pub fn thresholds(&self) -> &[u32] {
        &self.thr[1..256]
    }

    /// Largest number of thresholds inside one bucket (the compares after the lookup).
    pub fn max_steps(&self) -> usize {
        let n = (ONE_BITS >> LUT_SHIFT) as usize + 1;
        (0..n)
            .map(|i| {
                let next = if i + 1 < n {
                    self.base[i + 1]
                } else {
                    self.base[i]
                };
                usize::from(next - self.base[i])
            })
            .max()
            .unwrap_or(0)
    }
}

/// Display-encoded 16-bit samples.
pub fn encode_u16(img: &RgbImage, tone: DisplayTone) -> Vec<u16> {
    img.data
        .par_iter()
        .map(|&v| (tone.encode(v) * 65535.0 + 0.5) as u16)
        .collect()
}

fn dims(img: &RgbImage) -> Result<(u32, u32)> {
    img.validate()?;
    let w = u32::try_from(img.width).map_err(|_| Error::limits("image too wide"))?;
    let h = u32::try_from(img.height).map_err(|_| Error::limits("image too tall"))?;
    if w == 0 || h == 0 {
        return Err(Error::invalid("cannot write an empty image"));
    }
    Ok((w, h))
}

fn img_err(e: image::ImageError) -> Error {
    match e {
        image::ImageError::IoError(io) => Error::Io(io),
        other => Error::invalid(format!("image encoding failed: {other}")),
    }
}

/// Display-encoded samples as the `image` encoders take them (native-endian for 16 bit).
fn encoded(img: &RgbImage, opts: &PngOptions) -> (Vec<u8>, image::ExtendedColorType) {
    if opts.sixteen_bit {
        let native = encode_u16(img, opts.tone)
            .iter()
            .flat_map(|v| v.to_ne_bytes())
            .collect();
        (native, image::ExtendedColorType::Rgb16)
    } else {
        (encode_u8(img, opts.tone), image::ExtendedColorType::Rgb8)
    }
}

/// Write a display-referred PNG of the linear image `img` atomically.
pub fn write_png(
    img: &RgbImage,
    path: &Path,
    opts: &PngOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    let (w, h) = dims(img)?;
    if !opts.sixteen_bit {
        // 8-bit: row groups filtered and deflated in parallel (crate::encode::png_rows)
        let bytes = encode_u8(img, opts.tone);
        return crate::encode::png_rows::write_png_rgb8(
            &bytes, img.width, img.height, opts.tone, path, policy,
        );
    }
    write_atomic(path, policy, |out| {
        let (bytes, color) = encoded(img, opts);
        image::codecs::png::PngEncoder::new(out)
            .write_image(&bytes, w, h, color)
            .map_err(img_err)
    })
}

/// Write a display-referred 16-bit (or 8-bit) RGB TIFF of the linear image atomically.
pub fn write_tiff(
    img: &RgbImage,
    path: &Path,
    opts: &PngOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    let (w, h) = dims(img)?;
    write_atomic(path, policy, |out| {
        let (bytes, color) = encoded(img, opts);
        image::codecs::tiff::TiffEncoder::new(out)
            .write_image(&bytes, w, h, color)
            .map_err(img_err)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const TONES: [DisplayTone; 3] = [
        DisplayTone::Srgb,
        DisplayTone::Gamma22,
        DisplayTone::Release,
    ];

    /// The tones with a table.
    const LUT_TONES: [DisplayTone; 2] = [DisplayTone::Srgb, DisplayTone::Gamma22];

    fn lut(tone: DisplayTone) -> &'static Lut8 {
        Lut8::cached(tone).unwrap_or_else(|| panic!("no lookup table for {tone:?}"))
    }

    /// Compare the table with the formula on bit patterns `start, start + step, ...` below
    /// `end` (u64 so that the end of the range is reachable); returns the first mismatch.
    fn mismatch(tone: DisplayTone, start: u64, end: u64, step: u64) -> Option<u32> {
        let l = lut(tone);
        let chunk = 1u64 << 24;
        (start / chunk..end.div_ceil(chunk))
            .into_par_iter()
            .find_map_first(|c| {
                let lo = (c * chunk).max(start);
                let lo = lo + (step - (lo - start) % step) % step;
                let hi = ((c + 1) * chunk).min(end);
                (lo..hi)
                    .step_by(step as usize)
                    .map(|b| b as u32)
                    .find(|&b| {
                        let v = f32::from_bits(b);
                        l.get(v) != quantize_u8_slow(tone, v)
                    })
            })
    }

    #[test]
    fn release_tone_is_not_monotone_and_has_no_table() {
        assert!(Lut8::cached(DisplayTone::Release).is_none());
        // the window guard of `build` detects it too
        assert!(Lut8::build(DisplayTone::Release).is_none());
        let q = |b: u32| quantize_u8_slow(DisplayTone::Release, f32::from_bits(b));
        assert!((0x3f43_2b00..0x3f43_2c46).any(|b| q(b) > q(0x3f43_2c46)));
    }

    #[test]
    fn lookup_equals_formula_on_a_dense_sweep_and_at_every_threshold() {
        for tone in LUT_TONES {
            let l = lut(tone);
            // every 97th bit pattern over all 2^32 (44 M per tone; [0, 1] is 1/4 of them)
            assert_eq!(mismatch(tone, 0, 1 << 32, 97), None, "{tone:?}");
            // both sides of every threshold, and the specials
            for &t in l.thresholds() {
                for b in t.saturating_sub(2)..=t.saturating_add(2).min(ONE_BITS + 2) {
                    let v = f32::from_bits(b);
                    assert_eq!(l.get(v), quantize_u8_slow(tone, v), "{tone:?} {b:#x}");
                }
            }
            for v in [
                0.0,
                -0.0,
                1.0,
                f32::NAN,
                -f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::MIN_POSITIVE,
                f32::from_bits(1),
                f32::MAX,
                f32::MIN,
                0.5,
                crate::color::srgb::KNEE,
            ] {
                assert_eq!(l.get(v), quantize_u8_slow(tone, v), "{tone:?} {v}");
            }
            // every code 0..=255 is reached and the bucket step is small
            assert!(l.thresholds()[254] <= ONE_BITS, "{tone:?}");
            assert!(l.max_steps() <= 2, "{tone:?}: {}", l.max_steps());
        }
        assert_eq!(lut(DisplayTone::Srgb).max_steps(), 1);
    }

    /// All 2^32 bit patterns for every tone: `scripts/test.sh --slow`, or `cargo test
    /// --release --lib png::tests::slow_lookup_equals_formula_for_every_f32 -- --ignored
    /// --nocapture` (20-120 s on 2 shared cores in release, depending on their load).
    #[test]
    #[ignore = "slow: all 2^32 f32 bit patterns per tone (scripts/test.sh --slow)"]
    fn slow_lookup_equals_formula_for_every_f32() {
        for tone in LUT_TONES {
            let t0 = std::time::Instant::now();
            assert_eq!(mismatch(tone, 0, 1 << 32, 1), None, "{tone:?}");
            eprintln!(
                "{tone:?}: all 2^32 f32 equal ({:.1} s)",
                t0.elapsed().as_secs_f64()
            );
        }
    }

    proptest! {
        #[test]
        fn lookup_equals_formula_on_random_bits(bits in any::<u32>(), t in 0usize..2) {
            let v = f32::from_bits(bits);
            prop_assert_eq!(lut(LUT_TONES[t]).get(v), quantize_u8_slow(LUT_TONES[t], v));
        }

        #[test]
        fn lookup_equals_formula_on_random_values(v in -0.5f32..1.5, t in 0usize..2) {
            prop_assert_eq!(lut(LUT_TONES[t]).get(v), quantize_u8_slow(LUT_TONES[t], v));
        }
    }

    #[test]
    fn encode_u8_equals_the_reference() {
        let mut img = RgbImage::new(61, 7);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = (i as f32 * 0.618_034).fract() * 1.2 - 0.1;
        }
        img.data[0] = f32::NAN;
        img.data[1] = f32::INFINITY;
        for tone in TONES {
            assert_eq!(encode_u8(&img, tone), encode_u8_slow(&img, tone));
        }
    }

    #[test]
    fn rgb8_bytes_give_the_write_png_file() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = RgbImage::new(7, 5);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = (i as f32 * 0.37).sin();
        }
        let policy = OutputPolicy::default();
        let a = dir.path().join("a.png");
        write_png(&img, &a, &PngOptions::default(), &policy).unwrap();
        let bytes: Vec<u8> = img
            .data
            .chunks(9)
            .flat_map(|c| encode_u8_slice(c, DisplayTone::Srgb))
            .collect();
        assert_eq!(bytes, encode_u8(&img, DisplayTone::Srgb));
        let b = dir.path().join("b.png");
        crate::encode::png_rows::write_png_rgb8(&bytes, 7, 5, DisplayTone::Srgb, &b, &policy)
            .unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let mem = crate::encode::png_rows::png_rgb8_bytes(&bytes, 7, 5, DisplayTone::Srgb);
        assert_eq!(mem.unwrap(), std::fs::read(&a).unwrap());
        let c = dir.path().join("c.png");
        assert!(crate::encode::png_rows::write_png_rgb8(
            &bytes[1..],
            7,
            5,
            DisplayTone::Srgb,
            &c,
            &policy
        )
        .is_err());
        assert!(!c.exists());
        // the release tone (no lookup) goes through the formula
        let r: Vec<u8> = encode_u8_slice(&img.data, DisplayTone::Release);
        assert_eq!(r, encode_u8_slow(&img, DisplayTone::Release));
    }

    #[test]
    fn png_8_and_16_bit_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = RgbImage::new(4, 2);
        img.data[0] = 1.0;
        img.data[1] = 0.18;
        img.data[2] = f32::NAN;
        for sixteen in [false, true] {
            let p = dir.path().join(format!("a{sixteen}.png"));
            let opts = PngOptions {
                sixteen_bit: sixteen,
                tone: DisplayTone::Srgb,
            };
            write_png(&img, &p, &opts, &OutputPolicy::default()).unwrap();
            let back = image::open(&p).unwrap();
            if sixteen {
                let b = back.to_rgb16();
                assert_eq!(b.get_pixel(0, 0).0, [65535, 30235, 0]);
            } else {
                let b = back.to_rgb8();
                assert_eq!(b.get_pixel(0, 0).0, [255, 118, 0]);
            }
            let t = dir.path().join(format!("a{sixteen}.tif"));
            write_tiff(&img, &t, &opts, &OutputPolicy::default()).unwrap();
            assert_eq!(image::open(&t).unwrap().width(), 4);
        }
    }
}
