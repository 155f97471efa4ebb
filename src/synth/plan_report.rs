//! What planning found besides the draws: where the neutrals and the noise model came from,
//! the stages that will run, what the renders do with the input's opcode lists, the
//! target's size when a TrimBounds changes it, and the warnings. It sits beside the
//! [`Plan`](super::Plan) (which holds only what was drawn and what the draws depend on), is
//! carried with it through the job ([`Planned`](super::Planned)) and is written as the
//! sidecar's `report`.

use crate::bounds::MAX_LIST;
use crate::error::{Error, Result};
use crate::isp::opcodes::OpcodeReport;
use crate::noise::NoiseProvenance;
use serde::{Deserialize, Serialize};

/// Most opcode entries (applied, skipped or dropped) and opcode warnings in a plan's
/// report: every opcode the reader accepts, three lists of
/// [`crate::limits::MAX_OPCODES_PER_LIST`] (a plan that `synth` samples for such a file must
/// replay).
pub const MAX_PLAN_OPCODES: usize = 3 * crate::limits::MAX_OPCODES_PER_LIST as usize;

/// The report of one plan (the sidecar's `report`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanReport {
    /// Where the day neutral came from.
    pub day_neutral_source: String,
    /// How the night neutral was computed.
    pub night_neutral_definition: String,
    /// Where the noise model came from (its source text).
    pub noise_model_source: String,
    /// Where the noise model came from and which camera it belongs to (also the sidecar's
    /// `calibration.provenance.noise`); null when unknown.
    pub noise_provenance: Option<NoiseProvenance>,
    /// The stages that run, in order. From `normalize` to `denormalize` they run in one
    /// fused row pass (synth/relight.rs, `run_clean`), not in functions of those names.
    pub stages: Vec<String>,
    /// What the renders (target, network input) do with the input's DNG opcode lists: the
    /// mode and the opcodes applied, skipped and dropped; null when the input has none.
    pub opcodes: Option<OpcodeReport>,
    /// Size `[width, height]` of the rendered target (and network input) when an
    /// OpcodeList3 TrimBounds changes it; null otherwise (the target is then the raw's
    /// DefaultCrop, oriented).
    pub target_size: Option<[usize; 2]>,
    /// Warnings raised while planning (the reader's corrections first, then e.g. ISO
    /// extrapolation).
    pub warnings: crate::diagnostics::Diagnostics,
}

fn field(name: &str, why: impl std::fmt::Display) -> Error {
    Error::invalid(format!("report field {name}: {why}"))
}

impl PlanReport {
    /// The stages of a synthesis that computed `products` ([`super::night::Night::stages`]):
    /// the planned stages, then `apply_opcodes` when a render ran with opcodes applied,
    /// then the products.
    pub fn stages_with(&self, products: &[String]) -> Vec<String> {
        let mut stages = self.stages.clone();
        let renders = products
            .iter()
            .any(|s| s == "render_target" || s == "render_input");
        if renders && self.opcodes.as_ref().is_some_and(|r| !r.applied.is_empty()) {
            stages.push("apply_opcodes".into());
        }
        stages.extend(products.iter().cloned());
        stages
    }

    /// Error naming the first list of this report longer than a plan can make (a hostile
    /// or damaged sidecar is refused before any work), or a target size out of range.
    pub fn validate_bounds(&self) -> Result<()> {
        let max_side = crate::dng::read::MAX_DIMENSION as usize;
        if let Some([w, h]) = self.target_size {
            for (name, v) in [("target_size[0]", w), ("target_size[1]", h)] {
                if v == 0 || v > max_side {
                    return Err(field(name, format!("{v} is outside 1..={max_side}")));
                }
            }
        }
        if self.stages.len() > MAX_LIST {
            return Err(field("stages", format!("more than {MAX_LIST}")));
        }
        // One warning per opcode is possible, besides the others.
        if self.warnings.len() > MAX_LIST + MAX_PLAN_OPCODES {
            return Err(field(
                "warnings",
                format!("more than {}", MAX_LIST + MAX_PLAN_OPCODES),
            ));
        }
        if let Some(o) = &self.opcodes {
            if o.applied.len() > MAX_PLAN_OPCODES
                || o.skipped.len() > MAX_PLAN_OPCODES
                || o.dropped.len() > MAX_PLAN_OPCODES
            {
                return Err(field(
                    "opcodes",
                    format!("more than {MAX_PLAN_OPCODES} entries"),
                ));
            }
        }
        Ok(())
    }
}
