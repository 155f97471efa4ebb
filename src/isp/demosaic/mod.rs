//! Bayer demosaicing of a normalized (and usually white-balanced) CFA plane.
//!
//! Methods: [`Demosaic::Bilinear`], [`Demosaic::Mhc`] (Malvar, He and Cutler 2004) and
//! [`Demosaic::Menon`] (Menon, Andriani and Calvagno 2007, DDFAPD with the refining step,
//! the authors' choice). Borders are handled by mirror reflection without repeating the edge
//! sample (`d c b | a b c d | c b a`), which keeps the CFA phase in the reflected border.
//! Work is split over rows with rayon; every output sample depends only on the input, so
//! results are identical whatever the thread count.

mod bilinear;
mod menon;
mod mhc;

use super::rgb::RgbImage;
use crate::error::{Error, Result};
use crate::raw::Bayer;
use rayon::prelude::*;

/// Demosaicing method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Demosaic {
    /// Bilinear interpolation of each colour plane (fast, soft, zipper artefacts).
    Bilinear,
    /// Malvar-He-Cutler 2004 gradient-corrected linear interpolation (5x5 kernels).
    #[default]
    Mhc,
    /// Menon et al. 2007 directional filtering with a posteriori decision and refinement.
    Menon,
}

impl Demosaic {
    /// All methods.
    pub const ALL: [Demosaic; 3] = [Demosaic::Bilinear, Demosaic::Mhc, Demosaic::Menon];
}

crate::choices! {
    Demosaic, ignore_case: true,
    unknown: |s| Error::invalid(format!(
        "unknown demosaic method {s:?} ({})",
        crate::choice::listed::<Demosaic>(", ", ", ")
    )),
    Bilinear => "bilinear": "Bilinear interpolation of each colour plane (fast, soft)",
    Mhc => "mhc" | "malvar": "Malvar-He-Cutler 2004 gradient-corrected interpolation",
    Menon => "menon" | "ddfapd": "Menon et al. 2007 directional filtering (DDFAPD)",
}

/// Demosaic a `width x height` CFA plane (row-major, Bayer pattern `bayer` at (0, 0)) into
/// an RGB image. Values are not clipped.
pub fn demosaic(
    plane: &[f32],
    width: usize,
    height: usize,
    bayer: Bayer,
    method: Demosaic,
) -> Result<RgbImage> {
    let n = width
        .checked_mul(height)
        .ok_or_else(|| Error::limits("CFA dimensions overflow"))?;
    if width == 0 || height == 0 || plane.len() != n {
        return Err(Error::invalid(format!(
            "CFA plane holds {} samples, expected {}x{}",
            plane.len(),
            width,
            height
        )));
    }
    Ok(demosaic_rows(
        width,
        height,
        bayer,
        method,
        |r, out| out.copy_from_slice(&plane[r * width..(r + 1) * width]),
        &|_| {},
    ))
}

/// Demosaic a CFA plane produced row by row by `fill(row, out)` (rows are filled in
/// parallel): lets the caller fuse normalization and white balance into the copy that the
/// demosaicer needs anyway. `post` is applied to every finished interleaved RGB row while
/// it is still in cache (e.g. the colour matrix). `width` and `height` must be non-zero.
pub fn demosaic_rows<F>(
    width: usize,
    height: usize,
    bayer: Bayer,
    method: Demosaic,
    fill: F,
    post: &Post,
) -> RgbImage
where
    F: Fn(usize, &mut [f32]) + Sync + Send,
{
    let cfa = Padded::build(width, height, fill);
    match method {
        Demosaic::Bilinear => bilinear::run(&cfa, bayer, post),
        Demosaic::Mhc => mhc::run(&cfa, bayer, post),
        Demosaic::Menon => menon::run(&cfa, bayer, post),
    }
}

/// A single-pass row kernel (see `mhc::rgb_row`): `(plane, stride, index of (y, x0), y,
/// x0, bayer, out_row)`.
pub(crate) type RowKernel = fn(&[f32], usize, usize, usize, usize, Bayer, &mut [f32]);

/// The row kernel of `method` if it is a single-pass method whose neighbourhood fits in
/// [`PAD`] samples (bilinear, MHC), so that it can run on bands of the image; `None` for
/// Menon (several whole-image passes).
pub(crate) fn row_kernel(method: Demosaic) -> Option<RowKernel> {
    match method {
        Demosaic::Bilinear => Some(bilinear::rgb_row),
        Demosaic::Mhc => Some(mhc::rgb_row),
        Demosaic::Menon => None,
    }
}

/// The Malvar-He-Cutler row kernel (keeps every measured sample: a site's own colour is
/// its sample), for callers that demosaic rectangles ([`demosaic_rect`]).
pub(crate) fn mhc_row_kernel() -> RowKernel {
    mhc::rgb_row
}

/// A `width x height` CFA of pattern `bayer`, demosaiced row by row with `kernel`
/// ([`demosaic_rect`]).
#[derive(Clone, Copy)]
pub(crate) struct RowDemosaic {
    /// Image width and height.
    pub(crate) width: usize,
    pub(crate) height: usize,
    /// The CFA pattern.
    pub(crate) bayer: Bayer,
    /// The row demosaicer.
    pub(crate) kernel: RowKernel,
}

/// Demosaic the rectangle `rows x cols` (image coordinates, non-empty, inside the image)
/// of the CFA `cfa`. `fill(r, cs, out)` must set `out[k]` to
/// the CFA sample at (r, cs[k]). The rectangle is read with a [`PAD`]-wide neighbourhood
/// taken from the image, mirrored at the image edges exactly like [`Padded::mirror`]
/// (sample (r, c) of the padded plane = sample (mirror(r), mirror(c))), so every output
/// pixel equals the whole-image result bit for bit. `emit(i, rgb)` gets row `rows.start +
/// i` (pixels of `cols`), after `post`, in increasing order.
pub(crate) fn demosaic_rect<F, E>(
    cfa: RowDemosaic,
    rows: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
    mut fill: F,
    post: &Post,
    mut emit: E,
) where
    F: FnMut(usize, &[usize], &mut [f32]),
    E: FnMut(usize, &mut [f32]),
{
    let RowDemosaic {
        width,
        height,
        bayer,
        kernel,
    } = cfa;
    let (rh, rw) = (rows.len(), cols.len());
    let s = rw + 2 * PAD;
    let cs: Vec<usize> = (0..s)
        .map(|k| mirror(cols.start as isize + k as isize - PAD as isize, width))
        .collect();
    let mut plane = vec![0.0f32; s * (rh + 2 * PAD)];
    for (k, prow) in plane.chunks_exact_mut(s).enumerate() {
        let r = mirror(rows.start as isize + k as isize - PAD as isize, height);
        fill(r, &cs, prow);
    }
    let mut rgb = vec![0.0f32; 3 * rw];
    for i in 0..rh {
        kernel(
            &plane,
            s,
            (i + PAD) * s + PAD,
            rows.start + i,
            cols.start,
            bayer,
            &mut rgb,
        );
        post(&mut rgb);
        emit(i, &mut rgb);
    }
}

/// Border width of [`Padded`] planes (even, so the CFA phase is the same in padded and
/// unpadded coordinates).
pub(crate) const PAD: usize = 2;

/// A plane with a `PAD`-wide mirrored (or zero) border, for branch-free neighbourhoods.
#[derive(Debug, Clone)]
pub(crate) struct Padded {
    pub w: usize,
    pub h: usize,
    /// Row stride (`w + 2 * PAD`).
    pub s: usize,
    pub d: Vec<f32>,
}

/// Reflect101 index of `i` (may be negative or >= n) into 0..n.
#[inline]
fn mirror(i: isize, n: usize) -> usize {
    let n = n as isize;
    let j = if i < 0 {
        -i
    } else if i >= n {
        2 * n - 2 - i
    } else {
        i
    };
    j.clamp(0, n - 1) as usize
}

impl Padded {
    pub fn zeros(w: usize, h: usize) -> Padded {
        let s = w + 2 * PAD;
        Padded {
            w,
            h,
            s,
            d: vec![0.0; s * (h + 2 * PAD)],
        }
    }

    /// Compute the interior row by row in parallel (`f(row, out_row)`), then mirror the border.
    pub fn build<F>(w: usize, h: usize, f: F) -> Padded
    where
        F: Fn(usize, &mut [f32]) + Sync + Send,
    {
        let mut p = Padded::build_unmirrored(w, h, f);
        p.mirror();
        p
    }

    /// Like [`Padded::build`] but leave the border at zero.
    pub fn build_unmirrored<F>(w: usize, h: usize, f: F) -> Padded
    where
        F: Fn(usize, &mut [f32]) + Sync + Send,
    {
        let mut p = Padded::zeros(w, h);
        let s = p.s;
        p.d.par_chunks_mut(s).enumerate().for_each(|(pr, row)| {
            if pr >= PAD && pr < h + PAD {
                f(pr - PAD, &mut row[PAD..PAD + w]);
            }
        });
        p
    }

    /// Index of padded (pr, pc).
    #[inline(always)]
    pub fn idx(&self, pr: usize, pc: usize) -> usize {
        pr * self.s + pc
    }

    /// Fill the border by reflection of the interior.
    pub fn mirror(&mut self) {
        let (w, h, s) = (self.w, self.h, self.s);
        for pr in PAD..h + PAD {
            for k in 0..PAD {
                let l = mirror(k as isize - PAD as isize, w) + PAD;
                self.d[pr * s + k] = self.d[pr * s + l];
                let rc = w + PAD + k;
                let l = mirror((w + k) as isize, w) + PAD;
                self.d[pr * s + rc] = self.d[pr * s + l];
            }
        }
        for k in 0..PAD {
            let src = mirror(k as isize - PAD as isize, h) + PAD;
            self.d.copy_within(src * s..(src + 1) * s, k * s);
            let dst = h + PAD + k;
            let src = mirror((h + k) as isize, h) + PAD;
            self.d.copy_within(src * s..(src + 1) * s, dst * s);
        }
    }
}

/// A per-row transform of finished interleaved RGB rows.
pub type Post = dyn Fn(&mut [f32]) + Sync;

/// Interleave three padded planes into an RGB image.
pub(crate) fn interleave(r: &Padded, g: &Padded, b: &Padded, post: &Post) -> RgbImage {
    let (w, h) = (r.w, r.h);
    let mut out = RgbImage::new(w, h);
    out.data
        .par_chunks_mut(3 * w)
        .enumerate()
        .for_each(|(y, row)| {
            let o = r.idx(y + PAD, PAD);
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                px[0] = r.d[o + x];
                px[1] = g.d[o + x];
                px[2] = b.d[o + x];
            }
            post(row);
        });
    out
}

/// Per-row output driver for single-pass methods: `f(row, out_rgb_row)`.
pub(crate) fn per_row<F>(w: usize, h: usize, post: &Post, f: F) -> RgbImage
where
    F: Fn(usize, &mut [f32]) + Sync + Send,
{
    let mut out = RgbImage::new(w, h);
    out.data
        .par_chunks_mut(3 * w)
        .enumerate()
        .for_each(|(y, row)| {
            f(y, row);
            post(row);
        });
    out
}

/// Mosaic an RGB image with `bayer` (keep one sample per pixel): for tests and accuracy
/// measurements.
pub fn mosaic(img: &RgbImage, bayer: Bayer) -> Vec<f32> {
    let w = img.width;
    let mut out = vec![0.0; w * img.height];
    for (i, v) in out.iter_mut().enumerate() {
        let (y, x) = (i / w, i % w);
        *v = img.data[3 * i + bayer.color_at(y, x) as usize];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn smooth_image(w: usize, h: usize) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        for y in 0..h {
            for x in 0..w {
                // textured, with correlated channels as in natural images
                let (fx, fy) = (x as f32, y as f32);
                let t = 0.5 + 0.2 * (fx * 0.9).sin() * (fy * 0.35).cos() + 0.1 * (fy * 0.8).sin();
                let i = 3 * (y * w + x);
                img.data[i] = 0.8 * t + 0.1;
                img.data[i + 1] = t;
                img.data[i + 2] = 0.6 * t + 0.05 * (fx / w as f32);
            }
        }
        img
    }

    #[test]
    fn constant_image_is_reproduced_exactly_by_every_method_and_phase() {
        for bayer in Bayer::ALL {
            let mut img = RgbImage::new(9, 7);
            for px in img.data.chunks_exact_mut(3) {
                px.copy_from_slice(&[0.25, 0.5, 0.75]);
            }
            let m = mosaic(&img, bayer);
            for method in Demosaic::ALL {
                let out = demosaic(&m, 9, 7, bayer, method).unwrap();
                for (a, b) in out.data.iter().zip(&img.data) {
                    assert!((a - b).abs() < 1e-5, "{method} {bayer}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn smooth_image_is_reproduced_closely_and_methods_rank() {
        let img = smooth_image(64, 48);
        for bayer in Bayer::ALL {
            let m = mosaic(&img, bayer);
            let mut errs = vec![];
            for method in Demosaic::ALL {
                let out = demosaic(&m, 64, 48, bayer, method).unwrap();
                // interior only: borders are extrapolated
                let mut se = 0.0f64;
                let mut n = 0;
                for y in 4..44 {
                    for x in 4..60 {
                        for c in 0..3 {
                            let i = 3 * (y * 64 + x) + c;
                            se += ((out.data[i] - img.data[i]) as f64).powi(2);
                            n += 1;
                        }
                    }
                }
                errs.push((se / n as f64).sqrt());
            }
            assert!(errs.iter().all(|&e| e < 0.05), "{bayer}: {errs:?}");
            assert!(
                errs[1] < errs[0] * 0.7,
                "{bayer}: mhc not better than bilinear {errs:?}"
            );
            assert!(
                errs[2] < errs[0] * 0.7,
                "{bayer}: menon not better than bilinear {errs:?}"
            );
        }
    }

    #[test]
    fn tiny_images_do_not_panic() {
        for (w, h) in [(1, 1), (2, 1), (1, 3), (2, 2), (3, 2)] {
            let p = vec![0.5; w * h];
            for method in Demosaic::ALL {
                let out = demosaic(&p, w, h, Bayer::RGGB, method).unwrap();
                assert_eq!(out.data.len(), 3 * w * h);
                assert!(out.data.iter().all(|v| v.is_finite()));
            }
        }
        assert!(demosaic(&[0.0; 3], 2, 2, Bayer::RGGB, Demosaic::Mhc).is_err());
    }

    #[test]
    fn mirror_keeps_parity() {
        assert_eq!(mirror(-1, 10), 1);
        assert_eq!(mirror(-2, 10), 2);
        assert_eq!(mirror(10, 10), 8);
        assert_eq!(mirror(11, 10), 7);
        assert_eq!(mirror(-2, 1), 0);
        assert_eq!(mirror(3, 2), 0);
    }

    #[test]
    fn parse_names() {
        assert_eq!("MHC".parse::<Demosaic>().unwrap(), Demosaic::Mhc);
        assert!("ahd".parse::<Demosaic>().is_err());
    }
}
