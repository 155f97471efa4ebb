//! `png_bytes`: an 8-bit image as a PNG file's bytes, by the library's PNG writer
//! (`day2night::encode::png_rows`, the one `day2night render -o x.png` uses).

use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use day2night::encode::png_rows::png_rgb8_bytes;
use day2night::isp::tone::DisplayTone;
use numpy::{PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// The bytes of an 8-bit RGB PNG of ``array`` (uint8, H x W x 3, or H x W grey, stored as
/// R = G = B): the file ``day2night render -o x.png`` writes for these samples, with the
/// colour chunk of ``tone`` (``"srgb"``: sRGB, ``"gamma22"``: gAMA 1/2.2, ``"release"``:
/// none). ``day2night.png.write_png`` writes it atomically.
///
/// >>> day2night.png_bytes(np.zeros((4, 6, 3), np.uint8))[:4]
/// b'\x89PNG'
#[pyfunction]
#[pyo3(signature = (array, tone="srgb"))]
pub(crate) fn png_bytes<'py>(
    py: Python<'py>,
    array: &Bound<'py, PyAny>,
    tone: &str,
) -> PyResult<Bound<'py, PyBytes>> {
    let tone: DisplayTone = tone.parse().map_err(py_err)?;
    let (rgb, h, w) = rgb8(array)?;
    let bytes = py
        .detach(move || on_pool(move || png_rgb8_bytes(&rgb, w, h, tone)))
        .map_err(py_err)?;
    Ok(PyBytes::new(py, &bytes))
}

/// Interleaved RGB bytes and (height, width) of a uint8 H x W x 3 or H x W array.
fn rgb8(a: &Bound<'_, PyAny>) -> PyResult<(Vec<u8>, usize, usize)> {
    if let Ok(arr) = a.extract::<PyReadonlyArray3<'_, u8>>() {
        let v = arr.as_array();
        let (h, w, c) = v.dim();
        if c == 3 {
            let rgb = match v.as_slice() {
                Some(s) => s.to_vec(),
                None => v.iter().copied().collect(),
            };
            return Ok((rgb, h, w));
        }
    } else if let Ok(arr) = a.extract::<PyReadonlyArray2<'_, u8>>() {
        let v = arr.as_array();
        let (h, w) = v.dim();
        return Ok((v.iter().flat_map(|&g| [g, g, g]).collect(), h, w));
    }
    let attr = |k: &str| a.getattr(k).map(|v| v.to_string()).unwrap_or_default();
    Err(value_err(format!(
        "PNG: a uint8 (H, W) or (H, W, 3) array expected, got dtype {}, shape {}",
        attr("dtype"),
        attr("shape")
    )))
}
