//! Day-to-night synthesis (docs/synthesis.md): a seeded [`Plan`] sampled up front by a
//! [`Planner`] (with its [`PlanReport`]), then a pure [`run`].
//!
//! ```no_run
//! use day2night::synth::{self, Calibration, SynthOptions};
//! # fn main() -> day2night::Result<()> {
//! let day = day2night::dng::read_dng("day.dng".as_ref())?;
//! let opts = SynthOptions::default();
//! let cal = Calibration::embedded(&opts)?;
//! let planned = synth::Planner::new(&day, &opts)
//!     .calibration(&cal)
//!     .name("day.dng")
//!     .plan()?;
//! let out = synth::run(&day, &planned.plan)?;
//! // out.clean: the clean night raw; out.noisy: one (ISO, raw) per --iso value.
//! # Ok(()) }
//! ```

pub mod burst;
pub mod config;
pub mod day_input;
pub mod dictionaries;
pub mod dim;
pub mod file_sink;
pub mod illuminant;
pub mod illuminant_choice;
pub mod job;
mod light_row;
pub mod masks;
pub mod neutral;
pub mod night;
pub mod noise_source;
pub mod options;
pub mod outputs;
pub mod patches;
pub mod plan;
pub mod plan_bounds;
pub mod plan_report;
pub mod readiness;
pub mod relight;
pub mod rng;
pub mod sidecar;
pub mod sidecar_read;
pub mod sidecar_v1;

pub use illuminant::{Covariance, Gaussian2, SamplerRules};
pub use illuminant_choice::{IlluminantChoice, IlluminantProvenance, ResolvedIlluminants};
pub use masks::{Light, LightKind, MaskEval};
pub use plan::{NoisePlan, Plan, Planned, Planner};
pub use plan_report::PlanReport;
pub use relight::{run, run_clean, RunReport};

use crate::error::{Error, Result};
use crate::isp::opcodes::OpcodeMode;
use crate::noise::{NoiseModel, NoiseParams};
use crate::raw::meta::RawMeta;
use crate::raw::RawImage;
use dictionaries::BrightnessDict;
use serde::{Deserialize, Serialize};

/// Relighting mode (docs/synthesis.md, "5. Relight").
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

/// Switches that reproduce the authors' released code where day2night deliberately differs
/// (docs/synthesis.md, "Release compatibility"). All off by default; the whole struct is
/// left out of serialized options when off, so default sidecars are unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Compat {
    /// Divide by the day neutral as stored (AsShotNeutral or `--day-neutral` as given), not
    /// normalized to green = 1 (the release; see [`neutral::day_neutral_as_stored`]).
    pub neutral_as_stored: bool,
    /// Truncate the noisy raws too when `truncate` is set (the release's `astype(uint16)`).
    pub truncate_noise: bool,
    /// Normalize and denormalize each site with its own range `white - black(site)`, not
    /// `white - black_max` (the release's `normalize`/`denormalize` with a 2x2 BlackLevel;
    /// see [`crate::normalize::Normalizer::with_range_per_site`]). Changes nothing when the
    /// black level is one value.
    pub range_per_site: bool,
    /// Sample every input's night illuminants from the paper phone's dictionary (its camera
    /// RGB), as the release does, unless `--illuminants` says otherwise; off: the CIE lamps
    /// through each file's colour matrices for cameras other than the phone (absent from
    /// serialized options when off, so sidecars written before it replay unchanged).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub paper_illuminants: bool,
    /// Use the embedded noise table (the paper's phone's) for inputs without a NoiseProfile
    /// instead of an estimate from the image (the release applies its table to every
    /// input). Absent from serialized options when off, so older sidecars are unchanged.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub embedded_noise: bool,
}

impl Compat {
    /// Every switch on (the `--compat release` preset's part of it).
    pub const RELEASE: Compat = Compat {
        neutral_as_stored: true,
        truncate_noise: true,
        range_per_site: true,
        paper_illuminants: true,
        embedded_noise: true,
    };
    /// True when no switch is on.
    pub fn is_off(&self) -> bool {
        *self == Compat::default()
    }
}

/// Declares the struct it is given and its `blank()`: every field at its type's default,
/// on which [`options::with_defaults`] sets the option table's defaults. So a field's
/// default is written once, in its option's entry (src/synth/options/table.rs), and a field
/// that is not an option has its type's default (`CONSTANTS` there says why it is fixed).
macro_rules! with_blank {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $($(#[$field_meta:meta])* pub $field:ident: $ty:ty,)*
        }
    ) => {
        $(#[$meta])*
        pub struct $name {
            $($(#[$field_meta])* pub $field: $ty,)*
        }

        impl $name {
            /// Every field at its type's default.
            fn blank() -> $name {
                $name {
                    $($field: Default::default(),)*
                }
            }
        }
    };
}

with_blank! {
/// Synthesis options (all serializable: the sidecar records them). The defaults are the
/// option table's ([`options::OPTIONS`]).
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
    /// Release-compatibility switches (absent from serialized options when all off).
    #[serde(default, skip_serializing_if = "Compat::is_off")]
    pub compat: Compat,
    /// Apply the input's DNG opcode lists in the rendered targets and inputs (`apply`, the
    /// default, absent from serialized options) or ignore them (`--compat release`). The
    /// raws never change: the night DNGs keep the lists byte for byte.
    #[serde(default, skip_serializing_if = "OpcodeMode::is_apply")]
    pub opcodes: OpcodeMode,
    /// Burst frames and their motion (`--burst N`); absent from serialized options for a
    /// single frame, so single-frame sidecars and dataset fingerprints are unchanged.
    #[serde(
        default = "options::burst_defaults",
        skip_serializing_if = "burst::BurstOptions::is_single"
    )]
    pub burst: burst::BurstOptions,
    /// Factor on the noise model's standard deviation at every ISO (`--noise-gain`; 1: the
    /// model as calibrated, absent from serialized options).
    #[serde(skip_serializing_if = "is_one")]
    pub noise_gain: f64,
}
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

impl Default for SynthOptions {
    /// The option table's defaults ([`options::with_defaults`]).
    fn default() -> Self {
        options::with_defaults(SynthOptions::blank())
    }
}

/// Largest Mahalanobis radius: the sampler's "no cut" (finite, so that it round-trips
/// through the JSON sidecar; every finite draw is within it).
pub const NO_MAHALANOBIS_CUT: f64 = f64::MAX;

impl SynthOptions {
    /// The `--compat release` preset applied to `self`: the authors' released code where it
    /// is deterministic (docs/synthesis.md, "Release compatibility"): the release formula,
    /// the unbiased covariance, truncation of clean and noisy raws, the day neutral as
    /// stored, illuminant draws not cut by a Mahalanobis radius, the paper phone's illuminant
    /// dictionary for every camera, and the release's sampled, resized light kernels. Errors when `self` asks for something else on one of these
    /// (the paper formula, the ML covariance, another mask evaluation).
    pub fn release_compat(mut self) -> Result<SynthOptions> {
        if self.formula != RelightFormula::Release {
            return Err(Error::invalid(
                "the release preset uses the release relight formula, not the paper's",
            ));
        }
        if self.covariance != Covariance::Unbiased {
            return Err(Error::invalid(
                "the release preset uses the unbiased covariance (numpy's np.cov), not ml",
            ));
        }
        if !matches!(self.mask_eval, MaskEval::Separable | MaskEval::Release) {
            return Err(Error::invalid(
                "the release preset evaluates masks as the release does (mask-eval release)",
            ));
        }
        self.truncate = true;
        self.compat = Compat::RELEASE;
        self.sampler.max_mahalanobis = NO_MAHALANOBIS_CUT;
        self.mask_eval = MaskEval::Release;
        // The authors' data preparation renders without the DNG opcodes.
        self.opcodes = OpcodeMode::Ignore;
        Ok(self)
    }
}

/// Upper bound on lights and bulbs (each costs a pass over its window).
pub use crate::bounds::MAX_LIGHTS;

impl SynthOptions {
    /// Error on out-of-range options.
    pub fn validate(&self) -> Result<()> {
        for &iso in &self.isos {
            crate::bounds::iso("", iso)?;
        }
        if self.isos.len() > plan_bounds::MAX_NOISE_ENTRIES {
            return Err(Error::invalid(format!(
                "{} ISOs (at most {})",
                self.isos.len(),
                plan_bounds::MAX_NOISE_ENTRIES
            )));
        }
        // the ranges of the option table (counts, numbers, the burst's)
        options::check_fields(self)?;
        if let MaskEval::Truncated { k } = self.mask_eval {
            if !(k > 0.0 && k.is_finite()) {
                return Err(Error::invalid("mask truncation radius must be > 0"));
            }
        }
        if self.compat.truncate_noise && !self.truncate {
            return Err(Error::invalid(
                "compat.truncate_noise truncates the noisy raws when truncating: it needs truncate",
            ));
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

/// Calibration used by planning: illuminant dictionary, optional brightness and noise model.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The night illuminant dictionary, resolved per input ([`IlluminantChoice::resolve`]).
    pub illuminants: IlluminantChoice,
    /// Brightness dictionary (`--brightness`), if any.
    pub brightness: Option<BrightnessDict>,
    /// Noise model file (`--noise-model`), if any; otherwise the input's NoiseProfile, an
    /// estimate from the image or the embedded table ([`noise_source`]).
    pub noise: Option<NoiseModel>,
}

impl Calibration {
    /// The default calibration for `opts`: night illuminants from the paper phone's
    /// dictionary for the phone and the CIE lamps through each file's colour matrices for
    /// other cameras (the phone's dictionary everywhere under the release preset), no
    /// brightness dictionary, the input's NoiseProfile or the embedded noise table.
    pub fn embedded(opts: &SynthOptions) -> Result<Calibration> {
        Ok(Calibration {
            illuminants: IlluminantChoice::default_for(opts.compat.paper_illuminants),
            brightness: None,
            noise: None,
        })
    }

    /// The night illuminant dictionary of an input with metadata `meta`
    /// ([`IlluminantChoice::resolve`]).
    pub fn illuminants_for(
        &self,
        meta: &RawMeta,
        opts: &SynthOptions,
    ) -> Result<ResolvedIlluminants> {
        self.illuminants.resolve(
            &crate::raw::camera::CameraId::of(meta),
            &meta.color,
            opts.covariance,
        )
    }

    /// The dictionary a sidecar records for `meta`: [`Calibration::illuminants_for`]; for
    /// the modes that sample no illuminant (`day`, `dimmed`) an input whose dictionary cannot
    /// be made (no colour matrices) records the paper phone's, saying it was not used.
    pub fn illuminants_recorded(
        &self,
        meta: &RawMeta,
        opts: &SynthOptions,
    ) -> Result<ResolvedIlluminants> {
        match self.illuminants_for(meta, opts) {
            Err(e) if matches!(opts.mode, Mode::Day | Mode::Dimmed) => {
                let mut r = IlluminantChoice::Paper.resolve(
                    &dictionaries::embedded::paper().illuminants_camera,
                    &meta.color,
                    opts.covariance,
                )?;
                let mode = if opts.mode == Mode::Day {
                    "day"
                } else {
                    "dimmed"
                };
                r.provenance.note = format!("not used (mode {mode}); this input has none: {e}");
                Ok(r)
            }
            r => r,
        }
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
    with_noisy_rows(clean, plan, index, |iso, meta, rows| {
        let img = RawImage {
            width: rows.width(),
            height: rows.height(),
            data: crate::raw::rows::to_plane(rows)?,
            meta: meta.clone(),
        };
        Ok((iso, img))
    })
}

/// Hand `f` the plan's `index`-th ISO, the noisy raw's metadata and its rows made on demand
/// from the clean night raw (the samples of [`run_noise`], without a noisy plane: a file
/// sink packs them strip by strip).
pub fn with_noisy_rows<T>(
    clean: &RawImage,
    plan: &Plan,
    index: usize,
    f: impl FnOnce(u32, &RawMeta, &dyn crate::raw::rows::RowSource) -> Result<T>,
) -> Result<T> {
    let np = plan
        .noise
        .get(index)
        .ok_or_else(|| Error::invalid(format!("plan has no noise entry {}", index)))?;
    let meta = night_meta(&clean.meta, plan, np.iso, &np.params);
    match &np.physics {
        Some(p) => {
            crate::noise::with_physics_rows(clean, p, np.seed, |rows| f(np.iso, &meta, rows))
        }
        None => {
            let rows = crate::noise::apply::gaussian_rows(
                clean,
                &np.params,
                np.seed,
                plan.truncate_noise,
                plan.noise_stream,
            )?;
            f(np.iso, &meta, &rows)
        }
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod compat_tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::Bayer;

    fn frame(neutral: [f64; 3]) -> RawImage {
        let (w, h) = (64usize, 48usize);
        let mut meta = RawMeta::new_bayer(Bayer::RGGB, 10, 64.0, 1023.0);
        meta.as_shot_neutral = Some(neutral);
        RawImage {
            width: w,
            height: h,
            data: (0..w * h)
                .map(|i| 100 + ((i * 7919) % 800) as u16)
                .collect(),
            meta,
        }
    }

    fn planned(img: &RawImage, o: &SynthOptions) -> Plan {
        Planner::new(img, o)
            .name("c.dng")
            .seed(7)
            .plan()
            .unwrap()
            .plan
    }

    #[test]
    fn defaults_serialize_without_compat_and_old_options_parse() {
        let o = SynthOptions::default();
        let j = serde_json::to_string(&o).unwrap();
        assert!(!j.contains("compat"), "{j}");
        let p = planned(&frame([0.5, 1.0, 0.4]), &o);
        let pj = serde_json::to_string(&p).unwrap();
        assert!(pj.contains("\"truncate_noise\":false"), "{pj}");
        // options written before the field existed parse to the defaults (plans of
        // version 1 without it: sidecar_v1)
        let back: SynthOptions = serde_json::from_str(&j).unwrap();
        assert_eq!(back, o);
        let back: Plan = serde_json::from_str(&pj).unwrap();
        assert_eq!(back, p);
    }

    #[test]
    fn release_preset_sets_each_piece_and_round_trips() {
        let r = SynthOptions::default().release_compat().unwrap();
        assert!(r.truncate);
        assert_eq!(r.compat, Compat::RELEASE);
        assert_eq!(r.sampler.max_mahalanobis, NO_MAHALANOBIS_CUT);
        assert_eq!(r.mask_eval, MaskEval::Release);
        r.validate().unwrap();
        let j = serde_json::to_string(&r).unwrap();
        assert_eq!(serde_json::from_str::<SynthOptions>(&j).unwrap(), r);
        let p = planned(&frame([0.5, 1.0, 0.4]), &r);
        assert!(p.truncate && p.truncate_noise);
        assert_eq!(p.mask_eval, MaskEval::Release);
        let pj = serde_json::to_string(&p).unwrap();
        assert_eq!(serde_json::from_str::<Plan>(&pj).unwrap(), p);
        // conflicting requests are refused, not overridden
        for bad in [
            SynthOptions {
                formula: RelightFormula::Paper,
                ..SynthOptions::default()
            },
            SynthOptions {
                covariance: Covariance::MaximumLikelihood,
                ..SynthOptions::default()
            },
            SynthOptions {
                mask_eval: MaskEval::Exact,
                ..SynthOptions::default()
            },
        ] {
            assert!(bad.release_compat().is_err());
        }
        // noise truncation only when truncating
        let lone = SynthOptions {
            compat: Compat {
                truncate_noise: true,
                ..Compat::default()
            },
            ..SynthOptions::default()
        };
        assert!(lone.validate().is_err());
    }

    #[test]
    fn neutral_as_stored_divides_by_the_stored_vector() {
        // green 2.477 stored: the global relight comes out 2.477x darker than ours
        let img = frame([1.0, 2.477, 1.462]);
        let base = SynthOptions {
            mode: Mode::Global,
            isos: vec![],
            ..SynthOptions::default()
        };
        let stored = SynthOptions {
            compat: Compat {
                neutral_as_stored: true,
                ..Compat::default()
            },
            ..base.clone()
        };
        let (a, b) = (planned(&img, &base), planned(&img, &stored));
        assert_eq!(a.lights, b.lights, "same draws");
        assert_eq!(b.day_neutral, [1.0, 2.477, 1.462]);
        let (oa, _) = run_clean(&img, &a).unwrap();
        let (ob, _) = run_clean(&img, &b).unwrap();
        // green sites (RGGB: row + col odd): y_w = y or y / 2.477, neither clipped here
        let (mut sa, mut sb) = (0.0, 0.0);
        for (i, (&x, &y)) in oa.data.iter().zip(&ob.data).enumerate() {
            if (i / img.width + i % img.width) % 2 == 1 {
                sa += x as f64 - 64.0;
                sb += y as f64 - 64.0;
            }
        }
        let ratio = sa / sb;
        assert!((ratio - 2.477).abs() < 0.01, "{ratio}");
    }

    #[test]
    fn noise_truncation_is_a_half_dn_bias_on_the_same_draws() {
        let img = frame([0.5, 1.0, 0.4]);
        let o = SynthOptions {
            mode: Mode::Dimmed,
            isos: vec![3200],
            truncate: true,
            ..SynthOptions::default()
        };
        let t = SynthOptions {
            compat: Compat {
                truncate_noise: true,
                ..Compat::default()
            },
            ..o.clone()
        };
        let (pr, pt) = (planned(&img, &o), planned(&img, &t));
        let (r, tr) = (run(&img, &pr).unwrap(), run(&img, &pt).unwrap());
        assert_eq!(r.clean.data, tr.clean.data);
        let (mut n, mut sum) = (0f64, 0f64);
        for (&a, &b) in r.noisy[0].1.data.iter().zip(&tr.noisy[0].1.data) {
            let d = b as f64 - a as f64;
            assert!(d == 0.0 || d == -1.0, "{a} {b}");
            if a > 0 && a < 1023 {
                n += 1.0;
                sum += d;
            }
        }
        let bias = sum / n;
        eprintln!("noise truncation bias {bias:.4} DN over {n} samples");
        assert!((bias + 0.5).abs() < 0.05, "{bias}");
        // thread-count independent
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let one = pool.install(|| run(&img, &pt).unwrap());
        assert_eq!(one.noisy[0].1.data, tr.noisy[0].1.data);
    }
}
