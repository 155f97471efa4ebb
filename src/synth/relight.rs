//! Running a plan's deterministic part: one fused pass per active-area row doing normalize
//! (docs/synthesis.md, "1. Normalize"), remove the day illuminant (2), dim (3), relight (5)
//! and denormalize (6), with rayon over rows and per-thread row buffers (no whole-image
//! temporaries per light). The plan's stage names `normalize`, `remove_day_illuminant`,
//! `dim`, `masks`, `relight_*`, `bulbs` and `denormalize` (listed by the plan's report) all run
//! here, in this one pass, not in functions of those names: `dim.rs` only draws the
//! factor, `masks.rs` evaluates the masks this pass asks for, and the normalize and
//! denormalize arithmetic is [`crate::normalize::Normalizer`]'s.
//!
//! Local relighting per row: `num = w0 * R0`, `den = w0` for the ambient light (mask 1);
//! each local light whose window covers the row adds `m * w * R_k` to `num` and `m * w` to
//! `den` over its column range only (`m` its mask, `R_k = clip(y_e * l_k[c] * gain_k, 0, 1)`);
//! `y_r = num / max(den, 1e-30)`; each bulb on the row adds `g * m * clip(y_e * l[c], 0, 1)`;
//! finally `y_r` is clipped to [0, 1]. Arithmetic per pixel is f32 (normalize and
//! denormalize are f64 via [`crate::normalize::Normalizer`]).
//!
//! Mode `day` changes nothing except what a clip cut (step 1's clip at 0, step 2's clip at
//! 1, the output range [0, white]): every other sample is the stored (linearized) input
//! value itself, whatever `truncate` says, not its f32 round trip (truncating that put
//! 33-39 % of samples 1 DN low).

use super::dim::dim_factor;
use super::light_row::{local_row, parity, parity2, Prepared, Scratch};
use super::masks::{LightKind, PreparedMask};
use super::plan::Plan;
use super::{Mode, SynthOutput};
use crate::error::Result;
use crate::normalize::{Normalizer, RoundClamp, SiteTable};
use crate::raw::crop::Crop;
use crate::raw::RawImage;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Values computed while running (recorded in the sidecar).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunReport {
    /// The dimming factor used.
    pub dim_scale: f64,
    /// Mean white-balanced intensity (only computed for a brightness-dictionary plan).
    pub mean_white_balanced: Option<f64>,
    /// Active-area sites saturated in the input (linear value >= white).
    pub saturated_sites: u64,
    /// Warnings about what the renders made (a target or network input that came out
    /// constant, [`crate::isp::flat`]).
    pub warnings: crate::diagnostics::Diagnostics,
}

/// Run normalize..denormalize: the clean night raw (whole stored image; outside the
/// ActiveArea the linearized input samples are kept). The result holds linear values and
/// the input's metadata (see [`super::night_meta`] for the metadata of outputs).
pub fn run_clean(img: &RawImage, plan: &Plan) -> Result<(RawImage, RunReport)> {
    let a = img.active_area();
    let pass = CleanPass::new(img, plan, Crop::whole(a.width(), a.height()))?;
    let (top, left, aw, ah) = (a.top as usize, a.left as usize, a.width(), a.height());
    let width = img.width;
    let norm = &pass.norm;
    // Whole stored image, linearized (so a dropped LinearizationTable stays truthful).
    // Without a table linearizing is the identity: a plain copy (the active-area rows are
    // overwritten below anyway).
    let mut data = crate::limits::try_with_capacity::<u16>(img.data.len(), "the clean night raw")?;
    if norm.is_identity() {
        data.extend_from_slice(&img.data);
    } else {
        img.data
            .par_iter()
            .map(|&x| norm.linearize(x).clamp(0.0, u16::MAX as f64) as u16)
            .collect_into_vec(&mut data);
    }
    let saturated: u64 = data
        .par_chunks_mut(width)
        .enumerate()
        .skip(top)
        .take(ah)
        .map_init(
            || Scratch::new(aw),
            |scr, (srow, row)| {
                let src = &img.data[srow * width..][..width];
                pass.row(srow - top, src, &mut row[left..left + aw], scr)
            },
        )
        .sum();
    let mut meta = img.meta.clone();
    meta.linearization_table = None;
    Ok((
        RawImage {
            width,
            height: img.height,
            data,
            meta,
        },
        pass.report(saturated),
    ))
}

/// [`run_clean`] computed in the day raw's own plane: each stored row is copied aside and
/// relit in place, so the clean raw takes the day plane's memory instead of a second plane
/// (the day samples are gone afterwards). The same image and report as [`run_clean`].
pub fn run_clean_in_place(mut img: RawImage, plan: &Plan) -> Result<(RawImage, RunReport)> {
    let a = img.active_area();
    let pass = CleanPass::new(&img, plan, Crop::whole(a.width(), a.height()))?;
    let (top, left, aw, ah) = (a.top as usize, a.left as usize, a.width(), a.height());
    let width = img.width;
    let norm = &pass.norm;
    let identity = norm.is_identity();
    let mut data = std::mem::take(&mut img.data);
    let saturated: u64 = data
        .par_chunks_mut(width.max(1))
        .enumerate()
        .map_init(
            || (Scratch::new(aw), Vec::with_capacity(width)),
            |(scr, src), (srow, row)| {
                let active = (top..top + ah).contains(&srow);
                if active {
                    src.clear();
                    src.extend_from_slice(row);
                }
                // outside the active area the linearized input is kept (as run_clean)
                if !identity {
                    for x in row.iter_mut() {
                        *x = norm.linearize(*x).clamp(0.0, u16::MAX as f64) as u16;
                    }
                }
                if active {
                    pass.row(srow - top, src, &mut row[left..left + aw], scr)
                } else {
                    0
                }
            },
        )
        .sum();
    img.data = data;
    img.meta.linearization_table = None;
    let report = pass.report(saturated);
    Ok((img, report))
}

/// [`run_clean`] on the active-area rectangle `crop` only: its clean night samples
/// (`crop.height` rows of `crop.width`, row-major), each equal to the same site of
/// [`run_clean`]'s image, computed without touching the rest of the frame (except the
/// whole-frame mean that a brightness-dictionary plan's dimming needs). The report's
/// `saturated_sites` counts the crop's sites. `crop.left` must be even (CFA phase).
pub fn run_clean_crop(img: &RawImage, plan: &Plan, crop: Crop) -> Result<(Vec<u16>, RunReport)> {
    let a = img.active_area();
    crop.check(a.width(), a.height())?;
    let pass = CleanPass::new(img, plan, crop)?;
    let mut data = crate::limits::try_filled(0u16, crop.width * crop.height, "the clean crop")?;
    let (top, width) = (a.top as usize, img.width);
    let saturated: u64 = data
        .par_chunks_mut(crop.width.max(1))
        .enumerate()
        .map_init(
            || Scratch::new(crop.width),
            |scr, (i, row)| {
                let src = &img.data[(crop.top + i + top) * width..][..width];
                pass.row(crop.top + i, src, row, scr)
            },
        )
        .sum();
    Ok((data, pass.report(saturated)))
}

/// The whole-frame mean white-balanced intensity `mean(y_w)` that a brightness-dictionary
/// plan's dimming divides by ([`super::dim::dim_factor`]), exactly as the clean pass computes
/// it (so a plan that carries it, [`Plan::frame_mean`], gives the same bytes). It reads
/// every active-area sample once.
pub fn frame_mean_y_w(img: &RawImage, plan: &Plan) -> Result<f64> {
    let mut plan = plan.clone();
    plan.frame_mean = Default::default();
    plan.dim = super::dim::DimPlan::None;
    plan.lights.clear();
    let a = img.active_area();
    let row = Crop {
        top: 0,
        left: 0,
        height: 1.min(a.height()),
        width: a.width(),
    };
    let pass = CleanPass::new(img, &plan, row)?;
    let yw_table = SiteTable::new(&pass.norm, |r, c, x| {
        pass.y_w(x, pass.norm.black_at(r, c), pass.inv_row(r)[c])
    });
    Ok(pass.mean_y_w(img, yw_table.as_ref()))
}

/// Everything one clean pass needs, prepared once for the columns `crop.left..` of
/// `crop.width` (the whole active area for [`run_clean`]); [`CleanPass::row`] computes one
/// row segment.
struct CleanPass<'a> {
    plan: &'a Plan,
    norm: Normalizer,
    /// Active-area left edge in the stored image and active-area width.
    left: usize,
    aw: usize,
    /// First column and width of the computed segment of every row.
    x0: usize,
    sw: usize,
    inv_n: [f64; 3],
    lo: f64,
    hi: f64,
    s: f64,
    mean_wb: Option<f64>,
    ye_table: Option<SiteTable<f32>>,
    ambient: Vec<Prepared>,
    locals: Vec<Prepared>,
    bulbs: Vec<Prepared>,
    day_n: [f32; 3],
}

impl<'a> CleanPass<'a> {
    fn new(img: &RawImage, plan: &'a Plan, crop: Crop) -> Result<CleanPass<'a>> {
        plan.check_against(img)?;
        let norm = Normalizer::new(img)?;
        let norm = if plan.range_per_site {
            norm.with_range_per_site()
        } else {
            norm
        };
        let a = img.active_area();
        let (left, aw, ah) = (a.left as usize, a.width(), a.height());
        let inv_n = plan.day_neutral.map(|v| 1.0 / v);
        let lo = if plan.keep_negative {
            f64::NEG_INFINITY
        } else {
            0.0
        };
        let hi = if plan.keep_highlights {
            f64::INFINITY
        } else {
            1.0
        };
        let mut pass = CleanPass {
            plan,
            norm,
            left,
            aw,
            x0: crop.left,
            sw: crop.width,
            inv_n,
            lo,
            hi,
            s: 1.0,
            mean_wb: None,
            ye_table: None,
            ambient: Vec::new(),
            locals: Vec::new(),
            bulbs: Vec::new(),
            day_n: plan.day_neutral.map(|v| v as f32),
        };
        // When the black level depends on the 2x2 position only (the usual case), y_w of
        // every stored value up to white is tabulated per position: the same expression,
        // so the same bits, one load instead of a division and two clamps per sample.
        let yw_table = SiteTable::new(&pass.norm, |r, c, x| {
            pass.y_w(x, pass.norm.black_at(r, c), pass.inv_row(r)[c])
        });
        let mut mean_wb = None;
        let s = dim_factor(&plan.dim, || {
            let m = plan
                .frame_mean
                .get(plan.mean_key())
                .unwrap_or_else(|| pass.mean_y_w(img, yw_table.as_ref()));
            mean_wb = Some(m);
            m
        });
        let s32 = s as f32;
        let cols = crop.left..crop.left + crop.width;
        let prep = |kind: LightKind| -> Vec<Prepared> {
            plan.lights
                .iter()
                .filter(|l| l.kind == kind)
                .map(|l| Prepared {
                    mask: PreparedMask::new_in(l, aw, ah, plan.mask_eval, cols.clone()),
                    illum: l.illuminant.map(|v| v as f32),
                    gain: l.gain as f32,
                    weight: l.weight as f32,
                })
                .collect()
        };
        pass.ye_table = yw_table.as_ref().map(|t| t.map(|v| v as f32 * s32));
        pass.ambient = prep(LightKind::Ambient);
        pass.locals = prep(LightKind::Local);
        pass.bulbs = prep(LightKind::Bulb);
        pass.s = s;
        pass.mean_wb = mean_wb;
        Ok(pass)
    }

    /// White-balanced value of a sample whose black level is `black`.
    #[inline]
    fn y_w(&self, x: u16, black: f64, inv: f64) -> f64 {
        let mut y = self.norm.normalize_with_black(x, black);
        if !self.plan.keep_negative && y < 0.0 {
            y = 0.0;
        }
        (y * inv).clamp(self.lo, self.hi)
    }

    /// `mean(y_w)` over the whole active area of `img` (rows summed in parallel, then the
    /// row sums in order: the same bits for any thread count); `yw_table` is the pass's
    /// table of `y_w` per stored value, when the black level allows one.
    fn mean_y_w(&self, img: &RawImage, yw_table: Option<&SiteTable<f64>>) -> f64 {
        let norm = &self.norm;
        let a = img.active_area();
        let (top, left, aw, ah) = (a.top as usize, a.left as usize, a.width(), a.height());
        let width = img.width;
        let sums: Vec<f64> = (0..ah)
            .into_par_iter()
            .map_init(
                || vec![0.0f64; aw],
                |blk, r| {
                    let row = &img.data[(r + top) * width + left..][..aw];
                    if let Some(t) = yw_table {
                        let (t0, t1) = t.row(r);
                        let mut sum = 0.0f64;
                        for (c, &x) in row.iter().enumerate() {
                            let tab = if c & 1 == 0 { t0 } else { t1 };
                            sum += match tab.get(x as usize) {
                                Some(&v) => v,
                                None => self.y_w(x, norm.black_at(r, c), self.inv_row(r)[c & 1]),
                            };
                        }
                        return sum;
                    }
                    norm.black_row(r, blk);
                    let k = self.inv_row(r);
                    row.iter()
                        .zip(blk.iter())
                        .enumerate()
                        .map(|(c, (&x, &b))| self.y_w(x, b, k[c & 1]))
                        .sum::<f64>()
                },
            )
            .collect();
        sums.iter().sum::<f64>() / (aw * ah) as f64
    }

    #[inline]
    fn inv_row(&self, r: usize) -> [f64; 2] {
        let bayer = self.plan.bayer;
        [
            self.inv_n[bayer.color_at(r, 0) as usize],
            self.inv_n[bayer.color_at(r, 1) as usize],
        ]
    }

    fn report(&self, saturated: u64) -> RunReport {
        RunReport {
            dim_scale: self.s,
            mean_white_balanced: self.mean_wb,
            saturated_sites: saturated,
            warnings: Default::default(),
        }
    }

    /// The clean night samples of active-area row `r`, columns `x0..x0 + sw`, into `seg`,
    /// from `stored`, the input's whole stored row `r + top`; returns the number of
    /// saturated input sites among them.
    fn row(&self, r: usize, stored: &[u16], seg: &mut [u16], scr: &mut Scratch) -> u64 {
        clean_row(self, r, stored, seg, scr)
    }

    /// [`CleanPass::row`]'s body.
    #[inline(always)]
    fn row_body(&self, r: usize, stored: &[u16], seg: &mut [u16], scr: &mut Scratch) -> u64 {
        let (norm, plan, x0, sw) = (&self.norm, self.plan, self.x0, self.sw);
        let s32 = self.s as f32;
        let white = norm.white;
        let src = &stored[self.left + x0..][..sw];
        let mut sat = 0u64;
        let k = self.inv_row(r);
        // Per-site black levels of the whole row (only without the table), taken out of the
        // scratch while the row is computed.
        let blk_row = std::mem::take(&mut scr.blk);
        let mut blk_row = blk_row;
        if self.ye_table.is_none() {
            blk_row.resize(self.aw, 0.0);
            norm.black_row(r, &mut blk_row);
        }
        let blk = &blk_row[x0.min(blk_row.len())..];
        if let Some(t) = &self.ye_table {
            let (t0, t1) = t.row(r);
            // the even and odd columns' tables
            let tabs = if x0 & 1 == 0 { [t0, t1] } else { [t1, t0] };
            // Flat loops, the table picked by the index's parity: the saturation count
            // becomes whole-register compares, and the lookups lose the pairs' bookkeeping
            // (docs/benchmarks.md, "Flat loops where the compiler had gone wrong").
            sat += if norm.is_identity() {
                src.iter().filter(|&&x| x as f64 >= white).count()
            } else {
                src.iter().filter(|&&x| norm.linearize(x) >= white).count()
            } as u64;
            for (i, (&x, ye)) in src.iter().zip(scr.ye.iter_mut()).enumerate() {
                let tab = if i & 1 == 0 { tabs[0] } else { tabs[1] };
                *ye = match tab.get(x as usize) {
                    Some(&v) => v,
                    None => {
                        let c = x0 + i;
                        self.y_w(x, norm.black_at(r, c), k[c & 1]) as f32 * s32
                    }
                };
            }
        } else {
            for (i, ((&x, ye), &b)) in src
                .iter()
                .zip(scr.ye.iter_mut())
                .zip(blk.iter())
                .enumerate()
            {
                let c = x0 + i;
                if norm.linearize(x) >= white {
                    sat += 1;
                }
                *ye = self.y_w(x, b, k[c & 1]) as f32 * s32;
            }
        }
        let bayer = plan.bayer;
        let cols = [bayer.color_at(r, 0) as usize, bayer.color_at(r, 1) as usize];
        let out = &mut scr.num;
        let day_n = self.day_n;
        match plan.mode {
            Mode::Day => {
                let k = parity([day_n[cols[0]], day_n[cols[1]]], x0);
                for (c, (o, &y)) in out.iter_mut().zip(&scr.ye).enumerate() {
                    *o = y * k[c & 1];
                }
            }
            Mode::Dimmed => {
                let k = parity([day_n[cols[0]], day_n[cols[1]]], x0);
                for (c, (o, &y)) in out.iter_mut().zip(&scr.ye).enumerate() {
                    *o = (y * k[c & 1]).clamp(0.0, 1.0);
                }
            }
            Mode::Global => {
                let l = self.ambient.first().map(|p| p.illum).unwrap_or([1.0; 3]);
                let k = parity([l[cols[0]], l[cols[1]]], x0);
                for (c, (o, &y)) in out.iter_mut().zip(&scr.ye).enumerate() {
                    *o = (y * k[c & 1]).clamp(0.0, 1.0);
                }
            }
            Mode::Local => local_row(r, x0, cols, &self.ambient, &self.locals, &self.bulbs, scr),
        }
        if self.ye_table.is_some() {
            // 2x2-periodic black: the even and odd columns' levels
            let b = parity2([norm.black_at(r, 0), norm.black_at(r, 1)], x0);
            if plan.truncate {
                for (pair, y) in seg.chunks_mut(2).zip(scr.num.chunks(2)) {
                    for ((d, &y), &b) in pair.iter_mut().zip(y).zip(&b) {
                        *d = norm.denormalize_with_black(y as f64, b, true);
                    }
                }
            } else {
                // `denormalize_with_black(y, b, false)` with its per-lane range and the
                // white level taken out of the loop: the same expression, so the same bits
                let range = b.map(|b| norm.range_at_black(b));
                let round = RoundClamp::new(norm.white.min(u16::MAX as f64));
                for (i, (d, &y)) in seg.iter_mut().zip(scr.num.iter()).enumerate() {
                    let (rg, bl) = if i & 1 == 0 {
                        (range[0], b[0])
                    } else {
                        (range[1], b[1])
                    };
                    *d = round.apply(y as f64 * rg + bl);
                }
            }
        } else {
            for ((d, &y), &b) in seg.iter_mut().zip(scr.num.iter()).zip(blk.iter()) {
                *d = norm.denormalize_with_black(y as f64, b, plan.truncate);
            }
        }
        scr.blk = blk_row;
        if plan.mode == Mode::Day {
            self.day_identity(r, src, seg);
        }
        sat
    }

    /// Mode `day`: every sample of `seg` (active-area row `r` from column `x0`, computed
    /// from `src`) that no clip changed becomes its linearized input value exactly.
    fn day_identity(&self, r: usize, src: &[u16], seg: &mut [u16]) {
        let norm = &self.norm;
        let k = self.inv_row(r);
        for (i, (&x, d)) in src.iter().zip(seg.iter_mut()).enumerate() {
            let c = self.x0 + i;
            let lin = norm.linearize(x);
            let y = norm.normalize_with_black(x, norm.black_at(r, c));
            let v = y * k[c & 1];
            let clipped = (!self.plan.keep_negative && y < 0.0)
                || v.clamp(self.lo, self.hi) != v
                || !(0.0..=norm.white.min(u16::MAX as f64)).contains(&lin)
                || lin.fract() != 0.0;
            if !clipped {
                *d = lin as u16;
            }
        }
    }
}

/// Run the whole plan: clean night raw plus one noisy raw per planned ISO, with output
/// metadata set (see [`super::night_meta`]).
pub fn run(img: &RawImage, plan: &Plan) -> Result<SynthOutput> {
    let (mut clean, report) = run_clean(img, plan)?;
    clean.meta = super::night_meta(&img.meta, plan, plan.clean_iso, &plan.clean_noise);
    let mut noisy = Vec::with_capacity(plan.noise.len());
    for i in 0..plan.noise.len() {
        noisy.push(super::run_noise(&clean, plan, i)?);
    }
    Ok(SynthOutput {
        clean,
        noisy,
        report,
    })
}

/// [`CleanPass::row`], compiled twice, the second time for AVX2, picked at run time (the
/// same operations per element, so the same bits; docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn clean_row(
    pass: &CleanPass<'_>,
    r: usize,
    stored: &[u16],
    seg: &mut [u16],
    scr: &mut Scratch,
) -> u64 {
    pass.row_body(r, stored, seg, scr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::Bayer;
    use crate::synth::{Calibration, Compat, Planner, SynthOptions};

    /// A 10-bit frame with stored values below black, across the range, at and above white.
    fn frame(bayer: Bayer, table: bool, delta: bool) -> RawImage {
        let (w, h) = (41usize, 27usize);
        let data = (0..w * h).map(|i| ((i * 7919) % 1400) as u16).collect();
        let mut meta = RawMeta::new_bayer(bayer, 10, 64.0, 1023.0);
        meta.as_shot_neutral = Some([0.6, 1.2, 0.3]);
        meta.levels.black = vec![60.0, 64.5, 66.0, 70.0];
        meta.levels.black_repeat = (2, 2);
        if table {
            // a curve with integer entries (LinearizationTable holds u16)
            meta.linearization_table = Some(
                (0..1200u32)
                    .map(|x| (x * 9 / 10 + x * x / 8000) as u16)
                    .collect(),
            );
        }
        if delta {
            meta.levels.black_delta_h = (0..w).map(|c| (c % 3) as f64 * 0.75).collect();
        }
        RawImage {
            width: w,
            height: h,
            data,
            meta,
        }
    }

    #[test]
    fn day_mode_returns_every_unclipped_sample_exactly() {
        for b in Bayer::ALL {
            for (table, delta) in [(false, false), (true, false), (false, true)] {
                let img = frame(b, table, delta);
                let norm = Normalizer::new(&img).unwrap();
                for (keep_negative, keep_highlights) in [(false, false), (true, true)] {
                    for truncate in [false, true] {
                        let stored = Compat {
                            neutral_as_stored: true,
                            ..Compat::default()
                        };
                        // the whole preset's switches (truncating the noise needs truncate)
                        let release = Compat {
                            truncate_noise: truncate,
                            ..Compat::RELEASE
                        };
                        for compat in [Compat::default(), stored, release] {
                            let norm = if compat.range_per_site {
                                norm.clone().with_range_per_site()
                            } else {
                                norm.clone()
                            };
                            let opts = SynthOptions {
                                mode: Mode::Day,
                                isos: vec![],
                                truncate,
                                keep_negative,
                                keep_highlights,
                                compat,
                                ..SynthOptions::default()
                            };
                            let cal = Calibration::embedded(&opts).unwrap();
                            let p = Planner::new(&img, &opts)
                                .calibration(&cal)
                                .name("d.dng")
                                .plan()
                                .map(|p| p.plan)
                                .unwrap();
                            let (out, _) = run_clean(&img, &p).unwrap();
                            let crop = Crop {
                                top: 2,
                                left: 4,
                                height: 20,
                                width: 31,
                            };
                            let (cropped, _) = run_clean_crop(&img, &p, crop).unwrap();
                            let (mut same, mut clipped) = (0, 0);
                            for r in 0..img.height {
                                for c in 0..img.width {
                                    let x = img.get(r, c);
                                    let lin = norm.linearize(x);
                                    let y = norm.normalize_with_black(x, norm.black_at(r, c));
                                    let v = y / p.day_neutral[b.color_at(r, c) as usize];
                                    let cut = (!keep_negative && y < 0.0)
                                        || (!keep_highlights && v > 1.0)
                                        || lin > 1023.0;
                                    if cut {
                                        clipped += 1;
                                    } else {
                                        same += 1;
                                        assert_eq!(out.get(r, c) as f64, lin, "{b} ({r},{c})");
                                    }
                                    if (2..22).contains(&r) && (4..35).contains(&c) {
                                        let k = (r - 2) * 31 + (c - 4);
                                        assert_eq!(cropped[k], out.get(r, c));
                                    }
                                }
                            }
                            assert!(same > 100 && clipped > 10, "{same} {clipped}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn range_per_site_puts_saturated_sites_at_white_on_every_black() {
        for b in Bayer::ALL {
            let img = frame(b, false, false);
            let opts = SynthOptions {
                isos: vec![],
                bulbs: Some(1),
                ..SynthOptions::default()
            }
            .release_compat()
            .unwrap();
            let cal = Calibration::embedded(&opts).unwrap();
            let mut p = Planner::new(&img, &opts)
                .calibration(&cal)
                .name("s.dng")
                .seed(1)
                .plan()
                .map(|p| p.plan)
                .unwrap();
            assert!(p.range_per_site);
            // one bulb over the whole frame, bright enough to saturate every lit site
            let bulb = p.lights.last_mut().unwrap();
            bulb.center = [13.0, 20.0];
            bulb.window = Some([27.0, 41.0]);
            bulb.gain = 1e15;
            let norm = Normalizer::new(&img).unwrap();
            let (on, _) = run_clean(&img, &p).unwrap();
            p.range_per_site = false;
            let (off, _) = run_clean(&img, &p).unwrap();
            let (mut lit, mut moved) = (0, 0);
            for r in 0..img.height {
                for c in 0..img.width {
                    if norm.normalize(img.get(r, c), r, c) <= 0.0 {
                        continue;
                    }
                    lit += 1;
                    // the release: y = 1 is white on every site
                    assert_eq!(on.get(r, c), 1023, "{b} ({r},{c})");
                    // white - black_max as the unit: 1 is white - (black_max - black)
                    let short = 70.0 - norm.black_at(r, c);
                    assert_eq!(
                        off.get(r, c) as f64,
                        (1023.0 - short).trunc(),
                        "{b} ({r},{c})"
                    );
                    moved += (short > 0.0) as u32;
                }
            }
            assert!(lit > 500 && moved > 300, "{lit} {moved}");
        }
    }

    #[test]
    fn range_per_site_changes_nothing_with_one_black_level() {
        let mut img = frame(Bayer::GBRG, false, false);
        img.meta.levels.black = vec![64.0];
        img.meta.levels.black_repeat = (1, 1);
        let opts = SynthOptions {
            isos: vec![],
            ..SynthOptions::default()
        }
        .release_compat()
        .unwrap();
        let cal = Calibration::embedded(&opts).unwrap();
        let mut p = Planner::new(&img, &opts)
            .calibration(&cal)
            .name("o.dng")
            .seed(4)
            .plan()
            .map(|p| p.plan)
            .unwrap();
        let (on, _) = run_clean(&img, &p).unwrap();
        p.range_per_site = false;
        let (off, _) = run_clean(&img, &p).unwrap();
        assert_eq!(on.data, off.data);
    }

    #[test]
    fn in_place_gives_run_clean_s_image_and_report() {
        use crate::raw::Rect;
        for mode in [Mode::Day, Mode::Dimmed, Mode::Global, Mode::Local] {
            for (table, delta, area) in [
                (false, false, false),
                (true, false, true),
                (false, true, false),
            ] {
                let mut img = frame(Bayer::GRBG, table, delta);
                if area {
                    img.meta.active_area = Some(Rect {
                        top: 2,
                        left: 4,
                        bottom: 25,
                        right: 38,
                    });
                }
                let opts = SynthOptions {
                    mode,
                    isos: vec![],
                    bulbs: Some(2),
                    ..SynthOptions::default()
                };
                let cal = Calibration::embedded(&opts).unwrap();
                let p = Planner::new(&img, &opts)
                    .calibration(&cal)
                    .name("i.dng")
                    .seed(3)
                    .plan()
                    .map(|p| p.plan)
                    .unwrap();
                let (a, ra) = run_clean(&img, &p).unwrap();
                let (b, rb) = run_clean_in_place(img.clone(), &p).unwrap();
                assert_eq!(a.data, b.data, "{mode:?} {table} {delta} {area}");
                assert_eq!((a.width, a.height, &a.meta), (b.width, b.height, &b.meta));
                assert_eq!(ra, rb);
                // the pass changed something (not a copy of the input)
                assert_ne!(a.data, img.data, "{mode:?}");
            }
        }
    }
}
