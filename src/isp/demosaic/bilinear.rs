//! Bilinear demosaicing: each missing sample is the mean of its nearest same-colour
//! neighbours (2 or 4).

use super::{per_row, Padded, Post, PAD};
use crate::isp::rgb::RgbImage;
use crate::raw::Bayer;

pub(super) fn run(p: &Padded, bayer: Bayer, post: &Post) -> RgbImage {
    per_row(p.w, p.h, post, |y, row| {
        rgb_row(&p.d, p.s, p.idx(y + PAD, PAD), y, 0, bayer, row)
    })
}

/// One interleaved RGB row, as [`super::mhc::rgb_row`] (1 sample of neighbourhood needed).
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
        let v = d[i];
        let hz = 0.5 * (d[i - 1] + d[i + 1]);
        let vt = 0.5 * (d[i - s] + d[i + s]);
        let cross = 0.5 * (hz + vt);
        let diag = 0.25 * (d[i - s - 1] + d[i - s + 1] + d[i + s - 1] + d[i + s + 1]);
        match bayer.color_at(y, x) {
            0 => px.copy_from_slice(&[v, cross, diag]),
            2 => px.copy_from_slice(&[diag, cross, v]),
            _ => {
                if bayer.color_at(y, x + 1) == 0 {
                    px.copy_from_slice(&[hz, v, vt]);
                } else {
                    px.copy_from_slice(&[vt, v, hz]);
                }
            }
        }
    }
}
