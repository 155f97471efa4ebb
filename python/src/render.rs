//! `render` (the software ISP's linear render, as `day2night render --format exr`).

use crate::convert::rgb_array;
use crate::diagnostics::warn_lines;
use crate::errors::py_err;
use crate::pool::on_pool;
use crate::raw::Raw;
use day2night::isp::render::{render_linear, RenderOptions};
use day2night::isp::Demosaic;
use pyo3::prelude::*;

/// Linear sRGB (Rec.709, D65) render of a raw, float32 HxWx3 in [0, 1], the values of
/// ``day2night render IN.dng -o OUT.exr --float``: white balance by ``neutral`` (default:
/// the file's AsShotNeutral), demosaic (``"mhc"``, ``"bilinear"`` or ``"menon"``), colour
/// matrices, DefaultCrop (``crop``) and orientation (``orient``); the DNG opcode lists (lens
/// shading, distortion) are applied unless ``opcodes="ignore"``. A LinearRaw raw (already
/// demosaiced) is rendered without demosaicing (``demosaic`` is not used).
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
    let name = raw.get().file_name.clone();
    // The command line's warnings: skipped optional opcodes, opcodes that make their samples
    // constant, a TrimBounds that changes the size, a render that comes out constant.
    let (rgb, warnings) = py
        .detach(move || {
            on_pool(move || {
                use day2night::isp::opcodes::check::check_render;
                let checked = check_render(&day.raw, opts.opcodes, opts.crop, opts.orient)?;
                let rgb = render_linear(&day.raw, &opts)?;
                let mut w = checked.warnings;
                w.extend(day2night::isp::flat::warning(&rgb, "the render"));
                Ok((rgb, w))
            })
        })
        .map_err(py_err)?;
    warn_lines(py, &name, &warnings)?;
    rgb_array(py, rgb)
}

/// 8-bit display encoding of a linear RGB image (HxWx3, any float dtype): the bytes
/// ``day2night render -o x.png`` and ``day2night synth --target png`` write for these
/// samples (``tone``: ``"srgb"`` (default, the PNG targets'), ``"gamma22"`` or
/// ``"release"``; each sample clamped to [0, 1], encoded, ``* 255 + 0.5`` truncated).
/// Returns a uint8 HxWx3 array.
///
/// >>> day2night.encode_u8(day2night.render(raw)).dtype
/// dtype('uint8')
#[pyfunction]
#[pyo3(signature = (rgb, tone="srgb"))]
pub(crate) fn encode_u8<'py>(
    py: Python<'py>,
    rgb: &Bound<'py, PyAny>,
    tone: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let tone: day2night::isp::tone::DisplayTone = tone.parse().map_err(py_err)?;
    let img = crate::convert::float_rgb(rgb, "rgb")?;
    let (h, w) = (img.height, img.width);
    let bytes = py
        .detach(move || on_pool(move || Ok(day2night::encode::png::encode_u8(&img, tone))))
        .map_err(py_err)?;
    let arr = numpy::ndarray::Array3::from_shape_vec((h, w, 3), bytes)
        .map_err(|e| crate::errors::value_err(e.to_string()))?;
    Ok(numpy::IntoPyArray::into_pyarray(arr, py).into_any())
}
