//! Menon, Andriani and Calvagno (2007) demosaicing as the `colour-demosaicing` package
//! computes it, the release's demosaic: float64 planes over the whole image, NumPy/SciPy
//! border rules (1-D filters mirror about the edge sample, the direction classifier pads
//! with zeros), each filter summed in SciPy's order so that the planes are those of the
//! package to the last bit or nearly. The project's own [`crate::isp::demosaic`] Menon works
//! in float32 on its own borders; this one is only the release's.
//!
//! Stages (one plane each, as the package's `np.where` steps): directional greens, colour
//! differences and their gradients, the decision (horizontal where the vertical gradient
//! sum is not smaller), red and blue at green sites then at blue and red sites, then the
//! refining step (green, red/blue at green sites, red/blue at blue/red sites).

use rayon::prelude::*;

/// Rows of the image a band's planes hold: `rows` (global row numbers) of an image
/// `full_h` rows high and `w` wide.
#[derive(Clone, Copy)]
struct Geo {
    w: usize,
    full_h: usize,
    y0: usize,
    h: usize,
}

/// A float64 plane over the rows of a [`Geo`], row-major, indexed by global row numbers.
/// A row outside the held rows reads the nearest held row: the values that depend on it
/// are wrong, but they lie within [`HALO`] rows of a band's edge and are never output.
struct Plane {
    w: usize,
    full_h: usize,
    y0: usize,
    h: usize,
    d: Vec<f64>,
}

/// Index of `i` mirrored about the edge samples into `0..n` (`d c b | a b c d | c b a`).
fn mirror(i: isize, n: usize) -> usize {
    let n = n as isize;
    if n == 1 {
        return 0;
    }
    let period = 2 * (n - 1);
    let m = i.rem_euclid(period);
    (if m < n { m } else { period - m }) as usize
}

impl Plane {
    fn build(g: Geo, f: impl Fn(usize, usize) -> f64 + Sync) -> Plane {
        let mut d = vec![0.0; g.w * g.h];
        d.par_chunks_mut(g.w).enumerate().for_each(|(i, row)| {
            let r = g.y0 + i;
            for (c, o) in row.iter_mut().enumerate() {
                *o = f(r, c);
            }
        });
        Plane {
            w: g.w,
            full_h: g.full_h,
            y0: g.y0,
            h: g.h,
            d,
        }
    }
    fn at(&self, r: usize, c: usize) -> f64 {
        let r = r.clamp(self.y0, self.y0 + self.h - 1) - self.y0;
        self.d[r * self.w + c]
    }
    /// Sample at (r, c + dc), mirrored.
    fn hx(&self, r: usize, c: usize, dc: isize) -> f64 {
        self.at(r, mirror(c as isize + dc, self.w))
    }
    /// Sample at (r + dr, c), mirrored about the image's first and last rows.
    fn vx(&self, r: usize, c: usize, dr: isize) -> f64 {
        self.at(mirror(r as isize + dr, self.full_h), c)
    }
    /// Sample at (r + dr, c + dc), zero outside the image.
    fn zero_pad(&self, r: usize, c: usize, dr: isize, dc: isize) -> f64 {
        let (y, x) = (r as isize + dr, c as isize + dc);
        if y < 0 || x < 0 || y >= self.full_h as isize || x >= self.w as isize {
            0.0
        } else {
            self.at(y as usize, x as usize)
        }
    }
}

/// A symmetric 1-D filter along a row (`vertical` false) or column, SciPy's sum order: the
/// centre tap, then the pairs from the outermost in. `taps` = [centre, 1 off, 2 off, ...].
fn filt(p: &Plane, r: usize, c: usize, taps: &[f64], vertical: bool) -> f64 {
    let get = |k: isize| {
        if vertical {
            p.vx(r, c, k)
        } else {
            p.hx(r, c, k)
        }
    };
    let mut s = get(0) * taps[0];
    for k in (1..taps.len()).rev() {
        let k = k as isize;
        s += (get(-k) + get(k)) * taps[k as usize];
    }
    s
}

const H0: [f64; 3] = [0.0, 0.5, 0.0];
const H1: [f64; 3] = [0.5, 0.0, -0.25];
const KB: [f64; 2] = [0.0, 0.5];
const THIRD: f64 = 1.0 / 3.0;
const FIR: [f64; 2] = [THIRD, THIRD];

/// Rows of context a band takes on each side so that its own rows come out as in the whole
/// image. The longest chain of vertical reaches is 12 rows: the vertical green estimate (2),
/// its gradient (2 more), the classifier's window (2), the decision's use by the
/// colour-difference steps (3) and the refining step's means (3).
pub const HALO: usize = 16;

/// Demosaic `codes` (w x h, CFA colours `cfa` row-major from the top-left) into interleaved
/// RGB float64, as `demosaicing_CFA_Bayer_Menon2007(codes, pattern)` with its refining step.
pub fn demosaic(codes: &[u16], w: usize, h: usize, cfa: [u8; 4]) -> Vec<f64> {
    demosaic_rows(codes, w, h, cfa, 0..h)
}

/// The rows `rows` of [`demosaic`]`(codes, w, h, cfa)`, the same values, computed from those
/// rows and [`HALO`] rows on each side only: `3 * w * rows.len()` samples.
pub fn demosaic_rows(
    codes: &[u16],
    w: usize,
    h: usize,
    cfa: [u8; 4],
    rows: std::ops::Range<usize>,
) -> Vec<f64> {
    let y0 = rows.start.saturating_sub(HALO);
    let geo = Geo {
        w,
        full_h: h,
        y0,
        h: (rows.end + HALO).min(h) - y0,
    };
    let col = move |r: usize, c: usize| cfa[((r & 1) << 1) | (c & 1)];
    let row_has = move |r: usize, k: u8| cfa[(r & 1) << 1] == k || cfa[((r & 1) << 1) | 1] == k;
    let col_has = move |c: usize, k: u8| cfa[c & 1] == k || cfa[2 | (c & 1)] == k;
    let x = Plane::build(geo, |r, c| f64::from(codes[r * w + c]));
    let (g, m) = green_and_decision(&x, geo, col);
    let own = |k: u8| Plane::build(geo, |r, c| if col(r, c) == k { x.at(r, c) } else { 0.0 });
    let (r0, b0) = (own(0), own(2));
    // X + filt(P) - filt(Q) along a row or column, the package's colour-difference step.
    let step = |base: &Plane, p: &Plane, q: &Plane, r: usize, c: usize, v: bool| {
        base.at(r, c) + filt(p, r, c, &KB, v) - filt(q, r, c, &KB, v)
    };
    let green_in = |r: usize, c: usize, k: u8| col(r, c) == 1 && row_has(r, k);
    let pick = |cond: bool, a: f64, b: f64| if cond { a } else { b };
    let r1 = Plane::build(geo, |r, c| {
        pick(
            green_in(r, c, 0),
            step(&g, &r0, &g, r, c, false),
            r0.at(r, c),
        )
    });
    let r2 = Plane::build(geo, |r, c| {
        pick(
            green_in(r, c, 2),
            step(&g, &r1, &g, r, c, true),
            r1.at(r, c),
        )
    });
    let b1 = Plane::build(geo, |r, c| {
        pick(
            green_in(r, c, 2),
            step(&g, &b0, &g, r, c, false),
            b0.at(r, c),
        )
    });
    let b2 = Plane::build(geo, |r, c| {
        pick(
            green_in(r, c, 0),
            step(&g, &b1, &g, r, c, true),
            b1.at(r, c),
        )
    });
    let horizontal = |r: usize, c: usize| m.at(r, c) == 1.0;
    let r3 = Plane::build(geo, |r, c| {
        let here = row_has(r, 2) && col(r, c) == 2;
        pick(
            here,
            step(&b2, &r2, &b2, r, c, !horizontal(r, c)),
            r2.at(r, c),
        )
    });
    let b3 = Plane::build(geo, |r, c| {
        let here = row_has(r, 0) && col(r, c) == 0;
        pick(
            here,
            step(&r3, &b2, &r3, r, c, !horizontal(r, c)),
            b2.at(r, c),
        )
    });
    drop((r0, b0, r1, r2, b1, b2));
    refine(&r3, &g, &b3, &m, (col, row_has, col_has), rows)
}

/// Steps 1-3: the horizontal and vertical green estimates, the colour-difference gradients
/// and the decision (1 = horizontal): (green, decision).
fn green_and_decision(
    x: &Plane,
    geo: Geo,
    col: impl Fn(usize, usize) -> u8 + Sync + Copy,
) -> (Plane, Plane) {
    let green_est = |v: bool| {
        Plane::build(geo, |r, c| {
            if col(r, c) == 1 {
                x.at(r, c)
            } else {
                filt(x, r, c, &H0, v) + filt(x, r, c, &H1, v)
            }
        })
    };
    let (gh, gv) = (green_est(false), green_est(true));
    let diff = |g: &Plane| {
        Plane::build(geo, |r, c| {
            if col(r, c) == 1 {
                0.0
            } else {
                x.at(r, c) - g.at(r, c)
            }
        })
    };
    let (ch, cv) = (diff(&gh), diff(&gv));
    let dh = Plane::build(geo, |r, c| (ch.at(r, c) - ch.hx(r, c, 2)).abs());
    let dv = Plane::build(geo, |r, c| (cv.at(r, c) - cv.vx(r, c, 2)).abs());
    drop((ch, cv));
    // The classifier's 5x5 kernel (and its transpose): (row, column) offsets and weights.
    const TAPS: [(isize, isize, f64); 8] = [
        (2, 0, 1.0),
        (2, -2, 1.0),
        (1, -1, 1.0),
        (0, 0, 3.0),
        (0, -2, 3.0),
        (-1, -1, 1.0),
        (-2, 0, 1.0),
        (-2, -2, 1.0),
    ];
    let m = Plane::build(geo, |r, c| {
        let sum_h: f64 = TAPS
            .iter()
            .map(|&(a, b, k)| k * dh.zero_pad(r, c, a, b))
            .sum();
        let sum_v: f64 = TAPS
            .iter()
            .map(|&(a, b, k)| k * dv.zero_pad(r, c, b, a))
            .sum();
        if sum_v >= sum_h {
            1.0
        } else {
            0.0
        }
    });
    let g = Plane::build(geo, |r, c| {
        if m.at(r, c) == 1.0 {
            gh.at(r, c)
        } else {
            gv.at(r, c)
        }
    });
    (g, m)
}

/// The colour masks of a CFA: a site's colour, whether a row holds a colour, whether a
/// column does.
type Masks<A, B, C> = (A, B, C);

/// The refining step: green at red/blue sites, red/blue at green sites, red at blue and blue
/// at red sites, each from colour differences averaged along the decided direction (or the
/// colour's row/column); interleaved RGB.
fn refine<A, B, C>(
    r3: &Plane,
    g: &Plane,
    b3: &Plane,
    m: &Plane,
    masks: Masks<A, B, C>,
    rows: std::ops::Range<usize>,
) -> Vec<f64>
where
    A: Fn(usize, usize) -> u8 + Sync + Copy,
    B: Fn(usize, u8) -> bool + Sync + Copy,
    C: Fn(usize, u8) -> bool + Sync + Copy,
{
    let (col, row_has, col_has) = masks;
    let geo = Geo {
        w: g.w,
        full_h: g.full_h,
        y0: g.y0,
        h: g.h,
    };
    let w = g.w;
    let horizontal = |r: usize, c: usize| m.at(r, c) == 1.0;
    let sub = |a: &Plane, b: &Plane| Plane::build(geo, |r, c| a.at(r, c) - b.at(r, c));
    // The decided direction's 3-tap mean at sites of colour k, else 0.
    let mean_at = |p: &Plane, k: u8| {
        Plane::build(geo, |r, c| {
            if col(r, c) == k {
                filt(p, r, c, &FIR, !horizontal(r, c))
            } else {
                0.0
            }
        })
    };
    let (rg, bg) = (sub(r3, g), sub(b3, g));
    let (bgm, rgm) = (mean_at(&bg, 2), mean_at(&rg, 0));
    drop((rg, bg));
    let g2 = Plane::build(geo, |r, c| match col(r, c) {
        0 => r3.at(r, c) - rgm.at(r, c),
        2 => b3.at(r, c) - bgm.at(r, c),
        _ => g.at(r, c),
    });
    let (rg2, bg2) = (sub(r3, &g2), sub(b3, &g2));
    let green = |r: usize, c: usize| col(r, c) == 1;
    // Red at greens of blue rows (vertical), then of blue columns (horizontal).
    let rgm2 = Plane::build(geo, |r, c| {
        if green(r, c) && row_has(r, 2) {
            filt(&rg2, r, c, &KB, true)
        } else {
            rgm.at(r, c)
        }
    });
    let r4 = Plane::build(geo, |r, c| {
        if green(r, c) && row_has(r, 2) {
            g2.at(r, c) + rgm2.at(r, c)
        } else {
            r3.at(r, c)
        }
    });
    let r5 = Plane::build(geo, |r, c| {
        if green(r, c) && col_has(c, 2) {
            g2.at(r, c) + filt(&rg2, r, c, &KB, false)
        } else {
            r4.at(r, c)
        }
    });
    // Blue at greens of red rows (vertical), then of red columns (horizontal).
    let bgm2 = Plane::build(geo, |r, c| {
        if green(r, c) && row_has(r, 0) {
            filt(&bg2, r, c, &KB, true)
        } else {
            bgm.at(r, c)
        }
    });
    let b4 = Plane::build(geo, |r, c| {
        if green(r, c) && row_has(r, 0) {
            g2.at(r, c) + bgm2.at(r, c)
        } else {
            b3.at(r, c)
        }
    });
    let b5 = Plane::build(geo, |r, c| {
        if green(r, c) && col_has(c, 0) {
            g2.at(r, c) + filt(&bg2, r, c, &KB, false)
        } else {
            b4.at(r, c)
        }
    });
    drop((rgm2, bgm2, r4, b4, rg2, bg2));
    // Red at blue sites and blue at red sites through R - B.
    let rb = sub(&r5, &b5);
    let (rbm_b, rbm_r) = (mean_at(&rb, 2), mean_at(&rb, 0));
    let mut out = vec![0.0; 3 * w * rows.len()];
    out.par_chunks_mut(3 * w).enumerate().for_each(|(i, row)| {
        let r = rows.start + i;
        for (c, px) in row.chunks_exact_mut(3).enumerate() {
            let red = if col(r, c) == 2 {
                b5.at(r, c) + rbm_b.at(r, c)
            } else {
                r5.at(r, c)
            };
            let blue = if col(r, c) == 0 {
                red - rbm_r.at(r, c)
            } else {
                b5.at(r, c)
            };
            px.copy_from_slice(&[red, g2.at(r, c), blue]);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_reflects_about_the_edge_samples() {
        let m: Vec<usize> = (-3..8).map(|i| mirror(i, 5)).collect();
        assert_eq!(m, vec![3, 2, 1, 0, 1, 2, 3, 4, 3, 2, 1]);
        assert_eq!(mirror(-4, 1), 0);
        assert_eq!(mirror(9, 2), 1);
    }

    /// A mosaic of one colour comes back as that colour everywhere, borders included, for
    /// each Bayer phase (the filters' taps sum to 1 and the mirror keeps the CFA phase).
    #[test]
    fn one_colour_is_kept_exactly() {
        let rgb = [5000u16, 9000, 2000];
        for cfa in [[0, 1, 1, 2], [1, 0, 2, 1], [1, 2, 0, 1], [2, 1, 1, 0]] {
            let (w, h) = (9, 6);
            let codes: Vec<u16> = (0..w * h)
                .map(|i| rgb[cfa[(((i / w) & 1) << 1) | ((i % w) & 1)] as usize])
                .collect();
            let out = demosaic(&codes, w, h, cfa);
            for px in out.chunks_exact(3) {
                assert_eq!(px, [5000.0, 9000.0, 2000.0], "{cfa:?}");
            }
        }
    }

    /// Any band of rows, with its halo, is those rows of the whole image's demosaic to the
    /// bit, for every Bayer phase, at the top and bottom edges and in between (rough
    /// content, so that both directions are decided somewhere).
    #[test]
    fn bands_equal_the_whole_image_bit_for_bit() {
        let (w, h) = (13, 2 * HALO + 23);
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let codes: Vec<u16> = (0..w * h)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s % 16384) as u16
            })
            .collect();
        for cfa in [[0, 1, 1, 2], [1, 0, 2, 1], [1, 2, 0, 1], [2, 1, 1, 0]] {
            let whole = demosaic(&codes, w, h, cfa);
            for band in [1, 2, 3, 7, 16, 40, h] {
                let mut got = Vec::new();
                for a in (0..h).step_by(band) {
                    got.extend(demosaic_rows(&codes, w, h, cfa, a..(a + band).min(h)));
                }
                let same = got
                    .iter()
                    .zip(&whole)
                    .all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same && got.len() == whole.len(), "{cfa:?} band {band}");
            }
        }
    }

    /// The sites' own samples are kept where the refining step does not touch them (green
    /// at green sites), and an edge picks the direction along it.
    #[test]
    fn greens_kept_and_edges_followed() {
        let (w, h) = (8, 8);
        // Vertical stripes: columns 0-3 dark, 4-7 bright.
        let codes: Vec<u16> = (0..w * h)
            .map(|i| if i % w < 4 { 1000 } else { 12000 })
            .collect();
        let out = demosaic(&codes, w, h, [0, 1, 1, 2]);
        for r in 0..h {
            for c in 0..w {
                if (r + c) % 2 == 1 {
                    assert_eq!(out[3 * (r * w + c) + 1], f64::from(codes[r * w + c]));
                }
            }
        }
        // Away from the edge the flat areas stay flat.
        assert_eq!(out[3 * (3 * w) + 1], 1000.0);
        assert_eq!(out[3 * (3 * w + 7)], 12000.0);
    }
}
