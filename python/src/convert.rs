//! Conversions between the library's types and Python values: images to and from numpy
//! arrays, serializable values to Python objects (through JSON), a raw's metadata to the
//! dict of `Raw.meta`, and the reader's metadata corrections to `UserWarning`s.

use crate::errors::value_err;
use day2night::isp::RgbImage;
use day2night::raw::meta::RawMeta;
use day2night::RawImage;
use numpy::ndarray::{Array2, Array3};
use numpy::{
    IntoPyArray, PyArray2, PyArrayDescrMethods, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A serializable value as the Python object its JSON spells (dicts, lists, numbers).
pub(crate) fn json_obj<'py>(
    py: Python<'py>,
    v: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let s = serde_json::to_string(v).map_err(|e| value_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (s,))
}

/// A raw's samples as a uint16 height x width array.
pub(crate) fn u16_array(py: Python<'_>, img: RawImage) -> PyResult<Bound<'_, PyArray2<u16>>> {
    Ok(Array2::from_shape_vec((img.height, img.width), img.data)
        .map_err(|e| value_err(e.to_string()))?
        .into_pyarray(py))
}

/// An RGB image as a float32 height x width x 3 array.
pub(crate) fn rgb_array(py: Python<'_>, img: RgbImage) -> PyResult<Bound<'_, PyAny>> {
    Ok(Array3::from_shape_vec((img.height, img.width, 3), img.data)
        .map_err(|e| value_err(e.to_string()))?
        .into_pyarray(py)
        .into_any())
}

/// A float32 height x width x 3 array as an RGB image (`what` names it in errors).
pub(crate) fn rgb_from(a: &PyReadonlyArray3<'_, f32>, what: &str) -> PyResult<RgbImage> {
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

/// A height x width x 3 numpy array of any float dtype (float16, float32, float64, ...) as
/// an RGB image of f32 samples, the precision `day2night eval` reads EXRs in: float16 and
/// float32 are exact, wider floats are rounded to the nearest f32. `what` names the
/// argument in errors (`ValueError`).
pub(crate) fn float_rgb(a: &Bound<'_, PyAny>, what: &str) -> PyResult<RgbImage> {
    let arr = a.cast::<PyUntypedArray>().map_err(|_| {
        value_err(format!(
            "{what} must be a numpy float array of height x width x 3 (got {})",
            a.get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_else(|_| "?".into())
        ))
    })?;
    let dtype = arr.dtype();
    if dtype.kind() != b'f' {
        return Err(value_err(format!(
            "{what}: dtype {dtype} is not a float dtype (float16, float32 or float64)"
        )));
    }
    let shape = arr.shape();
    if shape.len() != 3 || shape[2] != 3 {
        let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        return Err(value_err(format!(
            "{what} must be height x width x 3 (got shape ({}{}))",
            dims.join(", "),
            if dims.len() == 1 { "," } else { "" }
        )));
    }
    let f32_arr = if dtype.is_equiv_to(&numpy::dtype::<f32>(a.py())) {
        a.clone()
    } else {
        a.call_method1("astype", ("float32",))?
    };
    let v: PyReadonlyArray3<'_, f32> = f32_arr
        .extract()
        .map_err(|_| value_err(format!("{what}: cannot be read as float32")))?;
    rgb_from(&v, what)
}

/// A 2-D uint16 array with the metadata `meta` as a raw (`what` names it in errors).
pub(crate) fn raw_image_from(
    arr: &Bound<'_, PyAny>,
    meta: &RawMeta,
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

/// The dict of `Raw.meta`.
pub(crate) fn meta_dict<'py>(py: Python<'py>, raw: &RawImage) -> PyResult<Bound<'py, PyDict>> {
    let m = &raw.meta;
    let d = PyDict::new(py);
    let a = raw.active_area();
    let (aw, ah) = (a.width(), a.height());
    d.set_item("cfa_pattern", raw.bayer().ok().map(|b| b.name()))?;
    d.set_item(
        "black_level_repeat_dim",
        (m.levels.black_repeat.0, m.levels.black_repeat.1),
    )?;
    match &m.linear_raw {
        None => {
            d.set_item("samples_per_pixel", 1)?;
            d.set_item("black_level", m.levels.black.clone())?;
            d.set_item("white_level", m.levels.white)?;
        }
        Some(lr) => {
            // As the DNG stores them: BlackLevel rows x cols x samples, WhiteLevel per sample.
            d.set_item("samples_per_pixel", lr.samples_per_pixel)?;
            d.set_item("black_level", lr.black.clone())?;
            d.set_item("white_level", lr.white.clone())?;
        }
    }
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
    crate::raw_from::extra_meta(&d, raw)?;
    Ok(d)
}

/// Raise each metadata correction of the reader (`day2night::dng::check`) as a Python
/// `UserWarning`: `<file>: <message>`, as the command line says `day2night: <file>: warning:`.
pub(crate) fn warn_meta(py: Python<'_>, path: &std::path::Path, meta: &RawMeta) -> PyResult<()> {
    warn_lines(py, &path.display().to_string(), &meta.warnings)
}

/// Raise each of `warnings` about the raw `name` as a `UserWarning` (`<name>: <message>`),
/// as the command line prints `day2night: <file>: warning: <message>`.
pub(crate) fn warn_lines(py: Python<'_>, name: &str, warnings: &[String]) -> PyResult<()> {
    for w in warnings {
        let msg = std::ffi::CString::new(format!("{name}: {w}"))
            .unwrap_or_else(|_| c"day2night warning".into());
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
/// another camera), another camera's illuminants, ISO extrapolation, opcodes; then
/// `extra` (the run's); each a `UserWarning` `<file>: <message>`, as `day2night synth`
/// prints `day2night: <file>: warning: <message>`.
pub(crate) fn warn_plan(
    py: Python<'_>,
    file: &str,
    meta: &RawMeta,
    report: &day2night::synth::PlanReport,
    extra: &[String],
) -> PyResult<()> {
    // The plan's list starts with the reader's corrections (dng::check).
    let own = if report.warnings.starts_with(&meta.warnings) {
        meta.warnings.len()
    } else {
        0
    };
    let mut new = report.warnings[own..].to_vec();
    new.extend(extra.iter().cloned());
    warn_lines(py, file, &new)
}
