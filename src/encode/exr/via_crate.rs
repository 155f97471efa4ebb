//! The `exr` crate's path for the compressions our own scan-line encoder does not write
//! (RLE, PIZ, PXR24, B44, B44A), with its header attributes sorted by name afterwards.

use super::{ExrOptions, HALF_MAX};
use crate::error::{Error, Result};
use crate::isp::RgbImage;
use exr::prelude::*;
use std::io::{Seek, Write};

fn map_err(e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(io) => Error::Io(io),
        exr::error::Error::NotSupported(m) => Error::unsupported(format!("EXR: {m}")),
        exr::error::Error::Invalid(m) => Error::malformed(format!("EXR: {m}")),
        exr::error::Error::Aborted => Error::invalid("EXR writing aborted"),
    }
}

fn text(s: &str) -> Text {
    Text::new_or_none(s).unwrap_or_else(|| {
        let ascii: String = s
            .chars()
            .map(|c| if c.is_ascii() { c } else { '?' })
            .collect();
        Text::new_or_none(ascii).unwrap_or_default()
    })
}

/// Reorder the attributes of a single-part EXR header by name, in place. The header keeps
/// its length, so the offset table after it stays valid.
pub(super) fn sort_header_attributes(bytes: &mut [u8]) -> Result<()> {
    let bad = || Error::malformed("EXR header produced by the encoder could not be parsed");
    // magic (4) + version (4); multi-part/deep files are not produced here
    let mut pos = 8usize;
    let mut attrs: Vec<(Vec<u8>, std::ops::Range<usize>)> = Vec::new();
    let cstr = |from: usize| -> Option<usize> {
        bytes
            .get(from..)?
            .iter()
            .position(|&b| b == 0)
            .map(|i| from + i)
    };
    loop {
        match bytes.get(pos) {
            None => return Err(bad()),
            Some(0) => break,
            Some(_) => {}
        }
        let start = pos;
        let name_end = cstr(pos).ok_or_else(bad)?;
        let type_end = cstr(name_end + 1).ok_or_else(bad)?;
        let size_bytes = bytes.get(type_end + 1..type_end + 5).ok_or_else(bad)?;
        let size = i32::from_le_bytes([size_bytes[0], size_bytes[1], size_bytes[2], size_bytes[3]]);
        let size = usize::try_from(size).map_err(|_| bad())?;
        let end = type_end + 5 + size;
        if end > bytes.len() {
            return Err(bad());
        }
        attrs.push((bytes[start..name_end].to_vec(), start..end));
        pos = end;
    }
    attrs.sort_by(|a, b| a.0.cmp(&b.0));
    let mut sorted = Vec::with_capacity(pos - 8);
    for (_, r) in &attrs {
        sorted.extend_from_slice(&bytes[r.clone()]);
    }
    bytes[8..pos].copy_from_slice(&sorted);
    Ok(())
}

pub(super) fn encode_unsorted<W: Write + Seek>(
    img: &RgbImage,
    out: W,
    opts: &ExrOptions,
    attributes: &[(String, String)],
) -> Result<()> {
    img.validate()?;
    if img.width == 0 || img.height == 0 {
        return Err(Error::invalid("cannot write an empty EXR image"));
    }
    let limit = if opts.half { HALF_MAX } else { f32::MAX };
    let sane = |v: f32| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-limit, limit)
        }
    };
    let w = img.width;
    let d = &img.data;
    let at = move |x: usize, y: usize, c: usize| sane(d[3 * (y * w + x) + c]);

    let mut layer_attrs = LayerAttributes {
        software_name: Some(text(&crate::software_name())),
        ..LayerAttributes::default()
    };
    for (k, v) in attributes {
        if k.is_empty() {
            return Err(Error::invalid("EXR attribute with an empty name"));
        }
        layer_attrs
            .other
            .insert(text(k), exr::meta::attribute::AttributeValue::Text(text(v)));
    }
    let encoding = Encoding {
        compression: opts.compression.to_exr(),
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let chroma = exr::meta::attribute::Chromaticities {
        red: Vec2(0.64, 0.33),
        green: Vec2(0.30, 0.60),
        blue: Vec2(0.15, 0.06),
        white: Vec2(0.3127, 0.3290),
    };
    let size = (img.width, img.height);
    // the crate compresses on a pool of its own (one thread per core): keep to one thread
    // when the caller's rayon pool has one (`--jobs 1`)
    let parallel = rayon::current_num_threads() > 1;
    if opts.half {
        let ch = SpecificChannels::rgb(|p: Vec2<usize>| {
            (
                f16::from_f32(at(p.0, p.1, 0)),
                f16::from_f32(at(p.0, p.1, 1)),
                f16::from_f32(at(p.0, p.1, 2)),
            )
        });
        let mut image = Image::from_layer(Layer::new(size, layer_attrs, encoding, ch));
        image.attributes.chromaticities = Some(chroma);
        if parallel {
            image.write().to_buffered(out).map_err(map_err)
        } else {
            image
                .write()
                .non_parallel()
                .to_buffered(out)
                .map_err(map_err)
        }
    } else {
        let ch = SpecificChannels::rgb(|p: Vec2<usize>| {
            (at(p.0, p.1, 0), at(p.0, p.1, 1), at(p.0, p.1, 2))
        });
        let mut image = Image::from_layer(Layer::new(size, layer_attrs, encoding, ch));
        image.attributes.chromaticities = Some(chroma);
        if parallel {
            image.write().to_buffered(out).map_err(map_err)
        } else {
            image
                .write()
                .non_parallel()
                .to_buffered(out)
                .map_err(map_err)
        }
    }
}
