//! The release's processed tree: its `clean_raw/NNN.png` (a 16-bit grey PNG of the merged
//! visible raw, `generate_real_gt.py`) made back into a raw image with the metadata of
//! `dng/iso_50/NNN.dng`.
//!
//! The PNG holds rawpy's `raw_image_visible`: the DNG's whole stored image when it has the
//! same size, else its ActiveArea (the samples outside it are then the iso_50 frame's). Any
//! other size is an error naming both sizes. Values are the release's truncated mean in the
//! frame's own DN scale, so the frame's levels apply unchanged.
//!
//! The release's target `clean/NNN.png` is checked before it is copied
//! ([`read_target_png`]): an 8-bit RGB PNG (what `cv2.imwrite` writes) whose size is the
//! scene's rendered size, as the layout defines it: the release ISP's window (the active
//! area cropped once more by NumPy's slicing with the ActiveArea rectangle,
//! [`crate::isp::release::window`]), the active area, the DefaultCrop (day2night's
//! `render`), or the clean_raw PNG's size, each with
//! width and height swapped when the iso_50 frame's Orientation turns the image by 90
//! degrees (5 to 8), as both ISPs do.

use crate::error::{Error, Result};
use crate::raw::RawImage;
use std::path::Path;

/// Largest PNG side accepted (a 16-bit grey image; larger is refused before decoding).
const MAX_SIDE: u32 = 1 << 16;

/// Decode a 16-bit grey PNG into `(width, height, samples)`.
pub fn read_png16(path: &Path) -> Result<(usize, usize, Vec<u16>)> {
    let file = std::fs::File::open(path).map_err(Error::Io)?;
    let mut reader = image::ImageReader::new(std::io::BufReader::new(file));
    reader.set_format(image::ImageFormat::Png);
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| Error::malformed(format!("not a readable PNG: {e}")))?;
    if w > MAX_SIDE || h > MAX_SIDE {
        return Err(Error::limits(format!("PNG of {w}x{h} is too large")));
    }
    crate::limits::check_pixels("clean_raw PNG", w as u64, h as u64)?;
    let file = std::fs::File::open(path).map_err(Error::Io)?;
    let mut reader = image::ImageReader::new(std::io::BufReader::new(file));
    reader.set_format(image::ImageFormat::Png);
    let img = reader
        .decode()
        .map_err(|e| Error::malformed(format!("not a readable PNG: {e}")))?;
    match img {
        image::DynamicImage::ImageLuma16(g) => {
            let (w, h) = g.dimensions();
            Ok((w as usize, h as usize, g.into_raw()))
        }
        other => Err(Error::invalid(format!(
            "clean_raw must be a 16-bit grey PNG (the release's merged raw), this one is {:?}",
            other.color()
        ))),
    }
}

/// The clean raw: the PNG's samples in a copy of `frame` (the iso_50 DNG) laid out as the
/// module documentation says.
pub fn clean_raw(png: (usize, usize, Vec<u16>), frame: &RawImage) -> Result<RawImage> {
    let (w, h, samples) = png;
    let mut img = RawImage {
        width: frame.width,
        height: frame.height,
        data: frame.data.clone(),
        meta: frame.meta.clone(),
    };
    let a = frame.active_area();
    if (w, h) == (frame.width, frame.height) {
        img.data = samples;
    } else if (w, h) == (a.width(), a.height()) {
        for (r, row) in samples.chunks(w).enumerate() {
            let start = (r + a.top as usize) * img.width + a.left as usize;
            img.data[start..start + w].copy_from_slice(row);
        }
    } else {
        return Err(Error::invalid(format!(
            "clean_raw PNG is {w}x{h} but the iso_50 DNG is {}x{} (ActiveArea {}x{})",
            frame.width,
            frame.height,
            a.width(),
            a.height()
        )));
    }
    img.meta.storage = None;
    img.validate()?;
    Ok(img)
}

/// The sizes a target of the scene may have (see the module documentation), `(w, h)`.
pub fn target_sizes(frame: &RawImage, png: (usize, usize)) -> Vec<(usize, usize)> {
    let a = frame.active_area();
    let mut v = vec![(a.width(), a.height()), png];
    if let Ok((_, _, h, w)) = crate::isp::release::window(frame) {
        v.push((w, h));
    }
    if let Some([w, h]) = frame.meta.default_crop_size {
        if w.is_finite() && h.is_finite() && w >= 1.0 && h >= 1.0 {
            v.push((w.round() as usize, h.round() as usize));
        }
    }
    if (5..=8).contains(&frame.meta.orientation) {
        v.iter_mut().for_each(|s| *s = (s.1, s.0));
    }
    let mut seen = Vec::new();
    v.retain(|s| {
        let new = !seen.contains(s);
        seen.push(*s);
        new
    });
    v
}

/// Read and check the release's target `clean/NNN.png` (see the module documentation):
/// its bytes, to be copied as they are.
pub fn read_target_png(path: &Path, frame: &RawImage, png: (usize, usize)) -> Result<Vec<u8>> {
    let bytes = std::fs::read(path).map_err(Error::Io)?;
    let reader = || {
        let mut r = image::ImageReader::new(std::io::Cursor::new(&bytes));
        r.set_format(image::ImageFormat::Png);
        r
    };
    let (w, h) = reader()
        .into_dimensions()
        .map_err(|e| Error::malformed(format!("the target is not a readable PNG: {e}")))?;
    let sizes = target_sizes(frame, png);
    if !sizes.contains(&(w as usize, h as usize)) {
        let list: Vec<String> = sizes.iter().map(|(a, b)| format!("{a}x{b}")).collect();
        return Err(Error::invalid(format!(
            "the target PNG is {w}x{h}, not the scene's size ({})",
            list.join(" or ")
        )));
    }
    let img = reader()
        .decode()
        .map_err(|e| Error::malformed(format!("the target is not a readable PNG: {e}")))?;
    if !matches!(img, image::DynamicImage::ImageRgb8(_)) {
        return Err(Error::invalid(format!(
            "the target must be an 8-bit RGB PNG (the release's render), this one is {:?}",
            img.color()
        )));
    }
    Ok(bytes)
}
