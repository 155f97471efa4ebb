//! Lossy JPEG tiles and strips (Compression 34892, "lossy DNG"), decoded by `zune-jpeg`:
//! 8-bit DCT JPEG, one stream per tile or strip, one component (CFA) or three (LinearRaw,
//! YCbCr-coded as libjpeg writes it and converted back to RGB, as the Adobe DNG SDK reads
//! it). The decoded image must have exactly the tile's (or strip's) size and the IFD's
//! samples per pixel. See docs/dng-support.md.

use crate::error::{Error, Result};
use zune_jpeg::zune_core::bytestream::ZCursor;
use zune_jpeg::zune_core::colorspace::ColorSpace;
use zune_jpeg::zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

/// Decode one lossy JPEG tile or strip of `w x h` pixels with `spp` samples each into
/// interleaved `u16` samples (0..=255), row-major. `what` names the block in errors.
pub(super) fn decode(data: &[u8], w: usize, h: usize, spp: usize, what: &str) -> Result<Vec<u16>> {
    let bad = |m: String| Error::malformed(format!("lossy JPEG {what}: {m}"));
    let out_space = match spp {
        1 => ColorSpace::Luma,
        3 => ColorSpace::RGB,
        n => {
            return Err(Error::unsupported(format!(
                "lossy JPEG with {n} samples per pixel (1 or 3 supported)"
            )))
        }
    };
    // Strict: a truncated or corrupt stream is an error, not a grey-filled tile. Frames
    // larger than the block are refused from the header, before any pixel is allocated.
    let options = DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(w.max(1))
        .set_max_height(h.max(1))
        .jpeg_set_out_colorspace(out_space);
    let mut dec = JpegDecoder::new_with_options(ZCursor::new(data), options);
    dec.decode_headers()
        .map_err(|e| bad(format!("cannot decode ({e:?})")))?;
    let info = dec.info().ok_or_else(|| bad("no frame header".into()))?;
    let (iw, ih) = (usize::from(info.width), usize::from(info.height));
    if (iw, ih) != (w, h) {
        return Err(bad(format!(
            "decodes to {iw}x{ih} pixels where the tile or strip geometry \
             (TileWidth x TileLength, or ImageWidth x RowsPerStrip) needs {w}x{h}"
        )));
    }
    if usize::from(info.components) != spp {
        return Err(bad(format!(
            "{} component(s), the image has {spp} sample(s) per pixel",
            info.components
        )));
    }
    let samples = w * h * spp;
    if dec.output_buffer_size() != Some(samples) {
        return Err(bad(format!(
            "output of {:?} samples, expected {samples}",
            dec.output_buffer_size()
        )));
    }
    let mut bytes = crate::limits::try_filled(0u8, samples, "a lossy JPEG tile")?;
    dec.decode_into(&mut bytes)
        .map_err(|e| bad(format!("cannot decode ({e:?})")))?;
    let mut out = crate::limits::try_filled(0u16, samples, "a lossy JPEG tile")?;
    for (o, &b) in out.iter_mut().zip(&bytes) {
        *o = u16::from(b);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_garbage_streams_are_errors() {
        for data in [&[][..], &[0xFF, 0xD8, 0xFF, 0xD9][..], &[0xAB; 64][..]] {
            let e = decode(data, 8, 8, 3, "tile 0").unwrap_err().to_string();
            assert!(e.contains("lossy JPEG tile 0"), "{e}");
        }
        let e = decode(&[0xFF, 0xD8], 8, 8, 2, "tile 0")
            .unwrap_err()
            .to_string();
        assert!(e.contains("2 samples per pixel"), "{e}");
    }
}
