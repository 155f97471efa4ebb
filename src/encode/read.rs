//! Reading images for `day2night eval`: PNG (8/16-bit), TIFF (8/16-bit, float) and OpenEXR
//! (any compression the `exr` crate decodes: ZIP, PIZ, B44, PXR24, ...; scan lines or tiles,
//! the largest mip level, the data window) into an [`RgbImage`] of `f32`.
//!
//! Integer images are scaled to [0, 1] and flagged display-referred (sRGB-encoded); float
//! images (EXR, float TIFF) are flagged linear. Grey images are replicated to RGB and alpha
//! is dropped. Non-finite EXR samples are kept as they are and counted, so that callers can
//! decide (eval replaces them and says so). Damaged files are refused with an error, never a
//! panic; absurd sizes are refused before allocating.

use crate::encode::exr::chunks::damaged_chunk;
use crate::encode::exr::error::{exr_err, guarded};
use crate::error::{Error, Result, ResultExt};
use crate::isp::RgbImage;
use std::io::Read;
use std::path::Path;

/// Largest image accepted, in pixels (a 1 GiB f32 RGB buffer is 89 MP).
pub const MAX_PIXELS: usize = 1 << 27;

/// An image read from disk.
#[derive(Debug, Clone)]
pub struct LoadedImage {
    /// The pixels.
    pub image: RgbImage,
    /// True for linear-light data (EXR, float TIFF), false for display-encoded integers.
    pub linear: bool,
    /// "png", "tiff" or "exr".
    pub format: &'static str,
    /// Number of NaN/Inf samples.
    pub non_finite: usize,
}

/// Read `path` (format from its magic bytes).
pub fn read_image(path: &Path) -> Result<LoadedImage> {
    let mut magic = [0u8; 8];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut magic))
        .map_err(Error::from)
        .in_file(path)?;
    let m = &magic[..n];
    let r = if m.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        read_exr(path)
    } else if m.starts_with(b"\x89PNG") || m.starts_with(b"II*\0") || m.starts_with(b"MM\0*") {
        read_raster(path)
    } else {
        Err(Error::unsupported(
            "not a PNG, TIFF or OpenEXR file (by its first bytes)",
        ))
    };
    r.in_file(path)
}

fn read_raster(path: &Path) -> Result<LoadedImage> {
    let reader = image::ImageReader::open(path)?
        .with_guessed_format()
        .map_err(Error::from)?;
    let format = match reader.format() {
        Some(image::ImageFormat::Png) => "png",
        Some(image::ImageFormat::Tiff) => "tiff",
        _ => {
            return Err(Error::unsupported(
                "the image format is neither PNG nor TIFF",
            ))
        }
    };
    let img = reader.decode().map_err(|e| match e {
        image::ImageError::IoError(io) => Error::Io(io),
        image::ImageError::Unsupported(u) => Error::unsupported(u.to_string()),
        image::ImageError::Limits(l) => Error::limits(l.to_string()),
        other => Error::malformed(other.to_string()),
    })?;
    let linear = matches!(
        img,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w.saturating_mul(h) > MAX_PIXELS {
        return Err(Error::limits(format!("{w}x{h} image is too large")));
    }
    let data = img.to_rgb32f().into_raw();
    let image = RgbImage {
        width: w,
        height: h,
        data,
    };
    let non_finite = image.count_non_finite();
    Ok(LoadedImage {
        image,
        linear,
        format,
        non_finite,
    })
}

/// Index of the R, G, B channels among `names` (the same index thrice for a grey image):
/// R/G/B (or `*.R` ...), else Y, else the only channel, else the first that is not alpha.
pub fn pick_rgb(names: &[String]) -> Result<[usize; 3]> {
    let find = |name: &str| {
        names
            .iter()
            .position(|n| n == name || n.ends_with(&format!(".{name}")))
    };
    match (find("R"), find("G"), find("B")) {
        (Some(r), Some(g), Some(b)) => Ok([r, g, b]),
        _ => match find("Y") {
            Some(y) => Ok([y; 3]),
            None if names.len() == 1 => Ok([0; 3]),
            None if !names.is_empty() => match names.iter().position(|n| n != "A") {
                Some(c) => Ok([c; 3]),
                None => Err(Error::unsupported("EXR: the file has no colour channel")),
            },
            None => Err(Error::unsupported("EXR: the file has no channel")),
        },
    }
}

/// Headers of an EXR file, checked before any pixel is decoded: size within `max_pixels`,
/// no deep data, a sane chunk offset table (no shared or overlapping chunks).
fn exr_meta(path: &Path, max_pixels: u64) -> Result<exr::meta::MetaData> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(exr_err)?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| Error::malformed("EXR: the file has no header"))?;
    let size = header.layer_size;
    crate::limits::Limits::with_max_pixels(max_pixels)?.check_pixels(
        "EXR data window",
        size.0 as u64,
        size.1 as u64,
    )?;
    if meta.headers.iter().any(|h| h.deep) {
        return Err(Error::unsupported(
            "EXR: the file holds deep data, which eval cannot read",
        ));
    }
    crate::encode::exr::chunks::check_chunk_table(path, &meta)?;
    Ok(meta)
}

fn read_exr(path: &Path) -> Result<LoadedImage> {
    use crate::error::Error;
    use exr::prelude::*;
    // Headers first: refuse absurd sizes and bombs before the decoder allocates.
    let max = (MAX_PIXELS as u64).min(crate::limits::Limits::current()?.max_pixels);
    exr_meta(path, max)?;
    // The decoder of a third-party crate on untrusted data: a panic is an error. When the
    // read fails, the first chunk that does not decode is named.
    let decoded = guarded(
        || {
            read()
                .no_deep_data()
                .largest_resolution_level()
                .all_channels()
                .first_valid_layer()
                .all_attributes()
                // sequential: a panic in a worker thread could not be contained here
                .non_parallel()
                .from_file(path)
                .map_err(exr_err)
        },
        || Error::malformed("EXR: the decoder failed on damaged data"),
    )
    .map_err(|e| damaged_chunk(path).unwrap_or(e))?;
    let layer = decoded.layer_data;
    let (w, h) = (layer.size.0, layer.size.1);
    let channels = &layer.channel_data.list;
    let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
    let picked: Vec<&AnyChannel<FlatSamples>> =
        pick_rgb(&names)?.iter().map(|&i| &channels[i]).collect();
    for c in &picked {
        if c.sampling != Vec2(1, 1) {
            return Err(Error::unsupported(format!(
                "EXR: channel {} is subsampled, which eval cannot read",
                c.name
            )));
        }
    }
    let planes: Vec<Vec<f32>> = picked
        .iter()
        .map(|c| c.sample_data.values_as_f32().collect())
        .collect();
    if planes.iter().any(|p| p.len() != w * h) {
        return Err(Error::malformed(
            "EXR: channel sample count does not match the data window",
        ));
    }
    let mut data = crate::limits::try_with_capacity(3 * w * h, "the EXR image")?;
    for ((r, g), b) in planes[0].iter().zip(&planes[1]).zip(&planes[2]) {
        data.extend([*r, *g, *b]);
    }
    let image = RgbImage {
        width: w,
        height: h,
        data,
    };
    let non_finite = image.count_non_finite();
    Ok(LoadedImage {
        image,
        linear: true,
        format: "exr",
        non_finite,
    })
}

/// An image to evaluate band by band: a whole image in memory (PNG, TIFF, tiled or
/// multi-part EXR), or a scan-line EXR read a band of rows at a time.
pub enum BandSource {
    /// Read whole.
    Whole(LoadedImage),
    /// Read in bands.
    Exr(crate::encode::exr::chunks::ExrBands),
}

impl BandSource {
    /// Width.
    pub fn width(&self) -> usize {
        match self {
            BandSource::Whole(l) => l.image.width,
            BandSource::Exr(b) => b.width,
        }
    }
    /// Height.
    pub fn height(&self) -> usize {
        match self {
            BandSource::Whole(l) => l.image.height,
            BandSource::Exr(b) => b.height,
        }
    }
    /// Linear light (EXR, float TIFF) or display-encoded.
    pub fn linear(&self) -> bool {
        match self {
            BandSource::Whole(l) => l.linear,
            BandSource::Exr(_) => true,
        }
    }
    /// "png", "tiff" or "exr".
    pub fn format(&self) -> &'static str {
        match self {
            BandSource::Whole(l) => l.format,
            BandSource::Exr(_) => "exr",
        }
    }
    /// Rows `y0..y1` as an image (`y1 - y0` rows, interleaved RGB f32).
    pub fn rows(&self, y0: usize, y1: usize) -> Result<RgbImage> {
        let w = self.width();
        let data = match self {
            BandSource::Whole(l) => {
                let src =
                    l.image.data.get(3 * w * y0..3 * w * y1).ok_or_else(|| {
                        Error::invalid(format!("rows {y0}..{y1} out of the image"))
                    })?;
                let mut v = crate::limits::try_with_capacity(src.len(), "an image band")?;
                v.extend_from_slice(src);
                v
            }
            BandSource::Exr(b) => b.rows(y0, y1).in_file(b.path())?,
        };
        Ok(RgbImage {
            width: w,
            height: y1 - y0,
            data,
        })
    }
}

/// Open `path` for band-wise reading: single-part scan-line EXRs are read in bands (up to
/// the process pixel limit, see [`crate::limits`]); other files are read whole
/// ([`read_image`], at most [`MAX_PIXELS`]).
pub fn open_bands(path: &Path) -> Result<BandSource> {
    let mut magic = [0u8; 4];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut magic))
        .map_err(Error::from)
        .in_file(path)?;
    if magic[..n] != [0x76, 0x2f, 0x31, 0x01] {
        return read_image(path).map(BandSource::Whole);
    }
    let opened = (|| {
        let max = crate::limits::Limits::current()?.max_pixels;
        let meta = exr_meta(path, max)?;
        crate::encode::exr::chunks::ExrBands::open(path, &meta, pick_rgb)
    })()
    .in_file(path)?;
    match opened {
        Some(b) => Ok(BandSource::Exr(b)),
        None => read_image(path).map(BandSource::Whole),
    }
}

impl From<image::ImageError> for Error {
    fn from(e: image::ImageError) -> Error {
        match e {
            image::ImageError::IoError(io) => Error::Io(io),
            other => Error::malformed(other.to_string()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::exr::{write_exr, ExrOptions};
    use crate::encode::png::{write_png, PngOptions};
    use crate::output::OutputPolicy;

    #[test]
    fn reads_back_what_we_write() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = RgbImage::new(6, 4);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = (i % 7) as f32 / 8.0;
        }
        let e = dir.path().join("a.exr");
        write_exr(
            &img,
            &e,
            &ExrOptions {
                half: false,
                ..Default::default()
            },
            &[],
            &OutputPolicy::default(),
        )
        .unwrap();
        let back = read_image(&e).unwrap();
        assert!(back.linear && back.format == "exr");
        assert_eq!(back.image, img);
        let p = dir.path().join("a.png");
        write_png(
            &img,
            &p,
            &PngOptions {
                sixteen_bit: true,
                ..Default::default()
            },
            &OutputPolicy::default(),
        )
        .unwrap();
        let back = read_image(&p).unwrap();
        assert!(!back.linear);
        assert_eq!((back.image.width, back.image.height), (6, 4));
        let bad = dir.path().join("x.exr");
        std::fs::write(&bad, b"v/1\x01garbage").unwrap();
        assert!(read_image(&bad).is_err());
        let txt = dir.path().join("x.txt");
        std::fs::write(&txt, b"hello").unwrap();
        assert!(read_image(&txt)
            .unwrap_err()
            .to_string()
            .contains("not a PNG"));
    }
}
