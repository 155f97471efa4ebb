//! Menon, Andriani and Calvagno, "Demosaicing with directional filtering and a posteriori
//! decision", IEEE TIP 16(1), 2007 (DDFAPD), with the refining step of their section IV.
//!
//! Follows the structure of the widely used reference implementation in the
//! `colour-demosaicing` Python package (the one the day-to-night authors used): horizontal
//! and vertical green estimates with the [0.5, 0, 0.5] + [-0.25, 0, 0.5, 0, -0.25] filters,
//! the decision from colour-difference gradients summed over a 5x5 causal window, red/blue
//! from colour differences along the chosen direction, then refinement of G, of R/B at
//! green sites and of R/B at blue/red sites with 3-tap means along the decided direction.
//! Each stage is one parallel pass over rows producing a mirror-padded plane.

use super::{interleave, Padded, Post, PAD};
use crate::isp::rgb::RgbImage;
use crate::raw::Bayer;

pub(super) fn run(c: &Padded, bayer: Bayer, post: &Post) -> RgbImage {
    let (w, h, s) = (c.w, c.h, c.s);
    // Colour at padded coordinates: PAD is even, so the phase is unchanged.
    let col = |pr: usize, pc: usize| bayer.color_at(pr, pc);
    // Is the green at padded (pr, pc) in a red row (horizontal neighbours red)?
    let red_row = |pr: usize, pc: usize| bayer.color_at(pr, pc + 1) == 0;
    let cd = &c.d;

    // 1-3. Green and the direction decision.
    let (g, m) = green_and_decision(c, bayer);
    let gd = &g.d;

    // 4. Red and blue at green sites, from colour differences along the row or column of
    //    their own colour.
    let rb_at_green = |target: u8| {
        Padded::build(w, h, |y, out| {
            let pr = y + PAD;
            for (x, o) in out.iter_mut().enumerate() {
                let pc = x + PAD;
                let i = c.idx(pr, pc);
                let cc = col(pr, pc);
                *o = if cc == target {
                    cd[i]
                } else if cc == 1 {
                    let horizontal = red_row(pr, pc) == (target == 0);
                    let k = if horizontal { 1 } else { s };
                    gd[i] + 0.5 * (cd[i - k] + cd[i + k]) - 0.5 * (gd[i - k] + gd[i + k])
                } else {
                    0.0
                };
            }
        })
    };
    let r1 = rb_at_green(0);
    let b1 = rb_at_green(2);

    // 5. Red at blue sites and blue at red sites along the decided direction.
    let rb_at_other = |target: u8, t1: &Padded, o1: &Padded| {
        let other = 2 - target;
        Padded::build(w, h, |y, out| {
            let pr = y + PAD;
            for (x, o) in out.iter_mut().enumerate() {
                let pc = x + PAD;
                let i = c.idx(pr, pc);
                *o = if col(pr, pc) == other {
                    let k = if m.d[i] > 0.5 { 1 } else { s };
                    cd[i] + 0.5 * (t1.d[i - k] + t1.d[i + k]) - 0.5 * (o1.d[i - k] + o1.d[i + k])
                } else {
                    t1.d[i]
                };
            }
        })
    };
    let r2 = rb_at_other(0, &r1, &b1);
    let b2 = rb_at_other(2, &b1, &r1);
    drop((r1, b1));

    // 6. Refinement of green at red/blue sites: G = X - mean3(X - G) along the direction.
    let g2 = Padded::build(w, h, |y, out| {
        let pr = y + PAD;
        for (x, o) in out.iter_mut().enumerate() {
            let pc = x + PAD;
            let i = c.idx(pr, pc);
            let x_plane = match col(pr, pc) {
                0 => &r2.d,
                2 => &b2.d,
                _ => {
                    *o = gd[i];
                    continue;
                }
            };
            let k = if m.d[i] > 0.5 { 1 } else { s };
            let diff = |j: usize| x_plane[j] - gd[j];
            *o = x_plane[i] - (diff(i - k) + diff(i) + diff(i + k)) / 3.0;
        }
    });
    drop(g);
    let g2d = &g2.d;

    // 7. Refinement of red/blue at green sites: X = G + mean2(X - G) along the row or
    //    column of that colour.
    let refine_green_sites = |target: u8, x2: &Padded| {
        Padded::build(w, h, |y, out| {
            let pr = y + PAD;
            for (x, o) in out.iter_mut().enumerate() {
                let pc = x + PAD;
                let i = c.idx(pr, pc);
                *o = if col(pr, pc) == 1 {
                    let horizontal = red_row(pr, pc) == (target == 0);
                    let k = if horizontal { 1 } else { s };
                    let xd = &x2.d;
                    g2d[i] + 0.5 * ((xd[i - k] - g2d[i - k]) + (xd[i + k] - g2d[i + k]))
                } else {
                    x2.d[i]
                };
            }
        })
    };
    let r3 = refine_green_sites(0, &r2);
    let b3 = refine_green_sites(2, &b2);
    drop((r2, b2));

    // 8. Refinement of red at blue sites and blue at red sites through R - B.
    let refine_rb = |target: u8| {
        let other = 2 - target;
        Padded::build(w, h, |y, out| {
            let pr = y + PAD;
            for (x, o) in out.iter_mut().enumerate() {
                let pc = x + PAD;
                let i = c.idx(pr, pc);
                let rb = |j: usize| r3.d[j] - b3.d[j];
                *o = if col(pr, pc) == other {
                    let k = if m.d[i] > 0.5 { 1 } else { s };
                    let mean = (rb(i - k) + rb(i) + rb(i + k)) / 3.0;
                    if target == 0 {
                        b3.d[i] + mean
                    } else {
                        r3.d[i] - mean
                    }
                } else if target == 0 {
                    r3.d[i]
                } else {
                    b3.d[i]
                };
            }
        })
    };
    let r4 = refine_rb(0);
    let b4 = refine_rb(2);
    interleave(&r4, &g2, &b4, post)
}

/// Steps 1-3: the horizontal and vertical green estimates, the decision between them from
/// colour-difference gradients (1 = horizontal) and the green plane it picks: (green,
/// decision).
fn green_and_decision(c: &Padded, bayer: Bayer) -> (Padded, Padded) {
    let (w, h, s) = (c.w, c.h, c.s);
    let col = |pr: usize, pc: usize| bayer.color_at(pr, pc);
    let cd = &c.d;

    // 1. Directional green estimates.
    let gh = Padded::build(w, h, |y, out| {
        let pr = y + PAD;
        for (x, o) in out.iter_mut().enumerate() {
            let i = c.idx(pr, x + PAD);
            *o = if col(pr, x + PAD) == 1 {
                cd[i]
            } else {
                0.5 * (cd[i - 1] + cd[i + 1]) + 0.5 * cd[i] - 0.25 * (cd[i - 2] + cd[i + 2])
            };
        }
    });
    let gv = Padded::build(w, h, |y, out| {
        let pr = y + PAD;
        for (x, o) in out.iter_mut().enumerate() {
            let i = c.idx(pr, x + PAD);
            *o = if col(pr, x + PAD) == 1 {
                cd[i]
            } else {
                0.5 * (cd[i - s] + cd[i + s]) + 0.5 * cd[i] - 0.25 * (cd[i - 2 * s] + cd[i + 2 * s])
            };
        }
    });

    // 2. Colour-difference gradients D_H = |C_H(j) - C_H(j+2)|, D_V likewise (zero border:
    //    the classifier's convolution uses constant padding).
    let dh = Padded::build_unmirrored(w, h, |y, out| {
        let pr = y + PAD;
        for (x, o) in out.iter_mut().enumerate() {
            let pc = x + PAD;
            if col(pr, pc) != 1 {
                let i = c.idx(pr, pc);
                *o = ((cd[i] - gh.d[i]) - (cd[i + 2] - gh.d[i + 2])).abs();
            }
        }
    });
    let dv = Padded::build_unmirrored(w, h, |y, out| {
        let pr = y + PAD;
        for (x, o) in out.iter_mut().enumerate() {
            let pc = x + PAD;
            if col(pr, pc) != 1 {
                let i = c.idx(pr, pc);
                *o = ((cd[i] - gv.d[i]) - (cd[i + 2 * s] - gv.d[i + 2 * s])).abs();
            }
        }
    });

    // 3. Decision (1 = horizontal) and green.
    let m = Padded::build_unmirrored(w, h, |y, out| {
        let pr = y + PAD;
        for (x, o) in out.iter_mut().enumerate() {
            let i = c.idx(pr, x + PAD);
            let a = &dh.d;
            let d_h = 3.0 * (a[i] + a[i - 2])
                + a[i + 2 * s]
                + a[i + 2 * s - 2]
                + a[i - 2 * s]
                + a[i - 2 * s - 2]
                + a[i + s - 1]
                + a[i - s - 1];
            let b = &dv.d;
            let d_v = 3.0 * (b[i] + b[i - 2 * s])
                + b[i + 2]
                + b[i - 2 * s + 2]
                + b[i - 2]
                + b[i - 2 * s - 2]
                + b[i - s + 1]
                + b[i - s - 1];
            *o = if d_v >= d_h { 1.0 } else { 0.0 };
        }
    });
    drop((dh, dv));
    let g = Padded::build(w, h, |y, out| {
        let o0 = c.idx(y + PAD, PAD);
        for (x, o) in out.iter_mut().enumerate() {
            let i = o0 + x;
            *o = if m.d[i] > 0.5 { gh.d[i] } else { gv.d[i] };
        }
    });
    drop((gh, gv));
    (g, m)
}
