//! Night bursts in Python (docs/python.md, "Bursts"): a burst's frames as one (N, H, W)
//! array, and the frames' transforms as Python values. The `burst=`, `motion=`,
//! `shake_step=`, `shake_roll=` and `warp_interp=` options are the option table's
//! (python/src/synth_options.rs).

use crate::convert::json_obj;
use crate::errors::value_err;
use day2night::raw::RawImage;
use day2night::synth::night::Night;
use day2night::synth::Plan;
use numpy::ndarray::{Array2, Array3};
use numpy::IntoPyArray;
use pyo3::prelude::*;

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
