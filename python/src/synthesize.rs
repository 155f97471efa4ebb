//! `synthesize` (one night variant in memory, whole frame or crop) and `write_outputs` (its
//! files, as `day2night synth` writes them).

use crate::args::{self, Isos, Param, ParamDefault, Seed, Variant};
use crate::convert::{json_obj, raw_image_from, rgb_array, u16_array};
use crate::diagnostics::warn_plan;
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use crate::raw::Raw;
use crate::synth_options::{job_config, job_for};
use day2night::isp::render_crop::target_origin;
use day2night::isp::RgbImage;
use day2night::output::OutputPolicy;
use day2night::raw::crop::Crop;
use day2night::synth::job::{DayInput, DirSink, SynthJob, Target};
use day2night::synth::night::{synthesize as lib_synthesize, Night, Request};
use day2night::synth::relight::RunReport;
use day2night::synth::Planned;
use day2night::Error;
use numpy::PyReadonlyArray3;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;
use std::sync::Arc;

/// What ``write_outputs`` needs besides the result's arrays: the job, the plan and its
/// report, the run report and the output metadata of each raw.
#[pyclass(module = "day2night", name = "Synthesis", frozen)]
pub(crate) struct Synthesis {
    job: Arc<SynthJob>,
    planned: Planned,
    report: RunReport,
    clean_meta: day2night::raw::meta::RawMeta,
    noisy_meta: Vec<(u32, day2night::raw::meta::RawMeta)>,
    crop: Option<Crop>,
    sha256: String,
}

/// `synthesize`'s parameters after `raw` (positional or keyword; its other keyword
/// arguments are the table's options): their one spelling, with their defaults.
pub(crate) const PARAMS: &[Param] = &[
    Param::pos("seed", ParamDefault::Table("seed")),
    Param::pos("variant", ParamDefault::Int(0)),
    Param::pos("mode", ParamDefault::Table("mode")),
    Param::pos("isos", ParamDefault::Table("iso")),
    Param::pos("target", ParamDefault::Str("linear")),
    Param::pos("crop", ParamDefault::None),
];

/// `synthesize`'s parameters after `raw`, bound as its signature says (positional or by
/// keyword), and its other keyword arguments (the synthesis options).
struct SynthCall<'py> {
    seed: u64,
    variant: u32,
    mode: String,
    isos: Vec<u32>,
    target: Option<String>,
    crop: Option<Bound<'py, PyAny>>,
    options: Bound<'py, PyDict>,
}

impl<'py> SynthCall<'py> {
    fn bind(args: &Bound<'py, PyTuple>, kwargs: Option<&Bound<'py, PyDict>>) -> PyResult<Self> {
        let (p, options) = args::bind_params("synthesize", PARAMS, args, kwargs, true)?;
        Ok(SynthCall {
            seed: p.extract::<Seed>("seed")?.0,
            variant: p.extract::<Variant>("variant")?.0,
            mode: args::string(p.get("mode")?, "mode")?,
            isos: p.extract::<Isos>("isos")?.0,
            target: match p.get("target")? {
                v if v.is_none() => None,
                v => Some(args::string(v, "target")?),
            },
            crop: Some(p.get("crop")?.clone()),
            options,
        })
    }
}

/// Synthesize one night variant of ``raw`` in memory.
///
/// The plan (lights, bulbs, illuminants, dimming, noise seeds) is sampled for the whole
/// frame from the stream keyed by (``seed``, ``raw.file_name``, ``variant``), exactly as
/// ``day2night synth --seed SEED`` samples its variant ``variant`` (0-based), so ``clean``,
/// ``noisy`` and ``target`` equal the pixels of the files that command writes.
///
/// With ``crop=(top, left, height, width)`` (active-area coordinates, even offsets) only
/// the crop and the 2-sample margin its demosaicer reads are computed: ``clean`` equals
/// that region of the whole-frame clean raw, ``target`` that region of the whole-frame
/// target (before orientation) and ``noisy`` carries the model's noise from the crop's own
/// random stream (keyed by the noise seed and the crop).
///
/// ``target``: ``"linear"`` (the float32 linear target) or None (no target). Options: the
/// command line's synthesis flags in snake case, with their values and defaults
/// (``relight_formula``, ``bulbs``, ``lights``, ``illuminants``, ``noise_model``, ...: the
/// option table, in the signature, docs/python.md and ``day2night._native.SYNTH_OPTIONS``);
/// ``illuminants`` defaults to the paper phone's dictionary for the S20 FE and under
/// ``compat="release"``, the CIE lamps through each file's colour matrices otherwise.
///
/// Bursts: ``burst=N`` (with ``motion="shake"|"none"``, ``shake_step``, ``shake_roll``,
/// ``warp_interp``, as ``--burst`` and its flags) makes every ``noisy[iso]`` an (N, H, W)
/// array, frame 00 first (N = 1 keeps the 2-D array); ``transforms`` lists each frame's
/// transform (``affine``, ``dx``, ``dy``, ``theta_deg``, ``valid``; None without a burst).
/// A crop is a window in frame coordinates: frame k's crop is that region of frame k.
///
/// Returns a dict: ``clean`` (uint16, the whole stored plane, or the crop), ``noisy``
/// ({iso: uint16 array}), ``transforms``, ``target`` (float32 HxWx3 linear Rec.709, or None), ``plan``
/// (the sidecar's plan: the draws), ``plan_report`` (the sidecar's report: provenance,
/// planned stages, opcodes, warnings), ``neutral`` (the night AsShotNeutral), ``noise_profile``
/// ({iso: [[S, O] per colour plane]}), ``clean_noise_profile``, ``report`` (the sidecar's
/// ``run``), ``stages``,
/// ``crop``, ``target_origin`` ((row, column) of the crop's target in the whole-frame
/// target, None outside the DefaultCrop or without a crop), ``noise_provenance`` (where
/// the noise model came from and whose camera it is: ``source``, ``camera``, ``note``; also
/// in ``plan_report``), ``illuminants_provenance`` (where the night illuminant dictionary came
/// from and whose camera colours it is: ``source``, ``camera``, ``note``, ``file``, as the
/// sidecar's ``calibration.provenance.illuminants``) and ``synthesis`` (for
/// ``write_outputs``).
///
/// The plan's warnings (e.g. another camera's noise table applied to this input) are
/// raised as ``UserWarning``, as ``day2night synth`` prints them.
///
/// >>> out = day2night.synthesize(raw, seed=0, isos=(1600,), crop=(0, 0, 512, 512))
/// >>> out["noisy"][1600].shape, out["target"].shape
/// ((512, 512), (512, 512, 3))
#[pyfunction]
#[pyo3(signature = (raw, *args, **kwargs))]
pub(crate) fn synthesize<'py>(
    raw: &Bound<'py, Raw>,
    args: &Bound<'py, PyTuple>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let py = raw.py();
    let call = SynthCall::bind(args, kwargs)?;
    let want_target = match call.target.as_deref() {
        None => false,
        Some("linear") => true,
        Some(t) => return Err(value_err(format!("target {t:?}: use \"linear\" or None"))),
    };
    let cfg = job_config(&call.mode, call.isos, want_target, Some(&call.options))?;
    let (seed, variant, crop) = (call.seed, call.variant, call.crop);
    let r = raw.get();
    let crop = match crop.filter(|c| !c.is_none()) {
        None => None,
        Some(c) => {
            let a = r.day.raw.active_area();
            Some(args::crop(&c, a.width(), a.height())?)
        }
    };
    let day = r.cfa_day()?;
    let file_name = r.file_name.clone();
    let (job, planned, night, ill) = py
        .detach(move || {
            on_pool(move || {
                let job = job_for(&cfg)?;
                let mut planned = job.plan(&day, &file_name, seed, variant)?;
                if crop.is_some() {
                    // a crop reads the whole-frame mean of the dimming from the input's memo
                    planned.plan = day.with_frame_mean(planned.plan)?;
                }
                // The dictionary as the sidecar records it (its provenance and camera).
                let ill = job.illuminants(&day)?;
                let req = Request {
                    target: want_target,
                    input: false,
                    crop,
                };
                let night = lib_synthesize(&day.raw, &planned.plan, &req)?;
                Ok((job, planned, night, ill))
            })
        })
        .map_err(py_err)?;
    let plan = &planned.plan;
    // a burst's frames, stacked per ISO (frame 00 first) before the night is taken apart
    let frames_n = plan.burst.as_ref().map_or(1, |b| b.frames);
    let mut stacks = Vec::new();
    if frames_n > 1 {
        for (iso, img) in &night.noisy {
            stacks.push(crate::burst::stack(
                py,
                &crate::burst::frames_of(&night, *iso, img),
            )?);
        }
    }
    let Night {
        clean,
        noisy,
        target,
        report,
        stages,
        crop,
        ..
    } = night;
    // The plan's warnings after the reader's (raised by read_dng already), then the run's.
    warn_plan(
        py,
        &r.file_name,
        &r.day.raw.meta,
        &planned.report,
        &report.warnings,
    )?;
    let d = PyDict::new(py);
    let bayer = plan.bayer;
    let profile = |p: &day2night::noise::NoiseParams| -> Vec<Vec<f64>> {
        p.to_dng_profile(bayer)
            .into_iter()
            .map(|(s, o)| vec![s, o])
            .collect()
    };
    let np = PyDict::new(py);
    let noisy_arrays = PyDict::new(py);
    let mut noisy_meta = Vec::new();
    let mut stacks = stacks.into_iter();
    for (iso, img) in noisy {
        noisy_meta.push((iso, img.meta.clone()));
        match stacks.next() {
            Some(a) => noisy_arrays.set_item(iso, a)?,
            None => noisy_arrays.set_item(iso, u16_array(py, img)?)?,
        }
    }
    d.set_item("transforms", crate::burst::transforms(py, plan)?)?;
    for n in &plan.noise {
        np.set_item(n.iso, profile(&n.params))?;
    }
    let a = r.day.raw.active_area();
    let origin = crop.and_then(|c| target_origin(&r.day.raw.meta, a.width(), a.height(), &c));
    d.set_item("clean_noise_profile", profile(&plan.clean_noise))?;
    d.set_item("noise_profile", np)?;
    d.set_item("neutral", plan.night_neutral.to_vec())?;
    d.set_item("plan", json_obj(py, plan)?)?;
    d.set_item("plan_report", json_obj(py, &planned.report)?)?;
    let noise_provenance = &planned.report.noise_provenance;
    d.set_item("noise_provenance", json_obj(py, noise_provenance)?)?;
    d.set_item("illuminants_provenance", json_obj(py, &ill.provenance)?)?;
    d.set_item("report", json_obj(py, &report)?)?;
    d.set_item("stages", planned.report.stages_with(&stages))?;
    d.set_item("crop", crop.map(|c| (c.top, c.left, c.height, c.width)))?;
    d.set_item("target_origin", origin)?;
    let synthesis = Synthesis {
        job,
        planned,
        report,
        clean_meta: clean.meta.clone(),
        noisy_meta,
        crop,
        sha256: r.day.sha256.clone(),
    };
    d.set_item("clean", u16_array(py, clean)?)?;
    d.set_item("noisy", noisy_arrays)?;
    d.set_item(
        "target",
        match target {
            Some(t) => Some(rgb_array(py, t)?),
            None => None,
        },
    )?;
    d.set_item("synthesis", Bound::new(py, synthesis)?)?;
    Ok(d)
}

/// Write a whole-frame ``synthesize`` result as the files ``day2night synth`` writes for
/// the same input, seed, variant and options (clean DNG, one DNG per ISO, the EXR target
/// (plus the sRGB PNG with ``png=True``), the sidecar), byte for byte, into ``out_dir``.
/// The arrays are taken from ``result`` (as returned, they give the same bytes). Existing
/// files are refused unless ``overwrite=True``. Returns the file names written.
///
/// >>> day2night.write_outputs(out, raw, "night/")
/// ['day_clean.dng', 'day_iso1600.dng', 'day_iso3200.dng', 'day_target.exr', 'day.json']
#[pyfunction]
#[pyo3(signature = (result, raw, out_dir, png=false, overwrite=false))]
pub(crate) fn write_outputs(
    py: Python<'_>,
    result: &Bound<'_, PyDict>,
    raw: &Bound<'_, Raw>,
    out_dir: PathBuf,
    png: bool,
    overwrite: bool,
) -> PyResult<Vec<String>> {
    let item = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        result.get_item(k)?.ok_or_else(|| {
            value_err(format!(
                "result has no {k:?}: pass what synthesize returned"
            ))
        })
    };
    let syn = item("synthesis")?;
    let syn: &Bound<'_, Synthesis> = syn
        .cast()
        .map_err(|_| value_err("result[\"synthesis\"] is not a synthesis"))?;
    let s = syn.get();
    if s.crop.is_some() {
        return Err(value_err(
            "invalid parameter: a crop's products are not written as files: synthesize the whole frame",
        ));
    }
    let r = raw.get();
    if r.day.sha256 != s.sha256 {
        return Err(value_err(
            "invalid parameter: the result was synthesized from another input",
        ));
    }
    let clean = raw_image_from(&item("clean")?, &s.clean_meta, "result[\"clean\"]")?;
    let noisy_d = item("noisy")?;
    let mut noisy = Vec::new();
    let mut frames = Vec::new();
    let n = s.planned.plan.burst.as_ref().map_or(1, |b| b.frames);
    for (iso, meta) in &s.noisy_meta {
        let a = noisy_d.get_item(*iso)?;
        let what = format!("result[\"noisy\"][{iso}]");
        if n == 1 {
            noisy.push((*iso, raw_image_from(&a, meta, &what)?));
            continue;
        }
        // a burst: (N, H, W), frame 00 first
        if a.len()? != n as usize {
            return Err(value_err(format!(
                "{what} must hold the burst's {n} frames"
            )));
        }
        for k in 0..n {
            let img = raw_image_from(&a.get_item(k)?, meta, &format!("{what}[{k}]"))?;
            match k {
                0 => noisy.push((*iso, img)),
                k => frames.push((*iso, k, img)),
            }
        }
    }
    let t = item("target")?;
    let target = if t.is_none() {
        None
    } else {
        let a: PyReadonlyArray3<'_, f32> = t
            .extract()
            .map_err(|_| value_err("result[\"target\"] must be a float32 HxWx3 array"))?;
        let v = a.as_array();
        let (h, w, c) = v.dim();
        if c != 3 {
            return Err(value_err("result[\"target\"] must be HxWx3"));
        }
        Some(RgbImage {
            width: w,
            height: h,
            data: v.iter().copied().collect(),
        })
    };
    let mut job = (*s.job).clone();
    // Variant k is the (k+1)-th variant of `day2night synth --variants k+1`: its names
    // carry `_v{k+1}` when k > 0, and the sidecar records k+1 variants.
    job.variants = s.planned.plan.variant.saturating_add(1);
    job.target = match (target.is_some(), png) {
        (false, _) => Target::None,
        (true, false) => Target::Exr,
        (true, true) => Target::Both,
    };
    let night = Night {
        clean,
        noisy,
        frames,
        target,
        input: None,
        report: s.report.clone(),
        stages: Vec::new(),
        crop: None,
    };
    let day = r.day.clone();
    let stem = r.name.clone();
    let planned = s.planned.clone();
    let from_file = r.from_file;
    let files = Files {
        day,
        from_file,
        stem,
        planned,
        job,
        night,
        out_dir,
        overwrite,
    };
    py.detach(move || on_pool(move || files.write()))
        .map_err(py_err)
}

/// A synthesized variant and where its files go.
struct Files {
    day: Arc<DayInput>,
    /// The input is a file (an output never replaces it).
    from_file: bool,
    stem: String,
    planned: Planned,
    job: SynthJob,
    night: Night,
    out_dir: PathBuf,
    overwrite: bool,
}

impl Files {
    /// Write the files, as `day2night synth` writes them; their names.
    fn write(self) -> Result<Vec<String>, Error> {
        let Files {
            day,
            from_file,
            stem,
            planned,
            job,
            night,
            out_dir,
            overwrite,
        } = self;
        std::fs::create_dir_all(&out_dir).map_err(|e| Error::from(e).in_file(&out_dir))?;
        let policy = OutputPolicy {
            overwrite,
            inputs: if from_file {
                vec![day.source.clone()]
            } else {
                Vec::new()
            },
            ..OutputPolicy::default()
        };
        let sink = DirSink::new(&out_dir, job.base_name(&stem, &planned.plan), &policy);
        Ok(job.write_night(&day, &planned, &night, &sink)?.files)
    }
}
