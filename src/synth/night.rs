//! The one synthesis path of an (input, variant): compute every product of a [`Plan`] into
//! memory or into a [`NightSink`] that consumes each product as it is made. `day2night
//! synth`, `day2night dataset` (through [`super::job::SynthJob`], whose sink encodes and
//! writes files) and the Python package (through [`synthesize`], which keeps everything in
//! memory) all run [`synthesize_into`], so their pixels cannot drift apart.
//!
//! Products, computed only when asked for ([`Request`]):
//! 1. the clean night raw (always): [`run_clean`] + [`night_meta`];
//! 2. one noisy raw per planned ISO, one after another, each handed over as rows made on
//!    demand ([`NightSink::noisy_rows`]: a file sink never holds a noisy plane; the first
//!    is made whole by [`run_noise`] when the network input is rendered from it);
//! 3. the linear target rendered from the clean raw (`request.target`), band by band when
//!    the sink can take bands ([`NightSink::banded`]), else as one image;
//! 4. the network input render of the first noisy raw (`request.input`, whole frame only).
//!
//! For a whole frame, 1's hand-over, 2 and 3 run as concurrent rayon tasks; errors are
//! reported in a fixed order (clean, noisy, target). With `request.crop` only the crop is
//! computed: the plan stays the whole frame's (lights, bulbs, illuminants), the clean pass
//! covers the crop plus the demosaicer's margin ([`run_clean_crop`]), the crop's Gaussian
//! noise draws from its own documented stream
//! ([`crate::noise::apply::apply_noise_crop_with`]; the physics model's draws are per site,
//! so a crop gets the frame's samples: [`crate::noise::apply_physics_noise_crop`])
//! and the target is the crop's region of the frame's render ([`crate::isp::render::render_crop`]).
//!
//! ```no_run
//! use day2night::synth::night::{synthesize, Request};
//! use day2night::raw::crop::Crop;
//! use day2night::synth::{self, Calibration, SynthOptions};
//! # fn main() -> day2night::Result<()> {
//! let day = day2night::dng::read_dng("day.dng".as_ref())?;
//! let opts = SynthOptions::default();
//! let cal = Calibration::embedded(&opts)?;
//! let plan = synth::Planner::new(&day, &opts).calibration(&cal).name("day.dng").plan()?.plan;
//! let crop = Crop { top: 512, left: 1024, height: 512, width: 512 };
//! let night = synthesize(&day, &plan, &Request { target: true, input: false, crop: Some(crop) })?;
//! assert_eq!(night.clean.data.len(), 512 * 512);
//! # Ok(()) }
//! ```

use super::burst::frames::{clean_crops, frame_noisy_crop, with_frame_rows};
use super::relight::{run_clean, run_clean_crop, run_clean_in_place, RunReport};
use super::{night_meta, run_noise, with_noisy_rows, Plan};
use crate::error::{Error, Result};
use crate::isp::flat::{self, FlatCheck};
use crate::isp::opcodes;
use crate::isp::render::{render, render_bands, render_crop, Bands, CropSamples, Output};
use crate::isp::render_crop::CROP_MARGIN;
use crate::isp::{RenderOptions, RgbImage};
use crate::raw::crop::{crop_meta, Crop};
use crate::raw::rows::RowSource;
use crate::raw::{RawImage, RawMeta};
use std::sync::Mutex;

/// What to compute of one variant besides the clean raw and the plan's noisy raws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Request {
    /// Render the linear target from the clean raw.
    pub target: bool,
    /// Render the network input (normalized, white-balanced, demosaiced first noisy raw;
    /// the clean raw when the plan has no ISO). Whole frame only.
    pub input: bool,
    /// Compute only this active-area rectangle (None = the whole frame).
    pub crop: Option<Crop>,
}

/// A rendered target as handed to a sink.
#[derive(Debug)]
pub enum TargetOut<B> {
    /// The sink's results of each band of [`crate::isp::render::BAND`] rows, in order.
    Bands(Bands<B>),
    /// The whole image.
    Image(RgbImage),
}

/// A consumer of the products of [`synthesize_into`], called from concurrent rayon tasks
/// (hence `Sync`): `clean` once, `noisy` once per ISO in plan order and, for a burst,
/// per frame of that ISO (frame 0 first; all from one task),
/// for a banded target `target_start` once, `target_band` for every band in parallel
/// (nearly top to bottom: see [`crate::isp::render::render_bands`]) then
/// `target` once, `input` last. After an error, `target` may never be called: a sink
/// that opened files in `target_start` discards them when it is dropped.
pub trait NightSink: Sync {
    /// What [`NightSink::target_band`] makes of a band (e.g. its encoded bytes).
    type Band: Send;
    /// The clean night raw (with its output metadata).
    fn clean(&self, clean: &RawImage) -> Result<()>;
    /// Frame `frame` of the noisy night raw at `iso` (with its output metadata); frame 0
    /// is the single-frame noisy raw, frames 1.. exist for a burst (`plan.burst`).
    fn noisy(&self, iso: u32, frame: u32, noisy: &RawImage) -> Result<()>;
    /// Frame `frame` of the noisy night raw at `iso` as rows made on demand, with its
    /// output metadata `meta` (the samples [`NightSink::noisy`] would get). The default
    /// makes the plane and hands it to [`NightSink::noisy`]; a sink that writes files packs
    /// the rows strip by strip instead, so no noisy plane is ever held.
    fn noisy_rows(&self, iso: u32, frame: u32, meta: &RawMeta, rows: &dyn RowSource) -> Result<()> {
        let noisy = RawImage {
            width: rows.width(),
            height: rows.height(),
            data: crate::raw::rows::to_plane(rows)?,
            meta: meta.clone(),
        };
        self.noisy(iso, frame, &noisy)
    }
    /// True when the sink takes the target band by band ([`NightSink::target_band`]).
    fn banded(&self) -> bool {
        false
    }
    /// The output size of a banded target, before its first band. Only called when
    /// [`NightSink::banded`] and the render is made band by band.
    fn target_start(&self, _width: usize, _height: usize) -> Result<()> {
        Ok(())
    }
    /// One band of the target: output rows from `y0`, `width` pixels each, interleaved
    /// linear RGB. Only called when [`NightSink::banded`], after
    /// [`NightSink::target_start`]. It must not wait for other rayon work (see
    /// [`crate::isp::render::render_bands`]).
    fn target_band(&self, _y0: usize, _width: usize, _rows: &[f32]) -> Result<Self::Band> {
        Err(Error::invalid("this sink does not take target bands"))
    }
    /// The whole target.
    fn target(&self, target: TargetOut<Self::Band>) -> Result<()>;
    /// The network input render.
    fn input(&self, _input: &RgbImage) -> Result<()> {
        Ok(())
    }
}

/// What [`synthesize_into`] returns besides what it handed to the sink.
#[derive(Debug, Clone)]
pub struct Synthesized {
    /// The clean night raw (the crop's, as a raw image of its own, for a crop).
    pub clean: RawImage,
    /// Values computed while running.
    pub report: RunReport,
    /// The products computed (`render_target`, `render_input`, `crop`); the whole list
    /// with the plan's stages is [`PlanReport::stages_with`](super::PlanReport::stages_with).
    pub stages: Vec<String>,
}

/// Compute the products of `plan` on `day` that `req` asks for, handing each to `sink`.
pub fn synthesize_into<S: NightSink>(
    day: &RawImage,
    plan: &Plan,
    req: &Request,
    sink: &S,
) -> Result<Synthesized> {
    let (clean, report) = match &req.crop {
        None => whole_frame(day, plan, req, sink)?,
        Some(crop) => {
            if req.input {
                return Err(Error::invalid(
                    "the network input render is made for whole frames only, not for a crop",
                ));
            }
            cropped(day, plan, req.target, crop, sink)?
        }
    };
    Ok(Synthesized {
        clean,
        report,
        stages: stage_names(req),
    })
}

/// [`synthesize_into`] that takes the day raw and, for a whole frame, computes the clean
/// raw in the day's own plane ([`super::relight::run_clean_in_place`]): the same products
/// with one plane of samples in memory instead of two.
pub fn synthesize_owned<S: NightSink>(
    day: RawImage,
    plan: &Plan,
    req: &Request,
    sink: &S,
) -> Result<Synthesized> {
    if req.crop.is_some() {
        return synthesize_into(&day, plan, req, sink);
    }
    let meta = day.meta.clone();
    let (clean, report) = run_clean_in_place(day, plan)?;
    let (clean, report) = whole_frame_of(&meta, clean, report, plan, req, sink)?;
    Ok(Synthesized {
        clean,
        report,
        stages: stage_names(req),
    })
}

/// The products [`Synthesized::stages`] lists for `req`.
fn stage_names(req: &Request) -> Vec<String> {
    let mut stages = Vec::new();
    if req.target {
        stages.push("render_target".into());
    }
    if req.input {
        stages.push("render_input".into());
    }
    if req.crop.is_some() {
        stages.push("crop".into());
    }
    stages
}

/// What the warnings about a constant render call the target and the network input.
const TARGET: &str = "the target render";
const INPUT: &str = "the network input render";

fn whole_frame<S: NightSink>(
    day: &RawImage,
    plan: &Plan,
    req: &Request,
    sink: &S,
) -> Result<(RawImage, RunReport)> {
    let (clean, report) = run_clean(day, plan)?;
    whole_frame_of(&day.meta, clean, report, plan, req, sink)
}

/// The products of a whole frame from its clean raw (`day_meta`: the day raw's metadata).
fn whole_frame_of<S: NightSink>(
    day_meta: &RawMeta,
    mut clean: RawImage,
    mut report: RunReport,
    plan: &Plan,
    req: &Request,
    sink: &S,
) -> Result<(RawImage, RunReport)> {
    clean.meta = night_meta(day_meta, plan, plan.clean_iso, &plan.clean_noise);
    let clean = clean;
    // Watches the target's bands as they are made: a constant render is said (sidecar).
    let target_flat = FlatCheck::new();
    let neutral = plan.night_neutral;
    // The clean hand-over, the noisy raws (made and handed over one ISO after the other)
    // and the target render run as concurrent rayon tasks: each product is computed the
    // same way whatever runs first. With one thread the tasks run one after another.
    let mut clean_res: Option<Result<()>> = None;
    let mut noisy_res: Option<Result<Option<RawImage>>> = None;
    let mut target_res: Option<Result<()>> = None;
    rayon::scope(|s| {
        let clean = &clean;
        let (clean_res, noisy_res) = (&mut clean_res, &mut noisy_res);
        s.spawn(move |_| *clean_res = Some(sink.clean(clean)));
        let noise_job = move |_: &rayon::Scope<'_>| {
            *noisy_res = Some((|| {
                let mut first_noisy = None;
                for i in 0..plan.noise.len() {
                    if i == 0 && req.input {
                        // kept whole: the network input is rendered from it
                        let (iso, noisy) = run_noise(clean, plan, i)?;
                        sink.noisy(iso, 0, &noisy)?;
                        first_noisy = Some(noisy);
                    } else {
                        with_noisy_rows(clean, plan, i, |iso, meta, rows| {
                            sink.noisy_rows(iso, 0, meta, rows)
                        })?;
                    }
                    // a burst's other frames, streamed one after another
                    for k in 1..plan.burst.as_ref().map_or(1, |b| b.frames) {
                        with_frame_rows(clean, plan, i, k, |iso, meta, rows| {
                            sink.noisy_rows(iso, k, meta, rows)
                        })?;
                    }
                }
                Ok(first_noisy)
            })());
        };
        // The noisy raws start once the target is rendered (or at once without a target):
        // the render then has both threads, and a single-threaded encoder in the sink
        // overlaps with the (parallel) noise instead of running alone at the end. Only
        // the order of work changes, not what is computed.
        let noise_job = std::cell::RefCell::new(Some(noise_job));
        let start_noise = || {
            if let Some(job) = noise_job.borrow_mut().take() {
                s.spawn(job);
            }
        };
        if req.target {
            target_res = Some((|| {
                let ropts = RenderOptions {
                    neutral: Some(neutral),
                    opcodes: plan.opcodes,
                    ..RenderOptions::default()
                };
                if sink.banded() {
                    let start = |w: usize, h: usize| sink.target_start(w, h);
                    let f = |y0: usize, w: usize, rows: &[f32]| {
                        target_flat.rows(rows);
                        sink.target_band(y0, w, rows)
                    };
                    if let Some(bands) = render_bands(clean, &ropts, start, f)? {
                        start_noise();
                        return sink.target(TargetOut::Bands(bands));
                    }
                }
                let rgb = render(clean, &ropts)?;
                target_flat.image(&rgb);
                start_noise();
                sink.target(TargetOut::Image(rgb))
            })());
        }
        start_noise();
    });
    // Errors in a fixed order (clean, noisy, target), whatever finished first.
    clean_res.unwrap_or(Ok(()))?;
    let first_noisy = noisy_res.unwrap_or(Ok(None))?;
    target_res.unwrap_or(Ok(()))?;
    report.warnings.extend(target_flat.warning(TARGET));
    if req.input {
        let src = first_noisy.as_ref().unwrap_or(&clean);
        let opts = RenderOptions {
            output: Output::Camera,
            neutral: Some(neutral),
            opcodes: plan.opcodes,
            ..RenderOptions::default()
        };
        let rgb = render(src, &opts)?;
        report.warnings.extend(flat::warning(&rgb, INPUT));
        sink.input(&rgb)?;
    }
    // The renders' warnings are about this input.
    report.warnings.about(&plan.input_name);
    Ok((clean, report))
}

fn cropped<S: NightSink>(
    day: &RawImage,
    plan: &Plan,
    target: bool,
    crop: &Crop,
    sink: &S,
) -> Result<(RawImage, RunReport)> {
    let a = day.active_area();
    let (aw, ah) = (a.width(), a.height());
    crop.check(aw, ah)?;
    // The target's demosaicer reads CROP_MARGIN samples around the crop.
    let outer = if target {
        crop.grown(CROP_MARGIN, aw, ah)
    } else {
        *crop
    };
    let (plane, mut report) = run_clean_crop(day, plan, outer)?;
    let target_flat = FlatCheck::new();
    let data = if outer == *crop {
        plane.clone()
    } else {
        crop.cut_from(&outer, &plane)
    };
    let frame_meta = night_meta(&day.meta, plan, plan.clean_iso, &plan.clean_noise);
    let clean = RawImage {
        width: crop.width,
        height: crop.height,
        data,
        meta: crop_meta(&frame_meta, crop),
    };
    let (c, (n, t)) = rayon::join(
        || sink.clean(&clean),
        || {
            rayon::join(
                || -> Result<()> {
                    // a burst's frames 1.. (their clean samples are shared by the ISOs)
                    let frames = clean_crops(day, plan, crop, &clean.data)?;
                    for np in &plan.noise {
                        // frame 00's noise is the single-frame crop's
                        let data = frame_noisy_crop(day, plan, crop, np, 0, &clean.data)?;
                        let meta = night_meta(&day.meta, plan, np.iso, &np.params);
                        let noisy = RawImage {
                            width: crop.width,
                            height: crop.height,
                            data,
                            meta: crop_meta(&meta, crop),
                        };
                        sink.noisy(np.iso, 0, &noisy)?;
                        for (k, fc) in frames.iter().enumerate() {
                            let k = k as u32 + 1;
                            let data = frame_noisy_crop(day, plan, crop, np, k, fc)?;
                            sink.noisy(
                                np.iso,
                                k,
                                &RawImage {
                                    data,
                                    ..noisy.clone()
                                },
                            )?;
                        }
                    }
                    Ok(())
                },
                || -> Result<()> {
                    if !target {
                        return Ok(());
                    }
                    let mode = plan.opcodes;
                    // The crop's target: before DefaultCrop and orientation.
                    let opts = RenderOptions {
                        neutral: Some(plan.night_neutral),
                        opcodes: mode,
                        crop: false,
                        orient: false,
                        ..RenderOptions::default()
                    };
                    let rgb = match opcodes::active(&day.meta, mode)? {
                        // Bad pixels, warps, TrimBounds: the crop's region of the frame's
                        // render (the whole frame is synthesized for it).
                        Some(p) if p.needs_whole_frame() => {
                            let (mut full, _) = run_clean(day, plan)?;
                            full.meta =
                                night_meta(&day.meta, plan, plan.clean_iso, &plan.clean_noise);
                            render_crop(&full, &opts, crop, CropSamples::Frame)?
                        }
                        _ => {
                            let stored = CropSamples::Stored {
                                outer: &outer,
                                plane: &plane,
                            };
                            render_crop(day, &opts, crop, stored)?
                        }
                    };
                    target_flat.image(&rgb);
                    sink.target(TargetOut::Image(rgb))
                },
            )
        },
    );
    c?;
    n?;
    t?;
    report.warnings.extend(target_flat.warning(TARGET));
    // The renders' warnings are about this input.
    report.warnings.about(&plan.input_name);
    Ok((clean, report))
}

/// Every product of one variant, in memory (what [`synthesize`] returns).
#[derive(Debug, Clone)]
pub struct Night {
    /// The clean night raw: the whole stored image with the night metadata, or the crop as
    /// a raw image of its own ([`crop_meta`]).
    pub clean: RawImage,
    /// (ISO, noisy raw) per planned ISO, same layout as `clean` (a burst's frame 00).
    pub noisy: Vec<(u32, RawImage)>,
    /// A burst's other frames: (ISO, frame 1.., noisy raw), ISO by ISO in plan order,
    /// frames in order; empty without a burst.
    pub frames: Vec<(u32, u32, RawImage)>,
    /// The linear target (whole frame: DefaultCrop and orientation applied, exactly the
    /// EXR target's pixels before half rounding; crop: the crop's region, unoriented).
    pub target: Option<RgbImage>,
    /// The network input render, if asked for.
    pub input: Option<RgbImage>,
    /// Values computed while running.
    pub report: RunReport,
    /// The products computed ([`Synthesized::stages`]).
    pub stages: Vec<String>,
    /// The crop, if any.
    pub crop: Option<Crop>,
}

/// The in-memory sink of [`synthesize`].
#[derive(Default)]
struct Collect {
    noisy: Mutex<Vec<(u32, RawImage)>>,
    frames: Mutex<Vec<(u32, u32, RawImage)>>,
    target: Mutex<Option<RgbImage>>,
    input: Mutex<Option<RgbImage>>,
}

impl NightSink for Collect {
    type Band = ();
    fn clean(&self, _clean: &RawImage) -> Result<()> {
        Ok(()) // returned by synthesize_into
    }
    fn noisy(&self, iso: u32, frame: u32, noisy: &RawImage) -> Result<()> {
        match frame {
            0 => lock(&self.noisy).push((iso, noisy.clone())),
            k => lock(&self.frames).push((iso, k, noisy.clone())),
        }
        Ok(())
    }
    fn target(&self, target: TargetOut<()>) -> Result<()> {
        if let TargetOut::Image(rgb) = target {
            *lock(&self.target) = Some(rgb);
        }
        Ok(())
    }
    fn input(&self, input: &RgbImage) -> Result<()> {
        *lock(&self.input) = Some(input.clone());
        Ok(())
    }
}

/// A poisoned lock only means another task panicked; its data is still the data.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Compute the products of `plan` on `day` that `req` asks for, into memory.
pub fn synthesize(day: &RawImage, plan: &Plan, req: &Request) -> Result<Night> {
    let sink = Collect::default();
    let out = synthesize_into(day, plan, req, &sink)?;
    Ok(Night {
        clean: out.clean,
        noisy: sink.noisy.into_inner().unwrap_or_else(|e| e.into_inner()),
        frames: sink.frames.into_inner().unwrap_or_else(|e| e.into_inner()),
        target: sink.target.into_inner().unwrap_or_else(|e| e.into_inner()),
        input: sink.input.into_inner().unwrap_or_else(|e| e.into_inner()),
        report: out.report,
        stages: out.stages,
        crop: req.crop,
    })
}

#[cfg(test)]
#[path = "night_tests.rs"]
mod tests;
