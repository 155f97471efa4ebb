//! Reading a sidecar of either version: version 2 as it is, version 1
//! (`day2night-sidecar/1`) through its one migration ([`super::sidecar_v1::migrate`]); then
//! the bounds of the plan, the report, the options and the output list, so that a hostile
//! or damaged sidecar is refused before any use, naming the field.

use super::sidecar::{Sidecar, SIDECAR_FORMAT};
use crate::error::{Error, Result};
use std::path::Path;

impl Sidecar {
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
