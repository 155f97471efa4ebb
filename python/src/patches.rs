//! `fresh_pair`: the night ISP's training pair of one synthesized crop (the release's
//! network input and the 8-bit target), whole or cut into patches, in one call
//! (`day2night.train.FreshPatches`; `day2night::synth::patches`).

use crate::args::{self, Iso, Param, ParamDefault, Seed, Variant};
use crate::diagnostics::warn_plan;
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use crate::raw::Raw;
use crate::synth_options::{job_config, job_for};
use day2night::isp::release_input::{check_table, release_table, RELEASE_GAMMA};
use day2night::isp::tone::DisplayTone;
use day2night::synth::patches::{crop_pair, cut_patches, cut_patches_into, PairInput};
use numpy::ndarray::{Array3, Array4};
use numpy::{
    IntoPyArray, PyArrayMethods, PyReadonlyArray1, PyReadwriteArray4, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// `fresh_pair`'s parameters after `iso` (positional or keyword; its other keyword
/// arguments are the table's options): their one spelling, with their defaults.
pub(crate) const PARAMS: &[Param] = &[
    Param::pos("seed", ParamDefault::Table("seed")),
    Param::pos("variant", ParamDefault::Int(0)),
    Param::pos("mode", ParamDefault::Table("mode")),
    Param::pos("task", ParamDefault::Str("noisy")),
    Param::pos("table", ParamDefault::None),
    Param::pos("patch", ParamDefault::None),
    Param::pos("tone", ParamDefault::Str("srgb")),
    Param::pos("out", ParamDefault::None),
];

/// `fresh_pair`'s parameters after `iso`, bound as Python binds them (positional or
/// keyword), and its other keyword arguments (the synthesis options).
struct PairCall<'py> {
    seed: Seed,
    variant: Variant,
    mode: String,
    task: String,
    table: Option<PyReadonlyArray1<'py, f32>>,
    patch: Option<usize>,
    tone: String,
    out: Option<Bound<'py, PyAny>>,
    options: Bound<'py, PyDict>,
}

impl<'py> PairCall<'py> {
    fn bind(args: &Bound<'py, PyTuple>, kwargs: Option<&Bound<'py, PyDict>>) -> PyResult<Self> {
        let (p, options) = args::bind_params("fresh_pair", PARAMS, args, kwargs, true)?;
        let opt = |v: &Bound<'py, PyAny>| Some(v.clone()).filter(|v| !v.is_none());
        Ok(PairCall {
            seed: p.extract("seed")?,
            variant: p.extract("variant")?,
            mode: args::string(p.get("mode")?, "mode")?,
            task: args::string(p.get("task")?, "task")?,
            table: opt(p.get("table")?).map(|t| t.extract()).transpose()?,
            patch: opt(p.get("patch")?).map(|t| t.extract()).transpose()?,
            tone: args::string(p.get("tone")?, "tone")?,
            out: opt(p.get("out")?),
            options,
        })
    }
}

/// The training pair of the ``crop`` of one night variant of ``raw``: what
/// ``synthesize(raw, seed=seed, variant=variant, mode=mode, isos=(iso,), crop=crop,
/// **options)`` makes of it, turned into the night ISP's input and target without
/// returning anything else.
///
/// - input: the release's network input (``day2night.train.preprocess``) of the crop's
///   noisy raw at ``iso`` (``task="noisy"``) or of its clean raw (``task="clean"``),
///   white-balanced by the variant's night neutral, through ``table`` (16384 float32
///   values, one per 14-bit code: ``preprocess``'s gamma table; default: ``code / 16383``
///   raised to 1/2.2 by Rust's ``powf``);
/// - target: the 8-bit ``tone`` encoding of the crop's linear target (``srgb8``).
///
/// With ``patch=None``: (input H x W x 3 float32, target H x W x 3 uint8). With
/// ``patch=p``: both cut into the (H/p) * (W/p) tiles of their row-major grid, k x 3 x p x
/// p float32 each, the target divided by 255 (``FreshPatches``' items). The crop's offsets
/// must be even; only the ISO the input needs gets noise.
///
/// >>> x, y = day2night.fresh_pair(raw, (0, 0, 512, 512), 1600, variant=3, patch=64)
/// >>> x.shape, y.shape
/// ((64, 3, 64, 64), (64, 3, 64, 64))
#[pyfunction]
#[pyo3(signature = (raw, crop, iso, *args, **kwargs))]
pub(crate) fn fresh_pair<'py>(
    py: Python<'py>,
    raw: &Bound<'py, Raw>,
    crop: &Bound<'py, PyAny>,
    iso: Iso,
    args: &Bound<'py, PyTuple>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let call = PairCall::bind(args, kwargs)?;
    let (seed, variant, mode, task, patch) = (
        call.seed,
        call.variant,
        call.mode.as_str(),
        call.task.as_str(),
        call.patch,
    );
    let (table, tone, options) = (call.table, call.tone.as_str(), Some(&call.options));
    let input = match task {
        "noisy" => PairInput::Noisy(iso.0),
        "clean" => PairInput::Clean,
        t => return Err(value_err(format!("task {t:?}: use \"noisy\" or \"clean\""))),
    };
    let tone: DisplayTone = tone.parse().map_err(py_err)?;
    let table = match &table {
        Some(t) => t.as_slice()?.to_vec(),
        None => release_table(Some(RELEASE_GAMMA)),
    };
    check_table(&table).map_err(py_err)?;
    if patch == Some(0) {
        return Err(value_err("patch must be at least 1"));
    }
    // `out=(x, y)`: the caller's float32 arrays of the patches (k x 3 x patch x patch each,
    // C-contiguous, writable), written in place instead of returned as new arrays
    let out = match &call.out {
        None => None,
        Some(o) => {
            if patch.is_none() {
                return Err(value_err("out= needs patch="));
            }
            let (x, y): (Bound<'py, PyAny>, Bound<'py, PyAny>) = o
                .extract()
                .map_err(|_| value_err("out must be a pair (x, y) of float32 arrays"))?;
            let rw = |a: &Bound<'py, PyAny>, name: &str| -> PyResult<PyReadwriteArray4<'py, f32>> {
                let a = a.cast::<numpy::PyArray4<f32>>().map_err(|_| {
                    value_err(format!("out's {name} must be a 4-D float32 numpy array"))
                })?;
                a.try_readwrite()
                    .map_err(|e| value_err(format!("out's {name} is not writable: {e}")))
            };
            Some((rw(&x, "x")?, rw(&y, "y")?, x, y))
        }
    };
    let cfg = job_config(mode, vec![iso.0], true, options)?;
    let r = raw.get();
    let a = r.day.raw.active_area();
    let crop = args::crop(crop, a.width(), a.height())?;
    if let Some(p) = patch {
        if crop.width % p != 0 || crop.height % p != 0 {
            return Err(value_err(format!(
                "crop {}x{} is not a whole number of {p}x{p} patches",
                crop.width, crop.height
            )));
        }
    }
    let mut out = out;
    let slices = match (out.as_mut(), patch) {
        (Some((xa, ya, _, _)), Some(p)) => {
            let want = [(crop.width / p) * (crop.height / p), 3, p, p];
            let xs = out_slice(xa, want, "x")?;
            Some((xs, out_slice(ya, want, "y")?))
        }
        _ => None,
    };
    let day = r.cfa_day()?;
    let file_name = r.file_name.clone();
    let (planned, pair, x, y) = py
        .detach(move || {
            on_pool(move || {
                let job = job_for(&cfg)?;
                let mut planned = job.plan(&day, &file_name, seed.0, variant.0)?;
                // the whole-frame mean of the dimming, worked out once per input
                planned.plan = day.with_frame_mean(planned.plan)?;
                let pair = crop_pair(&day.raw, &planned.plan, crop, input, tone)?;
                let (w, h) = (pair.width, pair.height);
                let look = |c: u16| table[(c as usize).min(table.len() - 1)];
                // v / 255 per byte value (numpy's float32 division, tabulated)
                let unit: Vec<f32> = (0..=255u8).map(|v| v as f32 / 255.0).collect();
                let (x, y) = match (patch, slices) {
                    (Some(p), Some((xs, ys))) => {
                        cut_patches_into(&pair.codes, w, h, p, look, xs)?;
                        cut_patches_into(&pair.target, w, h, p, |v| unit[v as usize], ys)?;
                        (Vec::new(), None)
                    }
                    (Some(p), None) => (
                        cut_patches(&pair.codes, w, h, p, look)?,
                        Some(cut_patches(&pair.target, w, h, p, |v| unit[v as usize])?),
                    ),
                    (None, _) => (pair.codes.iter().map(|&c| look(c)).collect(), None),
                };
                Ok((planned, pair, x, y))
            })
        })
        .map_err(py_err)?;
    // The plan's warnings (as `synthesize` raises them), then the run's.
    warn_plan(
        py,
        &r.file_name,
        &r.day.raw.meta,
        &planned.report,
        &pair.report.warnings,
    )?;
    if let Some((xa, ya, x, y)) = out {
        // the borrows end before the arrays go back to the caller
        drop((xa, ya));
        return Ok((x, y));
    }
    let shape_err = |e: numpy::ndarray::ShapeError| value_err(e.to_string());
    let (w, h) = (pair.width, pair.height);
    match (patch, y) {
        (Some(p), Some(y)) => {
            let k = (w / p) * (h / p);
            let x = Array4::from_shape_vec((k, 3, p, p), x).map_err(shape_err)?;
            let y = Array4::from_shape_vec((k, 3, p, p), y).map_err(shape_err)?;
            Ok((x.into_pyarray(py).into_any(), y.into_pyarray(py).into_any()))
        }
        _ => {
            let x = Array3::from_shape_vec((h, w, 3), x).map_err(shape_err)?;
            let y = Array3::from_shape_vec((h, w, 3), pair.target).map_err(shape_err)?;
            Ok((x.into_pyarray(py).into_any(), y.into_pyarray(py).into_any()))
        }
    }
}

/// The values of one of `out=`'s arrays, which must have the patches' shape `want` and be
/// C-contiguous.
fn out_slice<'a>(
    a: &'a mut PyReadwriteArray4<'_, f32>,
    want: [usize; 4],
    name: &str,
) -> PyResult<&'a mut [f32]> {
    if a.shape() != want {
        return Err(value_err(format!(
            "out's {name} has shape {:?}, the patches need {want:?}",
            a.shape()
        )));
    }
    a.as_slice_mut()
        .map_err(|_| value_err(format!("out's {name} must be C-contiguous")))
}
