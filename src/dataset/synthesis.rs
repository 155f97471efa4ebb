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
use crate::synth::options::burst_defaults;
use crate::synth::{Compat, SynthOptions};
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

impl SynthProcessor {
    /// The fingerprint the dataset's manifest keys its records by (as SHA-256), as tool
    /// version `version` makes it: everything that changes output bytes (options,
    /// calibration, output settings and the version: a new version may change the bytes).
    fn fingerprint_of(&self, version: &str) -> String {
        let job = &self.job;
        let cal = serde_json::json!({
            "illuminants": job.calibration.illuminants,
            "brightness": job.calibration.brightness,
            "noise": job.calibration.noise.as_ref().map(|n| n.to_json()),
        });
        let mut s = format!(
            "day2night {} dataset-outputs/1\noptions {}\ncalibration {}\ntarget {}\ninput_exr {}\ncompression {}",
            version,
            options_fingerprint(&job.options),
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
}

impl Processor for SynthProcessor {
    type Loaded = DayInput;

    fn fingerprint(&self) -> String {
        self.fingerprint_of(crate::VERSION)
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
        let job = self.job_for(unit);
        let plan = job.plan(input, &unit.rel, unit.seed, unit.variant.saturating_sub(1))?;
        let out = job.run_variant(input, &plan, sink)?;
        Ok(UnitInfo {
            iso: out.isos,
            night_neutral: Some(plan.plan.night_neutral),
            stages: out.stages,
        })
    }

    /// The last unit of an input relights the day plane in place
    /// ([`SynthJob::run_variant_owned`], as `synth` does for its last variant): the same
    /// files, without a copy of the plane (its time and its page faults).
    fn process_last(&self, input: DayInput, unit: &Unit, sink: &Sink) -> Result<UnitInfo> {
        let job = self.job_for(unit);
        let plan = job.plan(&input, &unit.rel, unit.seed, unit.variant.saturating_sub(1))?;
        let night_neutral = Some(plan.plan.night_neutral);
        let out = job.run_variant_owned(input, &plan, sink)?;
        Ok(UnitInfo {
            iso: out.isos,
            night_neutral,
            stages: out.stages,
        })
    }
}

impl SynthProcessor {
    /// The job for `unit` (its variant count, which the dataset may set per input).
    fn job_for(&self, unit: &Unit) -> Cow<'_, SynthJob> {
        if unit.variants == self.job.variants {
            Cow::Borrowed(&self.job)
        } else {
            Cow::Owned(SynthJob {
                variants: unit.variants,
                ..self.job.clone()
            })
        }
    }
}

/// The serialized option fields the fingerprint held when it was introduced (day2night
/// 0.1.0, dotted into nested objects). They stay in it whatever their value, so the
/// fingerprints of existing datasets do not change; a field added since is in it only when
/// its value is not the default, so adding an option (with a default that keeps the bytes)
/// does not recompute existing datasets, and setting it does.
const FINGERPRINT_V1_FIELDS: &[&str] = &[
    "mode",
    "formula",
    "bulbs",
    "local_lights",
    "isos",
    "truncate",
    "keep_negative",
    "keep_highlights",
    "dim_range",
    "ambient_gain",
    "bulb_gain",
    "sampler.floor",
    "sampler.max_mahalanobis",
    "sampler.max_tries",
    "covariance",
    "day_neutral",
    "mask_eval.eval",
    "mask_eval.k",
    "compat.neutral_as_stored",
    "compat.truncate_noise",
    "compat.range_per_site",
    "compat.paper_illuminants",
    "compat.embedded_noise",
    "opcodes",
    "burst.frames",
    "burst.motion",
    "burst.shake.step_px",
    "burst.shake.roll_deg",
    "burst.interp",
];

/// The options as the fingerprint holds them: their JSON in field order, less the fields
/// added since the fingerprint was introduced that are at their default.
fn options_fingerprint(options: &SynthOptions) -> String {
    let Ok(text) = serde_json::to_string(options) else {
        return String::new();
    };
    let Ok(tree) = serde_json::from_str::<Ordered>(&text) else {
        return text;
    };
    let mut reference = serde_json::to_value(SynthOptions::default()).unwrap_or_default();
    // Parts left out of the JSON at their default: compare with their own defaults.
    if let Some(r) = reference.as_object_mut() {
        r.insert("burst".into(), json_of(&burst_defaults()));
        r.insert("compat".into(), json_of(&Compat::default()));
    }
    serde_json::to_string(&tree.pruned(&reference, "", FINGERPRINT_V1_FIELDS)).unwrap_or(text)
}

fn json_of<T: serde::Serialize>(v: &T) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or_default()
}

/// A JSON value whose objects keep their keys in the order they were written
/// (`serde_json::Value` sorts them), so a pruned fingerprint writes what was read.
#[derive(Debug, Clone, PartialEq)]
enum Ordered {
    Object(Vec<(String, Ordered)>),
    Leaf(serde_json::Value),
}

impl Ordered {
    /// `self` (at the dotted `path`) less the leaves not in `kept` whose value is the one
    /// `reference` has at their path (an object left empty is dropped too).
    fn pruned(&self, reference: &serde_json::Value, path: &str, kept: &[&str]) -> Ordered {
        let Ordered::Object(fields) = self else {
            return self.clone();
        };
        let mut out = Vec::new();
        for (k, v) in fields {
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            let r = reference.get(k).unwrap_or(&serde_json::Value::Null);
            match v {
                Ordered::Leaf(x) if !kept.contains(&p.as_str()) && reference.get(k) == Some(x) => {}
                Ordered::Object(inner) if !inner.is_empty() => {
                    let pr = v.pruned(r, &p, kept);
                    if pr != Ordered::Object(Vec::new()) {
                        out.push((k.clone(), pr));
                    }
                }
                v => out.push((k.clone(), v.clone())),
            }
        }
        Ordered::Object(out)
    }
}

impl serde::Serialize for Ordered {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            Ordered::Leaf(v) => v.serialize(s),
            Ordered::Object(fields) => {
                let mut m = s.serialize_map(Some(fields.len()))?;
                for (k, v) in fields {
                    m.serialize_entry(k, v)?;
                }
                m.end()
            }
        }
    }
}

impl<'de> serde::Deserialize<'de> for Ordered {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Ordered;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("JSON")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut a: A,
            ) -> std::result::Result<Ordered, A::Error> {
                let mut fields = Vec::new();
                while let Some((k, v)) = a.next_entry::<String, Ordered>()? {
                    fields.push((k, v));
                }
                Ok(Ordered::Object(fields))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> std::result::Result<Ordered, A::Error> {
                let mut items = Vec::new();
                while let Some(v) = a.next_element::<serde_json::Value>()? {
                    items.push(v);
                }
                Ok(Ordered::Leaf(serde_json::Value::Array(items)))
            }
            fn visit_bool<E>(self, v: bool) -> std::result::Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_i64<E>(self, v: i64) -> std::result::Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_u64<E>(self, v: u64) -> std::result::Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_f64<E>(self, v: f64) -> std::result::Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_str<E>(self, v: &str) -> std::result::Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_unit<E>(self) -> std::result::Result<Ordered, E> {
                Ok(Ordered::Leaf(serde_json::Value::Null))
            }
        }
        d.deserialize_any(Visit)
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
    use crate::dataset::sha256_hex;
    use crate::encode::exr::ExrCompression;
    use crate::synth::options::{find, Draft, Spelling, Value};

    /// The processor `dataset` makes of `flags` (each a flag and its value as typed).
    fn processor(flags: &[(&str, Value)]) -> SynthProcessor {
        let mut d = Draft::new(1);
        for (name, v) in flags {
            d.set(find(name).unwrap(), v.clone(), Spelling::Cli)
                .unwrap();
        }
        SynthProcessor {
            job: d.finish(Spelling::Cli).unwrap().build().unwrap(),
        }
    }

    fn text(s: &str) -> Value {
        Value::Text(s.into())
    }

    /// Manifests written by 0.1.0 before the fingerprint pruned new default fields
    /// (tests/fingerprints/README.md): today's fingerprint of the same options is theirs,
    /// so those datasets resume without recomputing anything.
    #[test]
    fn fingerprints_of_datasets_made_before_are_unchanged() {
        let cases: [(&str, Vec<(&str, Value)>); 2] = [
            (
                include_str!("../../tests/fingerprints/default.manifest.jsonl"),
                vec![],
            ),
            (
                include_str!("../../tests/fingerprints/custom.manifest.jsonl"),
                vec![
                    ("ambient-gain", Value::Float(0.1)),
                    ("burst", Value::Int(2)),
                    ("mask-eval", text("exact")),
                    ("iso", text("800")),
                    ("exr-compression", text("piz")),
                    ("target", text("both")),
                ],
            ),
        ];
        for (manifest, flags) in cases {
            let record: serde_json::Value =
                serde_json::from_str(manifest.lines().next().unwrap()).unwrap();
            let sha = sha256_hex(processor(&flags).fingerprint_of("0.1.0").as_bytes());
            assert_eq!(record["options_sha256"], sha.as_str(), "{flags:?}");
        }
        // and the two differ: the fingerprint does see the options
        assert_ne!(
            processor(&[]).fingerprint(),
            processor(&[("ambient-gain", Value::Float(0.1))]).fingerprint()
        );
    }

    /// The default options' JSON with `extra` appended to the object at `at` ("" for the
    /// top level), and the reference with `default` at the same place: a field added to
    /// `SynthOptions` (or to one of its parts) since the fingerprint was introduced.
    fn with_new_field(at: &str, value: f64, default: f64) -> String {
        let mut o = SynthOptions::default();
        o.burst.frames = 2;
        let text = serde_json::to_string(&o).unwrap();
        let mut tree: Ordered = serde_json::from_str(&text).unwrap();
        let mut reference = serde_json::to_value(SynthOptions::default()).unwrap();
        reference["burst"] = json_of(&burst_defaults());
        let Ordered::Object(top) = &mut tree else {
            panic!()
        };
        let (fields, r) = if at.is_empty() {
            (top, &mut reference)
        } else {
            let (_, Ordered::Object(inner)) = top.iter_mut().find(|(k, _)| k == at).unwrap() else {
                panic!()
            };
            (inner, &mut reference[at])
        };
        fields.push(("new_knob".into(), Ordered::Leaf(value.into())));
        r["new_knob"] = default.into();
        serde_json::to_string(&tree.pruned(&reference, "", FINGERPRINT_V1_FIELDS)).unwrap()
    }

    #[test]
    fn a_new_field_counts_only_when_not_at_its_default() {
        let mut o = SynthOptions::default();
        o.burst.frames = 2;
        let before = serde_json::to_string(&o).unwrap();
        assert_eq!(options_fingerprint(&o), before);
        for at in ["", "burst"] {
            // added with its default: the fingerprint of every existing dataset is kept
            assert_eq!(with_new_field(at, 0.5, 0.5), before, "{at}");
            // set to another value: the outputs change, and so does the fingerprint
            let set = with_new_field(at, 0.75, 0.5);
            assert_ne!(set, before, "{at}");
            assert!(set.contains("\"new_knob\":0.75"), "{set}");
        }
        // the fields of 0.1.0 stay whatever their value (their form is unchanged)
        assert_eq!(
            options_fingerprint(&SynthOptions::default()),
            serde_json::to_string(&SynthOptions::default()).unwrap()
        );
        let release = SynthOptions::default().release_compat().unwrap();
        assert_eq!(
            options_fingerprint(&release),
            serde_json::to_string(&release).unwrap()
        );
    }

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
