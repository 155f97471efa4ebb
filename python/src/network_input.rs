//! The release's network input (`day2night.train.preprocess`): the 14-bit codes of a CFA
//! plane and OpenCV's bilinear demosaic, both `day2night::isp::release_input`'s. The code
//! table (``code / 16383`` raised to the gamma) stays with the caller, who indexes it.

use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use crate::raw_from::{cfa_from, flat_floats, input_meta};
use day2night::isp::release_input::{demosaic_bilinear as demosaic, release_codes as codes};
use day2night::isp::release_input::{CfaPlane, FrameFacts};
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::prelude::*;

/// The samples of a 2-D uint16 array (copied, so that the GIL can be released) and its
/// (height, width); a ValueError naming `what` otherwise.
fn plane_samples(a: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<u16>, usize, usize)> {
    let arr: PyReadonlyArray2<'_, u16> = a.extract().map_err(|_| {
        let attr = |k: &str| a.getattr(k).map(|v| v.to_string()).unwrap_or_default();
        value_err(format!(
            "{what} must be a 2-D uint16 array (got dtype {}, shape {})",
            attr("dtype"),
            attr("shape")
        ))
    })?;
    let v = arr.as_array();
    let (h, w) = v.dim();
    let samples = match v.as_slice() {
        Some(s) => s.to_vec(),
        None => v.iter().copied().collect(),
    };
    Ok((samples, h, w))
}

/// H x W x 3 uint16 of `codes` (R, G, B interleaved).
fn codes_array(py: Python<'_>, codes: Vec<u16>, h: usize, w: usize) -> PyResult<Bound<'_, PyAny>> {
    let a = Array3::from_shape_vec((h, w, 3), codes).map_err(|e| value_err(e.to_string()))?;
    Ok(a.into_pyarray(py).into_any())
}

/// The demosaiced 14-bit codes (H x W x 3 uint16) of the release's network input of a CFA
/// ``plane`` (2-D uint16: the active area, or a crop of it at (``top``, ``left``), whose
/// parity selects the CFA and BlackLevel phases): LinearizationTable, ``max(x - black, 0)
/// / (white - black)`` per 2x2 site, divided by ``neutral`` (default:
/// ``meta["as_shot_neutral"]``) and clipped to [0, 1], ``uint16(v * 16383)``, OpenCV's
/// bilinear Bayer demosaic. ``meta`` is a ``Raw.meta``-like dict (``cfa_pattern``,
/// ``black_level``, ``black_level_repeat_dim``, ``white_level``, optional
/// ``linearization_table`` and ``as_shot_neutral``). ``preprocess.network_input_array``
/// maps the codes through its table.
///
/// >>> codes = day2night.release_codes(plane, raw.meta)
#[pyfunction]
#[pyo3(signature = (plane, meta, neutral=None, top=0, left=0))]
pub(crate) fn release_codes<'py>(
    py: Python<'py>,
    plane: &Bound<'py, PyAny>,
    meta: &Bound<'py, PyAny>,
    neutral: Option<&Bound<'py, PyAny>>,
    top: usize,
    left: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let m = input_meta(meta)?;
    let neutral = match neutral.filter(|n| !n.is_none()) {
        Some(n) => flat_floats(n)
            .ok()
            .and_then(|v| <[f64; 3]>::try_from(v.as_slice()).ok())
            .ok_or_else(|| value_err(format!("neutral {n}: need 3 numbers")))?,
        None => m
            .as_shot_neutral
            .ok_or_else(|| value_err("no neutral given and the raw has no AsShotNeutral"))?,
    };
    let (data, h, w) = plane_samples(plane, "plane")?;
    let out = py
        .detach(move || {
            on_pool(move || {
                let plane = CfaPlane {
                    data: &data,
                    width: w,
                    height: h,
                    top,
                    left,
                };
                let frame = FrameFacts {
                    levels: &m.levels,
                    bayer: m.bayer,
                    neutral,
                    linearization: m.linearization.as_deref(),
                };
                codes(&plane, &frame)
            })
        })
        .map_err(py_err)?;
    codes_array(py, out, h, w)
}

/// OpenCV's bilinear Bayer demosaic (``cv2.cvtColor(m, COLOR_BAYER_*2RGB)``, bit for bit)
/// of a 2-D uint16 ``mosaic`` (at least 3 x 3) whose 2x2 pattern at the origin is ``cfa``
/// (``"RGGB"`` or four colour indices, 0 R, 1 G, 2 B): H x W x 3 uint16 (R, G, B).
///
/// >>> rgb = day2night.demosaic_bilinear(codes, "RGGB")
#[pyfunction]
pub(crate) fn demosaic_bilinear<'py>(
    py: Python<'py>,
    mosaic: &Bound<'py, PyAny>,
    cfa: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let bayer = cfa_from(cfa, "cfa")?;
    let (data, h, w) = plane_samples(mosaic, "mosaic")?;
    let out = py
        .detach(move || on_pool(move || demosaic(&data, w, h, bayer)))
        .map_err(py_err)?;
    codes_array(py, out, h, w)
}
