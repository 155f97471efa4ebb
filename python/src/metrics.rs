//! The image metrics of `day2night eval`: `psnr`, `ssim`, `delta_e2000`, and the per-pixel
//! `delta_e2000_map` behind the mean.

use crate::convert::float_rgb;
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use day2night::metrics::{
    delta_e_2000_map, mean_delta_e_2000, psnr as m_psnr, ssim as m_ssim, SsimOptions, SsimWindow,
};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;

/// PSNR in dB of ``pred`` against ``target`` (HxWx3 arrays of any float dtype, read as
/// float32 like an EXR), as ``day2night eval`` computes it for two images of the same
/// encoding; infinite for identical images.
#[pyfunction]
#[pyo3(signature = (pred, target, data_range=1.0))]
pub(crate) fn psnr(
    py: Python<'_>,
    pred: &Bound<'_, PyAny>,
    target: &Bound<'_, PyAny>,
    data_range: f64,
) -> PyResult<f64> {
    let (a, b) = (float_rgb(pred, "pred")?, float_rgb(target, "target")?);
    py.detach(move || on_pool(move || m_psnr(&a, &b, data_range)))
        .map_err(py_err)
}

/// SSIM of ``pred`` against ``target`` (HxWx3, any float dtype), as ``day2night eval``: window
/// ``"uniform"`` (scikit-image's 7x7 default) or ``"gaussian"`` (Wang et al. 2004).
#[pyfunction]
#[pyo3(signature = (pred, target, data_range=1.0, window="uniform"))]
pub(crate) fn ssim(
    py: Python<'_>,
    pred: &Bound<'_, PyAny>,
    target: &Bound<'_, PyAny>,
    data_range: f64,
    window: &str,
) -> PyResult<f64> {
    // The names of `day2night eval --ssim-window` (SsimWindow's own), exactly as spelled.
    let window = SsimWindow::ALL
        .into_iter()
        .find(|w| w.name() == window)
        .ok_or_else(|| value_err(format!("window {window:?}: use uniform or gaussian")))?;
    let (a, b) = (float_rgb(pred, "pred")?, float_rgb(target, "target")?);
    let opts = SsimOptions { data_range, window };
    py.detach(move || on_pool(move || m_ssim(&a, &b, &opts)))
        .map_err(py_err)
}

/// Mean CIEDE2000 of ``pred`` against ``target`` (HxWx3, any float dtype), as ``day2night eval``:
/// each image is linear sRGB (``*_linear=True``, e.g. an EXR) or display sRGB (False).
#[pyfunction]
#[pyo3(signature = (pred, target, pred_linear=true, target_linear=true))]
pub(crate) fn delta_e2000(
    py: Python<'_>,
    pred: &Bound<'_, PyAny>,
    target: &Bound<'_, PyAny>,
    pred_linear: bool,
    target_linear: bool,
) -> PyResult<f64> {
    let (a, b) = (float_rgb(pred, "pred")?, float_rgb(target, "target")?);
    py.detach(move || on_pool(move || mean_delta_e_2000(&a, &b, pred_linear, target_linear)))
        .map_err(py_err)
}

/// Per-pixel CIEDE2000 of ``pred`` against ``target`` (HxWx3, any float dtype, read as
/// ``delta_e2000`` reads them) as a float64 HxW array: the values whose mean
/// ``delta_e2000`` returns (the same conversions, the same ``*_linear`` switches).
#[pyfunction]
#[pyo3(signature = (pred, target, pred_linear=true, target_linear=true))]
pub(crate) fn delta_e2000_map<'py>(
    py: Python<'py>,
    pred: &Bound<'py, PyAny>,
    target: &Bound<'py, PyAny>,
    pred_linear: bool,
    target_linear: bool,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (a, b) = (float_rgb(pred, "pred")?, float_rgb(target, "target")?);
    let (h, w) = (a.height, a.width);
    let map = py
        .detach(move || on_pool(move || delta_e_2000_map(&a, &b, pred_linear, target_linear)))
        .map_err(py_err)?;
    Ok(Array2::from_shape_vec((h, w), map)
        .map_err(|e| value_err(e.to_string()))?
        .into_pyarray(py))
}
