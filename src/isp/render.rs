//! The render pipeline: normalize -> white balance -> demosaic -> camera -> XYZ -> linear
//! sRGB -> DefaultCrop -> orientation. Every stage is parallel over rows and deterministic.

use super::color::normalize_neutral;
use super::demosaic::{demosaic_rect, demosaic_rows, row_kernel, Demosaic, Post, RowKernel};
use super::opcodes::{self, pipeline, OpcodeMode};
use super::RgbImage;
use crate::error::{Error, Result};
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::RawImage;
use rayon::prelude::*;

pub use super::geometry::{
    apply_geometry, default_crop, orient_image, oriented_source, DisplayGeometry,
};
pub(crate) use super::render_parts::matrix_row;
pub use super::render_parts::{
    apply_matrix, color_matrix, resolve_neutral, Bands, RenderOptions, BAND,
};

/// Normalized, white-balanced (clipped to [0, 1]) and demosaiced camera RGB of the whole
/// active area, not clipped after demosaicing: no colour matrix, no crop, no orientation.
/// Normalization uses the shared [`Normalizer`] (DNG chapter 5), fused with the white
/// balance into the demosaicer's input, in parallel over rows.
fn render_camera_with(
    img: &RawImage,
    neutral: [f64; 3],
    method: Demosaic,
    post: &Post,
) -> Result<RgbImage> {
    let bayer = img.bayer()?;
    let n = normalize_neutral(neutral)?;
    let norm = Normalizer::new(img)?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let inv = [1.0 / n[0], 1.0, 1.0 / n[2]];
    let data = &img.data;
    let stride = img.width;
    Ok(demosaic_rows(
        w,
        h,
        bayer,
        method,
        |r, out| {
            let src = &data[(r + top) * stride + left..][..w];
            for (c, (o, &x)) in out.iter_mut().zip(src).enumerate() {
                let y = norm.normalize(x, r, c) * inv[bayer.color_at(r, c) as usize];
                *o = y.clamp(0.0, 1.0) as f32;
            }
        },
        post,
    ))
}

/// White-balanced demosaiced camera RGB of the whole active area, not clipped after
/// demosaicing (see [`render_camera`]).
pub fn render_camera_unclipped(
    img: &RawImage,
    neutral: [f64; 3],
    method: Demosaic,
) -> Result<RgbImage> {
    render_with(img, neutral, method, &|_| {}, false, false)
}

/// Clip every sample of a row to [0, 1].
fn clip_row(row: &mut [f32]) {
    row.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0))
}

/// [`render_camera_unclipped`] clipped to [0, 1]: the network input before geometry.
pub fn render_camera(img: &RawImage, neutral: [f64; 3], method: Demosaic) -> Result<RgbImage> {
    if img.meta.linear_raw.is_some() {
        return super::render_linear_raw::render_camera(
            img,
            neutral,
            false,
            false,
            OpcodeMode::Apply,
        );
    }
    render_with(img, neutral, method, &clip_row, false, false)
}

/// The render: demosaic with `post` applied to each finished row, then DefaultCrop (if
/// `crop`) and orientation (if `orient`). Single-pass demosaicers (bilinear, MHC) run
/// banded ([`render_banded`]); Menon runs on the whole image and is then cut and turned
/// ([`render_camera_with`] + [`apply_geometry`]). `post` must act on each pixel on its
/// own (both paths apply it to different row segments).
fn render_with(
    img: &RawImage,
    neutral: [f64; 3],
    method: Demosaic,
    post: &Post,
    crop: bool,
    orient: bool,
) -> Result<RgbImage> {
    match row_kernel(method) {
        Some(kernel) => render_banded(img, neutral, kernel, post, crop, orient),
        None => Ok(apply_geometry(
            render_camera_with(img, neutral, method, post)?,
            &img.meta,
            crop,
            orient,
        )),
    }
}

/// The fused render of a single-pass demosaicer: the output image (after crop and
/// orientation) is cut into bands of [`BAND`] rows, processed in parallel; each band maps
/// to a rectangle of the active area (rows for orientations 1-4, columns for 5-8), whose
/// CFA samples (normalized and white-balanced, plus the 2-sample neighbourhood the
/// kernels read) are computed into a band-sized plane, demosaiced row by row, passed
/// through `post` and written straight to their final place. No whole-image buffer but
/// the output. Every pixel is computed by the same expressions as in the whole-image path
/// ([`render_camera_with`] + [`apply_geometry`]), so the results are identical bit for
/// bit, for any thread count.
fn render_banded(
    img: &RawImage,
    neutral: [f64; 3],
    kernel: RowKernel,
    post: &Post,
    crop: bool,
    orient: bool,
) -> Result<RgbImage> {
    banded(img, neutral, kernel, post, crop, orient, |ow, oh, body| {
        let mut out = RgbImage::try_new(ow, oh)?;
        out.data
            .par_chunks_mut(3 * ow * BAND)
            .enumerate()
            .for_each(|(bi, band)| body(bi, band));
        Ok(out)
    })
}

/// The set-up of [`render_banded`]: resolves the geometry and calls `run(ow, oh, body)`,
/// where `body(bi, band)` renders output rows `[bi * BAND, bi * BAND + band.len() / (3 *
/// ow))` into `band` (interleaved RGB, `ow` pixels per row).
fn banded<R>(
    img: &RawImage,
    neutral: [f64; 3],
    kernel: RowKernel,
    post: &Post,
    crop: bool,
    orient: bool,
    run: impl FnOnce(usize, usize, &(dyn Fn(usize, &mut [f32]) + Sync)) -> Result<R>,
) -> Result<R> {
    let bayer = img.bayer()?;
    let n = normalize_neutral(neutral)?;
    let norm = Normalizer::new(img)?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let stride = img.width;
    if w == 0 || h == 0 || (top + h - 1) * stride + left + w > img.data.len() {
        return Err(Error::invalid(
            "the active area is empty or outside the pixel buffer",
        ));
    }
    let inv = [1.0 / n[0], 1.0, 1.0 / n[2]];
    let data = &img.data;
    // CFA sample (r, cs[k]) into out[k]: normalized, white-balanced, clipped. Wide bands
    // take the black levels of the whole row from `Normalizer::black_row` (bit-identical
    // to `black_at`, without two integer divisions per sample); narrow ones (orientations
    // 5-8) ask per sample.
    let site = |x: u16, r: usize, c: usize, black: f64| -> f32 {
        let y = norm.normalize_with_black(x, black) * inv[bayer.color_at(r, c) as usize];
        y.clamp(0.0, 1.0) as f32
    };
    // With a 2x2-periodic black level every stored value up to white is tabulated per
    // 2x2 position (same expression, same bits).
    let table = SiteTable::new(&norm, |r, c, x| site(x, r, c, norm.black_at(r, c)));
    let fill = |blacks: &mut Vec<f64>, r: usize, cs: &[usize], out: &mut [f32]| {
        let src = &data[(r + top) * stride + left..][..w];
        if let Some(t) = &table {
            let (t0, t1) = t.row(r);
            for (o, &c) in out.iter_mut().zip(cs) {
                let x = src[c];
                let tab = if c & 1 == 0 { t0 } else { t1 };
                *o = match tab.get(x as usize) {
                    Some(&v) => v,
                    None => site(x, r, c, norm.black_at(r, c)),
                };
            }
        } else if 2 * cs.len() >= w {
            blacks.resize(w, 0.0);
            norm.black_row(r, blacks);
            for (o, &c) in out.iter_mut().zip(cs) {
                let y = norm.normalize_with_black(src[c], blacks[c])
                    * inv[bayer.color_at(r, c) as usize];
                *o = y.clamp(0.0, 1.0) as f32;
            }
        } else {
            for (o, &c) in out.iter_mut().zip(cs) {
                let y = norm.normalize(src[c], r, c) * inv[bayer.color_at(r, c) as usize];
                *o = y.clamp(0.0, 1.0) as f32;
            }
        }
    };
    let (x0, y0, cw, ch) = if crop {
        default_crop(&img.meta, w, h)
    } else {
        (0, 0, w, h)
    };
    let o = if orient && (2..=8).contains(&img.meta.orientation) {
        img.meta.orientation
    } else {
        1
    };
    let swap = o >= 5;
    let (ow, oh) = if swap { (ch, cw) } else { (cw, ch) };
    let body = |bi: usize, band: &mut [f32]| {
        let a0 = bi * BAND;
        let b0 = a0 + band.len() / (3 * ow);
        let mut blacks = Vec::new();
        let fill = |r: usize, cs: &[usize], out: &mut [f32]| fill(&mut blacks, r, cs, out);
        if !swap {
            // Output rows [a0, b0) are crop rows [s0, s1), in reverse order for 3 and 4,
            // mirrored left-right for 2 and 3.
            let (s0, s1) = if o <= 2 { (a0, b0) } else { (ch - b0, ch - a0) };
            let flip = o == 2 || o == 3;
            let rows = y0 + s0..y0 + s1;
            demosaic_rect(
                w,
                h,
                bayer,
                kernel,
                rows,
                x0..x0 + cw,
                fill,
                post,
                |i, rgb| {
                    let yc = s0 + i;
                    let yo = if o <= 2 { yc } else { ch - 1 - yc };
                    let dst = &mut band[3 * ow * (yo - a0)..][..3 * ow];
                    if flip {
                        for (d, p) in dst.chunks_exact_mut(3).zip(rgb.chunks_exact(3).rev()) {
                            d.copy_from_slice(p);
                        }
                    } else {
                        dst.copy_from_slice(rgb);
                    }
                },
            );
        } else {
            // Output rows [a0, b0) are crop columns [s0, s1) (reversed for 7 and 8);
            // crop row y becomes output column y (5, 8) or ch - 1 - y (6, 7).
            let (s0, s1) = if o <= 6 { (a0, b0) } else { (cw - b0, cw - a0) };
            let cols = x0 + s0..x0 + s1;
            demosaic_rect(
                w,
                h,
                bayer,
                kernel,
                y0..y0 + ch,
                cols,
                fill,
                post,
                |y, rgb| {
                    let xo = if o == 5 || o == 8 { y } else { ch - 1 - y };
                    for (k, p) in rgb.chunks_exact(3).enumerate() {
                        let x = s0 + k;
                        let yo = if o <= 6 { x } else { cw - 1 - x };
                        let d = 3 * ((yo - a0) * ow + xo);
                        band[d..d + 3].copy_from_slice(p);
                    }
                },
            );
        }
    };
    run(ow, oh, &body)
}

/// Band-wise consumer of [`render_linear`]: the render is made band by band ([`BAND`]
/// output rows each, in parallel, into a per-thread buffer) and `f(first_row, width,
/// rows)` is called on each band (`rows` is interleaved linear RGB, `width` pixels per
/// row); the results come back in band order with the output size ([`Bands`]). The rows
/// are exactly those of [`render_linear`]'s image (same code), so consumers that encode
/// them (EXR blocks, 8-bit PNG samples) write the same bytes as from the whole image,
/// without holding it. `None` when the demosaicer is not banded (Menon): use
/// [`render_linear`]. See [`render_linear_bands_sized`] for the order in which bands are
/// made.
pub fn render_linear_bands<T, F>(
    img: &RawImage,
    opts: &RenderOptions,
    f: F,
) -> Result<Option<Bands<T>>>
where
    T: Send,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    render_linear_bands_sized(img, opts, |_, _| Ok(()), f)
}

/// [`render_linear_bands`] that first calls `start(width, height)` with the output size,
/// once, before any band (not at all when it returns `None`), e.g. to open a file that
/// `f` writes the bands into.
///
/// Bands are made nearly in order: each thread takes the lowest band not yet taken, and no
/// band is started more than 2 x threads + 1 bands beyond the lowest unfinished one, so a
/// consumer that writes the bands in order (holding those that come early) holds a few
/// bands at most. `f` must not wait for other rayon work (no parallel iterator or `join`
/// inside): other threads may be waiting for its band.
pub fn render_linear_bands_sized<T, S, F>(
    img: &RawImage,
    opts: &RenderOptions,
    start: S,
    f: F,
) -> Result<Option<Bands<T>>>
where
    T: Send,
    S: FnOnce(usize, usize) -> Result<()>,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    if img.meta.linear_raw.is_some() {
        return super::render_linear_raw::render_linear_bands(img, opts, start, f);
    }
    let Some(kernel) = row_kernel(opts.demosaic) else {
        return Ok(None);
    };
    if opcodes::active(&img.meta, opts.opcodes)?.is_some() {
        // The opcode path is not banded: render_linear makes the whole image.
        return Ok(None);
    }
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let post = move |row: &mut [f32]| matrix_row(row, &mf);
    banded(
        img,
        n,
        kernel,
        &post,
        opts.crop,
        opts.orient,
        |ow, oh, body| {
            start(ow, oh)?;
            let nb = oh.div_ceil(BAND);
            let bands = super::bands::in_order(nb, |bi, scratch: &mut Vec<f32>| {
                let rows = BAND.min(oh - bi * BAND);
                scratch.clear();
                scratch.resize(3 * ow * rows, 0.0);
                body(bi, scratch);
                f(bi * BAND, ow, scratch)
            })?;
            Ok(Some(Bands {
                width: ow,
                height: oh,
                bands,
            }))
        },
    )
}

/// The network input of the paper: normalized, white-balanced, demosaiced camera RGB
/// (no colour matrix), with the same DefaultCrop and orientation as [`render_linear`]'s
/// defaults so that input and target align. `neutral` None = the file's neutral.
/// The file's opcode lists are applied ([`render_input_with`] chooses).
pub fn render_input(
    img: &RawImage,
    neutral: Option<[f64; 3]>,
    method: Demosaic,
) -> Result<RgbImage> {
    render_input_with(img, neutral, method, OpcodeMode::Apply)
}

/// [`render_input`] with the opcode lists applied or ignored.
pub fn render_input_with(
    img: &RawImage,
    neutral: Option<[f64; 3]>,
    method: Demosaic,
    mode: OpcodeMode,
) -> Result<RgbImage> {
    render_input_opts(
        img,
        &RenderOptions {
            demosaic: method,
            neutral,
            crop: true,
            orient: true,
            opcodes: mode,
        },
    )
}

/// The network input (see [`render_input`]) with the crop, orientation and opcode choices
/// of `opts`.
pub fn render_input_opts(img: &RawImage, opts: &RenderOptions) -> Result<RgbImage> {
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    if img.meta.linear_raw.is_some() {
        return super::render_linear_raw::render_camera(
            img,
            n,
            opts.crop,
            opts.orient,
            opts.opcodes,
        );
    }
    if let Some(p) = opcodes::active(&img.meta, opts.opcodes)? {
        return pipeline::render_frame(
            img,
            &p,
            n,
            opts.demosaic,
            &clip_row,
            opts.crop,
            opts.orient,
        );
    }
    render_with(img, n, opts.demosaic, &clip_row, opts.crop, opts.orient)
}

/// Linear sRGB (Rec.709 primaries, D65) render of a raw image, values in [0, 1].
/// Demosaic, colour matrix, DefaultCrop and orientation are fused per band of output rows
/// for bilinear and MHC (no whole-image intermediate buffer); see `render_banded`.
pub fn render_linear(img: &RawImage, opts: &RenderOptions) -> Result<RgbImage> {
    if img.meta.linear_raw.is_some() {
        return super::render_linear_raw::render_linear(img, opts);
    }
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let post = move |row: &mut [f32]| matrix_row(row, &mf);
    if let Some(p) = opcodes::active(&img.meta, opts.opcodes)? {
        return pipeline::render_frame(img, &p, n, opts.demosaic, &post, opts.crop, opts.orient);
    }
    render_with(img, n, opts.demosaic, &post, opts.crop, opts.orient)
}

/// The unfused reference of [`render_linear`]: whole-image demosaic (colour matrix per
/// row), then [`apply_geometry`]. Kept for tests and benchmarks (the banded render must
/// equal it bit for bit).
#[doc(hidden)]
pub fn render_linear_reference(img: &RawImage, opts: &RenderOptions) -> Result<RgbImage> {
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let rgb = render_camera_with(img, n, opts.demosaic, &move |row: &mut [f32]| {
        matrix_row(row, &mf)
    })?;
    Ok(apply_geometry(rgb, &img.meta, opts.crop, opts.orient))
}

/// The unfused reference of [`render_input`] (see [`render_linear_reference`]).
#[doc(hidden)]
pub fn render_input_reference(
    img: &RawImage,
    neutral: Option<[f64; 3]>,
    method: Demosaic,
) -> Result<RgbImage> {
    let n = resolve_neutral(&img.meta, neutral)?;
    let rgb = render_camera_with(img, n, method, &clip_row)?;
    Ok(apply_geometry(rgb, &img.meta, true, true))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::{Bayer, RawMeta, Rect};

    fn numbered(w: usize, h: usize) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        for (i, px) in img.data.chunks_exact_mut(3).enumerate() {
            px[0] = i as f32;
        }
        img
    }

    #[test]
    fn orientations_match_their_definitions() {
        // 3x2 image: 0 1 2 / 3 4 5
        let img = numbered(3, 2);
        let red = |o: u16| -> (usize, usize, Vec<f32>) {
            let r = orient_image(&img, o);
            (r.width, r.height, r.data.chunks(3).map(|p| p[0]).collect())
        };
        assert_eq!(red(1), (3, 2, vec![0., 1., 2., 3., 4., 5.]));
        assert_eq!(red(2), (3, 2, vec![2., 1., 0., 5., 4., 3.]));
        assert_eq!(red(3), (3, 2, vec![5., 4., 3., 2., 1., 0.]));
        assert_eq!(red(4), (3, 2, vec![3., 4., 5., 0., 1., 2.]));
        assert_eq!(red(5), (2, 3, vec![0., 3., 1., 4., 2., 5.]));
        // rotate 90 clockwise
        assert_eq!(red(6), (2, 3, vec![3., 0., 4., 1., 5., 2.]));
        assert_eq!(red(7), (2, 3, vec![5., 2., 4., 1., 3., 0.]));
        // rotate 90 counter-clockwise
        assert_eq!(red(8), (2, 3, vec![2., 5., 1., 4., 0., 3.]));
        assert_eq!(red(0), red(1));
    }

    fn flat_raw(value: u16) -> RawImage {
        let (w, h) = (16, 12);
        let meta = RawMeta::new_bayer(Bayer::RGGB, 12, 64.0, 4095.0);
        RawImage {
            width: w,
            height: h,
            data: vec![value; w * h],
            meta,
        }
    }

    #[test]
    fn grey_card_renders_grey_and_crop_orientation_apply() {
        // A raw whose sites equal the neutral times a constant renders neutral grey.
        let mut img = flat_raw(0);
        let n = img.meta.as_shot_neutral.unwrap();
        let k = 0.3;
        for y in 0..img.height {
            for x in 0..img.width {
                let c = Bayer::RGGB.color_at(y, x) as usize;
                img.data[y * img.width + x] = (64.0 + k * n[c] * (4095.0 - 64.0)).round() as u16;
            }
        }
        img.meta.active_area = Some(Rect {
            top: 2,
            left: 2,
            bottom: 12,
            right: 16,
        });
        img.meta.default_crop_origin = Some([1.0, 2.0]);
        img.meta.default_crop_size = Some([10.0, 6.0]);
        img.meta.orientation = 6;
        for d in Demosaic::ALL {
            let out = render_linear(
                &img,
                &RenderOptions {
                    demosaic: d,
                    ..RenderOptions::default()
                },
            )
            .unwrap();
            assert_eq!((out.width, out.height), (6, 10));
            for px in out.data.chunks(3) {
                for v in px {
                    assert!((v - k as f32).abs() < 2e-3, "{d}: {px:?}");
                }
            }
        }
        let inp = render_input(&img, None, Demosaic::Bilinear).unwrap();
        assert_eq!((inp.width, inp.height), (6, 10));
        let off = render_linear(
            &img,
            &RenderOptions {
                crop: false,
                orient: false,
                ..RenderOptions::default()
            },
        )
        .unwrap();
        assert_eq!((off.width, off.height), (14, 10));
    }

    #[test]
    fn neutral_sources_and_errors() {
        let mut img = flat_raw(1000);
        assert_eq!(
            resolve_neutral(&img.meta, Some([2.0, 4.0, 1.0])).unwrap(),
            [0.5, 1.0, 0.25]
        );
        img.meta.as_shot_neutral = None;
        assert!(resolve_neutral(&img.meta, None).is_err());
        img.meta.as_shot_white_xy = Some(super::super::color::D65_XY);
        let n = resolve_neutral(&img.meta, None).unwrap();
        // the fixture matrix is Lindbloom's (white 0.31271, 0.32902): close to (1, 1, 1)
        assert!(n.iter().all(|v| (v - 1.0).abs() < 1e-3), "{n:?}");
        assert!(resolve_neutral(&img.meta, Some([0.0, 1.0, 1.0])).is_err());
    }

    #[test]
    fn display_geometry_matches_the_render_geometry() {
        let (aw, ah) = (9usize, 6usize);
        // pixel value = (column, row, 0) of the active area
        let mut img = RgbImage::new(aw, ah);
        for r in 0..ah {
            for c in 0..aw {
                img.data[3 * (r * aw + c)] = c as f32;
                img.data[3 * (r * aw + c) + 1] = r as f32;
            }
        }
        let mut meta = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        meta.default_crop_origin = Some([1.0, 2.0]);
        meta.default_crop_size = Some([6.0, 3.0]);
        for o in 0..=9u16 {
            meta.orientation = o;
            let g = DisplayGeometry::new(&meta, aw, ah);
            let shown = apply_geometry(img.clone(), &meta, true, true);
            assert_eq!(g.dims(), (shown.width, shown.height), "orientation {o}");
            for yo in 0..shown.height {
                for xo in 0..shown.width {
                    let p = shown.pixel(xo, yo).unwrap();
                    let (c, r) = g.active_site(xo, yo);
                    assert_eq!((c as f32, r as f32), (p[0], p[1]), "o {o} at {xo},{yo}");
                    // the pixel's centre maps forward to the displayed pixel's centre
                    let (x, y) = g.display_point(c as f64 + 0.5, r as f64 + 0.5).unwrap();
                    assert_eq!((x, y), (xo as f64 + 0.5, yo as f64 + 0.5), "o {o}");
                }
            }
        }
        assert_eq!(
            DisplayGeometry::new(&meta, aw, ah).display_point(0.5, 0.5),
            None
        );
        let id = DisplayGeometry::identity(aw, ah);
        assert_eq!(
            (id.dims(), id.active_site(100, 100)),
            ((aw, ah), (aw - 1, ah - 1))
        );
    }

    #[test]
    fn default_crop_is_clamped() {
        let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        assert_eq!(default_crop(&m, 10, 8), (0, 0, 10, 8));
        m.default_crop_origin = Some([8.0, 100.0]);
        m.default_crop_size = Some([50.0, f64::NAN]);
        assert_eq!(default_crop(&m, 10, 8), (8, 7, 2, 1));
    }

    /// A raw of `w x h` with hash-noise samples (clipping at both ends included), an
    /// active area inset by `inset` on the top/left, and the given pattern.
    fn noisy_raw(w: usize, h: usize, bayer: Bayer, inset: (u32, u32), seed: u64) -> RawImage {
        let mut meta = RawMeta::new_bayer(bayer, 12, 64.0, 4095.0);
        meta.as_shot_neutral = Some([0.55, 1.0, 0.7]);
        if inset != (0, 0) {
            meta.active_area = Some(Rect {
                top: inset.1,
                left: inset.0,
                bottom: h as u32,
                right: w as u32,
            });
        }
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let data = (0..w * h)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s % 4400) as u16
            })
            .collect();
        RawImage {
            width: w,
            height: h,
            data,
            meta,
        }
    }

    fn bits(img: &RgbImage) -> (usize, usize, Vec<u32>) {
        (
            img.width,
            img.height,
            img.data.iter().map(|v| v.to_bits()).collect(),
        )
    }

    #[test]
    fn banded_render_equals_the_whole_image_reference() {
        // sizes: tiny, odd, and more than one band in both directions
        let sizes = [
            (1, 1),
            (2, 1),
            (1, 3),
            (2, 2),
            (3, 5),
            (7, 4),
            (37, 70),
            (71, 41),
        ];
        let mut case = 0u64;
        for &(w, h) in &sizes {
            for bayer in Bayer::ALL {
                for d in [Demosaic::Bilinear, Demosaic::Mhc, Demosaic::Menon] {
                    case += 1;
                    let inset = if w > 3 && h > 3 { (1, 3) } else { (0, 0) };
                    let mut img = noisy_raw(w, h, bayer, inset, case);
                    let aw = w - inset.0 as usize;
                    let ah = h - inset.1 as usize;
                    if case.is_multiple_of(2) {
                        // per-site black (2x2 repeat) with BlackLevelDeltaH/V
                        let l = &mut img.meta.levels;
                        l.black_repeat = (2, 2);
                        l.black = vec![60.0, 64.5, 63.0, 70.25];
                        l.black_delta_h = (0..aw).map(|c| (c % 5) as f64 * 0.3).collect();
                        l.black_delta_v = (0..ah).map(|r| (r % 3) as f64 * 0.7 - 0.5).collect();
                    } else if case % 4 == 1 {
                        // per-site black without deltas: the tabulated path
                        let l = &mut img.meta.levels;
                        l.black_repeat = (2, 2);
                        l.black = vec![60.0, 64.5, 63.0, 70.25];
                    }
                    for orientation in 0..=8u16 {
                        img.meta.orientation = orientation;
                        // crop: none, and an odd origin/size when the area allows it
                        img.meta.default_crop_origin = None;
                        img.meta.default_crop_size = None;
                        for with_crop_tags in [false, true] {
                            if with_crop_tags {
                                img.meta.default_crop_origin = Some([1.0, 1.0]);
                                img.meta.default_crop_size =
                                    Some([(aw as f64 - 2.0).max(1.0), (ah as f64 - 3.0).max(1.0)]);
                            }
                            for (crop, orient) in [(true, true), (false, true), (true, false)] {
                                let opts = RenderOptions {
                                    demosaic: d,
                                    crop,
                                    orient,
                                    neutral: None,
                                    ..RenderOptions::default()
                                };
                                let a = render_linear(&img, &opts).unwrap();
                                let b = render_linear_reference(&img, &opts).unwrap();
                                assert_eq!(
                                    bits(&a),
                                    bits(&b),
                                    "{w}x{h} {bayer} {d} o{orientation} crop {crop} orient {orient}"
                                );
                                // band-wise consumers see exactly these rows, in order
                                let f = |y0: usize, bw: usize, rows: &[f32]| {
                                    Ok((y0, bw, rows.to_vec()))
                                };
                                match render_linear_bands(&img, &opts, f).unwrap() {
                                    Some(Bands {
                                        width: bw,
                                        height: bh,
                                        bands,
                                    }) => {
                                        assert_ne!(d, Demosaic::Menon);
                                        assert_eq!((bw, bh), (a.width, a.height));
                                        let mut next = 0;
                                        for (y0, ww, _) in &bands {
                                            assert_eq!((*y0, *ww), (next, bw));
                                            next += BAND;
                                        }
                                        let rows: Vec<f32> =
                                            bands.into_iter().flat_map(|b| b.2).collect();
                                        let c = RgbImage {
                                            width: bw,
                                            height: bh,
                                            data: rows,
                                        };
                                        assert_eq!(
                                            bits(&c),
                                            bits(&a),
                                            "bands {w}x{h} {d} o{orientation}"
                                        );
                                    }
                                    None => assert_eq!(d, Demosaic::Menon),
                                }
                            }
                            let a = render_input(&img, None, d).unwrap();
                            let b = render_input_reference(&img, None, d).unwrap();
                            assert_eq!(bits(&a), bits(&b), "input {w}x{h} {bayer} {d}");
                        }
                    }
                    let n = resolve_neutral(&img.meta, None).unwrap();
                    let a = render_camera_unclipped(&img, n, d).unwrap();
                    let b = render_camera_with(&img, n, d, &|_| {}).unwrap();
                    assert_eq!(bits(&a), bits(&b), "camera {w}x{h} {bayer} {d}");
                }
            }
        }
    }

    #[test]
    fn banded_render_is_deterministic_across_thread_counts() {
        let img = noisy_raw(90, 75, Bayer::GBRG, (2, 1), 7);
        for o in [1, 6] {
            let mut img = img.clone();
            img.meta.orientation = o;
            let a = render_linear(&img, &RenderOptions::default()).unwrap();
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            let b = pool.install(|| render_linear(&img, &RenderOptions::default()).unwrap());
            assert_eq!(bits(&a), bits(&b));
        }
    }

    #[test]
    fn render_is_deterministic_across_thread_counts() {
        let mut img = flat_raw(0);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = (64 + (i * 7919) % 4000) as u16;
        }
        let opts = RenderOptions {
            demosaic: Demosaic::Menon,
            ..RenderOptions::default()
        };
        let a = render_linear(&img, &opts).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| render_linear(&img, &opts).unwrap());
        assert_eq!(a, b);
    }
}
