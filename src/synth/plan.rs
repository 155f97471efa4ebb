//! The `Plan`: every random value of one (input, variant), sampled up front from the
//! (seed, input name, variant) stream, in a fixed order: dimming, lights (ambient, local
//! lights, bulbs; each: illuminant, then geometry, then gains), then one noise seed per ISO.
//! A [`Planner`] samples it; what planning found besides the draws (provenance, stages,
//! opcodes, warnings) is its [`PlanReport`], returned beside it.

use super::dim::{sample_dim, DimPlan};
use super::illuminant::Gaussian2;
use super::masks::{opencv_sigma, release_sigma, Light, LightKind, MaskEval, MASK_FLOOR};
use super::neutral::day_neutral_for;
use super::noise_source::choose_noise_model;
use super::plan_report::PlanReport;
use super::rng::SynthRng;
use super::{Calibration, Mode, RelightFormula, SynthOptions};
use crate::diagnostics::{Code, Diagnostics};
use crate::error::{Error, Result};
use crate::isp::opcodes::OpcodeMode;
use crate::noise::{Evaluated, NoiseEstimate, NoiseParams, PhysicsParams};
use crate::raw::{Bayer, RawImage};
use serde::{Deserialize, Serialize};

/// Format tag of serialized plans.
pub const PLAN_FORMAT: &str = "day2night-plan/2";

/// Noise to add for one ISO.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoisePlan {
    /// Target ISO (written to Exif ISO).
    pub iso: u32,
    /// Seed of the per-row noise streams.
    pub seed: u64,
    /// The model at this ISO (per 2x2 position, normalized units).
    pub params: NoiseParams,
    /// True when the ISO was outside the model's calibrated range.
    pub extrapolated: bool,
    /// The physics-based model at this ISO when `--noise-model` is a physics file (then
    /// `params` is its equivalent Gaussian, written as NoiseProfile); null otherwise.
    pub physics: Option<crate::noise::PhysicsParams>,
}

/// Everything needed to run synthesis on one image, with no randomness left: the draws
/// and what they depend on (geometry, mode, formula, rounding, neutrals, noise model
/// values, the renders' opcode mode). What planning found besides is its [`PlanReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// [`PLAN_FORMAT`].
    pub format: String,
    /// Input file name the stream was derived from.
    pub input_name: String,
    /// Master seed.
    pub seed: u64,
    /// Variant index (0-based).
    pub variant: u32,
    /// Active-area width the plan was made for.
    pub active_width: usize,
    /// Active-area height.
    pub active_height: usize,
    /// Bayer pattern of the active area.
    pub bayer: Bayer,
    /// Relighting mode.
    pub mode: Mode,
    /// Local relighting formula.
    pub formula: RelightFormula,
    /// Truncate instead of rounding when denormalizing (released code).
    pub truncate: bool,
    /// Truncate the noisy raws too (`truncate` and `compat.truncate_noise`).
    pub truncate_noise: bool,
    /// Normalize and denormalize each site with its own range `white - black(site)`
    /// (`compat.range_per_site`, the release; false: `white - black_max`).
    pub range_per_site: bool,
    /// Keep negative normalized values (no clip at 0).
    pub keep_negative: bool,
    /// Keep white-balanced values above 1 (no clip at 1 after removing the day illuminant).
    pub keep_highlights: bool,
    /// Mask evaluation.
    pub mask_eval: MaskEval,
    /// Day neutral (green = 1; as stored with `compat.neutral_as_stored`).
    pub day_neutral: [f64; 3],
    /// Dimming.
    pub dim: DimPlan,
    /// Lights: ambient first, then local lights, then bulbs (empty for `day`/`dimmed`; one
    /// ambient-kind light holding the illuminant for `global`).
    pub lights: Vec<Light>,
    /// Night neutral written as AsShotNeutral (green = 1).
    pub night_neutral: [f64; 3],
    /// ISO written to the clean DNG (input ISO, or 50 when unknown).
    pub clean_iso: u32,
    /// NoiseProfile model of the clean DNG (the model at `clean_iso`).
    pub clean_noise: NoiseParams,
    /// One entry per noisy output.
    pub noise: Vec<NoisePlan>,
    /// The random stream of the Gaussian noise rows ([`crate::noise::NoiseStream`]): 2, or
    /// 1 under `--compat release` and in plans written before the field existed (absent:
    /// 1, so that their sidecars replay byte for byte).
    #[serde(default = "crate::noise::NoiseStream::v1")]
    pub noise_stream: crate::noise::NoiseStream,
    /// What the renders (target, network input) do with the input's DNG opcode lists:
    /// `ignore` when the input has none (the report's `opcodes` lists them).
    pub opcodes: OpcodeMode,
    /// The burst (`--burst N`, N > 1): frames, motion model and every frame's transform,
    /// drawn from the burst's own stream; null for a single frame.
    pub burst: Option<super::burst::BurstPlan>,
    /// The mean white-balanced intensity of the image this plan was made from, when a
    /// caller that keeps the image ([`super::day_input::DayInput::frame_mean`]) worked it out
    /// for a brightness-dictionary dimming: a crop's clean pass then reads it instead of
    /// reading the whole frame again. Not serialized (a replayed plan computes it).
    #[serde(skip)]
    pub frame_mean: super::dim::FrameMean,
}

fn window_len(rng: &mut SynthRng, n: usize) -> f64 {
    // Integer in [ceil(n/2), n), at least 1.
    let lo = n.div_ceil(2).max(1) as u64;
    rng.int_range(lo, n as u64).max(1) as f64
}

fn center(rng: &mut SynthRng, n: usize) -> f64 {
    rng.range(0.1, 0.9) * n as f64
}

/// A plan and its report: what [`Planner::plan`] returns and what a job writes (`synth`,
/// `dataset`, `--replay`).
#[derive(Debug, Clone, PartialEq)]
pub struct Planned {
    /// The draws.
    pub plan: Plan,
    /// What planning found.
    pub report: PlanReport,
}

/// Samples the [`Plan`] of one (input, variant), set up step by step:
///
/// ```no_run
/// use day2night::synth::{Calibration, Planner, SynthOptions};
/// # fn main() -> day2night::Result<()> {
/// let day = day2night::dng::read_dng("day.dng".as_ref())?;
/// let opts = SynthOptions::default();
/// let cal = Calibration::embedded(&opts)?;
/// let planned = Planner::new(&day, &opts)
///     .calibration(&cal)
///     .name("day.dng")
///     .seed(7)
///     .variant(1)
///     .plan()?;
/// println!("{} lights; warnings {:?}", planned.plan.lights.len(), planned.report.warnings);
/// # Ok(()) }
/// ```
///
/// Defaults: the embedded calibration of the options ([`Calibration::embedded`]), input
/// name `""`, seed 0, variant 0, a job that renders, the noise estimate computed from the
/// image when the noise chain gets to it. The image's metadata and geometry are read; its
/// pixels only for that estimate ([`super::noise_source`]).
#[derive(Clone, Copy)]
pub struct Planner<'a> {
    img: &'a RawImage,
    opts: &'a SynthOptions,
    cal: Option<&'a Calibration>,
    input_name: &'a str,
    seed: u64,
    variant: u32,
    renders: bool,
    estimate: Option<&'a dyn Fn() -> Result<NoiseEstimate>>,
}

impl<'a> Planner<'a> {
    /// A planner for `img` with `opts` and the defaults above.
    pub fn new(img: &'a RawImage, opts: &'a SynthOptions) -> Planner<'a> {
        Planner {
            img,
            opts,
            cal: None,
            input_name: "",
            seed: 0,
            variant: 0,
            renders: true,
            estimate: None,
        }
    }

    /// The calibration (illuminant dictionary, brightness dictionary, noise model).
    pub fn calibration(self, cal: &'a Calibration) -> Self {
        Planner {
            cal: Some(cal),
            ..self
        }
    }

    /// The input's file name: it keys the random stream and is recorded in the plan.
    pub fn name(self, input_name: &'a str) -> Self {
        Planner { input_name, ..self }
    }

    /// The master seed.
    pub fn seed(self, seed: u64) -> Self {
        Planner { seed, ..self }
    }

    /// The variant index (0-based).
    pub fn variant(self, variant: u32) -> Self {
        Planner { variant, ..self }
    }

    /// Whether the job renders (a target or the network input). The opcode lists are
    /// checked for the renders ([`crate::isp::opcodes::check::check_render`]: an opcode
    /// that cannot be applied and is not optional is an error, opcodes that make their
    /// samples constant and a TrimBounds that changes the target's size are warnings);
    /// without a render nothing about them fails: lists that cannot be parsed or applied
    /// are warnings ([`crate::isp::opcodes::check::report_without_render`]).
    pub fn renders(self, renders: bool) -> Self {
        Planner { renders, ..self }
    }

    /// The image's noise estimate, called only when the noise chain gets to it (e.g. a
    /// cached one, [`super::job::DayInput::noise_estimate`]).
    pub fn estimate(self, estimate: &'a dyn Fn() -> Result<NoiseEstimate>) -> Self {
        Planner {
            estimate: Some(estimate),
            ..self
        }
    }

    /// Sample the plan and make its report.
    pub fn plan(&self) -> Result<Planned> {
        let embedded;
        let cal = match self.cal {
            Some(c) => c,
            None => {
                embedded = Calibration::embedded(self.opts)?;
                &embedded
            }
        };
        let own_estimate = || crate::noise::estimate(self.img, &Default::default());
        let estimate: &dyn Fn() -> Result<NoiseEstimate> = match self.estimate {
            Some(e) => e,
            None => &own_estimate,
        };
        self.sample(cal, estimate)
    }

    fn sample(
        &self,
        cal: &Calibration,
        estimate: &dyn Fn() -> Result<NoiseEstimate>,
    ) -> Result<Planned> {
        let (img, opts) = (self.img, self.opts);
        opts.validate()?;
        img.validate()?;
        let bayer = img.bayer()?;
        // Everything this input lacks for these options, listed at once (docs/your-camera.md).
        super::readiness::check(&img.meta, opts, cal, self.renders)?;
        let a = img.active_area();
        let (w, h) = (a.width(), a.height());
        let (day_neutral, day_neutral_source) = day_neutral_for(&img.meta, opts)?;
        let mut rng = SynthRng::new(self.seed, self.input_name, self.variant);
        // What the metadata checks corrected on reading (dng::check) comes first.
        let mut warnings = img.meta.warnings.clone();
        let mut stages: Vec<String> = vec!["normalize".into(), "remove_day_illuminant".into()];
        let dim = if opts.mode == Mode::Day {
            DimPlan::None
        } else {
            stages.push("dim".into());
            sample_dim(&mut rng, opts.dim_range, cal.brightness.as_ref())?
        };
        // The night illuminant dictionary of this input, only when illuminants are sampled
        // (docs/synthesis.md, "Night lamps in CIE xy"): another camera's colours are a warning.
        let resolved = match opts.mode {
            Mode::Global | Mode::Local => {
                let r = cal.illuminants_for(&img.meta, opts)?;
                warnings.extend(r.warnings.iter().cloned());
                Some(r.gaussian)
            }
            Mode::Day | Mode::Dimmed => None,
        };
        let lit = sample_lights(
            &mut rng,
            opts,
            resolved.as_ref(),
            (w, h),
            day_neutral,
            &mut stages,
        )?;
        let night_neutral = super::neutral::check_neutral(lit.neutral, "night neutral")?;
        stages.push("denormalize".into());
        let noise = plan_noise(img, cal, opts, estimate, &mut rng, &mut warnings)?;
        if !noise.entries.is_empty() {
            stages.push("noise".into());
        }
        // The burst's motion from its own stream (nothing drawn for a single frame).
        // Before any draw: a step the image cannot hold is refused with the image's size.
        super::burst::checks::check_step_fits(&opts.burst, (w, h))?;
        let key = (self.seed, self.input_name, self.variant);
        let burst = super::burst::motion::plan_burst(&opts.burst, (w, h), key)?;
        if let Some(b) = &burst {
            let valid = super::burst::checks::valid_area_warnings(&b.transforms, (w, h));
            warnings.extend(valid);
            stages.push("burst_frames".into());
            if b.transforms.iter().any(|t| !t.is_identity()) {
                stages.push("burst_warp".into());
            }
        }
        // The renders' opcodes: unapplicable optional ones are warnings, mandatory ones and
        // work over the budget errors (warnings when nothing is rendered, and no budget). The
        // stage `apply_opcodes` is recorded by the synthesis when a render runs.
        let (opcodes, target_size) = if self.renders {
            let c = crate::isp::opcodes::check::check_render(img, opts.opcodes, true, true)?;
            warnings.extend(c.warnings);
            let size = c.trimmed_size.map(|(w, h)| [w, h]);
            (c.prepared.map(|p| p.report), size)
        } else {
            let (r, w) = crate::isp::opcodes::check::report_without_render(&img.meta, opts.opcodes);
            warnings.extend(w);
            (r, None)
        };
        // Every warning of this plan is about this input.
        warnings.about(self.input_name);
        let plan = Plan {
            format: PLAN_FORMAT.into(),
            input_name: self.input_name.into(),
            seed: self.seed,
            variant: self.variant,
            active_width: w,
            active_height: h,
            bayer,
            mode: opts.mode,
            formula: opts.formula,
            truncate: opts.truncate,
            truncate_noise: opts.truncate && opts.compat.truncate_noise,
            range_per_site: opts.compat.range_per_site,
            keep_negative: opts.keep_negative,
            keep_highlights: opts.keep_highlights,
            mask_eval: opts.mask_eval,
            day_neutral,
            dim,
            lights: lit.lights,
            night_neutral,
            clean_iso: noise.clean_iso,
            clean_noise: noise.clean,
            noise: noise.entries,
            // the release preset keeps the stream it had (its noise path is untouched)
            noise_stream: if opts.compat == super::Compat::RELEASE {
                crate::noise::NoiseStream::V1
            } else {
                crate::noise::NoiseStream::V2
            },
            opcodes: opcodes.as_ref().map_or(OpcodeMode::Ignore, |r| r.mode),
            burst,
            frame_mean: Default::default(),
        };
        let report = PlanReport {
            day_neutral_source,
            night_neutral_definition: lit.definition,
            noise_model_source: noise.source,
            noise_provenance: Some(noise.provenance),
            stages,
            opcodes,
            target_size,
            warnings,
        };
        // The replay check (`synth --replay`) applies the same table: a plan synth writes is a
        // plan it reads back (e.g. a physics model extrapolated past the noise bounds is
        // refused here, naming the field, rather than written to a sidecar nobody can replay).
        plan.validate_bounds()?;
        report.validate_bounds()?;
        Ok(Planned { plan, report })
    }
}

/// The lights of a plan, the night neutral they give and how it was computed.
struct Lit {
    lights: Vec<Light>,
    neutral: [f64; 3],
    definition: String,
}

/// The light holding the illuminant of `global` mode, or the ambient light of `local`.
fn ambient(illuminant: [f64; 3], gain: f64, weight: f64) -> Light {
    Light {
        kind: LightKind::Ambient,
        illuminant,
        gain,
        weight,
        center: [0.0, 0.0],
        window: None,
        sigma: [0.0, 0.0],
        floor: 0.0,
    }
}

/// The lights of the mode (none for `day` and `dimmed`), adding their stages.
fn sample_lights(
    rng: &mut SynthRng,
    opts: &SynthOptions,
    resolved: Option<&Gaussian2>,
    size: (usize, usize),
    day_neutral: [f64; 3],
    stages: &mut Vec<String>,
) -> Result<Lit> {
    let sampled =
        || resolved.ok_or_else(|| Error::invalid("no night illuminant dictionary in this mode"));
    let lit = |lights, neutral, definition: &str| Lit {
        lights,
        neutral,
        definition: definition.into(),
    };
    match opts.mode {
        Mode::Day => {
            stages.push("relight_day".into());
            Ok(lit(vec![], day_neutral, "day neutral (mode day)"))
        }
        Mode::Dimmed => {
            stages.push("relight_dimmed".into());
            Ok(lit(vec![], day_neutral, "day neutral (mode dimmed)"))
        }
        Mode::Global => {
            stages.push("sample_illuminants".into());
            stages.push("relight_global".into());
            let l = sampled()?.sample(rng, &opts.sampler)?;
            Ok(lit(vec![ambient(l, 1.0, 1.0)], l, "the global illuminant"))
        }
        Mode::Local => local_lights(rng, opts, sampled()?, size, stages),
    }
}

/// `local` mode: the ambient light, the local lights and the bulbs, in that order.
fn local_lights(
    rng: &mut SynthRng,
    opts: &SynthOptions,
    g: &Gaussian2,
    (w, h): (usize, usize),
    stages: &mut Vec<String>,
) -> Result<Lit> {
    let rules = &opts.sampler;
    stages.push("sample_illuminants".into());
    let paper = opts.formula == RelightFormula::Paper;
    stages.push(
        if paper {
            "relight_local_paper"
        } else {
            "relight_local_release"
        }
        .into(),
    );
    stages.push("ambient".into());
    stages.push("masks".into());
    let l0 = g.sample(rng, rules)?;
    let (gain0, weight0) = if paper {
        (1.0, rng.range(0.05, 0.10))
    } else {
        (opts.ambient_gain, 1.0)
    };
    let mut lights = vec![ambient(l0, gain0, weight0)];
    let k = match opts.local_lights {
        Some(k) => k as u64,
        None if paper => rng.int_range(4, 7), // 5 to 7 lights in total
        None => 4,
    };
    for _ in 0..k {
        let illuminant = g.sample(rng, rules)?;
        let center = [center(rng, h), center(rng, w)];
        let local = |window, sigma, floor| Light {
            kind: LightKind::Local,
            illuminant,
            gain: 1.0,
            weight: 1.0,
            center,
            window,
            sigma,
            floor,
        };
        lights.push(if paper {
            let s = [
                rng.range(0.5, 1.0) * h as f64,
                rng.range(0.5, 1.0) * w as f64,
            ];
            local(None, s, 0.0)
        } else {
            let (wh, ww) = (window_len(rng, h), window_len(rng, w));
            local(Some([wh, ww]), release_sigma(wh, ww), MASK_FLOOR)
        });
    }
    let bulbs = opts.bulbs.unwrap_or(if paper { 0 } else { 5 });
    if bulbs > 0 {
        stages.push("bulbs".into());
    }
    for _ in 0..bulbs {
        let l = g.sample(rng, rules)?;
        let c = [center(rng, h), center(rng, w)];
        let (wh, ww) = (window_len(rng, h), window_len(rng, w));
        let u = rng.uniform();
        let gain = rng.range(opts.bulb_gain[0], opts.bulb_gain[1]);
        // Released code: OpenCV's size-to-sigma rule applied to a kernel size of
        // max(h, w) / (5 + 5u), then scaled per axis like the local lights.
        let m = wh.max(ww);
        let s = opencv_sigma(m / (5.0 + 5.0 * u));
        lights.push(Light {
            kind: LightKind::Bulb,
            illuminant: l,
            gain,
            weight: 1.0,
            center: c,
            window: Some([wh, ww]),
            sigma: [s * wh / m, s * ww / m],
            floor: MASK_FLOOR,
        });
    }
    let used: Vec<&Light> = lights
        .iter()
        .filter(|l| !paper || l.kind != LightKind::Bulb)
        .collect();
    let mut n = [0.0; 3];
    for l in &used {
        for (ni, li) in n.iter_mut().zip(l.illuminant) {
            *ni += li / used.len() as f64;
        }
    }
    let definition = if paper {
        "mean of the night illuminants (ambient and local lights; paper)"
    } else {
        "mean of all sampled lights: ambient, local lights and bulbs (released code)"
    };
    Ok(Lit {
        lights,
        neutral: n,
        definition: definition.into(),
    })
}

/// The noise part of a plan: the clean DNG's ISO and model, one entry per ISO (each with
/// its seed, drawn in order), and where the model came from.
struct NoiseDraws {
    clean_iso: u32,
    clean: NoiseParams,
    entries: Vec<NoisePlan>,
    source: String,
    provenance: crate::noise::NoiseProvenance,
}

fn plan_noise(
    img: &RawImage,
    cal: &Calibration,
    opts: &SynthOptions,
    estimate: &dyn Fn() -> Result<NoiseEstimate>,
    rng: &mut SynthRng,
    warnings: &mut Diagnostics,
) -> Result<NoiseDraws> {
    let choice = choose_noise_model(img, cal, opts, img.bayer()?, estimate)?;
    warnings.extend(choice.warnings);
    let model = choice.model;
    if model.physics.is_some() && opts.noise_gain != 1.0 {
        return Err(Error::invalid(
            "--noise-gain scales a Gaussian noise model (S, O); a physics model is refused",
        ));
    }
    let clean_iso = img.meta.iso_or_default();
    // Physics model: its equivalent Gaussian at this image's levels (the NoiseProfile).
    let scale = img.meta.levels.white - img.meta.levels.black_max();
    let at = |iso: u32| -> Result<(Evaluated, Option<PhysicsParams>)> {
        match &model.physics {
            Some(pm) => {
                let e = pm.at(iso)?;
                let ev = Evaluated {
                    params: e.params.to_noise_params(scale),
                    extrapolated: e.extrapolated,
                };
                Ok((ev, Some(e.params)))
            }
            None => Ok((model.at(iso)?, None)),
        }
    };
    let clean = at(clean_iso)?.0.params;
    let mut entries = Vec::new();
    for &iso in &opts.isos {
        let (e, physics) = at(iso)?;
        if e.extrapolated {
            let (lo, hi) = model.iso_range();
            let message = if model.physics.is_some() {
                format!(
                    "ISO {} is outside the physics noise model's calibrated range {}..{} ({}): K proportional to ISO, sigmas from the joint log-log fit",
                    iso, lo, hi, model.source
                )
            } else if lo == hi {
                format!(
                    "ISO {} scaled from the single calibrated ISO {} ({}): S in proportion to ISO, O to ISO^2",
                    iso, lo, model.source
                )
            } else {
                format!(
                    "ISO {} is outside the noise model's calibrated range {}..{} ({}): extrapolated",
                    iso, lo, hi, model.source
                )
            };
            warnings.warn(Code::NoiseExtrapolated, message);
        }
        entries.push(NoisePlan {
            iso,
            seed: rng.next_u64(),
            params: e.params.with_gain(opts.noise_gain),
            extrapolated: e.extrapolated,
            physics,
        });
    }
    Ok(NoiseDraws {
        clean_iso,
        clean,
        entries,
        source: model.source.clone(),
        provenance: choice.provenance,
    })
}

impl Plan {
    /// The key of this plan's clean pass for its whole-frame mean (`Plan::frame_mean`).
    pub fn mean_key(&self) -> super::dim::MeanKey {
        super::dim::MeanKey::new(
            self.day_neutral,
            self.keep_negative,
            self.keep_highlights,
            self.range_per_site,
        )
    }

    /// Error unless this plan fits `img` (geometry and CFA) and is internally sane.
    pub fn check_against(&self, img: &RawImage) -> Result<()> {
        if self.format != PLAN_FORMAT {
            return Err(Error::invalid(format!(
                "plan format {:?} (expected {:?})",
                self.format, PLAN_FORMAT
            )));
        }
        let a = img.active_area();
        if a.width() != self.active_width || a.height() != self.active_height {
            return Err(Error::invalid(format!(
                "plan made for a {}x{} active area, image has {}x{}",
                self.active_width,
                self.active_height,
                a.width(),
                a.height()
            )));
        }
        if img.bayer()? != self.bayer {
            return Err(Error::invalid(format!(
                "plan made for CFA {}, image has {}",
                self.bayer,
                img.bayer()?
            )));
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let ok = finite(&self.day_neutral)
            && finite(&self.night_neutral)
            && self.lights.iter().all(|l| {
                finite(&l.illuminant)
                    && finite(&[l.gain, l.weight, l.floor])
                    && finite(&l.center)
                    && finite(&l.sigma)
                    && l.window.map(|w| finite(&w)).unwrap_or(true)
                    && l.weight >= 0.0
            });
        let dim_ok = match &self.dim {
            super::dim::DimPlan::None => true,
            super::dim::DimPlan::Uniform { s, .. } => s.is_finite() && *s >= 0.0,
            super::dim::DimPlan::TargetMean { target_mean, .. } => {
                target_mean.is_finite() && *target_mean >= 0.0
            }
        };
        let noise_ok = self.noise.iter().all(|n| {
            n.params
                .positions
                .iter()
                .all(|p| p[0].is_finite() && p[1].is_finite())
                && n.physics.is_none_or(|p| p.check("plan").is_ok())
        });
        if !ok || !dim_ok || !noise_ok || self.day_neutral.iter().any(|&v| v <= 0.0) {
            return Err(Error::invalid("plan holds non-finite or invalid values"));
        }
        Ok(())
    }
}
