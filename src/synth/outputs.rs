//! What a synthesis job writes and where: the targets ([`Target`]), the outputs of a variant
//! ([`OutputKind`]), the [`OutputSink`] that names and places them (`synth`'s flat
//! [`DirSink`]; `dataset` has its own) and what was written ([`VariantOutputs`]).

use crate::dng::write::Compression;
use crate::error::{Error, Result};
use crate::output::OutputPolicy;
use std::path::{Path, PathBuf};

/// Which targets to render from the clean night raw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Target {
    /// Linear EXR (default).
    #[default]
    Exr,
    /// sRGB PNG.
    Png,
    /// Both.
    Both,
    /// None: the clean raw is not rendered at all.
    None,
}

impl Target {
    /// Whether an EXR target is written.
    pub fn exr(self) -> bool {
        matches!(self, Target::Exr | Target::Both)
    }
    /// Whether a PNG target is written.
    pub fn png(self) -> bool {
        matches!(self, Target::Png | Target::Both)
    }
}

crate::choices! {
    Target, ignore_case: false,
    unknown: |s| Error::malformed(format!(
        "sidecar target {s:?} (use {})",
        crate::choice::listed::<Target>(", ", " or ")
    )),
    Exr => "exr": "Linear EXR",
    Png => "png": "sRGB PNG",
    Both => "both": "Both",
    None => "none": "None",
}

/// Sidecar name of a DNG compression: `none` or `ljpeg` (its [`Compression::name`]).
pub fn compression_name(c: Compression) -> &'static str {
    c.name()
}

/// One output of a variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum OutputKind {
    /// The clean night raw DNG.
    CleanDng,
    /// The noisy night raw DNG at `iso`.
    NoisyDng {
        /// Its ISO.
        iso: u32,
    },
    /// Frame `frame` (0 = the reference) of a burst's noisy night raw at `iso` (a burst of
    /// more than one frame; a single frame is [`OutputKind::NoisyDng`]).
    NoisyFrame {
        /// Its ISO.
        iso: u32,
        /// Its frame index.
        frame: u32,
    },
    /// The EXR target.
    TargetExr,
    /// The PNG target.
    TargetPng,
    /// The network input EXR.
    InputExr,
    /// The sidecar JSON.
    Sidecar,
}

impl OutputKind {
    /// The noisy raw of frame `frame` at `iso` in a burst of `frames` frames: the
    /// single-frame name for one frame, the frame's own otherwise.
    pub fn noisy(iso: u32, frame: u32, frames: u32) -> OutputKind {
        if frames > 1 {
            OutputKind::NoisyFrame { iso, frame }
        } else {
            OutputKind::NoisyDng { iso }
        }
    }
}

/// Where the outputs of one variant go. Called from concurrent rayon tasks (hence `Sync`).
pub trait OutputSink: Sync {
    /// The path to write `kind` to (a sink may create its folder here).
    fn path(&self, kind: OutputKind) -> Result<PathBuf>;
    /// The name the sidecar's `outputs.files` gives `kind`.
    fn name(&self, kind: OutputKind) -> String;
    /// The policy every write follows (overwriting, inputs never replaced).
    fn policy(&self) -> &OutputPolicy;
    /// Called once `kind` has been completely written at [`OutputSink::path`] (e.g. to hash
    /// it); an error fails the variant.
    fn written(&self, _kind: OutputKind) -> Result<()> {
        Ok(())
    }
}

/// `synth`'s layout: every output of a variant in one folder, named `<base>_clean.dng`,
/// `<base>_iso<ISO>.dng` (a burst: `<base>_iso<ISO>_f<NN>.dng`, NN = 00..N-1), `<base>_target.exr|png`, `<base>_input.exr`, `<base>.json`, where
/// `<base>` is the input's stem plus `_vK` (K = variant + 1) when the job makes more than
/// one variant ([`SynthJob::base_name`](super::job::SynthJob::base_name)).
#[derive(Debug, Clone)]
pub struct DirSink<'a> {
    dir: &'a Path,
    base: String,
    policy: &'a OutputPolicy,
}

impl<'a> DirSink<'a> {
    /// The sink of the outputs named `base` in `dir`.
    pub fn new(dir: &'a Path, base: String, policy: &'a OutputPolicy) -> DirSink<'a> {
        DirSink { dir, base, policy }
    }
}

impl OutputSink for DirSink<'_> {
    fn path(&self, kind: OutputKind) -> Result<PathBuf> {
        Ok(self.dir.join(self.name(kind)))
    }
    fn name(&self, kind: OutputKind) -> String {
        let b = &self.base;
        match kind {
            OutputKind::CleanDng => format!("{b}_clean.dng"),
            OutputKind::NoisyDng { iso } => format!("{b}_iso{iso}.dng"),
            OutputKind::NoisyFrame { iso, frame } => format!("{b}_iso{iso}_f{frame:02}.dng"),
            OutputKind::TargetExr => format!("{b}_target.exr"),
            OutputKind::TargetPng => format!("{b}_target.png"),
            OutputKind::InputExr => format!("{b}_input.exr"),
            OutputKind::Sidecar => format!("{b}.json"),
        }
    }
    fn policy(&self) -> &OutputPolicy {
        self.policy
    }
}

/// What [`SynthJob::run_variant`](super::job::SynthJob::run_variant) wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VariantOutputs {
    /// Names of the files written, as the sidecar lists them (the sidecar last).
    pub files: Vec<String>,
    /// Stages run, in order (the plan's, then the outputs written).
    pub stages: Vec<String>,
    /// ISO of each noisy raw, in order.
    pub isos: Vec<u32>,
    /// Warnings about what the renders made (the sidecar's `run.warnings`: a constant
    /// target or input); the plan's warnings are in [`super::PlanReport::warnings`].
    pub warnings: crate::diagnostics::Diagnostics,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_names_round_trip() {
        for t in [Target::Exr, Target::Png, Target::Both, Target::None] {
            assert_eq!(t.name().parse::<Target>().unwrap(), t);
        }
        assert!("jpeg".parse::<Target>().is_err());
        assert!(Target::Both.exr() && Target::Both.png());
        assert!(!Target::None.exr() && !Target::None.png());
    }

    #[test]
    fn dir_sink_names() {
        let policy = OutputPolicy::default();
        let one = DirSink::new(Path::new("o"), "day".into(), &policy);
        assert_eq!(one.name(OutputKind::CleanDng), "day_clean.dng");
        assert_eq!(
            one.path(OutputKind::Sidecar).unwrap(),
            Path::new("o/day.json")
        );
        let v = DirSink::new(Path::new("o"), "day_v2".into(), &policy);
        assert_eq!(
            v.name(OutputKind::NoisyDng { iso: 800 }),
            "day_v2_iso800.dng"
        );
        assert_eq!(v.name(OutputKind::TargetPng), "day_v2_target.png");
        assert_eq!(
            v.name(OutputKind::noisy(1600, 3, 8)),
            "day_v2_iso1600_f03.dng"
        );
        assert_eq!(v.name(OutputKind::noisy(1600, 0, 1)), "day_v2_iso1600.dng");
        assert_eq!(v.name(OutputKind::InputExr), "day_v2_input.exr");
    }
}
