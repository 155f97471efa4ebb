//! Python bindings of day2night (`day2night._native`): a thin shell that converts types.
//! Every computation is the Rust library's (`day2night::synth::night::synthesize`, the same
//! path `day2night synth` runs), with the GIL released while it runs. Library errors become
//! `OSError` (I/O) or `ValueError` (everything else) with the command line's message.
#![forbid(unsafe_code)]

mod dataset_units;
mod pairs;
mod raw_from;

use day2night::isp::render::{render_linear, RenderOptions};
use day2night::isp::{Demosaic, RgbImage};
use day2night::metrics::{
    mean_delta_e_2000, psnr as m_psnr, ssim as m_ssim, SsimOptions, SsimWindow,
};
use day2night::output::OutputPolicy;
use day2night::synth::config::JobConfig;
use day2night::synth::crop::{target_origin, Crop};
use day2night::synth::job::{DayInput, DirSink, SynthJob, Target};
use day2night::synth::night::{synthesize as lib_synthesize, Night, Request};
use day2night::synth::relight::RunReport;
use day2night::synth::{Covariance, MaskEval, Mode, Plan, RelightFormula};
use day2night::{Error, RawImage};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// A library error as a Python exception: `OSError` for I/O, `ValueError` otherwise, with
/// the message the command line prints (after its `day2night: ` prefix).
pub(crate) fn py_err(e: Error) -> PyErr {
    let msg = e.to_string();
    let mut cur = &e;
    while let Error::File { source, .. } = cur {
        cur = source;
    }
    match cur {
        Error::Io(_) => PyOSError::new_err(msg),
        _ => PyValueError::new_err(msg),
    }
}

/// The worker threads of a Python thread: each Python thread that computes gets its own
/// rayon pool (so two Python threads with `set_threads(1)` compute on two cores at once,
/// instead of queueing on one shared worker), owned by the process that made it. A process
/// forked from one that had already computed (a `DataLoader` worker) inherits the pool's
/// bookkeeping but none of its threads, so a pool is only used in the process that built
/// it; a child builds its own (and forgets the parent's).
struct Pool {
    pid: u32,
    threads: usize,
    pool: Arc<rayon::ThreadPool>,
}

thread_local! {
    static POOL: std::cell::RefCell<Option<Pool>> = const { std::cell::RefCell::new(None) };
}
static THREADS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

fn pool() -> Result<Arc<rayon::ThreadPool>, Error> {
    POOL.with(|slot| {
        let mut slot = slot.borrow_mut();
        let want = THREADS.load(std::sync::atomic::Ordering::Relaxed);
        let pid = std::process::id();
        if let Some(p) = slot.as_ref() {
            if p.pid == pid && (want == 0 || want == p.threads) {
                return Ok(p.pool.clone());
            }
        }
        let mut b = rayon::ThreadPoolBuilder::new();
        if want > 0 {
            b = b.num_threads(want);
        }
        let pool = Arc::new(
            b.build()
                .map_err(|e| Error::invalid(format!("cannot start worker threads: {e}")))?,
        );
        if let Some(old) = slot.take() {
            if old.pid != pid {
                // Its threads live in the parent process only: never join or drop them here.
                std::mem::forget(old);
            }
        }
        *slot = Some(Pool {
            pid,
            threads: pool.current_num_threads(),
            pool: pool.clone(),
        });
        Ok(pool)
    })
}

/// Run `f` on the calling thread's worker threads.
pub(crate) fn on_pool<T: Send>(f: impl FnOnce() -> Result<T, Error> + Send) -> Result<T, Error> {
    pool()?.install(f)
}

/// Set the number of worker threads each computation uses (0 = one per core, the default;
/// the ``RAYON_NUM_THREADS`` environment variable also sets it). Every Python thread that
/// computes has its own workers: with several ``DataLoader`` workers or Python threads,
/// about cores / workers each avoids oversubscription.
///
/// >>> day2night.set_threads(1)
#[pyfunction]
fn set_threads(n: usize) {
    THREADS.store(n, std::sync::atomic::Ordering::Relaxed);
}

/// The number of worker threads computations of the calling thread use.
#[pyfunction]
fn threads() -> PyResult<usize> {
    Ok(pool().map_err(py_err)?.current_num_threads())
}

pub(crate) fn value_err(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A day DNG read into memory.
///
/// Attributes: ``data`` (uint16 ndarray of the whole stored plane, masked border
/// included: LibRaw's ``raw_image``), ``meta`` (dict), ``name`` (file stem), ``file_name``
/// (the name the random streams are keyed by, as in ``day2night synth``), ``path``.
///
/// >>> raw = day2night.read_dng("day.dng")
/// >>> raw.data.shape, raw.meta["cfa_pattern"]
/// ((3024, 4032), 'RGGB')
#[pyclass(module = "day2night", name = "Raw", frozen)]
pub(crate) struct Raw {
    day: Arc<DayInput>,
    name: String,
    file_name: String,
    /// Read from `day.source` (false: built in memory, e.g. `Raw.from_array`).
    from_file: bool,
    data: OnceLock<Py<PyArray2<u16>>>,
}

#[pymethods]
impl Raw {
    /// The whole stored CFA plane as a read-only uint16 array (height x width).
    #[getter]
    fn data<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u16>>> {
        if let Some(a) = self.data.get() {
            return Ok(a.bind(py).clone());
        }
        let raw = &self.day.raw;
        let arr = Array2::from_shape_vec((raw.height, raw.width), raw.data.clone())
            .map_err(|e| value_err(e.to_string()))?
            .into_pyarray(py);
        arr.readwrite().make_nonwriteable();
        let _ = self.data.set(arr.clone().unbind());
        Ok(self.data.get().map(|a| a.bind(py).clone()).unwrap_or(arr))
    }

    /// Metadata: cfa_pattern, black_level (BlackLevel pattern), black_level_repeat_dim,
    /// white_level, as_shot_neutral, iso, noise_profile, active_area [top, left, bottom,
    /// right], default_crop [top, left, height, width] (in active-area coordinates),
    /// orientation, make, model, width, height, bits_per_sample.
    #[getter]
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        meta_dict(py, &self.day.raw)
    }

    /// The file stem (``day`` for ``day.dng``).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The file name (``day.dng``): the key of the random streams, as in ``day2night synth``.
    #[getter]
    fn file_name(&self) -> &str {
        &self.file_name
    }

    /// The path the DNG was read from (None for a raw built in memory).
    #[getter]
    fn path(&self) -> Option<String> {
        self.from_file
            .then(|| self.day.source.display().to_string())
    }

    /// A raw from a 2-D uint16 CFA array (the whole stored plane; any strides) and a
    /// metadata dict with the keys of ``Raw.meta`` (cfa_pattern, black_level and
    /// white_level required; missing colour metadata gets the documented defaults, each
    /// with a warning). ``name`` is the file stem the outputs and random streams are keyed
    /// by (``file_name`` is ``name + ".dng"``). Checked as the DNG reader checks a file.
    ///
    /// >>> r = day2night.read_dng("day.dng")
    /// >>> same = day2night.Raw.from_array(r.data, r.meta, name=r.name)
    #[staticmethod]
    fn from_array(
        py: Python<'_>,
        data: &Bound<'_, PyAny>,
        meta: &Bound<'_, PyAny>,
        name: &str,
    ) -> PyResult<Raw> {
        raw_from::from_array(py, data, meta, name)
    }

    /// SHA-256 of the file's bytes (the sidecar's ``input.sha256``).
    #[getter]
    fn sha256(&self) -> &str {
        &self.day.sha256
    }

    fn __repr__(&self) -> String {
        let r = &self.day.raw;
        format!(
            "Raw({:?}, {}x{}, {})",
            self.file_name,
            r.width,
            r.height,
            r.bayer()
                .map(|b| b.name())
                .unwrap_or_else(|_| "non-Bayer".into())
        )
    }
}

fn meta_dict<'py>(py: Python<'py>, raw: &RawImage) -> PyResult<Bound<'py, PyDict>> {
    let m = &raw.meta;
    let d = PyDict::new(py);
    let a = raw.active_area();
    let (aw, ah) = (a.width(), a.height());
    d.set_item("cfa_pattern", raw.bayer().ok().map(|b| b.name()))?;
    d.set_item("black_level", m.levels.black.clone())?;
    d.set_item(
        "black_level_repeat_dim",
        (m.levels.black_repeat.0, m.levels.black_repeat.1),
    )?;
    d.set_item("white_level", m.levels.white)?;
    d.set_item("as_shot_neutral", m.as_shot_neutral.map(|n| n.to_vec()))?;
    d.set_item("iso", m.exif.iso)?;
    d.set_item(
        "noise_profile",
        m.noise_profile
            .as_ref()
            .map(|p| p.iter().map(|&(s, o)| vec![s, o]).collect::<Vec<_>>()),
    )?;
    d.set_item("active_area", vec![a.top, a.left, a.bottom, a.right])?;
    let (x0, y0, cw, ch) = day2night::isp::render::default_crop(m, aw, ah);
    d.set_item("default_crop", vec![y0, x0, ch, cw])?;
    d.set_item("orientation", m.orientation)?;
    d.set_item("make", m.make.clone())?;
    d.set_item("model", m.model.clone())?;
    d.set_item("width", raw.width)?;
    d.set_item("height", raw.height)?;
    d.set_item("bits_per_sample", m.bits_per_sample)?;
    raw_from::extra_meta(&d, raw)?;
    Ok(d)
}

/// Raise each metadata correction of the reader (`day2night::dng::check`) as a Python
/// `UserWarning`: `<file>: <message>`, as the command line says `day2night: <file>: warning:`.
fn warn_meta(
    py: Python<'_>,
    path: &std::path::Path,
    meta: &day2night::raw::meta::RawMeta,
) -> PyResult<()> {
    for w in &meta.warnings {
        let msg = std::ffi::CString::new(format!("{}: {w}", path.display()))
            .unwrap_or_else(|_| c"metadata corrected".into());
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &msg,
            1,
        )?;
    }
    Ok(())
}

/// Raise the warnings of a plan beyond the reader's own (those `read_dng` already raised):
/// the noise model's source (another camera's table, an untrusted estimate, a model file of
/// another camera), ISO extrapolation, opcodes; each a `UserWarning` `<file>: <message>`,
/// as `day2night synth` prints `day2night: <file>: warning: <message>`.
fn warn_plan(
    py: Python<'_>,
    file: &str,
    meta: &day2night::raw::meta::RawMeta,
    plan: &Plan,
) -> PyResult<()> {
    // The plan's list starts with the reader's corrections (dng::check).
    let own = if plan.warnings.starts_with(&meta.warnings) {
        meta.warnings.len()
    } else {
        0
    };
    for w in &plan.warnings[own..] {
        let msg = std::ffi::CString::new(format!("{file}: {w}"))
            .unwrap_or_else(|_| c"synthesis warning".into());
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &msg,
            1,
        )?;
    }
    Ok(())
}

/// Read a DNG into memory (the GIL is released while it is read and decoded).
///
/// >>> raw = day2night.read_dng("day.dng")
#[pyfunction]
fn read_dng(py: Python<'_>, path: PathBuf) -> PyResult<Raw> {
    let day = py
        .detach(|| on_pool(|| DayInput::read(&path)))
        .map_err(py_err)?;
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    let name = path
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| file_name.clone());
    warn_meta(py, &path, &day.raw.meta)?;
    Ok(Raw {
        day: Arc::new(day),
        name,
        file_name,
        from_file: true,
        data: OnceLock::new(),
    })
}

/// The job options a ``synthesize`` call spells, as the command line's flags.
fn job_config(
    mode: &str,
    isos: Vec<u32>,
    want_target: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<JobConfig> {
    let mut cfg = JobConfig::default();
    let o = &mut cfg.options;
    o.mode = mode.parse::<Mode>().map_err(py_err)?;
    o.isos = Vec::new();
    for iso in isos {
        if iso == 0 {
            return Err(value_err("invalid parameter: ISO 0"));
        }
        if !o.isos.contains(&iso) {
            o.isos.push(iso);
        }
    }
    let mut release = false;
    let mut opcodes = None;
    if let Some(opts) = options {
        for (k, v) in opts.iter() {
            let key: String = k.extract()?;
            let path = |v: &Bound<'_, PyAny>| -> PyResult<Option<PathBuf>> {
                if v.is_none() {
                    Ok(None)
                } else {
                    Ok(Some(v.extract::<PathBuf>()?))
                }
            };
            match key.as_str() {
                "relight_formula" | "formula" => {
                    o.formula = v
                        .extract::<String>()?
                        .parse::<RelightFormula>()
                        .map_err(py_err)?
                }
                "bulbs" => o.bulbs = v.extract()?,
                "lights" => o.local_lights = v.extract()?,
                "truncate" => o.truncate = v.extract()?,
                "covariance" => {
                    o.covariance = v
                        .extract::<String>()?
                        .parse::<Covariance>()
                        .map_err(py_err)?
                }
                "day_neutral" => {
                    o.day_neutral = if v.is_none() {
                        None
                    } else {
                        let n: Vec<f64> = v.extract()?;
                        match n.as_slice() {
                            [r, g, b] => Some([*r, *g, *b]),
                            _ => return Err(value_err("day_neutral must be (r, g, b)")),
                        }
                    }
                }
                "mask_eval" => {
                    o.mask_eval = v.extract::<String>()?.parse::<MaskEval>().map_err(py_err)?
                }
                "compat" => {
                    release = match v.extract::<Option<String>>()?.as_deref() {
                        None => false,
                        Some("release") => true,
                        Some(c) => {
                            return Err(value_err(format!("compat {c:?}: use \"release\" or None")))
                        }
                    }
                }
                "opcodes" => {
                    opcodes = Some(
                        v.extract::<String>()?
                            .parse::<day2night::isp::opcodes::OpcodeMode>()
                            .map_err(py_err)?,
                    )
                }
                "illuminants" => cfg.illuminants = path(&v)?,
                "brightness" => cfg.brightness = path(&v)?,
                "noise_model" => cfg.noise_model = path(&v)?,
                other => {
                    return Err(value_err(format!(
                    "unknown option {other:?} (known: relight_formula, bulbs, lights, truncate, \
covariance, day_neutral, mask_eval, opcodes, illuminants, brightness, noise_model)"
                )))
                }
            }
        }
    }
    if release {
        // Applied last, like --compat release: it checks the other options.
        cfg.options = cfg.options.clone().release_compat().map_err(py_err)?;
    }
    if let Some(m) = opcodes {
        cfg.options.opcodes = m;
    }
    cfg.target = if want_target {
        Target::Exr
    } else {
        Target::None
    };
    Ok(cfg)
}

/// Jobs already built (calibration files loaded), by their configuration: a data loader
/// calls `synthesize` with the same options for every item.
fn job_for(cfg: &JobConfig) -> Result<Arc<SynthJob>, Error> {
    static JOBS: OnceLock<Mutex<HashMap<String, Arc<SynthJob>>>> = OnceLock::new();
    let key = format!("{cfg:?}");
    let jobs = JOBS.get_or_init(Default::default);
    if let Some(j) = jobs.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Ok(j.clone());
    }
    let job = Arc::new(cfg.build()?);
    let mut map = jobs.lock().unwrap_or_else(|e| e.into_inner());
    if map.len() > 64 {
        map.clear();
    }
    map.insert(key, job.clone());
    Ok(job)
}

/// What ``write_outputs`` needs besides the result's arrays: the job, the plan, the run
/// report and the output metadata of each raw.
#[pyclass(module = "day2night", name = "Synthesis", frozen)]
struct Synthesis {
    job: Arc<SynthJob>,
    plan: Plan,
    report: RunReport,
    clean_meta: day2night::raw::meta::RawMeta,
    noisy_meta: Vec<(u32, day2night::raw::meta::RawMeta)>,
    crop: Option<Crop>,
    sha256: String,
}

fn json_obj<'py>(py: Python<'py>, v: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let s = serde_json::to_string(v).map_err(|e| value_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (s,))
}

fn u16_array(py: Python<'_>, img: RawImage) -> PyResult<Bound<'_, PyArray2<u16>>> {
    Ok(Array2::from_shape_vec((img.height, img.width), img.data)
        .map_err(|e| value_err(e.to_string()))?
        .into_pyarray(py))
}

fn rgb_array(py: Python<'_>, img: RgbImage) -> PyResult<Bound<'_, PyAny>> {
    Ok(Array3::from_shape_vec((img.height, img.width, 3), img.data)
        .map_err(|e| value_err(e.to_string()))?
        .into_pyarray(py)
        .into_any())
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
/// Options (as the command line's flags): relight_formula ("release" | "paper"), bulbs,
/// lights, truncate, covariance ("unbiased" | "ml"), day_neutral ((r, g, b)), mask_eval
/// ("separable" | "exact" | "truncated:K" | "release"), compat ("release": the authors'
/// release semantics, docs/synthesis.md), illuminants, brightness, noise_model (paths; a
/// physics noise model file is recognized).
///
/// Returns a dict: ``clean`` (uint16, the whole stored plane, or the crop), ``noisy``
/// ({iso: uint16 array}), ``target`` (float32 HxWx3 linear Rec.709, or None), ``plan``
/// (the sidecar's plan), ``neutral`` (the night AsShotNeutral), ``noise_profile``
/// ({iso: [[S, O] per colour plane]}), ``clean_noise_profile``, ``report``, ``stages``,
/// ``crop``, ``target_origin`` ((row, column) of the crop's target in the whole-frame
/// target, None outside the DefaultCrop or without a crop), ``noise_provenance`` (where
/// the noise model came from and whose camera it is: ``source``, ``camera``, ``note``; also
/// in ``plan``) and ``synthesis`` (for ``write_outputs``).
///
/// The plan's warnings (e.g. another camera's noise table applied to this input) are
/// raised as ``UserWarning``, as ``day2night synth`` prints them.
///
/// >>> out = day2night.synthesize(raw, seed=0, isos=(1600,), crop=(0, 0, 512, 512))
/// >>> out["noisy"][1600].shape, out["target"].shape
/// ((512, 512), (512, 512, 3))
#[pyfunction]
#[pyo3(signature = (raw, seed=0, variant=0, mode="local", isos=vec![1600, 3200], target=Some("linear"), crop=None, **options))]
#[allow(clippy::too_many_arguments)]
fn synthesize<'py>(
    py: Python<'py>,
    raw: &Bound<'py, Raw>,
    seed: u64,
    variant: u32,
    mode: &str,
    isos: Vec<u32>,
    target: Option<&str>,
    crop: Option<(usize, usize, usize, usize)>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let want_target = match target {
        None => false,
        Some("linear") => true,
        Some(t) => return Err(value_err(format!("target {t:?}: use \"linear\" or None"))),
    };
    let cfg = job_config(mode, isos, want_target, options)?;
    let crop = crop.map(|(top, left, height, width)| Crop {
        top,
        left,
        height,
        width,
    });
    let r = raw.get();
    let day = r.day.clone();
    let file_name = r.file_name.clone();
    let (job, plan, night) = py
        .detach(move || {
            on_pool(move || {
                let job = job_for(&cfg)?;
                let plan = job.plan(&day, &file_name, seed, variant)?;
                let req = Request {
                    target: want_target,
                    input: false,
                    crop,
                };
                let night = lib_synthesize(&day.raw, &plan, &req)?;
                Ok((job, plan, night))
            })
        })
        .map_err(py_err)?;
    let Night {
        clean,
        noisy,
        target,
        report,
        stages,
        crop,
        ..
    } = night;
    warn_plan(py, &r.file_name, &r.day.raw.meta, &plan)?;
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
    for (iso, img) in noisy {
        noisy_meta.push((iso, img.meta.clone()));
        noisy_arrays.set_item(iso, u16_array(py, img)?)?;
    }
    for n in &plan.noise {
        np.set_item(n.iso, profile(&n.params))?;
    }
    let a = r.day.raw.active_area();
    let origin = crop.and_then(|c| target_origin(&r.day.raw.meta, a.width(), a.height(), &c));
    d.set_item("clean_noise_profile", profile(&plan.clean_noise))?;
    d.set_item("noise_profile", np)?;
    d.set_item("neutral", plan.night_neutral.to_vec())?;
    d.set_item("plan", json_obj(py, &plan)?)?;
    d.set_item("noise_provenance", json_obj(py, &plan.noise_provenance)?)?;
    d.set_item("report", json_obj(py, &report)?)?;
    d.set_item("stages", stages)?;
    d.set_item("crop", crop.map(|c| (c.top, c.left, c.height, c.width)))?;
    d.set_item("target_origin", origin)?;
    let synthesis = Synthesis {
        job,
        plan,
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

fn raw_from(
    arr: &Bound<'_, PyAny>,
    meta: &day2night::raw::meta::RawMeta,
    what: &str,
) -> PyResult<RawImage> {
    let a: PyReadonlyArray2<'_, u16> = arr
        .extract()
        .map_err(|_| value_err(format!("{what} must be a 2-D uint16 array")))?;
    let v = a.as_array();
    let (h, w) = v.dim();
    Ok(RawImage {
        width: w,
        height: h,
        data: v.iter().copied().collect(),
        meta: meta.clone(),
    })
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
fn write_outputs(
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
    let clean = raw_from(&item("clean")?, &s.clean_meta, "result[\"clean\"]")?;
    let noisy_d = item("noisy")?;
    let mut noisy = Vec::new();
    for (iso, meta) in &s.noisy_meta {
        let a = noisy_d.get_item(*iso)?;
        noisy.push((
            *iso,
            raw_from(&a, meta, &format!("result[\"noisy\"][{iso}]"))?,
        ));
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
    job.variants = s.plan.variant.saturating_add(1);
    job.target = match (target.is_some(), png) {
        (false, _) => Target::None,
        (true, false) => Target::Exr,
        (true, true) => Target::Both,
    };
    let night = Night {
        clean,
        noisy,
        target,
        input: None,
        report: s.report.clone(),
        stages: Vec::new(),
        crop: None,
    };
    let day = r.day.clone();
    let stem = r.name.clone();
    let plan = s.plan.clone();
    let from_file = r.from_file;
    py.detach(move || {
        on_pool(move || write_files(day, from_file, stem, plan, job, night, out_dir, overwrite))
    })
    .map_err(py_err)
}

#[allow(clippy::too_many_arguments)]
fn write_files(
    day: Arc<DayInput>,
    from_file: bool,
    stem: String,
    plan: Plan,
    job: SynthJob,
    night: Night,
    out_dir: PathBuf,
    overwrite: bool,
) -> Result<Vec<String>, Error> {
    {
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
        let sink = DirSink::new(&out_dir, &stem, &job, &plan, &policy);
        Ok(job.write_night(&day, &plan, &night, &sink)?.files)
    }
}

/// Linear sRGB (Rec.709, D65) render of a raw, float32 HxWx3 in [0, 1], as ``day2night
/// render --format exr`` computes it: white balance by ``neutral`` (default: the file's
/// AsShotNeutral), demosaic (``"mhc"``, ``"bilinear"`` or ``"menon"``), colour matrices,
/// DefaultCrop (``crop``) and orientation (``orient``); the DNG opcode lists (lens shading,
/// distortion) are applied unless ``opcodes="ignore"``.
///
/// >>> rgb = day2night.render(raw)
#[pyfunction]
#[pyo3(signature = (raw, neutral=None, demosaic="mhc", crop=true, orient=true, opcodes="apply"))]
fn render<'py>(
    py: Python<'py>,
    raw: &Bound<'py, Raw>,
    neutral: Option<(f64, f64, f64)>,
    demosaic: &str,
    crop: bool,
    orient: bool,
    opcodes: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let method: Demosaic = demosaic.parse().map_err(py_err)?;
    let opcodes: day2night::isp::opcodes::OpcodeMode = opcodes.parse().map_err(py_err)?;
    let day = raw.get().day.clone();
    let opts = RenderOptions {
        demosaic: method,
        neutral: neutral.map(|(r, g, b)| [r, g, b]),
        crop,
        orient,
        opcodes,
    };
    let rgb = py
        .detach(move || on_pool(move || render_linear(&day.raw, &opts)))
        .map_err(py_err)?;
    rgb_array(py, rgb)
}

fn rgb_from(a: &PyReadonlyArray3<'_, f32>, what: &str) -> PyResult<RgbImage> {
    let v = a.as_array();
    let (h, w, c) = v.dim();
    if c != 3 {
        return Err(value_err(format!("{what} must be HxWx3")));
    }
    Ok(RgbImage {
        width: w,
        height: h,
        data: v.iter().copied().collect(),
    })
}

/// PSNR in dB of ``pred`` against ``target`` (float32 HxWx3 arrays), as ``day2night eval``
/// computes it for two images of the same encoding; infinite for identical images.
#[pyfunction]
#[pyo3(signature = (pred, target, data_range=1.0))]
fn psnr(
    py: Python<'_>,
    pred: PyReadonlyArray3<'_, f32>,
    target: PyReadonlyArray3<'_, f32>,
    data_range: f64,
) -> PyResult<f64> {
    let (a, b) = (rgb_from(&pred, "pred")?, rgb_from(&target, "target")?);
    py.detach(move || on_pool(move || m_psnr(&a, &b, data_range)))
        .map_err(py_err)
}

/// SSIM of ``pred`` against ``target`` (float32 HxWx3), as ``day2night eval``: window
/// ``"uniform"`` (scikit-image's 7x7 default) or ``"gaussian"`` (Wang et al. 2004).
#[pyfunction]
#[pyo3(signature = (pred, target, data_range=1.0, window="uniform"))]
fn ssim(
    py: Python<'_>,
    pred: PyReadonlyArray3<'_, f32>,
    target: PyReadonlyArray3<'_, f32>,
    data_range: f64,
    window: &str,
) -> PyResult<f64> {
    let window = match window {
        "uniform" => SsimWindow::Uniform7,
        "gaussian" => SsimWindow::Gaussian,
        w => return Err(value_err(format!("window {w:?}: use uniform or gaussian"))),
    };
    let (a, b) = (rgb_from(&pred, "pred")?, rgb_from(&target, "target")?);
    let opts = SsimOptions { data_range, window };
    py.detach(move || on_pool(move || m_ssim(&a, &b, &opts)))
        .map_err(py_err)
}

/// Mean CIEDE2000 of ``pred`` against ``target`` (float32 HxWx3), as ``day2night eval``:
/// each image is linear sRGB (``*_linear=True``, e.g. an EXR) or display sRGB (False).
#[pyfunction]
#[pyo3(signature = (pred, target, pred_linear=true, target_linear=true))]
fn delta_e2000(
    py: Python<'_>,
    pred: PyReadonlyArray3<'_, f32>,
    target: PyReadonlyArray3<'_, f32>,
    pred_linear: bool,
    target_linear: bool,
) -> PyResult<f64> {
    let (a, b) = (rgb_from(&pred, "pred")?, rgb_from(&target, "target")?);
    py.detach(move || on_pool(move || mean_delta_e_2000(&a, &b, pred_linear, target_linear)))
        .map_err(py_err)
}

/// The library version.
#[pyfunction]
fn version() -> &'static str {
    day2night::VERSION
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Raw>()?;
    m.add_class::<Synthesis>()?;
    m.add_function(wrap_pyfunction!(read_dng, m)?)?;
    m.add_function(wrap_pyfunction!(synthesize, m)?)?;
    m.add_function(wrap_pyfunction!(write_outputs, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(psnr, m)?)?;
    m.add_function(wrap_pyfunction!(ssim, m)?)?;
    m.add_function(wrap_pyfunction!(delta_e2000, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(set_threads, m)?)?;
    m.add_function(wrap_pyfunction!(threads, m)?)?;
    raw_from::register(m)?;
    m.add_function(wrap_pyfunction!(pairs::night_pair, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_units::dataset_units, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_units::write_unit, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_units::write_manifest, m)?)?;
    Ok(())
}
