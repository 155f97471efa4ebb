//! `render` (the software ISP's linear render, as `day2night render --format exr`).

use crate::convert::rgb_array;
use crate::diagnostics::warn_lines;
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use crate::raw::Raw;
use day2night::isp::render::RenderOptions;
use day2night::isp::Demosaic;
use pyo3::prelude::*;

/// Linear sRGB (Rec.709, D65) render of a raw, float32 HxWx3 in [0, 1], the values of
/// ``day2night render IN.dng -o OUT.exr --float``: white balance by ``neutral`` (default:
/// the file's AsShotNeutral), demosaic (``"mhc"``, ``"bilinear"`` or ``"menon"``), colour
/// matrices, DefaultCrop (``crop``) and orientation (``orient``); the DNG opcode lists (lens
/// shading, distortion) are applied unless ``opcodes="ignore"``. A LinearRaw raw (already
/// demosaiced) is rendered without demosaicing (``demosaic`` is not used).
///
/// ``isp="release"`` renders as the authors' release does instead (``day2night render --isp
/// release``, docs/isp.md): its linear sRGB before its gamma, in its own image window
/// (``release_window``) and orientation (``orient=False``: before it); ``demosaic``,
/// ``opcodes`` may then only name what it does (``"menon"``, ``"ignore"``) and ``crop``
/// must stay true.
///
/// >>> rgb = day2night.render(raw)
#[pyfunction]
#[pyo3(signature = (raw, neutral=None, demosaic="mhc", crop=true, orient=true, opcodes="apply", isp="day2night"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn render<'py>(
    py: Python<'py>,
    raw: &Bound<'py, Raw>,
    neutral: Option<(f64, f64, f64)>,
    demosaic: &str,
    crop: bool,
    orient: bool,
    opcodes: &str,
    isp: &str,
) -> PyResult<Bound<'py, PyAny>> {
    if release_isp(isp)? {
        let given = [("demosaic", demosaic), ("opcodes", opcodes)];
        if let Some(c) = day2night::isp::release::conflicts(given) {
            let (name, value, own) = (c.option, c.value, c.own);
            return Err(value_err(format!(
                "{name}={value:?}: isp='release' uses {name}={own:?} (leave it out)"
            )));
        }
        if !crop {
            return Err(value_err(
                "crop=False: isp='release' crops as the release does",
            ));
        }
        let day = raw.get().day.clone();
        let neutral = neutral.map(|(r, g, b)| [r, g, b]);
        let r = py
            .detach(move || {
                on_pool(move || day2night::isp::release::render_f32(&day.raw, neutral, orient))
            })
            .map_err(py_err)?;
        warn_lines(py, &raw.get().file_name, &r.warnings)?;
        return rgb_array(py, r.image.into_rgb_image());
    }
    let method: Demosaic = demosaic.parse().map_err(py_err)?;
    let opcodes: day2night::isp::opcodes::OpcodeMode = opcodes.parse().map_err(py_err)?;
    let day = raw.get().day.clone();
    let opts = RenderOptions {
        demosaic: method,
        neutral: neutral.map(|(r, g, b)| [r, g, b]),
        crop,
        orient,
        opcodes,
        ..RenderOptions::default()
    };
    let name = raw.get().file_name.clone();
    // The command line's warnings: skipped optional opcodes, opcodes that make their samples
    // constant, a TrimBounds that changes the size, a render that comes out constant.
    let (rgb, warnings) = py
        .detach(move || {
            on_pool(move || {
                use day2night::isp::opcodes::check::check_render;
                let checked = check_render(&day.raw, opts.opcodes, opts.crop, opts.orient)?;
                let rgb = day2night::isp::render(&day.raw, &opts)?;
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

/// Whether `isp` names the release's ISP (`"release"`) rather than day2night's.
fn release_isp(isp: &str) -> PyResult<bool> {
    use day2night::choice::Choice;
    use day2night::isp::release::Isp;
    isp.parse::<Isp>().map(|i| i == Isp::Release).map_err(|_| {
        let names: Vec<String> = Isp::NAMES.iter().map(|n| format!("{:?}", n.name)).collect();
        value_err(format!("isp={isp:?}: use {}", names.join(" or ")))
    })
}

/// The first of `given` (keyword, value) that ``isp="release"`` refuses, as (keyword,
/// value, the release's own value), or None: ``day2night::isp::release::conflicts``, the
/// rule ``day2night render --isp release`` and ``render(isp="release")`` apply.
///
/// >>> day2night._native.release_conflicts([("tone", "gamma22")])
/// ('tone', 'gamma22', 'release')
#[pyfunction]
pub(crate) fn release_conflicts(given: Vec<(String, String)>) -> Option<(String, String, String)> {
    let given = given.iter().map(|(k, v)| (k.as_str(), v.as_str()));
    day2night::isp::release::conflicts(given).map(|c| (c.option.into(), c.value, c.own.into()))
}

/// The release's 8-bit target of a raw (``day2night render --isp release -o x.png``, byte
/// for byte): uint8 HxWx3 in the release's image window and orientation (``orient=False``:
/// before it). ``neutral`` replaces the raw's AsShotNeutral for white balance and the
/// colour matrix. ``day2night.train.targets.render_target(raw, isp="release")`` calls it.
///
/// >>> day2night.render_release_u8(raw).dtype
/// dtype('uint8')
#[pyfunction]
#[pyo3(signature = (raw, neutral=None, orient=true))]
pub(crate) fn render_release_u8<'py>(
    py: Python<'py>,
    raw: &Bound<'py, Raw>,
    neutral: Option<(f64, f64, f64)>,
    orient: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let day = raw.get().day.clone();
    let neutral = neutral.map(|(r, g, b)| [r, g, b]);
    let r = py
        .detach(move || {
            on_pool(move || day2night::isp::release::render_u8(&day.raw, neutral, orient))
        })
        .map_err(py_err)?;
    warn_lines(py, &raw.get().file_name, &r.warnings)?;
    let (w, h) = (r.image.width, r.image.height);
    let arr = numpy::ndarray::Array3::from_shape_vec((h, w, 3), r.image.data)
        .map_err(|e| value_err(e.to_string()))?;
    Ok(numpy::IntoPyArray::into_pyarray(arr, py).into_any())
}

/// The release's image window of a raw in active-area coordinates, before its orientation:
/// ``(top, left, height, width)``. The release crops the active area again by the
/// ActiveArea rectangle (when the raw is in IFD0), so its targets can be smaller than the
/// active area (docs/isp.md).
///
/// >>> top, left, h, w = day2night.release_window(raw)
#[pyfunction]
pub(crate) fn release_window(raw: &Bound<'_, Raw>) -> PyResult<(usize, usize, usize, usize)> {
    day2night::isp::release::window(&raw.get().day.raw).map_err(py_err)
}
