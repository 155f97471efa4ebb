//! The render pipeline's public API: one [`RenderOptions`] record (what to make) and one
//! [`Execution`] (how to run it): [`render`], [`render_with`], [`render_bands`] and
//! [`render_crop`]. One driver (`drive`, drive.rs) runs the stages of [`STAGES`] in order
//! for every execution, and each execution (a `Walk`) supplies only how it walks the image
//! (see [`super::stages`] and docs/isp.md, "The pipeline"):
//!
//! * the whole frame ([`Execution::WholeFrame`]): every stage on whole images, the
//!   reference the others equal bit for bit;
//! * bands of output rows ([`Execution::Bands`], [`render_bands`]): DefaultCrop and
//!   orientation cut the output into bands, each band computing the active-area rectangle it
//!   shows (`render_bands.rs` without opcodes, `opcodes/banded.rs` with them);
//! * a crop of the active area ([`render_crop`]), from its own samples (`render_crop.rs`)
//!   or cut from the whole frame's;
//! * a LinearRaw image (`render_linear_raw.rs`): already demosaiced, whole frame.
//!
//! [`Execution::Auto`] ([`render`]) takes bands when the demosaicer and the opcodes allow
//! (bilinear, MHC; no TrimBounds), else the whole frame. Every stage is parallel over rows
//! and deterministic.

use super::demosaic::{demosaic_rows, row_kernel, Post};
use super::opcodes::banded::Tune;
use super::opcodes::pipeline;
use super::opcodes::warp_window::WindowStats;
use super::rgb::RgbImage;
use crate::error::{Error, Result};
use crate::raw::crop::Crop;
use crate::raw::RawImage;

use super::drive::{drive, Pipe, Walk};
pub use super::geometry::{
    apply_geometry, default_crop, orient_image, oriented_source, DisplayGeometry,
};
use super::place::{collect_bands, collect_bands_of};
use super::pre_demosaic::{CfaSites, FillRow};
use super::render_bands::{banded_any, Consumer};
pub use super::render_parts::{
    apply_matrix, color_matrix, resolve_neutral, Bands, Output, RenderOptions, BAND,
};
pub use super::stages::{Stage, STAGES};

/// How a render runs its stages (the pixels are the same, bit for bit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Execution {
    /// Bands when the demosaicer and the opcodes allow, else the whole frame ([`render`]).
    #[default]
    Auto,
    /// Every stage on the whole frame: the reference.
    WholeFrame,
    /// Bands of `rows` output rows (the renders use [`BAND`]), the warps' windows holding at
    /// most `limit` lines before the whole-image path runs (`None`: the renders' limit).
    /// Not possible (`None` from [`render_with`]) with Menon, a TrimBounds or a LinearRaw
    /// image.
    Bands {
        /// Output rows per band.
        rows: usize,
        /// Lines a warp's window may hold.
        limit: Option<usize>,
    },
}

impl Execution {
    /// Every kind of execution, for tests that compare them.
    pub const ALL: [Execution; 3] = [
        Execution::Auto,
        Execution::WholeFrame,
        Execution::Bands {
            rows: BAND,
            limit: None,
        },
    ];
}

/// What [`render_with`] made: the image, what the warps' window did (all zero without a
/// warp or outside bands) and the stages the execution ran.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// The render.
    pub image: RgbImage,
    /// The warp window's statistics ([`Execution::Bands`]).
    pub window: WindowStats,
    /// The stages run, in pipeline order ([`STAGES`] for every execution).
    pub stages: Vec<Stage>,
}

/// Where [`render_crop`] takes the crop's samples from.
#[derive(Debug, Clone, Copy)]
pub enum CropSamples<'a> {
    /// The stored samples `plane` (row-major) of the active-area rectangle `outer`, which
    /// must hold the crop grown by [`CROP_MARGIN`](super::render_crop::CROP_MARGIN) and cut
    /// to the active area ([`Crop::grown`]); the frame's LinearizationTable is ignored (the
    /// samples are linear). Bilinear and MHC only, and opcodes that act pointwise only
    /// ([`crate::isp::opcodes::Prepared::needs_whole_frame`]).
    Stored {
        /// The rectangle the samples cover.
        outer: &'a Crop,
        /// Its samples.
        plane: &'a [u16],
    },
    /// The frame's own samples: the whole frame is rendered and the crop cut from it (what
    /// opcodes that need the whole frame ask for).
    Frame,
}

/// The render of `img` as `opts` asks ([`Execution::Auto`]).
pub fn render(img: &RawImage, opts: &RenderOptions) -> Result<RgbImage> {
    Ok(drive(img, opts, Auto)?.out)
}

/// The render of `img` as `opts` asks, run as `how` says, with what it ran; `None` when the
/// execution is not possible for this image ([`Execution::Bands`]). For tests and
/// benchmarks: every execution gives the pixels of [`render`].
pub fn render_with(
    img: &RawImage,
    opts: &RenderOptions,
    how: Execution,
) -> Result<Option<Rendered>> {
    let mut window = WindowStats::default();
    let driven = match how {
        Execution::Auto => drive(img, opts, Auto)?.map(Some),
        Execution::WholeFrame => drive(img, opts, WholeFrame)?.map(Some),
        Execution::Bands { rows, limit } => {
            let walk = BandsOf {
                rows,
                limit,
                stats: &mut window,
            };
            drive(img, opts, walk)?
        }
    };
    Ok(driven.out.map(|image| Rendered {
        image,
        window,
        stages: driven.stages,
    }))
}

/// The render handed to a consumer band by band: `start(width, height)` is called once
/// with the output size, before any band, then `f(first_row, width, rows)` on each band of
/// [`BAND`] output rows (`rows` interleaved RGB, `width` pixels per row); the results come
/// back in band order with the output size ([`Bands`]). The rows are exactly those of
/// [`render`]'s image, so consumers that encode them (EXR blocks, 8-bit PNG samples) write
/// the same bytes as from the whole image, without holding it. `None` (and neither
/// `start` nor `f` called) when the render is not made in bands: Menon, a TrimBounds in
/// OpcodeList3, the network input of a LinearRaw image (use [`render`]). A LinearRaw linear
/// render is made whole and handed out in bands.
///
/// Bands are made nearly in order: each thread takes the lowest band not yet taken, and no
/// band is started more than 2 x threads + 1 bands beyond the lowest unfinished one, so a
/// consumer that writes the bands in order (holding those that come early) holds a few
/// bands at most. `f` must not wait for other rayon work (no parallel iterator or `join`
/// inside): other threads may be waiting for its band.
pub fn render_bands<T, S, F>(
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
    let linear_raw = img.meta.linear_raw.is_some();
    if linear_raw && opts.output == Output::Camera {
        return Ok(None);
    }
    if !linear_raw && row_kernel(opts.demosaic).is_none() {
        return Ok(None);
    }
    Ok(drive(img, opts, Consumer { start, f })?.out)
}

/// The render of the active-area rectangle `crop` of the frame `frame` (levels, colour and
/// opcodes from `frame`), from `samples`: the same pixels as the region of the whole
/// frame's render before DefaultCrop and orientation, so `opts` must turn both off. The
/// result is `crop.width x crop.height`, aligned with the crop's CFA samples.
pub fn render_crop(
    frame: &RawImage,
    opts: &RenderOptions,
    crop: &Crop,
    samples: CropSamples,
) -> Result<RgbImage> {
    if opts.crop || opts.orient {
        return Err(Error::invalid(
            "a crop render is made before DefaultCrop and orientation: turn crop and orient off",
        ));
    }
    let rgb = match samples {
        CropSamples::Stored { outer, plane } => {
            super::render_crop::stored(frame, opts, outer, plane, crop)?
        }
        CropSamples::Frame => drive(frame, opts, FrameRegion { crop })?.out,
    };
    Ok(rgb)
}

/// [`CropSamples::Frame`]: the region `crop` of the whole frame's render (no DefaultCrop,
/// no orientation).
struct FrameRegion<'c> {
    crop: &'c Crop,
}

impl Walk for FrameRegion<'_> {
    type Out = RgbImage;
    const NAME: &'static str = "frame crop";

    fn walk(self, pipe: &Pipe) -> Result<RgbImage> {
        let p = match pipe.opcodes() {
            Some(p) if pipe.img.meta.linear_raw.is_none() => p,
            _ => return cut(&WholeFrame.walk(pipe)?, self.crop),
        };
        let rows = pipe.rows();
        let post = move |row: &mut [f32]| rows.run(row);
        let sites = pipe.cfa(true)?;
        let (n, method) = (pipe.neutral(), pipe.method());
        pipeline::render_frame_region(pipe.img, p, &sites, n, method, &post, self.crop)
    }
}

/// The rectangle `crop` of `img`.
fn cut(img: &RgbImage, crop: &Crop) -> Result<RgbImage> {
    if crop.width == 0
        || crop.height == 0
        || crop.left + crop.width > img.width
        || crop.top + crop.height > img.height
    {
        return Err(Error::invalid(format!(
            "the crop {crop:?} is not inside the {}x{} render",
            img.width, img.height
        )));
    }
    let mut out = RgbImage::try_new(crop.width, crop.height)?;
    for (y, row) in out.data.chunks_exact_mut(3 * crop.width).enumerate() {
        let i = 3 * ((crop.top + y) * img.width + crop.left);
        row.copy_from_slice(&img.data[i..][..3 * crop.width]);
    }
    Ok(out)
}

/// [`Execution::Auto`]: bands when possible, else the whole frame.
struct Auto;

impl Walk for Auto {
    type Out = RgbImage;
    const NAME: &'static str = "automatic";

    fn walk(self, pipe: &Pipe) -> Result<RgbImage> {
        if pipe.img.meta.linear_raw.is_some() {
            return super::render_linear_raw::render(pipe);
        }
        if let Some(kernel) = row_kernel(pipe.method()) {
            if let Some(rgb) = banded_any(pipe, kernel, Tune::default(), collect_bands)? {
                return Ok(rgb);
            }
        }
        WholeFrame.walk(pipe)
    }
}

/// [`Execution::Bands`] of `rows` output rows (`None` when not possible).
struct BandsOf<'s> {
    rows: usize,
    limit: Option<usize>,
    stats: &'s mut WindowStats,
}

impl Walk for BandsOf<'_> {
    type Out = Option<RgbImage>;
    const NAME: &'static str = "bands";

    fn walk(self, pipe: &Pipe) -> Result<Option<RgbImage>> {
        if pipe.img.meta.linear_raw.is_some() {
            return Ok(None);
        }
        let Some(kernel) = row_kernel(pipe.method()) else {
            return Ok(None);
        };
        let rows = self.rows.max(1);
        let tune = Tune {
            band: rows,
            limit: self.limit,
            stats: Some(self.stats),
        };
        banded_any(pipe, kernel, tune, collect_bands_of(rows))
    }
}

/// [`Execution::WholeFrame`]: every stage on whole images.
struct WholeFrame;

impl Walk for WholeFrame {
    type Out = RgbImage;
    const NAME: &'static str = "whole frame";

    fn walk(self, pipe: &Pipe) -> Result<RgbImage> {
        let img = pipe.img;
        if img.meta.linear_raw.is_some() {
            return super::render_linear_raw::render(pipe);
        }
        let rows = pipe.rows();
        let post = move |row: &mut [f32]| rows.run(row);
        let (crop, orient) = pipe.geometry();
        let sites = pipe.cfa(true)?;
        let method = pipe.method();
        match pipe.opcodes() {
            Some(p) => {
                let n = pipe.neutral();
                pipeline::render_frame(img, p, &sites, n, method, &post, (crop, orient))
            }
            None => {
                let rgb = demosaic_whole(img, &sites, method, &post)?;
                Ok(apply_geometry(rgb, &img.meta, crop, orient))
            }
        }
    }
}

/// The demosaiced camera RGB of the whole active area of a file without opcodes, its
/// input filled by the pre-demosaic step ([`CfaSites`]), `post` applied to every row: no
/// crop, no orientation.
fn demosaic_whole(
    img: &RawImage,
    sites: &CfaSites,
    method: super::Demosaic,
    post: &Post,
) -> Result<RgbImage> {
    let bayer = img.bayer()?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let data = &img.data;
    let stride = img.width;
    let cs: Vec<usize> = (0..w).collect();
    Ok(demosaic_rows(
        w,
        h,
        bayer,
        method,
        |r, out| {
            let src = &data[(r + top) * stride + left..][..w];
            let mut blacks = Vec::new();
            let row = FillRow {
                src,
                offset: 0,
                r,
                w,
                blacks: &mut blacks,
            };
            sites.fill(row, &cs, out);
        },
        post,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::isp::Demosaic;
    use crate::raw::{Bayer, RawMeta, Rect};

    /// The whole-frame execution's image (the reference).
    fn whole(img: &RawImage, opts: &RenderOptions) -> RgbImage {
        let r = render_with(img, opts, Execution::WholeFrame)
            .unwrap()
            .unwrap();
        assert_eq!(r.stages, STAGES.to_vec());
        r.image
    }

    /// The network input's options: demosaic `d`, crop and orientation on.
    fn input(d: Demosaic) -> RenderOptions {
        RenderOptions {
            output: Output::Camera,
            demosaic: d,
            ..RenderOptions::default()
        }
    }

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
            let out = render(
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
        let inp = render(&img, &input(Demosaic::Bilinear)).unwrap();
        assert_eq!((inp.width, inp.height), (6, 10));
        let off = render(
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
                                let a = render(&img, &opts).unwrap();
                                let b = whole(&img, &opts);
                                assert_eq!(
                                    bits(&a),
                                    bits(&b),
                                    "{w}x{h} {bayer} {d} o{orientation} crop {crop} orient {orient}"
                                );
                                // band-wise consumers see exactly these rows, in order
                                let f = |y0: usize, bw: usize, rows: &[f32]| {
                                    Ok((y0, bw, rows.to_vec()))
                                };
                                match render_bands(&img, &opts, |_, _| Ok(()), f).unwrap() {
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
                            let a = render(&img, &input(d)).unwrap();
                            let b = whole(&img, &input(d));
                            assert_eq!(bits(&a), bits(&b), "input {w}x{h} {bayer} {d}");
                        }
                    }
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
            let a = render(&img, &RenderOptions::default()).unwrap();
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            let b = pool.install(|| render(&img, &RenderOptions::default()).unwrap());
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
        let a = render(&img, &opts).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| render(&img, &opts).unwrap());
        assert_eq!(a, b);
    }
}
