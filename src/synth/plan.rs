//! The `Plan`: every random value of one (input, variant), sampled up front from the
//! (seed, input name, variant) stream, in a fixed order: dimming, lights (ambient, local
//! lights, bulbs; each: illuminant, then geometry, then gains), then one noise seed per ISO.

use super::dim::{sample_dim, DimPlan};
use super::illuminant::Gaussian2;
use super::masks::{opencv_sigma, release_sigma, Light, LightKind, MaskEval, MASK_FLOOR};
use super::neutral::day_neutral_for;
use super::noise_source::choose_noise_model;
use super::rng::SynthRng;
use super::{Calibration, Mode, RelightFormula, SynthOptions};
use crate::diagnostics::{Code, Diagnostics};
use crate::error::{Error, Result};
use crate::isp::opcodes::{OpcodeMode, OpcodeReport};
use crate::noise::{Evaluated, NoiseEstimate, NoiseParams, NoiseProvenance, PhysicsParams};
use crate::raw::{Bayer, RawImage};
use serde::{Deserialize, Serialize};

/// Format tag of serialized plans.
pub const PLAN_FORMAT: &str = "day2night-plan/1";

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
    /// `params` is its equivalent Gaussian, written as NoiseProfile). Absent otherwise, so
    /// Gaussian plans and sidecars are unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<crate::noise::PhysicsParams>,
}

/// Everything needed to run synthesis on one image, with no randomness left.
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
    /// Size `[width, height]` of the rendered target (and network input) when an
    /// OpcodeList3 TrimBounds changes it; absent otherwise (the target is then the raw's
    /// DefaultCrop, oriented), so other sidecars are unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_size: Option<[usize; 2]>,
    /// Bayer pattern of the active area.
    pub bayer: Bayer,
    /// Relighting mode.
    pub mode: Mode,
    /// Local relighting formula.
    pub formula: RelightFormula,
    /// Truncate instead of rounding when denormalizing (released code).
    pub truncate: bool,
    /// Truncate the noisy raws too (`truncate` and `compat.truncate_noise`; absent = false).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub truncate_noise: bool,
    /// Normalize and denormalize each site with its own range `white - black(site)`
    /// (`compat.range_per_site`, the release; absent = false: `white - black_max`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub range_per_site: bool,
    /// Keep negative normalized values (no clip at 0).
    pub keep_negative: bool,
    /// Keep white-balanced values above 1 (no clip at 1 after removing the day illuminant).
    pub keep_highlights: bool,
    /// Mask evaluation.
    pub mask_eval: MaskEval,
    /// Day neutral (green = 1; as stored with `compat.neutral_as_stored`).
    pub day_neutral: [f64; 3],
    /// Where the day neutral came from.
    pub day_neutral_source: String,
    /// Dimming.
    pub dim: DimPlan,
    /// Lights: ambient first, then local lights, then bulbs (empty for `day`/`dimmed`; one
    /// ambient-kind light holding the illuminant for `global`).
    pub lights: Vec<Light>,
    /// Night neutral written as AsShotNeutral (green = 1).
    pub night_neutral: [f64; 3],
    /// How the night neutral was computed.
    pub night_neutral_definition: String,
    /// ISO written to the clean DNG (input ISO, or 50 when unknown).
    pub clean_iso: u32,
    /// NoiseProfile model of the clean DNG (the model at `clean_iso`).
    pub clean_noise: NoiseParams,
    /// Where the noise model came from.
    pub noise_model_source: String,
    /// Where the noise model came from and which camera it belongs to (also the sidecar's
    /// `calibration.provenance.noise`). Absent in plans written before it existed, so their
    /// sidecars replay byte for byte.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_provenance: Option<NoiseProvenance>,
    /// One entry per noisy output.
    pub noise: Vec<NoisePlan>,
    /// The stages that run, in order.
    pub stages: Vec<String>,
    /// Warnings raised while planning (e.g. ISO extrapolation), about the input
    /// (`input_name`); a version-1 sidecar's plain strings read as `legacy` warnings.
    pub warnings: Diagnostics,
    /// What the renders (target, network input) do with the input's DNG opcode lists: the
    /// mode and the opcodes applied and skipped. Absent when the input has no opcode list,
    /// and in sidecars written before opcodes were applied: the renders then ignore them,
    /// so such sidecars replay byte for byte.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opcodes: Option<OpcodeReport>,
    /// The burst (`--burst N`, N > 1): frames, motion model and every frame's transform,
    /// drawn from the burst's own stream. Absent for a single frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub burst: Option<super::burst::BurstPlan>,
}

impl Plan {
    /// The opcode mode of this plan's renders ([`Plan::opcodes`]; ignore when absent).
    pub fn opcode_mode(&self) -> OpcodeMode {
        self.opcodes.as_ref().map_or(OpcodeMode::Ignore, |r| r.mode)
    }
}

fn window_len(rng: &mut SynthRng, n: usize) -> f64 {
    // Integer in [ceil(n/2), n), at least 1.
    let lo = n.div_ceil(2).max(1) as u64;
    rng.int_range(lo, n as u64).max(1) as f64
}

fn center(rng: &mut SynthRng, n: usize) -> f64 {
    rng.range(0.1, 0.9) * n as f64
}

/// Sample a plan for `img` (metadata and geometry; the pixels are read only when the noise
/// model is estimated from the image, [`super::noise_source`]), for a job that renders (a
/// target or the network input): [`plan_for`] with `renders` true.
pub fn plan(
    img: &RawImage,
    input_name: &str,
    seed: u64,
    variant: u32,
    opts: &SynthOptions,
    cal: &Calibration,
) -> Result<Plan> {
    plan_for(img, input_name, seed, variant, opts, cal, true)
}

/// [`plan`] for a job that renders (`renders`: a target or the network input) or not. The
/// opcode lists are checked for the renders ([`crate::isp::opcodes::check::check_render`]:
/// an opcode that cannot be applied and is not optional is an error, opcodes that make
/// their samples constant and a TrimBounds that changes the target's size are warnings);
/// without a render nothing about them fails: lists that cannot be parsed or applied are
/// warnings ([`crate::isp::opcodes::check::report_without_render`]).
pub fn plan_for(
    img: &RawImage,
    input_name: &str,
    seed: u64,
    variant: u32,
    opts: &SynthOptions,
    cal: &Calibration,
    renders: bool,
) -> Result<Plan> {
    plan_with_estimate(img, input_name, seed, variant, opts, cal, renders, &|| {
        crate::noise::estimate(img, &Default::default())
    })
}

/// [`plan_for`] with the image's noise estimate given by `estimate` (called only when the
/// noise chain gets to it; e.g. a cached one, [`super::job::DayInput::noise_estimate`]).
#[allow(clippy::too_many_arguments)]
pub fn plan_with_estimate(
    img: &RawImage,
    input_name: &str,
    seed: u64,
    variant: u32,
    opts: &SynthOptions,
    cal: &Calibration,
    renders: bool,
    estimate: &dyn Fn() -> Result<NoiseEstimate>,
) -> Result<Plan> {
    opts.validate()?;
    img.validate()?;
    let bayer = img.bayer()?;
    // Everything this input lacks for these options, listed at once (docs/your-camera.md).
    super::readiness::check(&img.meta, opts, cal, renders)?;
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (dn, dn_src) = day_neutral_for(&img.meta, opts)?;
    let mut rng = SynthRng::new(seed, input_name, variant);
    // What the metadata checks corrected on reading (dng::check) comes first.
    let mut warnings = img.meta.warnings.clone();
    // The stage names of the sidecar's `stages`: from normalize to denormalize they run in
    // one fused row pass (synth/relight.rs, `run_clean`), not in functions of those names.
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
    let sampled = || -> Result<&Gaussian2> {
        resolved
            .as_ref()
            .ok_or_else(|| Error::invalid("no night illuminant dictionary in this mode"))
    };
    let rules = &opts.sampler;
    let mut lights = Vec::new();
    let (night_neutral, definition) = match opts.mode {
        Mode::Day => {
            stages.push("relight_day".into());
            (dn, "day neutral (mode day)".to_string())
        }
        Mode::Dimmed => {
            stages.push("relight_dimmed".into());
            (dn, "day neutral (mode dimmed)".to_string())
        }
        Mode::Global => {
            stages.push("sample_illuminants".into());
            stages.push("relight_global".into());
            let l = sampled()?.sample(&mut rng, rules)?;
            lights.push(Light {
                kind: LightKind::Ambient,
                illuminant: l,
                gain: 1.0,
                weight: 1.0,
                center: [0.0, 0.0],
                window: None,
                sigma: [0.0, 0.0],
                floor: 0.0,
            });
            (l, "the global illuminant".to_string())
        }
        Mode::Local => {
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
            let g = sampled()?;
            // Ambient.
            let l0 = g.sample(&mut rng, rules)?;
            let (gain0, weight0) = if paper {
                (1.0, rng.range(0.05, 0.10))
            } else {
                (opts.ambient_gain, 1.0)
            };
            lights.push(Light {
                kind: LightKind::Ambient,
                illuminant: l0,
                gain: gain0,
                weight: weight0,
                center: [0.0, 0.0],
                window: None,
                sigma: [0.0, 0.0],
                floor: 0.0,
            });
            let k = match opts.local_lights {
                Some(k) => k as u64,
                None if paper => rng.int_range(4, 7), // 5 to 7 lights in total
                None => 4,
            };
            for _ in 0..k {
                let l = g.sample(&mut rng, rules)?;
                let c = [center(&mut rng, h), center(&mut rng, w)];
                if paper {
                    let s = [
                        rng.range(0.5, 1.0) * h as f64,
                        rng.range(0.5, 1.0) * w as f64,
                    ];
                    lights.push(Light {
                        kind: LightKind::Local,
                        illuminant: l,
                        gain: 1.0,
                        weight: 1.0,
                        center: c,
                        window: None,
                        sigma: s,
                        floor: 0.0,
                    });
                } else {
                    let (wh, ww) = (window_len(&mut rng, h), window_len(&mut rng, w));
                    lights.push(Light {
                        kind: LightKind::Local,
                        illuminant: l,
                        gain: 1.0,
                        weight: 1.0,
                        center: c,
                        window: Some([wh, ww]),
                        sigma: release_sigma(wh, ww),
                        floor: MASK_FLOOR,
                    });
                }
            }
            let bulbs = opts.bulbs.unwrap_or(if paper { 0 } else { 5 });
            if bulbs > 0 {
                stages.push("bulbs".into());
            }
            for _ in 0..bulbs {
                let l = g.sample(&mut rng, rules)?;
                let c = [center(&mut rng, h), center(&mut rng, w)];
                let (wh, ww) = (window_len(&mut rng, h), window_len(&mut rng, w));
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
            let def = if paper {
                "mean of the night illuminants (ambient and local lights; paper)"
            } else {
                "mean of all sampled lights: ambient, local lights and bulbs (released code)"
            };
            (n, def.to_string())
        }
    };
    let night_neutral = super::neutral::check_neutral(night_neutral, "night neutral")?;
    stages.push("denormalize".into());

    let choice = choose_noise_model(img, cal, opts, bayer, estimate)?;
    warnings.extend(choice.warnings);
    let model = choice.model;
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
    let clean_noise = at(clean_iso)?.0.params;
    let mut noise = Vec::new();
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
        noise.push(NoisePlan {
            iso,
            seed: rng.next_u64(),
            params: e.params,
            extrapolated: e.extrapolated,
            physics,
        });
    }
    if !noise.is_empty() {
        stages.push("noise".into());
    }
    // The burst's motion from its own stream (nothing drawn for a single frame).
    // Before any draw: a step the image cannot hold is refused with the image's size.
    super::burst::checks::check_step_fits(&opts.burst, (w, h))?;
    let burst = super::burst::motion::plan_burst(&opts.burst, (w, h), (seed, input_name, variant))?;
    if let Some(b) = &burst {
        warnings.extend(super::burst::checks::valid_area_warnings(
            &b.transforms,
            (w, h),
        ));
        stages.push("burst_frames".into());
        if b.transforms.iter().any(|t| !t.is_identity()) {
            stages.push("burst_warp".into());
        }
    }
    // The renders' opcodes: unapplicable optional ones are warnings, mandatory ones and
    // work over the budget errors (warnings when nothing is rendered, and no budget). The
    // stage `apply_opcodes` is recorded by the synthesis when a render runs.
    let (opcodes, target_size) = if renders {
        let c = crate::isp::opcodes::check::check_render(img, opts.opcodes, true, true)?;
        warnings.extend(c.warnings);
        (
            c.prepared.map(|p| p.report),
            c.trimmed_size.map(|(w, h)| [w, h]),
        )
    } else {
        let (r, w) = crate::isp::opcodes::check::report_without_render(&img.meta, opts.opcodes);
        warnings.extend(w);
        (r, None)
    };
    // Every warning of this plan is about this input.
    warnings.about(input_name);
    let plan = Plan {
        format: PLAN_FORMAT.into(),
        input_name: input_name.into(),
        seed,
        variant,
        active_width: w,
        active_height: h,
        target_size,
        bayer,
        mode: opts.mode,
        formula: opts.formula,
        truncate: opts.truncate,
        truncate_noise: opts.truncate && opts.compat.truncate_noise,
        range_per_site: opts.compat.range_per_site,
        keep_negative: opts.keep_negative,
        keep_highlights: opts.keep_highlights,
        mask_eval: opts.mask_eval,
        day_neutral: dn,
        day_neutral_source: dn_src,
        dim,
        lights,
        night_neutral,
        night_neutral_definition: definition,
        clean_iso,
        clean_noise,
        noise_model_source: model.source.clone(),
        noise_provenance: Some(choice.provenance),
        noise,
        stages,
        warnings,
        opcodes,
        burst,
    };
    // The replay check (`synth --replay`) applies the same table: a plan synth writes is a
    // plan it reads back (e.g. a physics model extrapolated past the noise bounds is
    // refused here, naming the field, rather than written to a sidecar nobody can replay).
    plan.validate_bounds()?;
    Ok(plan)
}

impl Plan {
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
