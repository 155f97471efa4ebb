//! The JSON sidecar written next to each (input, variant)'s outputs, version 2
//! (`day2night-sidecar/2`, docs/synthesis.md "The sidecar"): every sampled value (the
//! [`Plan`]), what planning found besides (the [`PlanReport`]), the options, calibration
//! summary, values computed while running, the stages that ran, the tool version, the
//! input's name and SHA-256, and the output names. `--replay` rebuilds the plan from it and
//! reproduces the outputs byte for byte. Its content is deterministic (no timestamps), so a
//! replay rewrites it identically. Every field is always written (null when absent).
//!
//! Version-1 sidecars (`day2night-sidecar/1`, whose plan held its report) are read by
//! [`Sidecar::from_json`] through the one migration, [`super::sidecar_v1::migrate`].

use super::illuminant::Gaussian2;
use super::illuminant_choice::IlluminantProvenance;
use super::plan::Plan;
use super::plan_report::{PlanReport, Planned};
use super::relight::RunReport;
use super::SynthOptions;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::Path;

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
    /// Parse a sidecar of version 2, or of version 1 through its migration
    /// ([`super::sidecar_v1::migrate`]), and check its bounds.
    pub fn from_json(text: &str) -> Result<Sidecar> {
        let v: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| Error::malformed(format!("sidecar JSON: {}", e)))?;
        Sidecar::from_value(v)
    }

    /// [`Sidecar::from_json`] of a parsed document.
    pub fn from_value(v: serde_json::Value) -> Result<Sidecar> {
        let format = v.get("format").and_then(|f| f.as_str()).unwrap_or_default();
        let json = |e: serde_json::Error| Error::malformed(format!("sidecar JSON: {}", e));
        let s: Sidecar = match format {
            SIDECAR_FORMAT => serde_json::from_value(v).map_err(json)?,
            super::sidecar_v1::FORMAT => {
                super::sidecar_v1::migrate(serde_json::from_value(v).map_err(json)?)?
            }
            other => {
                return Err(Error::malformed(format!(
                    "sidecar format {:?} (expected {:?} or {:?})",
                    other,
                    SIDECAR_FORMAT,
                    super::sidecar_v1::FORMAT
                )))
            }
        };
        // Bounds before any use: a hostile sidecar is refused at once, naming the field.
        s.plan
            .validate_bounds()
            .and_then(|()| s.report.validate_bounds())
            .map_err(|e| Error::invalid(format!("sidecar: {}", strip_kind(&e))))?;
        s.options
            .validate()
            .map_err(|e| Error::invalid(format!("sidecar options: {}", strip_kind(&e))))?;
        if s.outputs.files.len() > 4 * super::plan_bounds::MAX_NOISE_ENTRIES + 16 {
            return Err(Error::invalid(format!(
                "sidecar: outputs.files lists {} files",
                s.outputs.files.len()
            )));
        }
        Ok(s)
    }

    /// The plan and its report, as planning made them (what `--replay` runs).
    pub fn planned(&self) -> Planned {
        Planned {
            plan: self.plan.clone(),
            report: self.report.clone(),
        }
    }

    /// Read a sidecar file.
    pub fn read(path: &Path) -> Result<Sidecar> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::from(e).in_file(path))?;
        Sidecar::from_json(&text).map_err(|e| e.in_file(path))
    }
}

/// The message of an `InvalidParam` error without its "invalid parameter: " prefix.
fn strip_kind(e: &Error) -> String {
    match e {
        Error::InvalidParam(m) => m.clone(),
        other => other.to_string(),
    }
}

/// SHA-256 of bytes as lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{:02x}", b))
        .collect()
}
