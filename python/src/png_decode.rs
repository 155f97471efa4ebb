//! `png_decode`: a PNG file's bytes as a numpy array, by the `image` crate's decoder (the
//! one `day2night real-pairs` reads the release's PNGs with, src/realpairs/processed.rs).
//! The work is bounded before any pixel is inflated: the header's size against the
//! library's pixel limit (`D2N_MAX_PIXELS`) and 65535 a side, and the decoder's allocations
//! against what that image needs.

use crate::errors::{text, value_err};
use day2night::limits::check_pixels;
use image::codecs::png::PngDecoder;
use image::{DynamicImage, ImageDecoder, Limits};
use numpy::ndarray::Array3;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use std::io::Cursor;

/// Largest PNG side decoded (the library's image side limit).
const MAX_SIDE: u32 = 65535;

/// The samples of the PNG file ``data`` (its bytes): uint8 or uint16 (the file's bit
/// depth; 1, 2 and 4 bits are widened to 8), shape H x W x C with C the file's channels
/// (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA; a palette is expanded to RGB or RGBA).
/// A ValueError with one line says why a file is not read: not a PNG, truncated or
/// corrupt, or larger than the pixel limit (``D2N_MAX_PIXELS``) or 65535 a side, checked
/// on its header before anything is inflated.
///
/// >>> day2night.png_decode(day2night.png_bytes(np.zeros((4, 6, 3), np.uint8))).shape
/// (4, 6, 3)
#[pyfunction]
pub(crate) fn png_decode<'py>(py: Python<'py>, data: &[u8]) -> PyResult<Bound<'py, PyAny>> {
    let data = data.to_vec();
    let img = py.detach(move || decode(&data))?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let c = usize::from(img.color().channel_count());
    let shaped = |e: numpy::ndarray::ShapeError| value_err(format!("PNG: {e}"));
    Ok(match img {
        DynamicImage::ImageLuma16(i) => u16s(py, i.into_raw(), h, w, c)?,
        DynamicImage::ImageLumaA16(i) => u16s(py, i.into_raw(), h, w, c)?,
        DynamicImage::ImageRgb16(i) => u16s(py, i.into_raw(), h, w, c)?,
        DynamicImage::ImageRgba16(i) => u16s(py, i.into_raw(), h, w, c)?,
        img @ (DynamicImage::ImageLuma8(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageRgb8(_)
        | DynamicImage::ImageRgba8(_)) => Array3::from_shape_vec((h, w, c), img.into_bytes())
            .map_err(shaped)?
            .into_pyarray(py)
            .into_any(),
        other => {
            return Err(value_err(format!(
                "PNG: samples of type {:?} are not read",
                other.color()
            )))
        }
    })
}

fn u16s(py: Python<'_>, v: Vec<u16>, h: usize, w: usize, c: usize) -> PyResult<Bound<'_, PyAny>> {
    let a = Array3::from_shape_vec((h, w, c), v).map_err(|e| value_err(format!("PNG: {e}")))?;
    Ok(a.into_pyarray(py).into_any())
}

/// The decoded image, its size checked on the header first.
fn decode(data: &[u8]) -> PyResult<DynamicImage> {
    let bad = |e: image::ImageError| value_err(format!("PNG: not a readable PNG ({e})"));
    let dec = PngDecoder::new(Cursor::new(data)).map_err(bad)?;
    let (w, h) = dec.dimensions();
    if w > MAX_SIDE || h > MAX_SIDE {
        return Err(value_err(format!(
            "PNG: {w}x{h} is larger than {MAX_SIDE} a side"
        )));
    }
    check_pixels("image", u64::from(w), u64::from(h))
        .map_err(|e| value_err(format!("PNG: {}", text(&e))))?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    // the output (at most 4 channels of 16 bits) and the decoder's row buffers
    limits.max_alloc = Some(u64::from(w) * u64::from(h) * 8 + (16 << 20));
    let dec = PngDecoder::with_limits(Cursor::new(data), limits).map_err(bad)?;
    DynamicImage::from_decoder(dec).map_err(bad)
}
