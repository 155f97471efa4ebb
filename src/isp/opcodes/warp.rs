//! WarpRectilinear (opcode 1) and WarpFisheye (opcode 2) on the stage-3 image (OpcodeList3),
//! as the Adobe DNG SDK's `dng_filter_warp`:
//! * the optical centre is `(l + cx (r - l), t + cy (b - t))` of the image bounds, in pixel
//!   coordinates where pixel (row, col) sits at (row, col);
//! * the normalising radius is the largest distance from the centre to a corner of the
//!   bounds (`MaxDistancePointToRect`), so `r = 1` at the farthest corner;
//! * each destination (corrected) pixel `d` maps to the source (uncorrected) position
//!   `s = c + R (n ratio + tan)` with `n = (d - c) / R`, `r^2 = min(|n|^2, 1)`,
//!   rectilinear `ratio = kr0 + kr1 r^2 + kr2 r^4 + kr3 r^6`,
//!   `tan_v = kt0 (r^2 + 2 n_v^2) + 2 kt1 n_h n_v`, `tan_h = kt1 (r^2 + 2 n_h^2) + 2 kt0 n_h n_v`;
//!   fisheye `ratio = f(r) / r` with `f(r) = t (kr0 + kr1 t^2 + kr2 t^4 + kr3 t^6)`,
//!   `t = atan(r)` (no tangential terms);
//! * the source is resampled with the SDK's separable bicubic kernel (A = -0.75, 4x4 taps,
//!   weights normalised to sum 1; the SDK quantises the fraction to 1/32 of a pixel, day2night
//!   does not), edges repeated, and the result pinned into [0, 1].
//!
//! One set of coefficients applies to every plane; one per plane when the opcode has as
//! many as the image. Square pixels (PixelAspectRatio 1).

use super::Bounds;
use crate::error::{Error, Result};
use rayon::prelude::*;

/// The radial model of a warp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Model {
    /// Rectilinear: radial kr0..kr3 and tangential kt0, kt1.
    Rectilinear {
        /// kr0..kr3.
        kr: [f64; 4],
        /// kt0, kt1.
        kt: [f64; 2],
    },
    /// Fisheye: kr0..kr3 of `atan(r)`.
    Fisheye {
        /// kr0..kr3.
        kr: [f64; 4],
    },
}

/// A warp ready to map destination pixels to source positions.
#[derive(Debug, Clone)]
pub struct Warp {
    planes: Vec<Model>,
    cv: f64,
    ch: f64,
    norm: f64,
    inv: f64,
}

fn poly(k: &[f64; 4], x2: f64) -> f64 {
    k[0] + x2 * (k[1] + x2 * (k[2] + x2 * k[3]))
}

impl Warp {
    /// A warp with `models` (one, or one per plane) about the relative centre (x, y) of an
    /// image of `bounds` with `planes` planes. Errors when the number of coefficient sets
    /// is neither 1 nor `planes` (the SDK refuses such a file too).
    pub fn new(models: Vec<Model>, center: [f64; 2], b: Bounds, planes: usize) -> Result<Warp> {
        if models.is_empty() || (models.len() != 1 && models.len() != planes) {
            return Err(Error::malformed(format!(
                "OpcodeList3: a warp with {} coefficient sets for a {planes}-plane image",
                models.len()
            )));
        }
        if !center.iter().all(|c| (0.0..=1.0).contains(c)) {
            return Err(Error::malformed(format!(
                "OpcodeList3: warp optical centre {center:?} outside [0, 1]"
            )));
        }
        let cv = b.t as f64 + b.h() as f64 * center[1];
        let ch = b.l as f64 + b.w() as f64 * center[0];
        let norm = [(b.t, b.l), (b.t, b.r), (b.b, b.l), (b.b, b.r)]
            .iter()
            .map(|&(y, x)| (y as f64 - cv).hypot(x as f64 - ch))
            .fold(0.0f64, f64::max);
        let planes = (0..planes)
            .map(|p| models[if models.len() == 1 { 0 } else { p }])
            .collect();
        Ok(Warp {
            planes,
            cv,
            ch,
            norm,
            inv: if norm > 0.0 { 1.0 / norm } else { 0.0 },
        })
    }

    /// The source (uncorrected) position (row, col) of destination pixel (row, col) in plane
    /// `p`.
    pub fn source(&self, p: usize, row: f64, col: f64) -> (f64, f64) {
        let (dv, dh) = (row - self.cv, col - self.ch);
        let (nv, nh) = (dv * self.inv, dh * self.inv);
        let rr = (nv * nv + nh * nh).min(1.0);
        match self.planes[p] {
            Model::Rectilinear { kr, kt } => {
                let ratio = poly(&kr, rr);
                if kt == [0.0, 0.0] {
                    (self.cv + dv * ratio, self.ch + dh * ratio)
                } else {
                    let tv = kt[0] * (rr + 2.0 * nv * nv) + 2.0 * kt[1] * nh * nv;
                    let th = kt[1] * (rr + 2.0 * nh * nh) + 2.0 * kt[0] * nh * nv;
                    (
                        self.cv + self.norm * (nv * ratio + tv),
                        self.ch + self.norm * (nh * ratio + th),
                    )
                }
            }
            Model::Fisheye { kr } => {
                let ratio = if rr < 1e-12 {
                    1.0
                } else {
                    let r = rr.sqrt();
                    let t = r.atan();
                    t * poly(&kr, t * t) / r
                };
                (self.cv + dv * ratio, self.ch + dh * ratio)
            }
        }
    }
}

/// The SDK's bicubic kernel (A = -0.75).
fn cubic(x: f64) -> f64 {
    const A: f64 = -0.75;
    let x = x.abs();
    if x >= 2.0 {
        0.0
    } else if x >= 1.0 {
        ((A * x - 5.0 * A) * x + 8.0 * A) * x - 4.0 * A
    } else {
        ((A + 2.0) * x - (A + 3.0)) * x * x + 1.0
    }
}

/// The four normalised tap weights and the first tap index of position `s`.
fn taps(s: f64) -> (i64, [f64; 4]) {
    let f = s.floor();
    let i = if f.is_finite() {
        f.clamp(-1e15, 1e15) as i64
    } else {
        0
    };
    let fr = if f.is_finite() { s - f } else { 0.0 };
    let mut w = [0.0; 4];
    for (k, wk) in w.iter_mut().enumerate() {
        *wk = cubic(k as f64 - 1.0 - fr);
    }
    let t: f64 = w.iter().sum();
    if t != 0.0 {
        w.iter_mut().for_each(|v| *v /= t);
    }
    (i - 1, w)
}

/// Warp a stage-3 image (`w x h` pixels of `planes` interleaved samples in [0, 1], pixel
/// (0, 0) at stage position (`bounds.t`, `bounds.l`)): every output pixel is the bicubic
/// resample of `data` at its source position.
pub fn apply(
    warp: &Warp,
    data: &[f32],
    w: usize,
    h: usize,
    planes: usize,
    bounds: Bounds,
) -> Vec<f32> {
    let mut out = vec![0.0f32; data.len()];
    if w == 0 || h == 0 || planes == 0 {
        return out;
    }
    let clampi = |v: i64, n: usize| v.clamp(0, n as i64 - 1) as usize;
    // One set of coefficients for every plane (the usual case): one source position and
    // one set of tap weights per pixel.
    let shared = warp.planes.windows(2).all(|p| p[0] == p[1]);
    out.par_chunks_mut(w * planes)
        .enumerate()
        .for_each(|(y, orow)| {
            let row = (bounds.t + y as i64) as f64;
            let mut cache = None;
            for x in 0..w {
                let col = (bounds.l + x as i64) as f64;
                for p in 0..planes {
                    let ((y0, wy), (x0, wx)) = match cache {
                        Some(t) if shared && p > 0 => t,
                        _ => {
                            let (sv, sh) = warp.source(p, row, col);
                            let t = (taps(sv - bounds.t as f64), taps(sh - bounds.l as f64));
                            cache = Some(t);
                            t
                        }
                    };
                    let mut total = 0.0f64;
                    for (i, wyi) in wy.iter().enumerate() {
                        let yy = clampi(y0 + i as i64, h);
                        let srow = &data[yy * w * planes..];
                        let mut acc = 0.0f64;
                        for (j, wxj) in wx.iter().enumerate() {
                            let xx = clampi(x0 + j as i64, w);
                            acc += wxj * srow[xx * planes + p] as f64;
                        }
                        total += wyi * acc;
                    }
                    orow[x * planes + p] = super::pin(total as f32, 1.0);
                }
                cache = None;
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_warp_keeps_the_image() {
        let (w, h) = (7, 5);
        let data: Vec<f32> = (0..w * h * 3).map(|i| (i % 11) as f32 / 11.0).collect();
        let warp = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, 0.0, 0.0, 0.0],
                kt: [0.0, 0.0],
            }],
            [0.5, 0.5],
            Bounds::of_size(w, h),
            3,
        )
        .unwrap();
        let out = apply(&warp, &data, w, h, 3, Bounds::of_size(w, h));
        for (a, b) in out.iter().zip(&data) {
            assert!((a - b).abs() < 1e-6);
        }
    }

    #[test]
    fn radial_source_positions_follow_the_formula() {
        let b = Bounds::of_size(200, 100);
        let warp = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, 0.1, 0.0, 0.0],
                kt: [0.0, 0.0],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        // centre (50, 100), R = hypot(50, 100)
        let r = 50f64.hypot(100.0);
        let (sv, sh) = warp.source(0, 10.0, 180.0);
        let (nv, nh) = ((10.0 - 50.0) / r, (180.0 - 100.0) / r);
        let ratio = 1.0 + 0.1 * (nv * nv + nh * nh);
        assert!((sv - (50.0 + (10.0 - 50.0) * ratio)).abs() < 1e-9);
        assert!((sh - (100.0 + 80.0 * ratio)).abs() < 1e-9);
        // tangential terms
        let t = Warp::new(
            vec![Model::Rectilinear {
                kr: [1.0, 0.0, 0.0, 0.0],
                kt: [0.01, 0.02],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        let (sv, sh) = t.source(0, 10.0, 180.0);
        let rr = nv * nv + nh * nh;
        let tv = 0.01 * (rr + 2.0 * nv * nv) + 2.0 * 0.02 * nh * nv;
        let th = 0.02 * (rr + 2.0 * nh * nh) + 2.0 * 0.01 * nh * nv;
        assert!((sv - (50.0 + r * (nv + tv))).abs() < 1e-9);
        assert!((sh - (100.0 + r * (nh + th))).abs() < 1e-9);
    }

    #[test]
    fn fisheye_and_bad_inputs() {
        let b = Bounds::of_size(10, 10);
        let f = Warp::new(
            vec![Model::Fisheye {
                kr: [1.0, 0.0, 0.0, 0.0],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        let (sv, _) = f.source(0, 5.0, 5.0);
        assert_eq!(sv, 5.0);
        let (sv, _) = f.source(0, 0.0, 5.0);
        let r = 5.0 / 50f64.sqrt();
        assert!((sv - (5.0 - 5.0 * r.atan() / r)).abs() < 1e-9);
        let two = vec![Model::Fisheye { kr: [1.0; 4] }; 2];
        assert!(Warp::new(two, [0.5, 0.5], b, 3).is_err());
        assert!(Warp::new(vec![Model::Fisheye { kr: [1.0; 4] }], [1.5, 0.5], b, 3).is_err());
        // NaN coefficients: output pinned, no NaN
        let n = Warp::new(
            vec![Model::Rectilinear {
                kr: [f64::NAN; 4],
                kt: [0.0; 2],
            }],
            [0.5, 0.5],
            b,
            1,
        )
        .unwrap();
        let out = apply(&n, &[0.5; 100], 10, 10, 1, b);
        assert!(out.iter().all(|v| v.is_finite()));
        // a 1x1 image
        let out = apply(&f, &[0.25], 1, 1, 1, Bounds::of_size(1, 1));
        assert_eq!(out, vec![0.25]);
    }
}
