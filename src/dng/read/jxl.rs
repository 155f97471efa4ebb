//! JPEG XL tiles and strips (Compression 52546, DNG 1.7), decoded by `jxl-oxide`: one
//! codestream (or container) per tile or strip, grayscale for CFA data and RGB for
//! LinearRaw. The decoded image must have exactly the tile's (or strip's) size and the
//! IFD's samples per pixel; integer samples come back exactly (lossless data is the source's
//! bit for bit). See docs/dng-support.md.

use crate::error::{Error, Result};
use jxl_oxide::image::BitDepth;
use jxl_oxide::{AllocTracker, JxlImage, JxlThreadPool, PixelFormat};

/// Bytes the decoder may allocate per decoded sample (its own f32 planes, group buffers
/// and the rendered copy need about 12), plus a fixed allowance for small tiles.
const BYTES_PER_SAMPLE: usize = 32;
const BASE_ALLOWANCE: usize = 16 << 20;

/// Decode one JPEG XL tile or strip of `w x h` pixels with `spp` samples each into
/// interleaved `u16` samples, row-major. `what` names the block in errors ("tile 3").
pub(super) fn decode(data: &[u8], w: usize, h: usize, spp: usize, what: &str) -> Result<Vec<u16>> {
    let bad = |m: String| Error::malformed(format!("JPEG XL {what}: {m}"));
    let samples = w
        .checked_mul(h)
        .and_then(|n| n.checked_mul(spp))
        .ok_or_else(|| bad(format!("{w}x{h}x{spp} samples overflow")))?;
    let limit = samples
        .saturating_mul(BYTES_PER_SAMPLE)
        .saturating_add(BASE_ALLOWANCE);
    let image = JxlImage::builder()
        .pool(JxlThreadPool::none())
        .alloc_tracker(AllocTracker::with_limit(limit))
        .read(data)
        .map_err(|e| bad(format!("cannot decode ({e})")))?;
    let (iw, ih) = (image.width() as usize, image.height() as usize);
    if (iw, ih) != (w, h) {
        return Err(bad(format!(
            "decodes to {iw}x{ih} pixels where the tile or strip geometry \
             (TileWidth x TileLength, or ImageWidth x RowsPerStrip) needs {w}x{h}"
        )));
    }
    let meta = &image.image_header().metadata;
    if meta.orientation != 1 {
        return Err(bad(format!(
            "codestream orientation {} (a DNG tile is stored upright)",
            meta.orientation
        )));
    }
    let bits = match meta.bit_depth {
        BitDepth::IntegerSample { bits_per_sample } if (1..=16).contains(&bits_per_sample) => {
            bits_per_sample
        }
        BitDepth::IntegerSample { bits_per_sample } => {
            return Err(Error::unsupported(format!(
                "JPEG XL {what}: {bits_per_sample}-bit samples (1..16 supported)"
            )))
        }
        BitDepth::FloatSample { .. } => {
            return Err(Error::unsupported(format!(
                "JPEG XL {what}: floating-point samples are not supported"
            )))
        }
    };
    let channels = match image.pixel_format() {
        PixelFormat::Gray => 1,
        PixelFormat::Rgb => 3,
        other => {
            return Err(Error::unsupported(format!(
                "JPEG XL {what}: pixel format {other:?} (grayscale or RGB supported)"
            )))
        }
    };
    if channels != spp {
        return Err(bad(format!(
            "{channels} channel(s), the image has {spp} sample(s) per pixel"
        )));
    }
    if !image.is_loading_done() || image.num_loaded_keyframes() == 0 {
        return Err(bad("the codestream ends early (truncated?)".into()));
    }
    let render = image
        .render_frame(0)
        .map_err(|e| bad(format!("cannot decode ({e})")))?;
    let mut stream = render.stream_no_alpha();
    if (
        stream.width() as usize,
        stream.height() as usize,
        stream.channels() as usize,
    ) != (w, h, spp)
    {
        return Err(bad(format!(
            "renders {}x{}x{}, expected {w}x{h}x{spp}",
            stream.width(),
            stream.height(),
            stream.channels()
        )));
    }
    let mut f = crate::limits::try_filled(0f32, samples, "a JPEG XL tile")?;
    let written = stream.write_to_buffer(&mut f);
    if written != samples {
        return Err(bad(format!("rendered {written} of {samples} samples")));
    }
    // Integer samples are stored as v / (2^bits - 1); scale back and round (exact for
    // lossless data: f32 holds v / 65535 to well under half a code).
    let max = f64::from((1u32 << bits) - 1);
    let mut out = crate::limits::try_filled(0u16, samples, "a JPEG XL tile")?;
    for (o, &v) in out.iter_mut().zip(&f) {
        let x = (f64::from(v) * max).round();
        *o = if x.is_nan() {
            0
        } else {
            x.clamp(0.0, 65535.0) as u16
        };
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_garbage_codestreams_are_errors() {
        for data in [&[][..], &[0xFF, 0x0A][..], &[0xAB; 64][..]] {
            let e = decode(data, 8, 8, 1, "tile 0").unwrap_err().to_string();
            assert!(e.contains("JPEG XL tile 0"), "{e}");
        }
    }
}
