//! The render pipeline: normalize -> white balance -> demosaic -> camera -> XYZ -> linear
//! sRGB -> DefaultCrop -> orientation. Every stage is parallel over rows and deterministic.

use super::color::normalize_neutral;
use super::demosaic::{demosaic_rows, row_kernel, Demosaic, Post, RowKernel};
use super::opcodes::warp_window::WindowStats;
use super::opcodes::{self, pipeline, OpcodeMode};
use super::RgbImage;
use crate::error::Result;
use crate::normalize::Normalizer;
use crate::raw::RawImage;

pub use super::geometry::{
    apply_geometry, default_crop, orient_image, oriented_source, DisplayGeometry,
};
use super::place::{collect_bands, collect_bands_of};
use super::render_bands::{banded, banded_any};
pub use super::render_bands::{
    render_input_bands_sized, render_linear_bands, render_linear_bands_sized,
};
pub use super::render_parts::{
    apply_matrix, color_matrix, resolve_neutral, Bands, RenderOptions, BAND,
};
pub(crate) use super::render_parts::{clip_row, matrix_row};

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

fn render_banded(
    img: &RawImage,
    neutral: [f64; 3],
    kernel: RowKernel,
    post: &Post,
    crop: bool,
    orient: bool,
) -> Result<RgbImage> {
    banded(img, neutral, kernel, post, crop, orient, collect_bands)
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
    if let Some(p) = opcodes::active_image(img, opts.opcodes)? {
        if let Some(kernel) = row_kernel(opts.demosaic) {
            let ends = (opts.crop, opts.orient);
            let got = banded_any(img, Some(&p), n, kernel, &clip_row, ends, collect_bands)?;
            if let Some(rgb) = got {
                return Ok(rgb);
            }
        }
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
    if let Some(p) = opcodes::active_image(img, opts.opcodes)? {
        if let Some(kernel) = row_kernel(opts.demosaic) {
            let ends = (opts.crop, opts.orient);
            let got = banded_any(img, Some(&p), n, kernel, &post, ends, collect_bands)?;
            if let Some(rgb) = got {
                return Ok(rgb);
            }
        }
        return pipeline::render_frame(img, &p, n, opts.demosaic, &post, opts.crop, opts.orient);
    }
    render_with(img, n, opts.demosaic, &post, opts.crop, opts.orient)
}

/// [`render_linear`] of a file with opcodes made in bands of `band` output rows (any
/// height; the renders use [`BAND`]), `None` when its opcodes are not banded. For tests:
/// it must equal [`render_linear_whole_frame`] bit for bit.
#[doc(hidden)]
pub fn render_linear_banded_by(
    img: &RawImage,
    opts: &RenderOptions,
    band: usize,
) -> Result<Option<RgbImage>> {
    Ok(render_linear_windowed(img, opts, band, None)?.map(|(rgb, _)| rgb))
}

/// [`render_linear_banded_by`] whose warps' window may hold `limit` lines before the
/// whole-image path runs (`None`: the renders' limit), with what the window did (all
/// zero without a warp). For tests and benchmarks.
#[doc(hidden)]
pub fn render_linear_windowed(
    img: &RawImage,
    opts: &RenderOptions,
    band: usize,
    limit: Option<usize>,
) -> Result<Option<(RgbImage, WindowStats)>> {
    let (Some(kernel), Some(p)) = (
        row_kernel(opts.demosaic),
        opcodes::active_image(img, opts.opcodes)?,
    ) else {
        return Ok(None);
    };
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let post = move |row: &mut [f32]| matrix_row(row, &mf);
    let ends = (opts.crop, opts.orient);
    let band = band.max(1);
    let mut stats = WindowStats::default();
    let tune = opcodes::banded::Tune {
        band,
        limit,
        stats: Some(&mut stats),
    };
    let rows = opcodes::banded::RowRender {
        neutral: n,
        kernel,
        post: &post,
    };
    let got = opcodes::banded::render(img, &p, rows, ends, tune, collect_bands_of(band))?;
    Ok(got.map(|rgb| (rgb, stats)))
}

/// The whole-frame opcode render ([`pipeline::render_frame`]: every stage on whole
/// images), the reference the banded opcode render must equal bit for bit. Kept for tests
/// and benchmarks; files without applicable opcodes take [`render_linear`].
#[doc(hidden)]
pub fn render_linear_whole_frame(img: &RawImage, opts: &RenderOptions) -> Result<RgbImage> {
    let Some(p) = opcodes::active_image(img, opts.opcodes)? else {
        return render_linear(img, opts);
    };
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let post = move |row: &mut [f32]| matrix_row(row, &mf);
    pipeline::render_frame(img, &p, n, opts.demosaic, &post, opts.crop, opts.orient)
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
        img.meta.as_shot_white_xy = Some(crate::color::xyz::D65_XY);
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
