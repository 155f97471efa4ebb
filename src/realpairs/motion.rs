//! Motion between two frames of a scene: the global translation of a downsampled green plane,
//! found by a coarse-to-fine search of the mean squared difference (docs/real-pairs.md,
//! "Motion check").
//!
//! 1. [`GreenPlane::of`]: the active area is normalized (black/white levels), each 2 x 2 CFA
//!    block becomes the mean of its green sites (of all its sites for a non-Bayer CFA), the
//!    block plane is box-averaged down to at most [`MAX_SIDE`] on its long side and divided
//!    by its mean, so frames of different exposure, ISO or level scaling compare.
//! 2. [`shift`]: a pyramid of 2 x 2 box averages down to about 64 px; an exhaustive integer
//!    search of +-[`SEARCH`] px at the coarsest level, then +-1 px at each finer level, and a
//!    parabola through the costs at -1, 0, +1 on each axis for the sub-pixel part. The cost is
//!    the mean squared difference over the overlap (at least half of each axis).
//!
//! The result is in raw pixels (plane pixels times the plane's scale).
//!
//! 3. What cannot be measured is said, never guessed ([`Motion::Unmeasurable`]): a plane
//!    with no signal above the black level (mean <= 0), planes with no structure (the cost
//!    at the coarsest level is below [`MIN_COST`] everywhere in the search window: flat or
//!    identical featureless frames), and costs without a distinct minimum (the best cost is
//!    not below [`DISTINCT`] times the window's median: noise only, or a frame with no
//!    content against a textured one).

use crate::error::{Error, Result};
use crate::normalize::{normalize, NormalizeOptions};
use crate::raw::RawImage;

/// Longest side of a green plane, in plane pixels.
pub const MAX_SIDE: usize = 2048;
/// Search radius at the coarsest pyramid level, in its pixels.
pub const SEARCH: i64 = 6;
/// The pyramid stops halving below this many pixels on the short side.
const COARSEST: usize = 48;
/// Below this median cost (mean squared difference of mean-1 planes over the coarsest
/// search window) the frames hold no structure to align.
pub const MIN_COST: f64 = 1e-10;
/// The best cost must be below this fraction of the window's median cost.
pub const DISTINCT: f64 = 0.5;

/// The outcome of a motion measurement.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// The translation `(dx, dy)` in raw pixels.
    Shift(f64, f64),
    /// No translation can be measured, and why.
    Unmeasurable(String),
}

/// A frame's green plane, mean-normalized.
#[derive(Debug, Clone, PartialEq)]
pub struct GreenPlane {
    /// Width in plane pixels.
    pub width: usize,
    /// Height in plane pixels.
    pub height: usize,
    /// Samples, row-major, mean 1 (or all 0 for a black frame).
    pub data: Vec<f32>,
    /// Raw pixels per plane pixel.
    pub scale: f64,
    /// False when the plane's mean is not above 0 (nothing above the black level): it was
    /// not normalized and no motion can be measured against it.
    pub signal: bool,
}

impl GreenPlane {
    /// The green plane of a raw image (see the module documentation).
    pub fn of(img: &RawImage) -> Result<GreenPlane> {
        let p = normalize(
            img,
            NormalizeOptions {
                clip_negative: false,
            },
        )?;
        let (bw, bh) = (p.width / 2, p.height / 2);
        if bw < 8 || bh < 8 {
            return Err(Error::invalid(format!(
                "active area {}x{} is too small to measure motion (needs 16x16)",
                p.width, p.height
            )));
        }
        let greens: Vec<usize> = match img.bayer() {
            Ok(b) => (0..4).filter(|&i| b.0[i] == 1).collect(),
            Err(_) => (0..4).collect(),
        };
        let inv = 1.0 / greens.len() as f32;
        let mut block = vec![0f32; bw * bh];
        for (by, row) in block.chunks_mut(bw).enumerate() {
            for (bx, v) in row.iter_mut().enumerate() {
                let mut s = 0f32;
                for &i in &greens {
                    let (r, c) = (2 * by + (i >> 1), 2 * bx + (i & 1));
                    s += p.data[r * p.width + c];
                }
                *v = s * inv;
            }
        }
        let f = bw.max(bh).div_ceil(MAX_SIDE).max(1);
        let (mut plane, w, h) = box_down(&block, bw, bh, f);
        let mean = plane.iter().map(|&x| x as f64).sum::<f64>() / plane.len() as f64;
        let signal = mean.is_finite() && mean > 1e-9;
        if signal {
            let k = (1.0 / mean) as f32;
            plane.iter_mut().for_each(|x| *x *= k);
        }
        Ok(GreenPlane {
            width: w,
            height: h,
            data: plane,
            scale: 2.0 * f as f64,
            signal,
        })
    }
}

/// Average `f x f` boxes (partial boxes at the edges dropped).
fn box_down(src: &[f32], w: usize, h: usize, f: usize) -> (Vec<f32>, usize, usize) {
    if f <= 1 {
        return (src.to_vec(), w, h);
    }
    let (ow, oh) = (w / f, h / f);
    let inv = 1.0 / (f * f) as f32;
    let mut out = vec![0f32; ow * oh];
    for (oy, row) in out.chunks_mut(ow.max(1)).enumerate().take(oh) {
        for (ox, v) in row.iter_mut().enumerate() {
            let mut s = 0f32;
            for y in oy * f..(oy + 1) * f {
                let line = &src[y * w + ox * f..y * w + (ox + 1) * f];
                s += line.iter().sum::<f32>();
            }
            *v = s * inv;
        }
    }
    (out, ow, oh)
}

/// The translation `(dx, dy)` in raw pixels that best maps `a` onto `b`
/// (`b(x + dx, y + dy) ~ a(x, y)`), or why none can be measured (see the module
/// documentation). Errors when the planes differ in size.
pub fn shift(a: &GreenPlane, b: &GreenPlane) -> Result<Motion> {
    if (a.width, a.height) != (b.width, b.height) || a.scale != b.scale {
        return Err(Error::invalid(format!(
            "green planes of {}x{} and {}x{} cannot be compared",
            a.width, a.height, b.width, b.height
        )));
    }
    for (p, which) in [(a, "the reference"), (b, "this frame")] {
        if !p.signal {
            return Ok(Motion::Unmeasurable(format!(
                "{which} has no signal above the black level"
            )));
        }
    }
    let mut pa = vec![(a.data.clone(), a.width, a.height)];
    let mut pb = vec![(b.data.clone(), b.width, b.height)];
    while let (Some(la), Some(lb)) = (pa.last(), pb.last()) {
        if la.1.min(la.2) / 2 < COARSEST {
            break;
        }
        let na = box_down(&la.0, la.1, la.2, 2);
        let nb = box_down(&lb.0, lb.1, lb.2, 2);
        pa.push(na);
        pb.push(nb);
    }
    let (mut dx, mut dy) = (0i64, 0i64);
    let levels = pa.len();
    for lvl in (0..levels).rev() {
        let (da, w, h) = (&pa[lvl].0, pa[lvl].1, pa[lvl].2);
        let db = &pb[lvl].0;
        let r = if lvl + 1 == levels {
            SEARCH.min(w as i64 / 4).min(h as i64 / 4)
        } else {
            dx *= 2;
            dy *= 2;
            1
        };
        let (cx, cy) = (dx, dy);
        let mut best = f64::INFINITY;
        let mut all = Vec::new();
        for sy in cy - r..=cy + r {
            for sx in cx - r..=cx + r {
                let c = cost(da, db, w, h, sx, sy);
                if c < best {
                    best = c;
                    (dx, dy) = (sx, sy);
                }
                all.push(c);
            }
        }
        if lvl + 1 == levels {
            if let Some(why) = indistinct(best, all) {
                return Ok(Motion::Unmeasurable(why));
            }
        }
    }
    let (da, w, h) = (&pa[0].0, pa[0].1, pa[0].2);
    let db = &pb[0].0;
    let c0 = cost(da, db, w, h, dx, dy);
    let sub = |m: f64, p: f64| {
        let den = m - 2.0 * c0 + p;
        if den > 0.0 && den.is_finite() {
            (0.5 * (m - p) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    };
    let fx = sub(
        cost(da, db, w, h, dx - 1, dy),
        cost(da, db, w, h, dx + 1, dy),
    );
    let fy = sub(
        cost(da, db, w, h, dx, dy - 1),
        cost(da, db, w, h, dx, dy + 1),
    );
    Ok(Motion::Shift(
        (dx as f64 + fx) * a.scale,
        (dy as f64 + fy) * a.scale,
    ))
}

/// Why the coarsest level's costs (`best` their least) show no measurable translation, if
/// they do not (see the module documentation).
fn indistinct(best: f64, mut all: Vec<f64>) -> Option<String> {
    all.retain(|c| c.is_finite());
    all.sort_by(f64::total_cmp);
    let median = all.get(all.len() / 2).copied().unwrap_or(0.0);
    if median < MIN_COST {
        return Some(
            "the frames hold no structure to align (flat or featureless at the search scale)"
                .into(),
        );
    }
    if best.partial_cmp(&(DISTINCT * median)) != Some(std::cmp::Ordering::Less) {
        return Some(format!(
            "no distinct match: the best alignment differs from the others by too little (best cost {:.3} of the median), e.g. a frame with no content or noise only",
            best / median
        ));
    }
    None
}

/// A length in pixels as a short text: plain decimals from 0.001 up to 1e6, exponent
/// notation outside (a tiny `--max-motion` does not print 300 digits).
pub fn px_text(v: f64) -> String {
    if v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        let t = format!("{v:.3}");
        let t = t.trim_end_matches('0').trim_end_matches('.');
        if t.is_empty() || t == "-" || t == "-0" {
            "0".into()
        } else {
            t.to_string()
        }
    } else {
        format!("{v:e}")
    }
}

/// Mean squared difference of `a(x, y)` and `b(x + sx, y + sy)` over their overlap;
/// infinite when the overlap is under half of either axis.
fn cost(a: &[f32], b: &[f32], w: usize, h: usize, sx: i64, sy: i64) -> f64 {
    let (wi, hi) = (w as i64, h as i64);
    if sx.abs() * 2 > wi || sy.abs() * 2 > hi {
        return f64::INFINITY;
    }
    let x0 = 0.max(-sx) as usize;
    let x1 = wi.min(wi - sx) as usize;
    let y0 = 0.max(-sy) as usize;
    let y1 = hi.min(hi - sy) as usize;
    let mut s = 0f64;
    for y in y0..y1 {
        let ra = &a[y * w + x0..y * w + x1];
        let yb = (y as i64 + sy) as usize;
        let xb0 = (x0 as i64 + sx) as usize;
        let rb = &b[yb * w + xb0..yb * w + xb0 + (x1 - x0)];
        let row: f32 = ra
            .iter()
            .zip(rb)
            .map(|(p, q)| {
                let d = p - q;
                d * d
            })
            .sum();
        s += row as f64;
    }
    s / ((x1 - x0) * (y1 - y0)) as f64
}

/// Length of a shift.
pub fn magnitude((dx, dy): (f64, f64)) -> f64 {
    (dx * dx + dy * dy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(w: usize, h: usize, ox: f64, oy: f64) -> GreenPlane {
        let mut data = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (u, v) = (x as f64 - ox, y as f64 - oy);
                let s = 1.0
                    + 0.5 * (u * 0.21).sin() * (v * 0.17).cos()
                    + 0.3 * (u * 0.05 + v * 0.07).sin();
                data.push(s as f32);
            }
        }
        GreenPlane {
            width: w,
            height: h,
            data,
            scale: 2.0,
            signal: true,
        }
    }

    fn xy(m: Motion) -> (f64, f64) {
        match m {
            Motion::Shift(x, y) => (x, y),
            Motion::Unmeasurable(w) => panic!("unmeasurable: {w}"),
        }
    }

    #[test]
    fn finds_integer_and_subpixel_shifts() {
        let a = plane(300, 200, 0.0, 0.0);
        let s = xy(shift(&a, &a).unwrap());
        assert_eq!(s, (0.0, 0.0));
        // b(x + 7, y - 3) = a(x, y): the content moved by (+7, -3) plane px = (14, -6) raw px.
        let b = plane(300, 200, 7.0, -3.0);
        let (dx, dy) = xy(shift(&a, &b).unwrap());
        assert!(
            (dx - 14.0).abs() < 0.3 && (dy + 6.0).abs() < 0.3,
            "{dx} {dy}"
        );
        let c = plane(300, 200, 0.5, 0.0);
        let (dx, dy) = xy(shift(&a, &c).unwrap());
        assert!((dx - 1.0).abs() < 0.3 && dy.abs() < 0.3, "{dx} {dy}");
        assert!(magnitude((3.0, 4.0)) == 5.0);
        assert!(shift(&a, &plane(30, 20, 0.0, 0.0)).is_err());
    }

    #[test]
    fn featureless_planes_are_unmeasurable() {
        let a = plane(300, 200, 0.0, 0.0);
        let flat = GreenPlane {
            data: vec![1.0; 300 * 200],
            ..a.clone()
        };
        let black = GreenPlane {
            data: vec![0.0; 300 * 200],
            signal: false,
            ..a.clone()
        };
        for (p, q) in [
            (&flat, &flat),
            (&a, &flat),
            (&flat, &a),
            (&a, &black),
            (&black, &black),
        ] {
            assert!(
                matches!(shift(p, q).unwrap(), Motion::Unmeasurable(_)),
                "{:?}",
                shift(p, q)
            );
        }
        assert_eq!(px_text(1.0), "1");
        assert_eq!(px_text(0.25), "0.25");
        assert_eq!(px_text(1e-300), "1e-300");
        assert_eq!(px_text(0.0), "0");
    }
}
