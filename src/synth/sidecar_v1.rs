//! Sidecars of version 1 (`day2night-sidecar/1`, written up to this change): their shape,
//! and the one migration to version 2 ([`migrate`]). In version 1 the plan held its report
//! (provenance, stages, opcode report, warnings) beside the draws, and fields added over
//! time were left out when they had their old value, so that older files replayed byte for
//! byte; this module owns those defaults. A migrated sidecar replays to the same outputs,
//! byte for byte, as the version-1 run wrote (tests/it/sidecar_v1.rs).

use super::dim::DimPlan;
use super::illuminant::Gaussian2;
use super::illuminant_choice::IlluminantProvenance;
use super::masks::{Light, MaskEval};
use super::plan::{NoisePlan, Plan, PLAN_FORMAT};
use super::plan_report::PlanReport;
use super::relight::RunReport;
use super::sidecar::{CalibrationInfo, InputInfo, OutputInfo, Provenance, Sidecar};
use super::{Mode, RelightFormula, SynthOptions};
use crate::error::{Error, Result};
use crate::isp::opcodes::{OpcodeMode, OpcodeReport};
use crate::noise::{NoiseParams, NoiseProvenance, PhysicsParams};
use crate::raw::Bayer;
use serde::Deserialize;

/// Format tag of version-1 sidecars.
pub const FORMAT: &str = "day2night-sidecar/1";
/// Format tag of version-1 plans.
pub const PLAN_FORMAT_V1: &str = "day2night-plan/1";

/// A version-1 sidecar.
#[derive(Debug, Clone, Deserialize)]
pub struct SidecarV1 {
    format: String,
    tool: String,
    version: String,
    input: InputInfo,
    options: SynthOptions,
    calibration: CalibrationV1,
    plan: PlanV1,
    run: RunV1,
    stages: Vec<String>,
    outputs: OutputsV1,
}

/// `calibration`: `provenance` absent in files written before it existed.
#[derive(Debug, Clone, Deserialize)]
struct CalibrationV1 {
    illuminants: Gaussian2,
    brightness: Option<super::dictionaries::BrightnessDict>,
    noise_model: String,
    #[serde(default)]
    provenance: Option<ProvenanceV1>,
}

#[derive(Debug, Clone, Deserialize)]
struct ProvenanceV1 {
    #[serde(default)]
    illuminants: Option<IlluminantProvenance>,
    #[serde(default)]
    noise: Option<NoiseProvenance>,
}

/// `run`: `warnings` absent when empty.
#[derive(Debug, Clone, Deserialize)]
struct RunV1 {
    dim_scale: f64,
    mean_white_balanced: Option<f64>,
    saturated_sites: u64,
    #[serde(default)]
    warnings: crate::diagnostics::Diagnostics,
}

/// `outputs`: `exr_compression` absent = "zip", `exr_zip_level` absent = 1 (sidecars of
/// 0.1.0 have neither: their EXRs were level-4 ZIP from the `exr` crate, so a replay
/// reproduces their raw outputs byte for byte and their EXR pixels exactly, in a
/// smaller-compression container).
#[derive(Debug, Clone, Deserialize)]
struct OutputsV1 {
    variants: u32,
    compression: String,
    target: String,
    input_exr: bool,
    files: Vec<String>,
    #[serde(default)]
    exr_compression: Option<String>,
    #[serde(default)]
    exr_zip_level: Option<u8>,
}

/// A version-1 noise entry: `physics` absent for Gaussian models.
#[derive(Debug, Clone, Deserialize)]
struct NoiseV1 {
    iso: u32,
    seed: u64,
    params: NoiseParams,
    extrapolated: bool,
    #[serde(default)]
    physics: Option<PhysicsParams>,
}

/// A version-1 plan: the draws and the report in one object. `target_size`,
/// `noise_provenance`, `opcodes` and `burst` absent when none (and in files written before
/// they existed: then the renders ignore the opcode lists); `truncate_noise` and
/// `range_per_site` absent when false.
#[derive(Debug, Clone, Deserialize)]
struct PlanV1 {
    format: String,
    input_name: String,
    seed: u64,
    variant: u32,
    active_width: usize,
    active_height: usize,
    #[serde(default)]
    target_size: Option<[usize; 2]>,
    bayer: Bayer,
    mode: Mode,
    formula: RelightFormula,
    truncate: bool,
    #[serde(default)]
    truncate_noise: bool,
    #[serde(default)]
    range_per_site: bool,
    keep_negative: bool,
    keep_highlights: bool,
    mask_eval: MaskEval,
    day_neutral: [f64; 3],
    day_neutral_source: String,
    dim: DimPlan,
    lights: Vec<Light>,
    night_neutral: [f64; 3],
    night_neutral_definition: String,
    clean_iso: u32,
    clean_noise: NoiseParams,
    noise_model_source: String,
    #[serde(default)]
    noise_provenance: Option<NoiseProvenance>,
    noise: Vec<NoiseV1>,
    stages: Vec<String>,
    warnings: crate::diagnostics::Diagnostics,
    #[serde(default)]
    opcodes: Option<OpcodeReport>,
    #[serde(default)]
    burst: Option<super::burst::BurstPlan>,
}

/// The one migration from version 1: the plan's draws stay the plan (format
/// `day2night-plan/2`; the renders' opcode mode is the opcode report's, `ignore` when the
/// plan had none), its provenance, stages, opcode report, target size and warnings become
/// the report; the defaults of absent fields are written out. Every value is kept as read,
/// so the outputs of a replay do not change.
pub fn migrate(v1: SidecarV1) -> Result<Sidecar> {
    if v1.format != FORMAT || v1.plan.format != PLAN_FORMAT_V1 {
        return Err(Error::malformed(format!(
            "sidecar format {:?} with plan format {:?} (expected {:?} with {:?})",
            v1.format, v1.plan.format, FORMAT, PLAN_FORMAT_V1
        )));
    }
    let p = v1.plan;
    let plan = Plan {
        format: PLAN_FORMAT.into(),
        input_name: p.input_name,
        seed: p.seed,
        variant: p.variant,
        active_width: p.active_width,
        active_height: p.active_height,
        bayer: p.bayer,
        mode: p.mode,
        formula: p.formula,
        truncate: p.truncate,
        truncate_noise: p.truncate_noise,
        range_per_site: p.range_per_site,
        keep_negative: p.keep_negative,
        keep_highlights: p.keep_highlights,
        mask_eval: p.mask_eval,
        day_neutral: p.day_neutral,
        dim: p.dim,
        lights: p.lights,
        night_neutral: p.night_neutral,
        clean_iso: p.clean_iso,
        clean_noise: p.clean_noise,
        noise: p.noise.into_iter().map(noise_entry).collect(),
        // version-1 plans drew from the first noise stream
        noise_stream: crate::noise::NoiseStream::V1,
        opcodes: p.opcodes.as_ref().map_or(OpcodeMode::Ignore, |r| r.mode),
        burst: p.burst,
        frame_mean: Default::default(),
    };
    let report = PlanReport {
        day_neutral_source: p.day_neutral_source,
        night_neutral_definition: p.night_neutral_definition,
        noise_model_source: p.noise_model_source,
        noise_provenance: p.noise_provenance,
        stages: p.stages,
        opcodes: p.opcodes,
        target_size: p.target_size,
        warnings: p.warnings,
    };
    let (c, o, r) = (v1.calibration, v1.outputs, v1.run);
    Ok(Sidecar {
        format: super::sidecar::SIDECAR_FORMAT.into(),
        tool: v1.tool,
        version: v1.version,
        input: v1.input,
        options: v1.options,
        calibration: CalibrationInfo {
            illuminants: c.illuminants,
            brightness: c.brightness,
            noise_model: c.noise_model,
            provenance: c.provenance.map(|p| Provenance {
                illuminants: p.illuminants,
                noise: p.noise,
            }),
        },
        plan,
        report,
        run: RunReport {
            dim_scale: r.dim_scale,
            mean_white_balanced: r.mean_white_balanced,
            saturated_sites: r.saturated_sites,
            warnings: r.warnings,
        },
        stages: v1.stages,
        outputs: OutputInfo {
            variants: o.variants,
            compression: o.compression,
            target: o.target,
            input_exr: o.input_exr,
            files: o.files,
            exr_compression: o.exr_compression.unwrap_or_else(|| "zip".into()),
            exr_zip_level: o
                .exr_zip_level
                .unwrap_or(crate::encode::exr::ExrOptions::DEFAULT_ZIP_LEVEL),
            // version-1 DNGs' IDs were SHA-256
            raw_data_unique_id: crate::dng::write::UniqueIdHash::Sha256.name().into(),
        },
    })
}

fn noise_entry(n: NoiseV1) -> NoisePlan {
    NoisePlan {
        iso: n.iso,
        seed: n.seed,
        params: n.params,
        extrapolated: n.extrapolated,
        physics: n.physics,
    }
}
