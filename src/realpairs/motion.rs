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

use crate::error::{Error, Result};
use crate::normalize::{normalize, NormalizeOptions};
use crate::raw::RawImage;

/// Longest side of a green plane, in plane pixels.
pub const MAX_SIDE: usize = 2048;
/// Search radius at the coarsest pyramid level, in its pixels.
pub const SEARCH: i64 = 6;
/// The pyramid stops halving below this many pixels on the short side.
const COARSEST: usize = 48;

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
        if mean.is_finite() && mean.abs() > 1e-12 {
            let k = (1.0 / mean) as f32;
            plane.iter_mut().for_each(|x| *x *= k);
        }
        Ok(GreenPlane {
            width: w,
            height: h,
            data: plane,
            scale: 2.0 * f as f64,
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
/// (`b(x + dx, y + dy) ~ a(x, y)`). Errors when the planes differ in size.
pub fn shift(a: &GreenPlane, b: &GreenPlane) -> Result<(f64, f64)> {
    if (a.width, a.height) != (b.width, b.height) || a.scale != b.scale {
        return Err(Error::invalid(format!(
            "green planes of {}x{} and {}x{} cannot be compared",
            a.width, a.height, b.width, b.height
        )));
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
        for sy in cy - r..=cy + r {
            for sx in cx - r..=cx + r {
                let c = cost(da, db, w, h, sx, sy);
                if c < best {
                    best = c;
                    (dx, dy) = (sx, sy);
                }
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
    Ok(((dx as f64 + fx) * a.scale, (dy as f64 + fy) * a.scale))
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
        }
    }

    #[test]
    fn finds_integer_and_subpixel_shifts() {
        let a = plane(300, 200, 0.0, 0.0);
        let s = shift(&a, &a).unwrap();
        assert_eq!(s, (0.0, 0.0));
        // b(x + 7, y - 3) = a(x, y): the content moved by (+7, -3) plane px = (14, -6) raw px.
        let b = plane(300, 200, 7.0, -3.0);
        let (dx, dy) = shift(&a, &b).unwrap();
        assert!(
            (dx - 14.0).abs() < 0.3 && (dy + 6.0).abs() < 0.3,
            "{dx} {dy}"
        );
        let c = plane(300, 200, 0.5, 0.0);
        let (dx, dy) = shift(&a, &c).unwrap();
        assert!((dx - 1.0).abs() < 0.3 && dy.abs() < 0.3, "{dx} {dy}");
        assert!(magnitude((3.0, 4.0)) == 5.0);
        assert!(shift(&a, &plane(30, 20, 0.0, 0.0)).is_err());
    }
}
