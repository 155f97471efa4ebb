//! Malvar, He and Cutler, "High-quality linear interpolation for demosaicing of
//! Bayer-patterned color images", ICASSP 2004: bilinear estimates corrected by the
//! Laplacian of the known channel, as four 5x5 kernels (their Figure 2).

use super::{per_row, Padded, Post, PAD};
use crate::isp::RgbImage;
use crate::raw::Bayer;

pub(super) fn run(p: &Padded, bayer: Bayer, post: &Post) -> RgbImage {
    per_row(p.w, p.h, post, |y, row| {
        rgb_row(&p.d, p.s, p.idx(y + PAD, PAD), y, 0, bayer, row)
    })
}

/// One interleaved RGB row: the pixels at image coordinates (y, x0 + x) for x in
/// `0..row.len() / 3`, from a plane `d` with row stride `s` (at least 2 samples of
/// neighbourhood around them) whose sample of (y, x0) is `d[i0]`. Both the whole-image
/// path and the banded render call this, so they agree bit for bit.
#[inline]
pub(crate) fn rgb_row(
    d: &[f32],
    s: usize,
    i0: usize,
    y: usize,
    x0: usize,
    bayer: Bayer,
    row: &mut [f32],
) {
    for (dx, px) in row.chunks_exact_mut(3).enumerate() {
        let (i, x) = (i0 + dx, x0 + dx);
        let c0 = d[i];
        let h1 = d[i - 1] + d[i + 1];
        let v1 = d[i - s] + d[i + s];
        let h2 = d[i - 2] + d[i + 2];
        let v2 = d[i - 2 * s] + d[i + 2 * s];
        let dg = d[i - s - 1] + d[i - s + 1] + d[i + s - 1] + d[i + s + 1];
        match bayer.color_at(y, x) {
            c @ (0 | 2) => {
                // G at R/B: [0 0 -1 0 0; 0 0 2 0 0; -1 2 4 2 -1; ...] / 8
                let g = (4.0 * c0 + 2.0 * (h1 + v1) - (h2 + v2)) * 0.125;
                // B at R (R at B): [0 0 -3/2 0 0; 0 2 0 2 0; -3/2 0 6 0 -3/2; ...] / 8
                let o = (6.0 * c0 + 2.0 * dg - 1.5 * (h2 + v2)) * 0.125;
                if c == 0 {
                    px.copy_from_slice(&[c0, g, o]);
                } else {
                    px.copy_from_slice(&[o, g, c0]);
                }
            }
            _ => {
                // At G: the colour of the horizontal neighbours from the "row" kernel
                // [0 0 1/2 0 0; 0 -1 0 -1 0; -1 4 5 4 -1; 0 -1 0 -1 0; 0 0 1/2 0 0] / 8,
                // the other from its transpose.
                let hk = (5.0 * c0 + 4.0 * h1 - h2 - dg + 0.5 * v2) * 0.125;
                let vk = (5.0 * c0 + 4.0 * v1 - v2 - dg + 0.5 * h2) * 0.125;
                if bayer.color_at(y, x + 1) == 0 {
                    px.copy_from_slice(&[hk, c0, vk]);
                } else {
                    px.copy_from_slice(&[vk, c0, hk]);
                }
            }
        }
    }
}
