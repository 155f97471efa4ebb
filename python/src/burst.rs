//! Night bursts in Python (docs/python.md, "Bursts"): the `burst=`, `motion=`,
//! `shake_step=`, `shake_roll=` and `warp_interp=` options, a burst's frames as one
//! (N, H, W) array, and the frames' transforms as Python values.

use crate::convert::json_obj;
use crate::errors::value_err;
use day2night::raw::RawImage;
use day2night::synth::burst::checks::{BurstRequest, Names};
use day2night::synth::burst::motion::MAX_FRAMES;
use day2night::synth::burst::BurstOptions;
use day2night::synth::night::Night;
use day2night::synth::Plan;
use numpy::ndarray::{Array2, Array3};
use numpy::IntoPyArray;
use pyo3::prelude::*;

/// The option names of a burst.
pub(crate) const OPTIONS: [&str; 5] =
    ["burst", "motion", "shake_step", "shake_roll", "warp_interp"];

/// Record the burst option `key` (one of [`OPTIONS`]) from `v` in `r`: only its Python type
/// is checked here (an int that is not a bool, a float, a str; a `TypeError` naming the
/// argument); the values are checked together by [`resolve`], the command line's check.
pub(crate) fn set_option(r: &mut BurstRequest, key: &str, v: &Bound<'_, PyAny>) -> PyResult<()> {
    match key {
        "burst" => r.frames = Some(crate::args::integer(v, key, 1, u64::from(MAX_FRAMES))?),
        "motion" => r.motion = Some(crate::args::string(v, key)?),
        "shake_step" => r.shake_step = Some(crate::args::float(v, key)?),
        "shake_roll" => r.shake_roll = Some(crate::args::float(v, key)?),
        "warp_interp" => r.warp_interp = Some(crate::args::string(v, key)?),
        other => return Err(value_err(format!("unknown burst option {other:?}"))),
    }
    Ok(())
}

/// The burst `r` asks for, by the same rules and messages as the command line's flags
/// (a `ValueError` naming the argument and its range).
pub(crate) fn resolve(r: &BurstRequest) -> PyResult<BurstOptions> {
    r.resolve(&Names::PYTHON)
        .map_err(|e| value_err(crate::errors::text(&e)))
}

/// The frames of `iso` in `night` (frame 00 first) as raws.
pub(crate) fn frames_of<'a>(night: &'a Night, iso: u32, frame0: &'a RawImage) -> Vec<&'a RawImage> {
    std::iter::once(frame0)
        .chain(night.frames.iter().filter(|f| f.0 == iso).map(|f| &f.2))
        .collect()
}

/// Frames of one size as a uint16 (N, H, W) array.
pub(crate) fn stack<'py>(py: Python<'py>, frames: &[&RawImage]) -> PyResult<Bound<'py, PyAny>> {
    let (h, w) = (frames[0].height, frames[0].width);
    let mut data = Vec::with_capacity(frames.len() * h * w);
    for f in frames {
        if (f.height, f.width) != (h, w) {
            return Err(value_err("burst frames of different sizes"));
        }
        data.extend_from_slice(&f.data);
    }
    Ok(Array3::from_shape_vec((frames.len(), h, w), data)
        .map_err(|e| value_err(e.to_string()))?
        .into_pyarray(py)
        .into_any())
}

/// The plan's frame transforms as a list of dicts (None without a burst).
pub(crate) fn transforms<'py>(py: Python<'py>, plan: &Plan) -> PyResult<Bound<'py, PyAny>> {
    match &plan.burst {
        Some(b) => json_obj(py, &b.transforms),
        None => Ok(py.None().into_bound(py)),
    }
}

/// The frames' affines as a float64 (N, 2, 3) array and their valid rectangles as an int64
/// (N, 4) array (top, left, height, width), or None without a burst.
pub(crate) fn transform_arrays<'py>(
    py: Python<'py>,
    plan: &Plan,
) -> PyResult<Option<(Bound<'py, PyAny>, Bound<'py, PyAny>)>> {
    let Some(b) = &plan.burst else {
        return Ok(None);
    };
    let n = b.transforms.len();
    let aff: Vec<f64> = b
        .transforms
        .iter()
        .flat_map(|t| t.affine.iter().flatten().copied())
        .collect();
    let valid: Vec<i64> = b
        .transforms
        .iter()
        .flat_map(|t| {
            let v = t.valid;
            [v.top, v.left, v.height, v.width].map(|x| x as i64)
        })
        .collect();
    let a = Array3::from_shape_vec((n, 2, 3), aff).map_err(|e| value_err(e.to_string()))?;
    let v = Array2::from_shape_vec((n, 4), valid).map_err(|e| value_err(e.to_string()))?;
    Ok(Some((
        a.into_pyarray(py).into_any(),
        v.into_pyarray(py).into_any(),
    )))
}
