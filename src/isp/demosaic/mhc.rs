//! Malvar, He and Cutler, "High-quality linear interpolation for demosaicing of
//! Bayer-patterned color images", ICASSP 2004: bilinear estimates corrected by the
//! Laplacian of the known channel, as four 5x5 kernels (their Figure 2).

use super::{per_row, Padded, Post, PAD};
use crate::isp::rgb::RgbImage;
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
///
/// The colour of each pixel only alternates along a row, so the row is dispatched once to
/// a loop over pixel pairs specialized for its two kinds ([`pixel`]); the arithmetic of
/// each pixel is exactly that of [`rgb_row_generic`] (tested equal bit for bit).
///
/// Compiled twice, the second time for AVX2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(crate) fn rgb_row(
    d: &[f32],
    s: usize,
    i0: usize,
    y: usize,
    x0: usize,
    bayer: Bayer,
    row: &mut [f32],
) {
    let kind = |x: usize| match bayer.color_at(y, x) {
        0 => RED,
        2 => BLUE,
        _ if bayer.color_at(y, x + 1) == 0 => GREEN_RED_ROW,
        _ => GREEN_BLUE_ROW,
    };
    match (kind(x0), kind(x0 + 1)) {
        (RED, GREEN_RED_ROW) => pairs::<RED, GREEN_RED_ROW>(d, s, i0, row),
        (GREEN_RED_ROW, RED) => pairs::<GREEN_RED_ROW, RED>(d, s, i0, row),
        (BLUE, GREEN_BLUE_ROW) => pairs::<BLUE, GREEN_BLUE_ROW>(d, s, i0, row),
        (GREEN_BLUE_ROW, BLUE) => pairs::<GREEN_BLUE_ROW, BLUE>(d, s, i0, row),
        _ => rgb_row_generic(d, s, i0, y, x0, bayer, row),
    }
}

/// Pixel kinds of [`pixel`].
const RED: u8 = 0;
const BLUE: u8 = 2;
/// Green whose horizontal neighbours are red.
const GREEN_RED_ROW: u8 = 3;
/// Green whose horizontal neighbours are blue.
const GREEN_BLUE_ROW: u8 = 4;

/// A row whose pixels alternate between kinds `A` (first) and `B`.
#[inline(always)]
fn pairs<const A: u8, const B: u8>(d: &[f32], s: usize, i0: usize, row: &mut [f32]) {
    let mut it = row.chunks_exact_mut(6);
    let mut i = i0;
    for p in &mut it {
        p[..3].copy_from_slice(&pixel::<A>(d, s, i));
        p[3..].copy_from_slice(&pixel::<B>(d, s, i + 1));
        i += 2;
    }
    let rest = it.into_remainder();
    if rest.len() == 3 {
        rest.copy_from_slice(&pixel::<A>(d, s, i));
    }
}

/// The MHC estimate of a pixel of kind `K` at plane index `i` (same expressions as
/// [`rgb_row_generic`]).
#[inline(always)]
fn pixel<const K: u8>(d: &[f32], s: usize, i: usize) -> [f32; 3] {
    let c0 = d[i];
    let h1 = d[i - 1] + d[i + 1];
    let v1 = d[i - s] + d[i + s];
    let h2 = d[i - 2] + d[i + 2];
    let v2 = d[i - 2 * s] + d[i + 2 * s];
    let dg = d[i - s - 1] + d[i - s + 1] + d[i + s - 1] + d[i + s + 1];
    if K == RED || K == BLUE {
        let g = (4.0 * c0 + 2.0 * (h1 + v1) - (h2 + v2)) * 0.125;
        let o = (6.0 * c0 + 2.0 * dg - 1.5 * (h2 + v2)) * 0.125;
        if K == RED {
            [c0, g, o]
        } else {
            [o, g, c0]
        }
    } else {
        let hk = (5.0 * c0 + 4.0 * h1 - h2 - dg + 0.5 * v2) * 0.125;
        let vk = (5.0 * c0 + 4.0 * v1 - v2 - dg + 0.5 * h2) * 0.125;
        if K == GREEN_RED_ROW {
            [hk, c0, vk]
        } else {
            [vk, c0, hk]
        }
    }
}

/// [`rgb_row`] pixel by pixel, with the colour looked up for each (the original form;
/// the fallback for rows that do not alternate as a Bayer row does).
fn rgb_row_generic(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specialized_rows_equal_the_generic_form_bit_for_bit() {
        let s = 16;
        let mut st = 0x1234_5678_9abc_def1u64;
        let d: Vec<f32> = (0..s * 7)
            .map(|_| {
                st ^= st << 13;
                st ^= st >> 7;
                st ^= st << 17;
                (st >> 40) as f32 / (1u64 << 24) as f32 * 1.2 - 0.1
            })
            .collect();
        for bayer in Bayer::ALL {
            for y in 0..2 {
                for x0 in 0..2 {
                    for n in 1..=10 {
                        let i0 = 3 * s + 2;
                        let mut a = vec![0.0; 3 * n];
                        let mut b = vec![0.0; 3 * n];
                        rgb_row(&d, s, i0, y, x0, bayer, &mut a);
                        rgb_row_generic(&d, s, i0, y, x0, bayer, &mut b);
                        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&a), bits(&b), "{bayer} y {y} x0 {x0} n {n}");
                    }
                }
            }
        }
    }
}
