//! The render stages with opcodes, in the Adobe DNG SDK's order (DNG 1.6 ch. 6):
//! 1. OpcodeList1 on a copy of the stored values (stored-image coordinates, stored units),
//!    rounded back to 16 bits;
//! 2. normalization (the shared [`Normalizer`](crate::normalize::Normalizer): linearization, black, scale) pinned into
//!    [0, 1] like the SDK's 16-bit stage-2 image, then OpcodeList2 (active-area coordinates);
//! 3. white balance by the neutral and clip (as the plain render), demosaic;
//! 4. OpcodeList3 on the demosaiced camera RGB of the active area: the white balance is
//!    taken out for it (`x * n`, pinned into [0, 1] like the SDK's stage-3 image) and put
//!    back after, so non-linear opcodes see camera values;
//! 5. the caller's per-row `post` (colour matrix, or the [0, 1] clip of the network input),
//!    then DefaultCrop and orientation (DefaultCrop intersected with a TrimBounds).
//!
//! Only files with applicable opcodes take this path ([`super::active`]); it holds a
//! normalized CFA plane and the RGB image of the active area (no banding). A crop's render
//! (`render_crop`) computes the same expressions on the crop's rectangle, so it equals the
//! frame render's region bit for bit, when every applied opcode is pointwise
//! ([`super::Prepared::needs_whole_frame`]).

use super::{apply_region, pin, Prepared, Region, StageRect};
use crate::dng::opcodes::{ListId, Opcode, OpcodeKind};
use crate::error::{Error, Result};
use crate::isp::color::normalize_neutral;
use crate::isp::demosaic::{demosaic_rect, demosaic_rows, row_kernel, Demosaic, Post, RowDemosaic};
use crate::isp::geometry::{apply_geometry, orient_image};
use crate::isp::pre_demosaic::CfaSites;
use crate::isp::rgb::RgbImage;
use crate::raw::crop::Crop;
use crate::raw::{Bayer, RawImage};
use rayon::prelude::*;

/// Rows per parallel band.
const BAND: usize = 32;

/// OpcodeList1 on the stored samples `data` of the stored-image rectangle at (`top`,
/// `left`) of `width x height` pixels, in an image of `stored_w x stored_h`. Returns the new
/// samples (rounded, pinned to 16 bits).
pub fn stage1(
    ops: &[Opcode],
    data: &[u16],
    rect: (usize, usize, usize, usize),
    stored: (usize, usize),
) -> Vec<u16> {
    stage1_planes(ops, data, 1, rect, stored)
}

/// [`stage1`] on `planes` interleaved samples per pixel (3 for a LinearRaw image).
pub fn stage1_planes(
    ops: &[Opcode],
    data: &[u16],
    planes: usize,
    (top, left, width, height): (usize, usize, usize, usize),
    (stored_w, stored_h): (usize, usize),
) -> Vec<u16> {
    let mut f: Vec<f32> = data.iter().map(|&v| v as f32).collect();
    let mut reg = Region {
        data: &mut f,
        top,
        left,
        width,
        height,
        planes,
        extent: StageRect::of_size(stored_w, stored_h),
        range: 65535.0,
    };
    apply_region(ops, &mut reg);
    f.iter().map(|&v| pin(v, 65535.0).round() as u16).collect()
}

/// The stage-2 plane of an active-area rectangle: normalized values pinned into [0, 1],
/// OpcodeList2 applied.
struct Stage2 {
    data: Vec<f32>,
    top: usize,
    left: usize,
    width: usize,
}

impl Stage2 {
    #[inline]
    fn get(&self, r: usize, c: usize) -> f32 {
        self.data[(r - self.top) * self.width + (c - self.left)]
    }
}

/// Normalize the stored samples `at(r, c)` (active-area coordinates) of `rect` and apply
/// `ops` (OpcodeList2) over an active area of `aw x ah`.
fn stage2(
    sites: &CfaSites,
    at: &(dyn Fn(usize, usize) -> u16 + Sync),
    rect: &Crop,
    ops: &[Opcode],
    (aw, ah): (usize, usize),
) -> Result<Stage2> {
    let n = rect.width * rect.height;
    let mut data = crate::limits::try_filled(0.0f32, n, "a normalized CFA plane")?;
    data.par_chunks_mut(rect.width.max(1))
        .enumerate()
        .for_each(|(i, row)| {
            let r = rect.top + i;
            for (k, o) in row.iter_mut().enumerate() {
                let c = rect.left + k;
                *o = sites.stage2(at(r, c), r, c);
            }
        });
    let mut reg = Region {
        data: &mut data,
        top: rect.top,
        left: rect.left,
        width: rect.width,
        height: rect.height,
        planes: 1,
        extent: StageRect::of_size(aw, ah),
        range: 1.0,
    };
    apply_region(ops, &mut reg);
    Ok(Stage2 {
        data,
        top: rect.top,
        left: rect.left,
        width: rect.width,
    })
}

/// Demosaic the rectangle `out` of the white-balanced, clipped stage-2 plane (which must
/// hold `out` and the demosaicer's neighbourhood, or the whole active area for Menon).
fn demosaic_stage(
    s2: &Stage2,
    (bayer, sites): (Bayer, &CfaSites),
    method: Demosaic,
    out: &Crop,
    (aw, ah): (usize, usize),
) -> Result<RgbImage> {
    let site = |r: usize, c: usize| -> f32 { sites.balanced(s2.get(r, c), r, c) };
    let Some(kernel) = row_kernel(method) else {
        if (out.width, out.height) != (aw, ah) {
            return Err(Error::unsupported(format!(
                "a crop render needs a row demosaicer (bilinear or mhc), not {}",
                method.name()
            )));
        }
        return Ok(demosaic_rows(
            aw,
            ah,
            bayer,
            method,
            |r, row| {
                for (c, o) in row.iter_mut().enumerate() {
                    *o = site(r, c);
                }
            },
            &|_| {},
        ));
    };
    let mut rgb = RgbImage::try_new(out.width, out.height)?;
    let w = out.width;
    rgb.data
        .par_chunks_mut(3 * w * BAND)
        .enumerate()
        .for_each(|(bi, band)| {
            let r0 = out.top + bi * BAND;
            let rows = r0..r0 + band.len() / (3 * w);
            let cfa = RowDemosaic {
                width: aw,
                height: ah,
                bayer,
                kernel,
            };
            demosaic_rect(
                cfa,
                rows,
                out.cols(),
                |r, cs, o| {
                    for (v, &c) in o.iter_mut().zip(cs) {
                        *v = site(r, c);
                    }
                },
                &|_| {},
                |i, px| band[3 * w * i..][..3 * w].copy_from_slice(px),
            );
        });
    Ok(rgb)
}

/// The stage-3 image: `rgb` covers (`top`, `left`) .. of the image `extent`.
pub(crate) struct Stage3 {
    /// Samples (three planes, in [0, 1]).
    pub(crate) rgb: RgbImage,
    /// Stage row of the first row.
    pub(crate) top: usize,
    /// Stage column of the first column.
    pub(crate) left: usize,
    /// The whole stage image (moved by a TrimBounds).
    pub(crate) extent: StageRect,
}

/// OpcodeList3 on the white-balanced camera RGB `s3` (white balance `n` taken out and put
/// back). Warps and TrimBounds need `s3` to cover its extent (the whole frame).
fn stage3(ops: &[Opcode], s3: &mut Stage3, n: [f64; 3]) -> Result<()> {
    if ops.is_empty() {
        return Ok(());
    }
    let nf = n.map(|v| v as f32);
    let inv = n.map(|v| (1.0 / v) as f32);
    s3.rgb.data.par_chunks_mut(3 * 1024).for_each(|c| {
        for px in c.chunks_exact_mut(3) {
            for k in 0..3 {
                px[k] = pin(px[k] * nf[k], 1.0);
            }
        }
    });
    apply_list3(ops, s3)?;
    s3.rgb.data.par_chunks_mut(3 * 1024).for_each(|c| {
        for px in c.chunks_exact_mut(3) {
            for k in 0..3 {
                px[k] *= inv[k];
            }
        }
    });
    Ok(())
}

/// OpcodeList3 `ops` on the camera RGB `s3` (values in [0, 1], no white balance): runs of
/// in-place opcodes through [`apply_region`], warps and TrimBounds one by one (they need
/// `s3` to cover its extent).
pub(crate) fn apply_list3(ops: &[Opcode], s3: &mut Stage3) -> Result<()> {
    let mut i = 0;
    while i < ops.len() {
        // Runs of in-place opcodes go through apply_region; warps and trims one by one.
        let j = ops[i..]
            .iter()
            .position(|o| moves_pixels(&o.kind))
            .map_or(ops.len(), |k| i + k);
        if j > i {
            let (w, h) = (s3.rgb.width, s3.rgb.height);
            let mut reg = Region {
                data: &mut s3.rgb.data,
                top: s3.top,
                left: s3.left,
                width: w,
                height: h,
                planes: 3,
                extent: s3.extent,
                range: 1.0,
            };
            apply_region(&ops[i..j], &mut reg);
        }
        if j == ops.len() {
            break;
        }
        let whole = s3.top as i64 == s3.extent.t
            && s3.left as i64 == s3.extent.l
            && s3.rgb.width as i64 == s3.extent.w()
            && s3.rgb.height as i64 == s3.extent.h();
        if !whole {
            return Err(Error::invalid(format!(
                "OpcodeList3: {} needs the whole image, not a crop",
                ops[j].name()
            )));
        }
        match &ops[j].kind {
            OpcodeKind::TrimBounds { bounds } => {
                let (d, b) = super::trim::trim(&s3.rgb.data, 3, s3.extent, *bounds)?;
                s3.rgb = RgbImage {
                    width: b.w() as usize,
                    height: b.h() as usize,
                    data: d,
                };
                s3.extent = b;
                s3.top = b.t as usize;
                s3.left = b.l as usize;
            }
            kind => {
                use super::warp::{apply, Warp};
                let warp = Warp::of_opcode(kind, s3.extent, 3).unwrap_or_else(|| {
                    Err(Error::invalid(format!(
                        "OpcodeList3: {} is not a warp",
                        ops[j].name()
                    )))
                })?;
                let (w, h) = (s3.rgb.width, s3.rgb.height);
                s3.rgb.data = apply(&warp, &s3.rgb.data, w, h, 3, s3.extent);
            }
        }
        i = j + 1;
    }
    Ok(())
}

/// True for the list-3 opcodes that move pixels (warps) or the image (TrimBounds).
pub(crate) fn moves_pixels(kind: &OpcodeKind) -> bool {
    matches!(
        kind,
        OpcodeKind::WarpRectilinear { .. }
            | OpcodeKind::WarpRectilinear2 { .. }
            | OpcodeKind::WarpFisheye { .. }
            | OpcodeKind::TrimBounds { .. }
    )
}

/// The active area of `img` as (width, height, top, left), checked to be non-empty and
/// inside the pixel buffer (the opcode paths index the buffer directly).
pub(crate) fn checked_active(img: &RawImage) -> Result<(usize, usize, usize, usize)> {
    let a = img.active_area();
    let (aw, ah) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    if aw == 0 || ah == 0 || (top + ah - 1) * img.width + left + aw > img.data.len() {
        return Err(Error::invalid(
            "the active area is empty or outside the pixel buffer",
        ));
    }
    Ok((aw, ah, top, left))
}

/// The stage-3 image of the whole frame of `img` with the opcodes `p` (white balanced by
/// the normalized neutral `n`), before `post`.
fn frame_stage3(
    img: &RawImage,
    p: &Prepared,
    sites: &CfaSites,
    n: [f64; 3],
    method: Demosaic,
) -> Result<Stage3> {
    let bayer = img.bayer()?;
    let (aw, ah, top, left) = checked_active(img)?;
    let l1 = p.list(ListId::List1);
    let stored: std::borrow::Cow<[u16]> = if l1.is_empty() {
        std::borrow::Cow::Borrowed(&img.data)
    } else {
        std::borrow::Cow::Owned(stage1(
            l1,
            &img.data,
            (0, 0, img.width, img.height),
            (img.width, img.height),
        ))
    };
    let sw = img.width;
    let at = |r: usize, c: usize| stored[(r + top) * sw + left + c];
    let whole = Crop::whole(aw, ah);
    let s2 = stage2(sites, &at, &whole, p.list(ListId::List2), (aw, ah))?;
    let rgb = demosaic_stage(&s2, (bayer, sites), method, &whole, (aw, ah))?;
    drop(s2);
    let mut s3 = Stage3 {
        rgb,
        top: 0,
        left: 0,
        extent: StageRect::of_size(aw, ah),
    };
    stage3(p.list(ListId::List3), &mut s3, n)?;
    Ok(s3)
}

/// The active-area rectangle `region` of the whole-frame render of `img` with the opcodes
/// `p` (no DefaultCrop, no orientation): what a crop's target is when the opcodes need the
/// whole frame. Errors when a TrimBounds removed part of `region`.
pub(crate) fn render_frame_region(
    img: &RawImage,
    p: &Prepared,
    sites: &CfaSites,
    neutral: [f64; 3],
    method: Demosaic,
    post: &Post,
    region: &Crop,
) -> Result<RgbImage> {
    let n = normalize_neutral(neutral)?;
    let s3 = frame_stage3(img, p, sites, n, method)?;
    let b = s3.extent;
    let inside = region.top as i64 >= b.t
        && region.left as i64 >= b.l
        && (region.top + region.height) as i64 <= b.b
        && (region.left + region.width) as i64 <= b.r;
    if !inside || region.width == 0 || region.height == 0 {
        return Err(Error::invalid(format!(
            "the crop {region:?} is not inside the image left by OpcodeList3's TrimBounds"
        )));
    }
    let (w, x0) = (s3.rgb.width, (region.left as i64 - b.l) as usize);
    let mut out = RgbImage::try_new(region.width, region.height)?;
    for (y, row) in out.data.chunks_exact_mut(3 * region.width).enumerate() {
        let sy = (region.top as i64 - b.t) as usize + y;
        row.copy_from_slice(&s3.rgb.data[3 * (sy * w + x0)..][..3 * region.width]);
        post(row);
    }
    Ok(out)
}

/// The whole-frame render of `img` with the opcodes `p`: the pre-demosaic step `sites`
/// around OpcodeList2, `method`, OpcodeList3 (the white balance by `neutral` taken out
/// and put back), `post` on every row of the stage-3 image, then
/// DefaultCrop (if `crop`) and orientation (if `orient`).
pub(crate) fn render_frame(
    img: &RawImage,
    p: &Prepared,
    sites: &CfaSites,
    neutral: [f64; 3],
    method: Demosaic,
    post: &Post,
    (crop, orient): (bool, bool),
) -> Result<RgbImage> {
    let n = normalize_neutral(neutral)?;
    let a = img.active_area();
    let (aw, ah) = (a.width(), a.height());
    let mut s3 = frame_stage3(img, p, sites, n, method)?;
    let w = s3.rgb.width.max(1);
    s3.rgb.data.par_chunks_mut(3 * w).for_each(post);
    finish_geometry(s3.rgb, s3.extent, &img.meta, (aw, ah), crop, orient)
}

/// DefaultCrop (if `crop`) and orientation (if `orient`) of the stage-3 image `rgb` of the
/// stage extent `b` in an active area of `aw x ah`: after a TrimBounds, the DefaultCrop
/// (or the whole area) intersected with `b`.
pub(crate) fn finish_geometry(
    rgb: RgbImage,
    b: StageRect,
    meta: &crate::raw::meta::RawMeta,
    (aw, ah): (usize, usize),
    crop: bool,
    orient: bool,
) -> Result<RgbImage> {
    if b == StageRect::of_size(aw, ah) {
        return Ok(apply_geometry(rgb, meta, crop, orient));
    }
    // Trimmed: DefaultCrop (or the whole area) intersected with the trimmed extent.
    let k = b.kept(meta, (aw, ah), crop)?;
    let cut = Crop {
        top: (k.t - b.t) as usize,
        left: (k.l - b.l) as usize,
        height: k.h() as usize,
        width: k.w() as usize,
    };
    let sw = rgb.width;
    let mut data = Vec::with_capacity(3 * cut.width * cut.height);
    for y in cut.top..cut.top + cut.height {
        data.extend_from_slice(&rgb.data[3 * (y * sw + cut.left)..][..3 * cut.width]);
    }
    let out = RgbImage {
        width: cut.width,
        height: cut.height,
        data,
    };
    Ok(if orient && (2..=8).contains(&meta.orientation) {
        orient_image(&out, meta.orientation)
    } else {
        out
    })
}

/// The stored samples `plane` of the active-area rectangle `outer` (row by row).
#[derive(Clone, Copy)]
pub struct StoredCrop<'a> {
    /// The rectangle the samples cover.
    pub outer: &'a Crop,
    /// Its samples.
    pub plane: &'a [u16],
}

/// The render of the active-area rectangle `crop` of a frame (levels and colour from
/// `frame`, normalized by `sites`: LinearizationTable ignored as in
/// [`crate::isp::render_crop`]) from the stored
/// samples `stored` (whose rectangle holds the crop and the demosaicer's margin), with the
/// pointwise opcodes `p`: the same expressions as [`render_frame`], so the result equals
/// the frame render's region (before DefaultCrop and orientation).
pub(crate) fn render_crop(
    frame: &RawImage,
    p: &Prepared,
    (sites, neutral): (&CfaSites, [f64; 3]),
    method: Demosaic,
    stored: StoredCrop,
    crop: &Crop,
    post: &Post,
) -> Result<RgbImage> {
    let StoredCrop { outer, plane } = stored;
    if p.needs_whole_frame() {
        return Err(Error::invalid(
            "the file's opcodes (bad pixels, warps, TrimBounds) need the whole frame: render it and cut the crop",
        ));
    }
    let n = normalize_neutral(neutral)?;
    let bayer = frame.bayer()?;
    let a = frame.active_area();
    let (aw, ah) = (a.width(), a.height());
    let l1 = p.list(ListId::List1);
    let values: std::borrow::Cow<[u16]> = if l1.is_empty() {
        std::borrow::Cow::Borrowed(plane)
    } else {
        std::borrow::Cow::Owned(stage1(
            l1,
            plane,
            (
                outer.top + a.top as usize,
                outer.left + a.left as usize,
                outer.width,
                outer.height,
            ),
            (frame.width, frame.height),
        ))
    };
    let at = |r: usize, c: usize| values[(r - outer.top) * outer.width + (c - outer.left)];
    let s2 = stage2(sites, &at, outer, p.list(ListId::List2), (aw, ah))?;
    let rgb = demosaic_stage(&s2, (bayer, sites), method, crop, (aw, ah))?;
    let mut s3 = Stage3 {
        rgb,
        top: crop.top,
        left: crop.left,
        extent: StageRect::of_size(aw, ah),
    };
    stage3(p.list(ListId::List3), &mut s3, n)?;
    let w = s3.rgb.width.max(1);
    s3.rgb.data.par_chunks_mut(3 * w).for_each(post);
    Ok(s3.rgb)
}
