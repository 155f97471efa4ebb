//! One synthesis job: every output of one (input, variant), written the same way by
//! `day2night synth` and `day2night dataset` (both call [`SynthJob::run_variant`], so their
//! bytes cannot drift apart).
//!
//! A [`SynthJob`] holds what is decided once per run: synthesis options, calibration and the
//! output settings. For a decoded [`DayInput`], [`SynthJob::plan`] samples one variant's
//! random values (a [`Planned`]: the plan and its report) and [`SynthJob::run_variant`] makes and writes, doing only what was asked:
//!
//! 1. the clean night raw (always) -> [`OutputKind::CleanDng`];
//! 2. one noisy raw per planned ISO -> [`OutputKind::NoisyDng`] (none for `isos: []`);
//! 3. the target rendered from the clean raw -> [`OutputKind::TargetExr`] and/or
//!    [`OutputKind::TargetPng`] (no render at all for [`Target::None`]);
//! 4. with `input_exr`, the network input render of the first noisy raw (the clean raw when
//!    there is no ISO) -> [`OutputKind::InputExr`];
//! 5. last, the sidecar JSON ([`Sidecar`]: options, calibration, plan, its report, run
//!    report, the stages run and the files written) -> [`OutputKind::Sidecar`].
//!
//! Steps 1, 2 and 3 are independent rayon tasks (the noisy raws are made one after another
//! inside theirs, so at most one is in memory); every output's bytes are the same whatever
//! the thread count or the order in which the tasks finish. Errors are reported in a fixed
//! order (clean, noisy, target), whatever failed first. Every file goes through
//! [`crate::output`] (temporary file, sync, rename) under the sink's [`OutputPolicy`](crate::output::OutputPolicy); the
//! syncs of steps 1-4 run on background threads ([`crate::output::DeferredSyncs`]) and their
//! files are renamed into place together before the sidecar is written, so a failed variant
//! leaves none of its outputs behind (and [`OutputSink::written`] is called for them then).
//!
//! An [`OutputSink`] says where each output goes and what the sidecar calls it: [`DirSink`]
//! gives `synth`'s flat names (`<base>_clean.dng`, `<base>_iso1600.dng`, `<base>.json`...);
//! `dataset` uses its own per-split folders.
//!
//! ```no_run
//! use day2night::synth::job::{DayInput, DirSink, SynthJob, Target};
//! use day2night::output::OutputPolicy;
//! # fn main() -> day2night::Result<()> {
//! let job = SynthJob {
//!     target: Target::Both,
//!     ..SynthJob::new(Default::default())?
//! };
//! let day = DayInput::read("day.dng".as_ref())?;
//! let policy = OutputPolicy::default();
//! for v in 0..job.variants {
//!     let planned = job.plan(&day, "day.dng", 0, v)?;
//!     let sink = DirSink::new("night".as_ref(), job.base_name("day", &planned.plan), &policy);
//!     let out = job.run_variant(&day, &planned, &sink)?;
//!     println!("{:?} ({:?})", out.files, out.stages);
//! }
//! # Ok(()) }
//! ```

#[cfg(doc)]
use super::night::synthesize;
use super::night::Night;
use super::night::{synthesize_into, synthesize_owned, NightSink, Request};
use super::relight::RunReport;
use super::sidecar::{CalibrationInfo, InputInfo, OutputInfo, Provenance, Sidecar, SIDECAR_FORMAT};
use super::SynthOptions;
use super::{Calibration, IlluminantChoice, Plan, Planned, Planner, ResolvedIlluminants};
use crate::dng::write::{Compression, UniqueIdHash};
use crate::encode::exr::ExrOptions;
use crate::error::{Error, Result};
use crate::output::{write_bytes_atomic, DeferredSyncs};
use std::sync::Arc;

pub use super::day_input::DayInput;
pub use super::file_sink::FileSink;
pub use super::outputs::{
    compression_name, DirSink, OutputKind, OutputSink, Target, VariantOutputs,
};

/// Everything decided once per run: what to synthesize and which outputs to write.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthJob {
    /// Synthesis options (recorded in the sidecar).
    pub options: SynthOptions,
    /// Calibration: illuminant fit, brightness dictionary, noise model.
    pub calibration: Calibration,
    /// Variants made per input (recorded in the sidecar; with more than one, [`DirSink`]
    /// names carry `_vK`).
    pub variants: u32,
    /// Rendered targets.
    pub target: Target,
    /// Also write the network input render (normalized, white-balanced, demosaiced noisy
    /// raw).
    pub input_exr: bool,
    /// DNG compression of the clean and noisy raws.
    pub compression: Compression,
    /// EXR options of the target and input renders.
    pub exr: ExrOptions,
    /// The hash of the DNGs' RawDataUniqueID (XXH3-128; SHA-256 when replaying a sidecar
    /// written before it, which records none).
    pub unique_id: UniqueIdHash,
}

impl SynthJob {
    /// A job with `options`, the embedded calibration and the default outputs (one variant,
    /// EXR target, no input EXR, uncompressed DNGs, default EXR options).
    pub fn new(options: SynthOptions) -> Result<SynthJob> {
        options.validate()?;
        let calibration = Calibration::embedded(&options)?;
        Ok(SynthJob {
            options,
            calibration,
            variants: 1,
            target: Target::default(),
            input_exr: false,
            compression: Compression::None,
            exr: ExrOptions::default(),
            unique_id: UniqueIdHash::default(),
        })
    }

    /// The job a sidecar was made with (for `--replay`): its options, calibration (the
    /// noise model comes from the plan) and output settings.
    pub fn from_sidecar(sc: &Sidecar) -> Result<SynthJob> {
        let exr = ExrOptions {
            compression: sc.outputs.exr_compression.parse()?,
            zip_level: sc.outputs.exr_zip_level,
            ..ExrOptions::default()
        };
        exr.validate()?;
        Ok(SynthJob {
            options: sc.options.clone(),
            calibration: Calibration {
                illuminants: IlluminantChoice::Gaussian(
                    sc.calibration.illuminants.clone(),
                    sc.calibration
                        .provenance
                        .as_ref()
                        .and_then(|p| p.illuminants.clone()),
                ),
                brightness: sc.calibration.brightness.clone(),
                noise: None,
            },
            variants: sc.outputs.variants,
            target: sc.outputs.target.parse()?,
            input_exr: sc.outputs.input_exr,
            compression: if sc.outputs.compression == "ljpeg" {
                Compression::Ljpeg
            } else {
                Compression::None
            },
            exr,
            unique_id: sc.outputs.raw_data_unique_id.parse()?,
        })
    }

    /// Sample the plan of variant `variant` (0-based) of `day`, with its report; the
    /// random stream is keyed by (`seed`, `name`, `variant`), and `name` is recorded as the
    /// sidecar's input name. A job that renders nothing (no target, no input EXR) does not
    /// fail on opcode lists a render could not apply ([`Planner::renders`]).
    pub fn plan(&self, day: &DayInput, name: &str, seed: u64, variant: u32) -> Result<Planned> {
        let req = self.request();
        Planner::new(&day.raw, &self.options)
            .calibration(&self.calibration)
            .name(name)
            .seed(seed)
            .variant(variant)
            .renders(req.target || req.input)
            .estimate(&|| day.noise_estimate())
            .plan()
    }

    /// The night illuminant dictionary of `day` as the sidecar records it: the one the plan
    /// samples from, its provenance and the warnings it gives
    /// ([`Calibration::illuminants_recorded`]).
    pub fn illuminants(&self, day: &DayInput) -> Result<ResolvedIlluminants> {
        self.calibration
            .illuminants_recorded(&day.raw.meta, &self.options)
    }

    /// The base of the output names of `plan`'s variant of the input `stem`: the stem, plus
    /// `_vK` (K = variant + 1) when the job makes more than one variant ([`DirSink`]).
    pub fn base_name(&self, stem: &str, plan: &Plan) -> String {
        if self.variants > 1 {
            format!("{}_v{}", stem, plan.variant.saturating_add(1))
        } else {
            stem.to_string()
        }
    }

    /// What [`super::night::synthesize_into`] must compute for this job's outputs.
    pub fn request(&self) -> Request {
        Request {
            target: self.target != Target::None,
            input: self.input_exr,
            crop: None,
        }
    }

    /// Make and write every output of one planned variant of `day` through `sink` (see the
    /// module documentation for the steps), the sidecar last: the products are computed by
    /// [`synthesize_into`] and handed to a [`FileSink`] that encodes and writes each one.
    /// Returns the names of the files written (as the sidecar lists them) and the stages
    /// run.
    pub fn run_variant(
        &self,
        day: &DayInput,
        planned: &Planned,
        sink: &dyn OutputSink,
    ) -> Result<VariantOutputs> {
        self.write_with(day, planned, sink, |files| {
            synthesize_into(&day.raw, &planned.plan, &self.request(), files).map(|s| s.report)
        })
    }

    /// [`SynthJob::run_variant`] that takes `day` and computes the clean raw in the day
    /// raw's own plane ([`super::night::synthesize_owned`]): the same files, byte for byte,
    /// with one plane of samples in memory instead of two (for an input's last variant).
    pub fn run_variant_owned(
        &self,
        mut day: DayInput,
        planned: &Planned,
        sink: &dyn OutputSink,
    ) -> Result<VariantOutputs> {
        let raw = crate::raw::RawImage {
            width: day.raw.width,
            height: day.raw.height,
            data: std::mem::take(&mut day.raw.data),
            meta: day.raw.meta.clone(),
        };
        self.write_with(&day, planned, sink, |files| {
            synthesize_owned(raw, &planned.plan, &self.request(), files).map(|s| s.report)
        })
    }

    /// Write the outputs of a variant already computed in memory ([`synthesize`] with this
    /// job's [`SynthJob::request`]): the same files, byte for byte, as
    /// [`SynthJob::run_variant`] writes for the same plan.
    pub fn write_night(
        &self,
        day: &DayInput,
        planned: &Planned,
        night: &Night,
        sink: &dyn OutputSink,
    ) -> Result<VariantOutputs> {
        if night.crop.is_some() {
            return Err(Error::invalid(
                "a crop's products are not written as files: synthesize the whole frame",
            ));
        }
        let plan = &planned.plan;
        let isos: Vec<u32> = night.noisy.iter().map(|(iso, _)| *iso).collect();
        let planned_isos: Vec<u32> = plan.noise.iter().map(|n| n.iso).collect();
        let frames = plan.burst.as_ref().map_or(1, |b| b.frames);
        let planned_frames: Vec<(u32, u32)> = planned_isos
            .iter()
            .flat_map(|&iso| (1..frames).map(move |k| (iso, k)))
            .collect();
        let got_frames: Vec<(u32, u32)> = night.frames.iter().map(|f| (f.0, f.1)).collect();
        if isos != planned_isos
            || got_frames != planned_frames
            || (self.target != Target::None) != night.target.is_some()
            || self.input_exr != night.input.is_some()
        {
            return Err(Error::invalid(
                "the computed variant does not hold the products this job writes (ISOs, target, input)",
            ));
        }
        self.write_with(day, planned, sink, |files| {
            let (c, (n, t)) = rayon::join(
                || files.clean(&night.clean),
                || {
                    rayon::join(
                        || -> Result<()> {
                            for (iso, noisy) in &night.noisy {
                                files.noisy(*iso, 0, noisy)?;
                                for (_, k, f) in night.frames.iter().filter(|f| f.0 == *iso) {
                                    files.noisy(*iso, *k, f)?;
                                }
                            }
                            Ok(())
                        },
                        || match &night.target {
                            Some(rgb) => files.target_image(rgb),
                            None => Ok(()),
                        },
                    )
                },
            );
            c.and(n).and(t)?;
            if let Some(rgb) = &night.input {
                files.input(rgb)?;
            }
            Ok(night.report.clone())
        })
    }

    /// The file-writing frame of a variant: a [`FileSink`] for `compute` to feed, then the
    /// deferred renames, the `written` calls and the sidecar.
    fn write_with(
        &self,
        day: &DayInput,
        planned: &Planned,
        sink: &dyn OutputSink,
        compute: impl FnOnce(&FileSink<'_>) -> Result<RunReport>,
    ) -> Result<VariantOutputs> {
        let plan = &planned.plan;
        // Every output but the sidecar is synced on a background thread and renamed into
        // place once all of them are on disk (crate::output): the compute threads never
        // wait for the disk, and on an error no output of the variant appears.
        let syncs = Arc::new(DeferredSyncs::default());
        let policy = sink.policy().deferring(&syncs);
        let files = FileSink::new(
            self.target,
            &self.exr,
            (self.compression, self.unique_id),
            (sink, &policy),
            &day.source,
            plan,
        );
        let report = compute(&files)?;
        let warnings = report.warnings.clone();
        let isos: Vec<u32> = plan.noise.iter().map(|np| np.iso).collect();
        let frames = plan.burst.as_ref().map_or(1, |b| b.frames);
        let noisy_kinds: Vec<OutputKind> = isos
            .iter()
            .flat_map(|&iso| (0..frames).map(move |k| OutputKind::noisy(iso, k, frames)))
            .collect();
        let (want_exr, want_png) = (self.target.exr(), self.target.png());
        let mut stages = planned.report.stages.clone();
        let mut files = vec![sink.name(OutputKind::CleanDng)];
        stages.push("write_clean_dng".into());
        files.extend(noisy_kinds.iter().map(|&k| sink.name(k)));
        if !isos.is_empty() {
            stages.push("write_noisy_dng".into());
        }
        if want_exr {
            files.push(sink.name(OutputKind::TargetExr));
            stages.push("target_exr".into());
        }
        if want_png {
            files.push(sink.name(OutputKind::TargetPng));
            stages.push("target_png".into());
        }
        if self.input_exr {
            files.push(sink.name(OutputKind::InputExr));
            stages.push("input_exr".into());
        }
        syncs.finish(sink.policy())?;
        let mut kinds = vec![OutputKind::CleanDng];
        kinds.extend(noisy_kinds.iter().copied());
        for (want, kind) in [
            (want_exr, OutputKind::TargetExr),
            (want_png, OutputKind::TargetPng),
            (self.input_exr, OutputKind::InputExr),
        ] {
            if want {
                kinds.push(kind);
            }
        }
        for kind in kinds {
            sink.written(kind)?;
        }
        files.push(sink.name(OutputKind::Sidecar));
        let ill = self.illuminants(day)?;
        // A replayed sidecar without provenance (written before it existed) records none.
        let illuminants = match &self.calibration.illuminants {
            IlluminantChoice::Gaussian(_, None) => None,
            _ => Some(ill.provenance),
        };
        let noise = planned.report.noise_provenance.clone();
        let provenance =
            (illuminants.is_some() || noise.is_some()).then_some(Provenance { illuminants, noise });
        let sc = Sidecar {
            format: SIDECAR_FORMAT.into(),
            tool: "day2night".into(),
            version: crate::VERSION.into(),
            input: InputInfo {
                name: plan.input_name.clone(),
                sha256: day.sha256.clone(),
            },
            options: self.options.clone(),
            calibration: CalibrationInfo {
                illuminants: ill.gaussian,
                brightness: self.calibration.brightness.clone(),
                noise_model: planned.report.noise_model_source.clone(),
                provenance,
            },
            plan: plan.clone(),
            report: planned.report.clone(),
            run: report,
            stages: stages.clone(),
            outputs: OutputInfo {
                variants: self.variants,
                compression: compression_name(self.compression).into(),
                target: self.target.name().into(),
                input_exr: self.input_exr,
                files: files.clone(),
                exr_compression: self.exr.compression.name().into(),
                exr_zip_level: self.exr.zip_level,
                raw_data_unique_id: self.unique_id.name().into(),
            },
        };
        let kind = OutputKind::Sidecar;
        write_bytes_atomic(&sink.path(kind)?, sink.policy(), sc.to_json()?.as_bytes())?;
        sink.written(kind)?;
        Ok(VariantOutputs {
            files,
            stages,
            isos,
            warnings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::OutputPolicy;
    use crate::raw::rows::RowSource;
    use crate::raw::{RawImage, RawMeta};
    use crate::synth::night::TargetOut;
    use crate::synth::SynthOptions;
    use std::path::{Path, PathBuf};

    fn small_day() -> DayInput {
        let fix = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/day.dng");
        DayInput::read(&fix).unwrap()
    }

    #[test]
    fn base_names_carry_the_variant_with_several() {
        let day = small_day();
        let mut job = SynthJob::new(SynthOptions::default()).unwrap();
        let plan = job.plan(&day, "day.dng", 0, 1).unwrap();
        assert_eq!(job.base_name("day", &plan.plan), "day");
        job.variants = 3;
        assert_eq!(job.base_name("day", &plan.plan), "day_v2");
    }

    /// Records every `written` call (and refuses one kind, to test error propagation).
    struct Recorder<'a> {
        inner: DirSink<'a>,
        seen: std::sync::Mutex<Vec<OutputKind>>,
        fail: Option<OutputKind>,
    }

    impl OutputSink for Recorder<'_> {
        fn path(&self, kind: OutputKind) -> Result<PathBuf> {
            self.inner.path(kind)
        }
        fn name(&self, kind: OutputKind) -> String {
            self.inner.name(kind)
        }
        fn policy(&self) -> &OutputPolicy {
            self.inner.policy()
        }
        fn written(&self, kind: OutputKind) -> Result<()> {
            self.seen.lock().unwrap().push(kind);
            if self.fail == Some(kind) {
                return Err(Error::invalid("refused by the test sink"));
            }
            Ok(())
        }
    }

    #[test]
    fn does_only_what_the_job_asks_and_records_it() {
        let day = small_day();
        let job = SynthJob {
            target: Target::None,
            ..SynthJob::new(SynthOptions {
                isos: vec![],
                ..SynthOptions::default()
            })
            .unwrap()
        };
        let dir = tempfile::tempdir().unwrap();
        let plan = job.plan(&day, "day.dng", 1, 0).unwrap();
        let policy = OutputPolicy::default();
        let sink = Recorder {
            inner: DirSink::new(dir.path(), job.base_name("day", &plan.plan), &policy),
            seen: Default::default(),
            fail: None,
        };
        let out = job.run_variant(&day, &plan, &sink).unwrap();
        assert_eq!(out.files, ["day_clean.dng", "day.json"]);
        assert!(out.isos.is_empty());
        assert_eq!(
            out.stages.last().map(String::as_str),
            Some("write_clean_dng")
        );
        assert!(!out.stages.iter().any(|s| s.starts_with("target")));
        assert_eq!(
            *sink.seen.lock().unwrap(),
            [OutputKind::CleanDng, OutputKind::Sidecar]
        );
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["day.json", "day_clean.dng"]);
        let sc = Sidecar::read(&dir.path().join("day.json")).unwrap();
        assert_eq!(sc.stages, out.stages);
        assert_eq!(sc.outputs.files, out.files);
        assert_eq!(SynthJob::from_sidecar(&sc).unwrap().target, Target::None);
    }

    fn dir_files(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let name = e.file_name().to_string_lossy().into_owned();
                (name, std::fs::read(e.path()).unwrap())
            })
            .collect()
    }

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    /// The targets streamed band by band during the render are the bytes of the
    /// whole-image writers ([`SynthJob::write_night`]), for any thread count, for output
    /// heights of one row, not a multiple of the band height, and turned by the orientation.
    #[test]
    fn streamed_targets_equal_the_whole_image_writers() {
        let base = small_day();
        let a = base.raw.active_area();
        let (aw, ah) = (a.width(), a.height());
        assert!(
            ah > 3 * crate::isp::render::BAND,
            "the fixture has several bands"
        );
        for (k, (crop_h, orientation)) in [(None, 1u16), (Some(1), 1), (Some(33), 3), (Some(65), 6)]
            .into_iter()
            .enumerate()
        {
            let mut day = base.clone();
            if let Some(ch) = crop_h {
                day.raw.meta.default_crop_origin = Some([0.0, 0.0]);
                day.raw.meta.default_crop_size = Some([aw as f64, ch as f64]);
            }
            day.raw.meta.orientation = orientation;
            let job = SynthJob {
                target: Target::Both,
                ..SynthJob::new(SynthOptions {
                    isos: vec![],
                    ..SynthOptions::default()
                })
                .unwrap()
            };
            let plan = job.plan(&day, "day.dng", 5, 0).unwrap();
            let policy = OutputPolicy::default();
            let t = tempfile::tempdir().unwrap();
            let whole = t.path().join("whole");
            std::fs::create_dir(&whole).unwrap();
            let night =
                crate::synth::night::synthesize(&day.raw, &plan.plan, &job.request()).unwrap();
            let rgb = night.target.as_ref().unwrap();
            let want_h = crop_h.unwrap_or(rgb.height);
            assert_eq!(
                if orientation == 6 {
                    rgb.width
                } else {
                    rgb.height
                },
                want_h,
                "case {k}"
            );
            let sink = DirSink::new(&whole, job.base_name("day", &plan.plan), &policy);
            job.write_night(&day, &plan, &night, &sink).unwrap();
            let want = dir_files(&whole);
            for threads in [1, 2, 3] {
                let d = t.path().join(format!("j{threads}"));
                std::fs::create_dir(&d).unwrap();
                let sink = DirSink::new(&d, job.base_name("day", &plan.plan), &policy);
                pool(threads)
                    .install(|| job.run_variant(&day, &plan, &sink))
                    .unwrap();
                let got = dir_files(&d);
                assert_eq!(
                    got.keys().collect::<Vec<_>>(),
                    want.keys().collect::<Vec<_>>()
                );
                for name in ["day_target.exr", "day_target.png"] {
                    assert!(
                        got[name] == want[name],
                        "case {k}, {threads} threads: {name}"
                    );
                }
            }
        }
    }

    /// A [`FileSink`] whose target band `fail_at` fails.
    struct FailingBand<'s, 'a> {
        inner: &'s FileSink<'a>,
        fail_at: usize,
    }

    impl NightSink for FailingBand<'_, '_> {
        type Band = ();
        fn clean(&self, clean: &RawImage) -> Result<()> {
            self.inner.clean(clean)
        }
        fn noisy(&self, iso: u32, frame: u32, noisy: &RawImage) -> Result<()> {
            self.inner.noisy(iso, frame, noisy)
        }
        fn noisy_rows(
            &self,
            iso: u32,
            frame: u32,
            meta: &RawMeta,
            rows: &dyn RowSource,
        ) -> Result<()> {
            self.inner.noisy_rows(iso, frame, meta, rows)
        }
        fn banded(&self) -> bool {
            self.inner.banded()
        }
        fn target_start(&self, w: usize, h: usize) -> Result<()> {
            self.inner.target_start(w, h)
        }
        fn target_band(&self, y0: usize, w: usize, rows: &[f32]) -> Result<()> {
            if y0 == self.fail_at * crate::isp::render::BAND {
                return Err(Error::invalid("band refused by the test"));
            }
            self.inner.target_band(y0, w, rows)
        }
        fn target(&self, target: TargetOut<()>) -> Result<()> {
            self.inner.target(target)
        }
    }

    /// A band that fails part-way through the streamed target leaves no output and no
    /// temporary file (the target files were open and partly written).
    #[test]
    fn a_failing_target_band_leaves_no_file() {
        let day = small_day();
        let job = SynthJob {
            target: Target::Both,
            ..SynthJob::new(SynthOptions {
                isos: vec![800],
                ..SynthOptions::default()
            })
            .unwrap()
        };
        let plan = job.plan(&day, "day.dng", 1, 0).unwrap();
        let policy = OutputPolicy::default();
        for (threads, fail_at) in [(1, 0), (1, 3), (2, 3), (3, 1)] {
            let dir = tempfile::tempdir().unwrap();
            let sink = DirSink::new(dir.path(), job.base_name("day", &plan.plan), &policy);
            let e = pool(threads)
                .install(|| {
                    job.write_with(&day, &plan, &sink, |files| {
                        let failing = FailingBand {
                            inner: files,
                            fail_at,
                        };
                        synthesize_into(&day.raw, &plan.plan, &job.request(), &failing)
                            .map(|s| s.report)
                    })
                })
                .unwrap_err();
            assert!(e.to_string().contains("band refused by the test"), "{e}");
            let left: Vec<String> = dir_files(dir.path()).into_keys().collect();
            assert!(
                left.is_empty(),
                "{threads} threads, band {fail_at}: {left:?}"
            );
        }
    }

    #[test]
    fn a_failed_output_fails_the_variant_before_the_sidecar() {
        let day = small_day();
        let job = SynthJob {
            target: Target::Png,
            ..SynthJob::new(SynthOptions {
                isos: vec![800],
                ..SynthOptions::default()
            })
            .unwrap()
        };
        let dir = tempfile::tempdir().unwrap();
        let plan = job.plan(&day, "day.dng", 1, 0).unwrap();
        let policy = OutputPolicy::default();
        let sink = Recorder {
            inner: DirSink::new(dir.path(), job.base_name("day", &plan.plan), &policy),
            seen: Default::default(),
            fail: Some(OutputKind::TargetPng),
        };
        let e = job.run_variant(&day, &plan, &sink).unwrap_err();
        assert!(e.to_string().contains("refused by the test sink"), "{e}");
        assert!(!dir.path().join("day.json").exists());
        // The independent outputs were still all made.
        let seen = sink.seen.lock().unwrap();
        assert!(seen.contains(&OutputKind::CleanDng));
        assert!(seen.contains(&OutputKind::NoisyDng { iso: 800 }));
        // An existing output is refused (no --overwrite), the clean DNG's error first.
        let e = job.run_variant(&day, &plan, &sink.inner).unwrap_err();
        assert!(e.to_string().contains("day_clean.dng"), "{e}");
    }
}
