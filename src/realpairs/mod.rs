//! Real night pairs from captures (the paper's Section 4; docs/real-pairs.md): per scene, the
//! long-exposure low-ISO burst is merged ([`crate::calibrate::merge`]) into the clean raw, the
//! clean raw is rendered by the software ISP ([`crate::isp`]) with the first low-ISO frame's
//! white balance into the target, and the first frame of each high-ISO burst is copied as that
//! ISO's noisy input.
//!
//! Three input layouts ([`Layout`]) are planned by [`discover`]; frames are checked against
//! each other and for motion ([`motion`]) before anything is written ([`scene`]); the outputs
//! go through the dataset's [`crate::dataset::Sink`] ([`outputs`]) and the run is driven,
//! resumed and recorded in a `dataset`-style `manifest.jsonl` by [`run`](mod@run).
//!
//! Layout of OUT:
//! ```text
//! manifest.jsonl                   one record per scene (kind "real", split "real")
//! real/clean_raw/<id>.dng          merged clean raw
//! real/noisy_raw/<id>_iso<ISO>.dng first frame of each high-ISO burst, byte for byte
//! real/target/<id>.png             8-bit sRGB target (and <id>.exr with --target exr|both)
//! real/meta/<id>.json              per-scene record: layout, frames, checks, merge
//! ```

pub mod discover;
pub mod motion;
pub mod outputs;
pub mod processed;
pub mod release_targets;
pub mod run;
pub mod scene;

use serde::Serialize;

pub use discover::{Layout, LayoutChoice};
pub use run::{run, Checkpoint, RunOptions, SceneDone, Summary};

/// The ISO of the release's clean bursts (`RAW_0_000050*`).
pub const RELEASE_LOW_ISO: u32 = 50;

/// The release's noisy ISOs (`generate_real_gt.py --iso_list`).
pub const RELEASE_NOISY_ISOS: [u32; 2] = [1600, 3200];

/// Default motion limit in raw pixels (docs/real-pairs.md, "Motion check").
pub const DEFAULT_MAX_MOTION_PX: f64 = 1.0;

/// Which targets are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TargetKind {
    /// 8-bit sRGB PNG only (the default: the release's target).
    Png,
    /// Linear EXR only.
    Exr,
    /// Both.
    Both,
}

impl TargetKind {
    /// Write the PNG.
    pub fn png(self) -> bool {
        matches!(self, TargetKind::Png | TargetKind::Both)
    }
    /// Write the EXR.
    pub fn exr(self) -> bool {
        matches!(self, TargetKind::Exr | TargetKind::Both)
    }
    /// Name as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TargetKind::Png => "png",
            TargetKind::Exr => "exr",
            TargetKind::Both => "both",
        }
    }
}

/// Everything that changes the outputs of a scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairOptions {
    /// Input layout (forced or auto-detected).
    pub layout: LayoutChoice,
    /// Noisy ISOs of the release layout (`RAW_0_00<ISO, 4 digits>*`).
    pub release_isos: Vec<u32>,
    /// Largest motion accepted, raw pixels.
    pub max_motion_px: f64,
    /// Targets written.
    pub target: TargetKind,
    /// Targets rendered by the authors' release ISP (`--isp release`) instead of
    /// day2night's. Left out of the fingerprint when false, so earlier outputs still match.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub release_isp: bool,
}

impl Default for PairOptions {
    fn default() -> Self {
        PairOptions {
            layout: LayoutChoice::Auto,
            release_isos: RELEASE_NOISY_ISOS.to_vec(),
            max_motion_px: DEFAULT_MAX_MOTION_PX,
            target: TargetKind::Png,
            release_isp: false,
        }
    }
}

impl PairOptions {
    /// Canonical text of the options (hashed into the manifest's `options_sha256`), with
    /// the tool version: a change recomputes every scene.
    pub fn fingerprint(&self) -> String {
        format!(
            "day2night {} real-pairs/1\n{}",
            crate::VERSION,
            serde_json::to_string(self).unwrap_or_default()
        )
    }
}

/// A scene's output id: its relative path with `/` replaced by `__` (as `dataset` names
/// samples).
pub fn scene_id(rel: &str) -> String {
    rel.replace('/', "__")
}
