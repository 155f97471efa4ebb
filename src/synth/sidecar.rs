//! The JSON sidecar written next to each (input, variant)'s outputs, version 2
//! (`day2night-sidecar/2`, docs/synthesis.md "The sidecar"): every sampled value (the
//! [`Plan`]), what planning found besides (the [`PlanReport`]), the options, calibration
//! summary, values computed while running, the stages that ran, the tool version, the
//! input's name and SHA-256, and the output names. `--replay` rebuilds the plan from it and
//! reproduces the outputs byte for byte. Its content is deterministic (no timestamps), so a
//! replay rewrites it identically. Every field is always written (null when absent).
//!
//! Reading (either version): [`super::sidecar_read`]; version-1 sidecars
//! (`day2night-sidecar/1`, whose plan held its report) go through the one migration,
//! `sidecar_v1::migrate`.

use super::illuminant::Gaussian2;
use super::illuminant_choice::IlluminantProvenance;
use super::plan::{Plan, Planned};
use super::plan_report::PlanReport;
use super::relight::RunReport;
use super::SynthOptions;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Format tag of sidecars.
pub const SIDECAR_FORMAT: &str = "day2night-sidecar/2";

/// The input file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputInfo {
    /// File name (the RNG stream is derived from it).
    pub name: String,
    /// SHA-256 of the file's bytes, lowercase hex.
    pub sha256: String,
}

/// Calibration summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationInfo {
    /// The illuminant Gaussian sampled from (this input's: in its camera's `[r/g, b/g]`).
    pub illuminants: Gaussian2,
    /// Brightness dictionary (name, mean, std), if used.
    pub brightness: Option<super::dictionaries::BrightnessDict>,
    /// Noise model source (the report's `noise_model_source`).
    pub noise_model: String,
    /// Where each calibration came from and which camera it belongs to; null in the
    /// replays of version-1 sidecars written before it existed.
    pub provenance: Option<Provenance>,
}

/// `calibration.provenance`: where each calibration of one input came from and which
/// camera it belongs to, one entry per calibration.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The night illuminant dictionary: embedded S20 FE, CIE lamps through this file's
    /// matrices, a file's camera RGB or xy; and its camera.
    pub illuminants: Option<IlluminantProvenance>,
    /// The noise model's (the report's `noise_provenance`).
    pub noise: Option<crate::noise::NoiseProvenance>,
}

/// Output settings and names (relative to the output directory).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputInfo {
    /// Number of variants of the run (decides the `_vK` part of names).
    pub variants: u32,
    /// DNG compression ("none" or "ljpeg").
    pub compression: String,
    /// Target kind ("exr", "png", "both" or "none").
    pub target: String,
    /// Whether the network input EXR was requested.
    pub input_exr: bool,
    /// Names of the files written.
    pub files: Vec<String>,
    /// EXR compression of the EXR outputs (`synth --exr-compression`).
    pub exr_compression: String,
    /// zlib level of zip/zips EXR outputs (`--exr-zip-level`).
    pub exr_zip_level: u8,
    /// The hash of the DNGs' RawDataUniqueID: "xxh3-128", or "sha256" in sidecars written
    /// before it (absent there).
    #[serde(default = "sha256_name")]
    pub raw_data_unique_id: String,
}

/// `outputs.raw_data_unique_id` of sidecars that record none.
fn sha256_name() -> String {
    crate::dng::write::UniqueIdHash::Sha256.name().into()
}

/// The sidecar document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sidecar {
    /// [`SIDECAR_FORMAT`].
    pub format: String,
    /// "day2night".
    pub tool: String,
    /// Tool version.
    pub version: String,
    /// Input.
    pub input: InputInfo,
    /// Options.
    pub options: SynthOptions,
    /// Calibration.
    pub calibration: CalibrationInfo,
    /// Every sampled value.
    pub plan: Plan,
    /// What planning found besides: provenance, planned stages, opcodes, warnings.
    pub report: PlanReport,
    /// Values computed while running.
    pub run: RunReport,
    /// Stages that ran (plan stages plus the outputs written).
    pub stages: Vec<String>,
    /// Outputs.
    pub outputs: OutputInfo,
}

impl Sidecar {
    /// Pretty JSON with a trailing newline.
    pub fn to_json(&self) -> Result<String> {
        let mut s = serde_json::to_string_pretty(self)
            .map_err(|e| Error::invalid(format!("sidecar serialization: {}", e)))?;
        s.push('\n');
        Ok(s)
    }
    /// The plan and its report, as planning made them (what `--replay` runs).
    pub fn planned(&self) -> Planned {
        Planned {
            plan: self.plan.clone(),
            report: self.report.clone(),
        }
    }
}

/// SHA-256 of bytes as lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{:02x}", b))
        .collect()
}
