//! The JSON sidecar written next to each (input, variant)'s outputs: every sampled value
//! (the whole [`Plan`]), the options, calibration summary, values computed while running,
//! the stages that ran, the tool version, the input's name and SHA-256, and the output
//! names. `--replay` rebuilds the plan from it and reproduces the outputs byte for byte.
//! Its content is deterministic (no timestamps), so a replay rewrites it identically.

use super::illuminant::Gaussian2;
use super::illuminant_choice::IlluminantProvenance;
use super::plan::Plan;
use super::relight::RunReport;
use super::SynthOptions;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::Path;

/// Format tag of sidecars.
pub const SIDECAR_FORMAT: &str = "day2night-sidecar/1";

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
    /// Noise model source.
    pub noise_model: String,
    /// Where each calibration came from and which camera it belongs to (issue 24). Absent
    /// in sidecars written before it existed (their replays write none, byte for byte).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
}

/// `calibration.provenance`: where each calibration of one input came from and which
/// camera it belongs to, one entry per calibration.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The night illuminant dictionary: embedded S20 FE, CIE lamps through this file's
    /// matrices, a file's camera RGB or xy; and its camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub illuminants: Option<IlluminantProvenance>,
    /// The noise model's (the plan's `noise_provenance`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
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
    /// EXR compression of the EXR outputs (`synth --exr-compression`); absent = "zip" (the
    /// default, not written so default sidecars stay as before).
    #[serde(
        default = "default_exr_compression",
        skip_serializing_if = "is_default_exr_compression"
    )]
    pub exr_compression: String,
    /// zlib level of zip/zips EXR outputs (`--exr-zip-level`); absent = 1 (the default, not
    /// written). Sidecars of 0.1.0 have no field: their EXRs were level-4 ZIP from the `exr`
    /// crate, so a replay reproduces their raw outputs byte for byte and their EXR pixels
    /// exactly, in a smaller-compression container.
    #[serde(
        default = "default_zip_level",
        skip_serializing_if = "is_default_zip_level"
    )]
    pub exr_zip_level: u8,
}

fn default_zip_level() -> u8 {
    crate::encode::exr::ExrOptions::DEFAULT_ZIP_LEVEL
}

fn is_default_zip_level(l: &u8) -> bool {
    *l == default_zip_level()
}

fn default_exr_compression() -> String {
    "zip".into()
}

fn is_default_exr_compression(s: &str) -> bool {
    s == "zip"
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
    /// Parse and check the format tag.
    pub fn from_json(text: &str) -> Result<Sidecar> {
        let s: Sidecar = serde_json::from_str(text)
            .map_err(|e| Error::malformed(format!("sidecar JSON: {}", e)))?;
        if s.format != SIDECAR_FORMAT {
            return Err(Error::malformed(format!(
                "sidecar format {:?} (expected {:?})",
                s.format, SIDECAR_FORMAT
            )));
        }
        // Bounds before any use: a hostile sidecar is refused at once, naming the field.
        s.plan
            .validate_bounds()
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
