//! Day-to-night synthesis (SYNTHESIS.md): a seeded [`Plan`] sampled up front by [`plan()`],
//! then a pure [`run`].
//!
//! ```no_run
//! use day2night::synth::{self, Calibration, SynthOptions};
//! # fn main() -> day2night::Result<()> {
//! let day = day2night::dng::read_dng("day.dng".as_ref())?;
//! let opts = SynthOptions::default();
//! let cal = Calibration::embedded(&opts)?;
//! let plan = synth::plan(&day, "day.dng", 0, 0, &opts, &cal)?;
//! let out = synth::run(&day, &plan)?;
//! // out.clean: the clean night raw; out.noisy: one (ISO, raw) per --iso value.
//! # Ok(()) }
//! ```

pub mod config;
pub mod crop;
pub mod dictionaries;
pub mod dim;
pub mod illuminant;
pub mod job;
pub mod masks;
pub mod neutral;
pub mod night;
pub mod plan;
pub mod plan_bounds;
pub mod relight;
pub mod rng;
pub mod sidecar;

pub use illuminant::{Covariance, Gaussian2, SamplerRules};
pub use masks::{Light, LightKind, MaskEval};
pub use plan::{plan, NoisePlan, Plan};
pub use relight::{run, run_clean, RunReport};

use crate::error::{Error, Result};
use crate::noise::{NoiseModel, NoiseParams};
use crate::raw::meta::RawMeta;
use crate::raw::RawImage;
use dictionaries::BrightnessDict;
use serde::{Deserialize, Serialize};

/// Relighting mode (SYNTHESIS.md 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// The day raw itself (steps 2-5 are the identity).
    Day,
    /// Dimmed only, day neutral re-applied.
    Dimmed,
    /// One night illuminant.
    Global,
    /// Several local lights (the paper's method; default).
    #[default]
    Local,
}

/// Local relighting formula.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RelightFormula {
    /// The authors' released code (default).
    #[default]
    Release,
    /// The paper's equation.
    Paper,
}

/// Synthesis options (all serializable: the sidecar records them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SynthOptions {
    /// Relighting mode.
    pub mode: Mode,
    /// Local relighting formula.
    pub formula: RelightFormula,
    /// Saturated bulbs (None = formula default: release 5, paper 0).
    pub bulbs: Option<u32>,
    /// Local lights besides the ambient (None = release 4; paper: 4 to 6 drawn).
    pub local_lights: Option<u32>,
    /// ISOs of the noisy outputs (empty = clean only).
    pub isos: Vec<u32>,
    /// Truncate instead of round when denormalizing (released code).
    pub truncate: bool,
    /// Keep negative normalized values.
    pub keep_negative: bool,
    /// Keep white-balanced values above 1.
    pub keep_highlights: bool,
    /// Range of the uniform dimming factor.
    pub dim_range: [f64; 2],
    /// Gain of the ambient light (release formula).
    pub ambient_gain: f64,
    /// Range of the bulbs' gain.
    pub bulb_gain: [f64; 2],
    /// Illuminant sampler rules.
    pub sampler: SamplerRules,
    /// Covariance estimator of the illuminant fit.
    pub covariance: Covariance,
    /// Day neutral overriding the file's (r, g, b).
    pub day_neutral: Option<[f64; 3]>,
    /// Mask evaluation.
    pub mask_eval: MaskEval,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            mode: Mode::Local,
            formula: RelightFormula::Release,
            bulbs: None,
            local_lights: None,
            isos: vec![1600, 3200],
            truncate: false,
            keep_negative: false,
            keep_highlights: false,
            dim_range: [0.55, 0.90],
            ambient_gain: 0.05,
            bulb_gain: [50.0, 100.0],
            sampler: SamplerRules::default(),
            covariance: Covariance::Unbiased,
            day_neutral: None,
            mask_eval: MaskEval::Separable,
        }
    }
}

/// Upper bound on lights and bulbs (each costs a pass over its window).
pub const MAX_LIGHTS: u32 = 256;

impl SynthOptions {
    /// Error on out-of-range options.
    pub fn validate(&self) -> Result<()> {
        if self.bulbs.unwrap_or(0) > MAX_LIGHTS || self.local_lights.unwrap_or(0) > MAX_LIGHTS {
            return Err(Error::invalid(format!(
                "at most {} lights or bulbs",
                MAX_LIGHTS
            )));
        }
        if self.isos.contains(&0) {
            return Err(Error::invalid("ISO 0"));
        }
        if self.isos.len() > plan_bounds::MAX_NOISE_ENTRIES {
            return Err(Error::invalid(format!(
                "{} ISOs (at most {})",
                self.isos.len(),
                plan_bounds::MAX_NOISE_ENTRIES
            )));
        }
        let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !(fin(&self.dim_range)
            && self.dim_range[0] > 0.0
            && self.dim_range[0] <= self.dim_range[1])
        {
            return Err(Error::invalid("dimming range must satisfy 0 < lo <= hi"));
        }
        if !fin(&self.bulb_gain) || self.bulb_gain[0] < 0.0 || self.bulb_gain[0] > self.bulb_gain[1]
        {
            return Err(Error::invalid("bulb gain range must satisfy 0 <= lo <= hi"));
        }
        if !(self.ambient_gain >= 0.0 && self.ambient_gain.is_finite()) {
            return Err(Error::invalid("ambient gain must be >= 0"));
        }
        if let MaskEval::Truncated { k } = self.mask_eval {
            if !(k > 0.0 && k.is_finite()) {
                return Err(Error::invalid("mask truncation radius must be > 0"));
            }
        }
        let s = &self.sampler;
        if s.max_mahalanobis.is_nan()
            || s.max_mahalanobis <= 0.0
            || !s.floor.is_finite()
            || s.max_tries == 0
        {
            return Err(Error::invalid(
                "illuminant sampler: radius must be > 0, floor finite, tries >= 1",
            ));
        }
        Ok(())
    }
}

/// Calibration used by planning: illuminant fit, optional brightness and noise model.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The fitted night illuminant Gaussian.
    pub illuminants: Gaussian2,
    /// Brightness dictionary (`--brightness`), if any.
    pub brightness: Option<BrightnessDict>,
    /// Noise model file (`--noise-model`), if any; otherwise the input's NoiseProfile or the
    /// embedded table is used.
    pub noise: Option<NoiseModel>,
}

impl Calibration {
    /// The embedded default (the paper phone's dictionary and noise table).
    pub fn embedded(opts: &SynthOptions) -> Result<Calibration> {
        Ok(Calibration {
            illuminants: Gaussian2::fit(&dictionaries::embedded::illuminants(), opts.covariance)?,
            brightness: None,
            noise: None,
        })
    }
}

/// Result of [`run`].
#[derive(Debug, Clone)]
pub struct SynthOutput {
    /// Clean night raw with its output metadata.
    pub clean: RawImage,
    /// (ISO, noisy raw) per planned ISO.
    pub noisy: Vec<(u32, RawImage)>,
    /// Values computed while running.
    pub report: RunReport,
}

/// Bits needed to hold `white`.
fn bits_for(white: f64) -> u16 {
    let mut b = 1u16;
    while b < 16 && ((1u32 << b) - 1) as f64 <= white - 0.5 {
        b += 1;
    }
    b
}

/// Metadata of a night output: AsShotNeutral = the night neutral (AsShotWhiteXY dropped),
/// Exif ISO = `iso`, NoiseProfile = `params` per colour plane; a LinearizationTable is
/// dropped (outputs hold linear values) and BitsPerSample raised to hold WhiteLevel.
pub fn night_meta(src: &RawMeta, plan: &Plan, iso: u32, params: &NoiseParams) -> RawMeta {
    let mut m = src.clone();
    m.as_shot_neutral = Some(plan.night_neutral);
    m.as_shot_white_xy = None;
    m.exif.iso = Some(iso);
    m.noise_profile = Some(params.to_dng_profile(plan.bayer));
    if m.linearization_table.take().is_some() {
        m.bits_per_sample = m.bits_per_sample.max(bits_for(m.levels.white)).min(16);
    }
    m
}

/// The noisy raw of the plan's `index`-th ISO from the clean night raw.
pub fn run_noise(clean: &RawImage, plan: &Plan, index: usize) -> Result<(u32, RawImage)> {
    let np = plan
        .noise
        .get(index)
        .ok_or_else(|| Error::invalid(format!("plan has no noise entry {}", index)))?;
    let mut img = match &np.physics {
        Some(p) => crate::noise::apply_physics_noise_image(clean, p, np.seed)?,
        None => crate::noise::apply_noise(clean, &np.params, np.seed)?,
    };
    img.meta = night_meta(&clean.meta, plan, np.iso, &np.params);
    Ok((np.iso, img))
}

#[cfg(test)]
mod tests;
