//! The real processing callback: day-to-night synthesis of one (input, variant) by the
//! library's [`SynthJob`] (the same code `day2night synth` runs, so the two write the same
//! bytes), with the outputs placed in the dataset layout through the unit's [`Sink`].
//!
//! The random stream of a unit is keyed by (run seed, relative input path, variant - 1), as
//! `synth` keys it by (seed, file name, variant): it depends on the file, never on its
//! position, shard or the thread count. For a file directly in DAY_DIR the relative path is
//! the file name, so its plan (sidecar `plan`) equals what `day2night synth` samples.

use super::{ensure_parent, Kind, Processor, Sink, Unit, UnitInfo};
use crate::encode::exr::ExrOptions;
use crate::error::Result;
use crate::output::OutputPolicy;
use crate::synth::job::{compression_name, DayInput, OutputKind, OutputSink, SynthJob};
use std::borrow::Cow;
use std::path::{Path, PathBuf};

pub use crate::synth::job::Target;

/// Everything the synthesis of a dataset needs: the job run on every (input, variant).
#[derive(Debug, Clone)]
pub struct SynthProcessor {
    /// Synthesis options, calibration and output settings. Its `variants` should be the
    /// run's (a unit with another count is run with that count).
    pub job: SynthJob,
}

impl Processor for SynthProcessor {
    type Loaded = DayInput;

    fn fingerprint(&self) -> String {
        // Everything that changes output bytes: options, calibration, output settings and
        // the tool version (a new version may change the bytes).
        let job = &self.job;
        let cal = serde_json::json!({
            "illuminants": job.calibration.illuminants,
            "brightness": job.calibration.brightness,
            "noise": job.calibration.noise.as_ref().map(|n| n.to_json()),
        });
        let mut s = format!(
            "day2night {} dataset-outputs/1\noptions {}\ncalibration {}\ntarget {}\ninput_exr {}\ncompression {}",
            crate::VERSION,
            serde_json::to_string(&job.options).unwrap_or_default(),
            cal,
            job.target.name(),
            job.input_exr,
            compression_name(job.compression)
        );
        // EXR settings only when not the default, so datasets made before they could be set
        // (always the default) keep their fingerprint and are not recomputed.
        if job.exr != ExrOptions::default() {
            s.push_str(&format!("\nexr {:?}", job.exr));
        }
        s
    }

    fn load(&self, path: &Path, bytes: &[u8]) -> Result<DayInput> {
        DayInput::from_bytes(path, bytes)
    }

    /// Metadata corrections: said once per input (through the run's progress), and
    /// recorded in every sidecar.
    fn warnings(&self, input: &DayInput) -> crate::diagnostics::Diagnostics {
        input.raw.meta.warnings.clone()
    }

    fn process(&self, input: &DayInput, unit: &Unit, sink: &Sink) -> Result<UnitInfo> {
        let job = if unit.variants == self.job.variants {
            Cow::Borrowed(&self.job)
        } else {
            Cow::Owned(SynthJob {
                variants: unit.variants,
                ..self.job.clone()
            })
        };
        let plan = job.plan(input, &unit.rel, unit.seed, unit.variant.saturating_sub(1))?;
        let out = job.run_variant(input, &plan, sink)?;
        Ok(UnitInfo {
            iso: out.isos,
            night_neutral: Some(plan.plan.night_neutral),
            stages: out.stages,
        })
    }
}

/// The dataset folder and file name of each synth output.
fn place(sink: &Sink, kind: OutputKind) -> (Kind, String) {
    match kind {
        OutputKind::CleanDng => (Kind::CleanRaw, ".dng".into()),
        OutputKind::NoisyDng { iso } => (Kind::NoisyRaw, format!("_iso{iso}.dng")),
        // a burst's frames: one folder per sample, `noisy_raw/<id>/<id>_iso<ISO>_f<NN>.dng`
        OutputKind::NoisyFrame { iso, frame } => (
            Kind::NoisyRaw,
            format!("/{}_iso{iso}_f{frame:02}.dng", sink.id()),
        ),
        OutputKind::TargetExr => (Kind::Target, ".exr".into()),
        OutputKind::TargetPng => (Kind::Target, ".png".into()),
        OutputKind::InputExr => (Kind::Input, ".exr".into()),
        OutputKind::Sidecar => (Kind::Meta, ".json".into()),
    }
}

/// The dataset layout: `<split>/<kind>/<id><suffix>` (see the module documentation of
/// [`crate::dataset`]); the sidecar lists these paths relative to OUT_DIR, and every file
/// is hashed into the manifest once written.
impl OutputSink for Sink {
    fn path(&self, kind: OutputKind) -> Result<PathBuf> {
        let (k, suffix) = place(self, kind);
        let p = Sink::path(self, k, &suffix);
        ensure_parent(&p)?;
        Ok(p)
    }
    fn name(&self, kind: OutputKind) -> String {
        let (k, suffix) = place(self, kind);
        self.rel_path(k, &suffix)
    }
    fn policy(&self) -> &OutputPolicy {
        Sink::policy(self)
    }
    fn written(&self, kind: OutputKind) -> Result<()> {
        let (k, suffix) = place(self, kind);
        self.adopt(k, &suffix)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::exr::ExrCompression;
    use crate::synth::SynthOptions;

    #[test]
    fn fingerprint_keeps_the_old_form_for_default_exr_and_changes_otherwise() {
        let p = SynthProcessor {
            job: SynthJob::new(SynthOptions::default()).unwrap(),
        };
        let f = p.fingerprint();
        // The form datasets made before --exr-compression was honoured were keyed by.
        assert!(f.starts_with(&format!(
            "day2night {} dataset-outputs/1\noptions {{",
            crate::VERSION
        )));
        assert!(
            f.ends_with("\ntarget exr\ninput_exr false\ncompression none"),
            "{f}"
        );
        let mut q = p.clone();
        q.job.exr.compression = ExrCompression::Piz;
        assert!(q.fingerprint().starts_with(&f));
        assert!(q.fingerprint().contains("\nexr ") && q.fingerprint().contains("Piz"));
        // Thread counts and variants are not output options.
        q.job = SynthJob {
            variants: 4,
            ..p.job.clone()
        };
        assert_eq!(q.fingerprint(), f);
    }
}
