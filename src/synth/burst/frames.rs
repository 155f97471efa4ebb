//! The noisy frames of a burst: frame k at an ISO is frame k's clean raw (the clean night
//! raw itself for an identity frame, else its warp: [`super::warp`]) plus that ISO's noise
//! drawn from the frame's own seed ([`super::motion::frame_noise_seed`]). Whole frames are
//! made row by row on demand ([`FrameRows`], a [`RowSource`] the DNG writer packs strip by
//! strip), crops as planes (`frame_crop`).

use super::motion::{frame_noise_seed, FrameTransform};
use super::warp::{CleanSource, WarpLevels, Warper, TILE};
use crate::error::{Error, Result};
use crate::noise::apply::{apply_noise_crop_stream, gaussian_map};
use crate::noise::apply_physics_noise_crop;
use crate::noise::physics_apply::with_physics_map;
use crate::normalize::Normalizer;
use crate::raw::crop::Crop;
use crate::raw::meta::RawMeta;
use crate::raw::rows::{plane_max, ActiveRowMap, MappedRows, RowSource};
use crate::raw::RawImage;
use crate::synth::relight::run_clean_crop;
use crate::synth::{night_meta, with_noisy_rows, NoisePlan, Plan};
use rayon::prelude::*;

/// The warp levels of `plan` on a clean raw normalized by `norm`.
fn levels<'a>(plan: &Plan, norm: &'a Normalizer) -> WarpLevels<'a> {
    WarpLevels {
        norm,
        bayer: plan.bayer,
        neutral: plan.night_neutral,
        active: (plan.active_width, plan.active_height),
        keep_negative: plan.keep_negative,
        truncate: plan.truncate,
    }
}

/// Frame `frame`'s transform in `plan` (an error when the plan has no such frame).
pub fn transform(plan: &Plan, frame: u32) -> Result<&FrameTransform> {
    plan.burst
        .as_ref()
        .and_then(|b| b.transforms.get(frame as usize))
        .ok_or_else(|| Error::invalid(format!("the plan has no burst frame {frame}")))
}

/// The interpolant of the plan's burst (a frame other than 00 exists only in a burst).
fn interp_of(plan: &Plan) -> Result<super::Interp> {
    plan.burst
        .as_ref()
        .map(|b| b.interp)
        .ok_or_else(|| Error::invalid("the plan has no burst"))
}

/// The noisy raw of frame `frame` at the plan's `index`-th ISO as rows made on demand,
/// handed to `f` with its ISO and output metadata. Frame 0 is exactly the single-frame
/// noisy raw ([`with_noisy_rows`]).
pub fn with_frame_rows<T>(
    clean: &RawImage,
    plan: &Plan,
    index: usize,
    frame: u32,
    f: impl FnOnce(u32, &RawMeta, &dyn RowSource) -> Result<T>,
) -> Result<T> {
    if frame == 0 {
        return with_noisy_rows(clean, plan, index, f);
    }
    let t = transform(plan, frame)?;
    let interp = interp_of(plan)?;
    let np = noise_plan(plan, index)?;
    let seed = frame_noise_seed(np.seed, frame);
    let meta = night_meta(&clean.meta, plan, np.iso, &np.params);
    let norm = Normalizer::new(clean)?;
    let lv = levels(plan, &norm);
    let a = clean.active_area();
    let warper = (!t.is_identity()).then(|| {
        let src = CleanSource {
            data: &clean.data,
            stride: clean.width,
            offset: a.top as usize * clean.width + a.left as usize,
            rows: 0..a.height(),
            cols: 0..a.width(),
        };
        Warper::new(src, &lv, t.inverse(), interp)
    });
    let run = |map: &dyn ActiveRowMap| {
        let rows = FrameRows {
            clean,
            warper: warper.as_ref(),
            map,
        };
        f(np.iso, &meta, &rows)
    };
    match &np.physics {
        Some(p) => with_physics_map(clean, p, seed, run),
        None => run(&gaussian_map(
            clean,
            &np.params,
            seed,
            plan.truncate_noise,
            plan.noise_stream,
        )?),
    }
}

fn noise_plan(plan: &Plan, index: usize) -> Result<&NoisePlan> {
    plan.noise
        .get(index)
        .ok_or_else(|| Error::invalid(format!("plan has no noise entry {}", index)))
}

/// A burst frame's rows: the clean raw's rows with the active-area part replaced by the
/// frame's clean samples (the warp; the clean raw's own for an identity frame), then
/// noised by `map`. Samples outside the active area are the clean raw's.
pub struct FrameRows<'a> {
    clean: &'a RawImage,
    warper: Option<&'a Warper<'a>>,
    map: &'a dyn ActiveRowMap,
}

impl RowSource for FrameRows<'_> {
    fn width(&self) -> usize {
        self.clean.width
    }
    fn height(&self) -> usize {
        self.clean.height
    }
    fn max_bound(&self) -> u16 {
        plane_max(&self.clean.data).max(self.map.bound())
    }
    fn fill_rows(&self, y0: usize, out: &mut [u16]) {
        let Some(warper) = self.warper else {
            return MappedRows::new(self.clean, self.map).fill_rows(y0, out);
        };
        let w = self.clean.width;
        let n = out.len() / w.max(1);
        out.copy_from_slice(&self.clean.data[y0 * w..(y0 + n) * w]);
        let a = self.clean.active_area();
        let (top, bottom, left) = (a.top as usize, a.bottom as usize, a.left as usize);
        // the active rows among y0..y0 + n, in active-area coordinates
        let (s, e) = (y0.max(top), (y0 + n).min(bottom));
        if s >= e {
            return;
        }
        let at = (s - y0) * w;
        warper.fill(s - top..e - top, 0..a.width(), &mut out[at..], (w, left));
        let mut scratch = Vec::new();
        for (i, row) in out[at..].chunks_exact_mut(w).take(e - s).enumerate() {
            let seg = &mut row[left..left + a.width()];
            self.map.map_row(s - top + i, seg, &mut scratch);
        }
    }
}

/// Frame `frame`'s clean samples of the active-area rectangle `crop` (frame-k
/// coordinates), computed from the part of the clean scene they read only: equal to the
/// same region of the whole frame's clean samples.
pub fn frame_clean_crop(day: &RawImage, plan: &Plan, crop: &Crop, frame: u32) -> Result<Vec<u16>> {
    let t = transform(plan, frame)?;
    let interp = interp_of(plan)?;
    let (aw, ah) = (plan.active_width, plan.active_height);
    crop.check(aw, ah)?;
    let inv = t.inverse();
    // the taps' window plus the demosaicer's neighbourhood, with even offsets
    let (wr, wc) = Warper::source_window(
        &inv,
        interp,
        (aw, ah),
        (&crop.rows(), &crop.cols()),
        crate::isp::demosaic::PAD,
    );
    let win = Crop {
        top: wr.start & !1,
        left: wc.start & !1,
        height: wr.end - (wr.start & !1),
        width: wc.end - (wc.start & !1),
    };
    let (plane, _) = run_clean_crop(day, plan, win)?;
    // the clean raw's levels: the day's, linear (the night metadata drops the table)
    let norm = Normalizer::new(day)?.without_linearization();
    let lv = levels(plan, &norm);
    let src = CleanSource {
        data: &plane,
        stride: win.width,
        offset: 0,
        rows: win.rows(),
        cols: win.cols(),
    };
    let warper = Warper::new(src, &lv, inv, interp);
    let mut out = crate::limits::try_filled(0u16, crop.width * crop.height, "a burst frame")?;
    out.par_chunks_mut(crop.width * TILE)
        .enumerate()
        .for_each(|(i, band)| {
            let r0 = crop.top + i * TILE;
            let r1 = (r0 + TILE).min(crop.top + crop.height);
            warper.fill(r0..r1, crop.cols(), band, (crop.width, 0));
        });
    Ok(out)
}

/// The clean samples of `crop` in a burst's frames 1.. (`clean` is frame 00's): an
/// identity frame's are frame 00's, a moved frame's its warp ([`frame_clean_crop`]).
pub fn clean_crops(
    day: &RawImage,
    plan: &Plan,
    crop: &Crop,
    clean: &[u16],
) -> Result<Vec<Vec<u16>>> {
    let n = plan.burst.as_ref().map_or(1, |b| b.frames);
    (1..n)
        .map(|k| {
            if transform(plan, k)?.is_identity() {
                Ok(clean.to_vec())
            } else {
                frame_clean_crop(day, plan, crop, k)
            }
        })
        .collect()
}

/// Frame `frame`'s noisy samples of `crop` at the plan's noise entry `np` from its clean
/// crop samples `clean` (the crop's own Gaussian stream, or the frame's physics draws at
/// the crop's sites), with the frame's noise seed.
pub fn frame_noisy_crop(
    day: &RawImage,
    plan: &Plan,
    crop: &Crop,
    np: &NoisePlan,
    frame: u32,
    clean: &[u16],
) -> Result<Vec<u16>> {
    let seed = frame_noise_seed(np.seed, frame);
    match &np.physics {
        Some(p) => apply_physics_noise_crop(day, crop, clean, p, seed),
        None => {
            let mut data = clean.to_vec();
            apply_noise_crop_stream(
                day,
                crop,
                &mut data,
                &np.params,
                (seed, plan.truncate_noise),
                plan.noise_stream,
            )?;
            Ok(data)
        }
    }
}
