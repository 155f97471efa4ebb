//! Linear RGB OpenEXR targets: half (default) or 32-bit float samples, scan lines, ZIP
//! (16 lines) compression at zip level 1 (the fastest) by default, a `chromaticities` attribute for
//! Rec.709 primaries with a D65 white, a `software` attribute and caller string attributes
//! (source file, neutral, ...). Samples are sanitized first: NaN -> 0, +-Inf and
//! out-of-range values clamp to the largest finite value of the sample type, so no NaN/Inf is
//! ever written.
//!
//! None, ZIPS and ZIP go through our own encoder (`scanline`: rows converted straight into
//! each block, blocks compressed in parallel at [`ExrOptions::zip_level`]: our own
//! run-length + Huffman zlib encoder at 1, miniz_oxide at 2..=9);
//! the rarer RLE, PIZ, PXR24, B44 and B44A go through the `exr` crate. Either way blocks are
//! written in increasing line order and header attributes are sorted by name, so the bytes
//! are identical from run to run and whatever the thread count (tested).

pub mod chunks;
pub mod error;
mod file;
mod options;
mod scanline;
mod via_crate;

pub use file::{write_exr_blocks, ExrFile};
pub use options::{ExrCompression, ExrOptions};

use crate::error::{Error, Result};
use crate::isp::RgbImage;
use crate::output::{write_atomic, OutputPolicy};
use std::io::{Seek, Write};
use std::path::Path;
use via_crate::{encode_unsorted, sort_header_attributes};

/// Largest finite half value.
pub const HALF_MAX: f32 = 65504.0;

/// Encode `img` as an EXR into `out` (see the module docs for what is written). Errors:
/// an empty image, a zip level outside 1..=9, an attribute name that is empty, longer than
/// 255 bytes, contains NUL, repeats or is one the encoder writes itself (`software`,
/// `channels`, ...). On the `exr` crate path the header attributes are sorted by name after
/// encoding: the crate keeps custom attributes in a `HashMap`, whose per-process random
/// order would otherwise make the bytes differ from run to run.
pub fn encode_exr<W: Write + Seek>(
    img: &RgbImage,
    mut out: W,
    opts: &ExrOptions,
    attributes: &[(String, String)],
) -> Result<()> {
    opts.validate()?;
    img.validate()?;
    if img.width == 0 || img.height == 0 {
        return Err(Error::invalid("cannot write an empty EXR image"));
    }
    scanline::check_attributes(attributes)?;
    if scanline::lines_per_block(opts.compression).is_some() {
        return scanline::encode(img, &mut out, opts, attributes);
    }
    let mut buf = std::io::Cursor::new(Vec::new());
    encode_unsorted(img, &mut buf, opts, attributes)?;
    let mut bytes = buf.into_inner();
    sort_header_attributes(&mut bytes)?;
    out.write_all(&bytes)?;
    Ok(())
}

/// Write `img` (linear Rec.709/sRGB, D65) as an EXR at `path` through
/// [`crate::output::write_atomic`]. `attributes` are extra string attributes, e.g.
/// `("day2night:source", "IMG_1.dng")`.
pub fn write_exr(
    img: &RgbImage,
    path: &Path,
    opts: &ExrOptions,
    attributes: &[(String, String)],
    policy: &OutputPolicy,
) -> Result<()> {
    write_atomic(path, policy, |w| encode_exr(img, w, opts, attributes))
}

/// True when `opts` can be written band by band ([`encode_exr_rows`] +
/// [`write_exr_blocks`]): the compressions of the own scan-line encoder (none, zips, zip).
pub fn encodes_rows(opts: &ExrOptions) -> bool {
    scanline::lines_per_block(opts.compression).is_some()
}

/// The stored blocks of the interleaved linear RGB `rows` (`width` pixels each) that start
/// at image line `first_row` (a multiple of 16 for zip; any multiple of 32 works for every
/// compression [`encodes_rows`] accepts). With [`write_exr_blocks`] this writes the same
/// bytes as [`write_exr`] of the whole image, without holding it.
pub fn encode_exr_rows(
    rows: &[f32],
    width: usize,
    first_row: usize,
    opts: &ExrOptions,
) -> Result<Vec<Vec<u8>>> {
    opts.validate()?;
    scanline::encode_rows(rows, width, first_row, opts)
}

/// The standard attributes of a day2night render: source file name, neutral, tool version.
pub fn standard_attributes(source: &Path, neutral: [f64; 3]) -> Vec<(String, String)> {
    vec![
        (
            "day2night:source".into(),
            source
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        ),
        (
            "day2night:neutral".into(),
            format!("{} {} {}", neutral[0], neutral[1], neutral[2]),
        ),
        ("day2night:version".into(), crate::VERSION.to_string()),
    ]
}

#[cfg(test)]
mod tests;
