//! `render` (the software ISP's linear render, as `day2night render --format exr`).

use crate::convert::rgb_array;
use crate::errors::py_err;
use crate::pool::on_pool;
use crate::raw::Raw;
use day2night::isp::render::{render_linear, RenderOptions};
use day2night::isp::Demosaic;
use pyo3::prelude::*;

/// Linear sRGB (Rec.709, D65) render of a raw, float32 HxWx3 in [0, 1], as ``day2night
/// render --format exr`` computes it: white balance by ``neutral`` (default: the file's
/// AsShotNeutral), demosaic (``"mhc"``, ``"bilinear"`` or ``"menon"``), colour matrices,
/// DefaultCrop (``crop``) and orientation (``orient``); the DNG opcode lists (lens shading,
/// distortion) are applied unless ``opcodes="ignore"``.
///
/// >>> rgb = day2night.render(raw)
#[pyfunction]
#[pyo3(signature = (raw, neutral=None, demosaic="mhc", crop=true, orient=true, opcodes="apply"))]
pub(crate) fn render<'py>(
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
