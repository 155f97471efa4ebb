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
mod scanline;

use crate::error::{Error, Result, ResultExt};
use crate::isp::RgbImage;
use crate::output::{write_atomic, AtomicFile, OutputPolicy};
use exr::prelude::*;
use std::io::{Seek, Write};
use std::path::Path;
use std::str::FromStr;

/// EXR compression choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ExrCompression {
    /// No compression.
    None,
    /// Run-length encoding.
    Rle,
    /// zlib, one scan line per block.
    Zips,
    /// zlib, 16 scan lines per block (default).
    #[default]
    Zip,
    /// Wavelet + Huffman (good on noisy images).
    Piz,
    /// Lossy for f32 (24-bit floats), lossless for half.
    Pxr24,
    /// Lossy 4x4 blocks for half (f32 stored uncompressed).
    B44,
    /// B44 with flat-area optimisation.
    B44a,
}

impl ExrCompression {
    /// All choices.
    pub const ALL: [ExrCompression; 8] = [
        ExrCompression::None,
        ExrCompression::Rle,
        ExrCompression::Zips,
        ExrCompression::Zip,
        ExrCompression::Piz,
        ExrCompression::Pxr24,
        ExrCompression::B44,
        ExrCompression::B44a,
    ];
    /// Command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            ExrCompression::None => "none",
            ExrCompression::Rle => "rle",
            ExrCompression::Zips => "zips",
            ExrCompression::Zip => "zip",
            ExrCompression::Piz => "piz",
            ExrCompression::Pxr24 => "pxr24",
            ExrCompression::B44 => "b44",
            ExrCompression::B44a => "b44a",
        }
    }
    fn to_exr(self) -> Compression {
        match self {
            ExrCompression::None => Compression::Uncompressed,
            ExrCompression::Rle => Compression::RLE,
            ExrCompression::Zips => Compression::ZIP1,
            ExrCompression::Zip => Compression::ZIP16,
            ExrCompression::Piz => Compression::PIZ,
            ExrCompression::Pxr24 => Compression::PXR24,
            ExrCompression::B44 => Compression::B44,
            ExrCompression::B44a => Compression::B44A,
        }
    }
}

impl std::fmt::Display for ExrCompression {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ExrCompression {
    type Err = Error;
    fn from_str(s: &str) -> Result<ExrCompression> {
        let l = s.to_ascii_lowercase();
        ExrCompression::ALL
            .into_iter()
            .find(|c| c.name() == l)
            .or(match l.as_str() {
                "zip16" => Some(ExrCompression::Zip),
                "zip1" => Some(ExrCompression::Zips),
                "uncompressed" => Some(ExrCompression::None),
                _ => None,
            })
            .ok_or_else(|| {
                Error::invalid(format!(
                    "unknown EXR compression {s:?} (none, rle, zips, zip, piz, pxr24, b44, b44a)"
                ))
            })
    }
}

/// Options of [`write_exr`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExrOptions {
    /// 16-bit half samples (default); false = 32-bit float.
    pub half: bool,
    /// Compression (default ZIP).
    pub compression: ExrCompression,
    /// zlib effort of ZIP/ZIPS blocks, 1 (fastest, default) ..= 9 (smallest); ignored by the
    /// other compressions. 1 is day2night's own run-length + Huffman encoder
    /// ([`crate::deflate`]), 2..=9 are miniz_oxide's levels (the `exr` crate, used before,
    /// hard-codes 4). See docs/benchmarks.md, "EXR writer", for time and size per level.
    pub zip_level: u8,
}

impl Default for ExrOptions {
    fn default() -> Self {
        ExrOptions {
            half: true,
            compression: ExrCompression::Zip,
            zip_level: ExrOptions::DEFAULT_ZIP_LEVEL,
        }
    }
}

impl ExrOptions {
    /// Default [`ExrOptions::zip_level`].
    pub const DEFAULT_ZIP_LEVEL: u8 = 1;

    /// Reject a zip level outside 1..=9 ([`crate::bounds::EXR_ZIP_LEVEL_RANGE`]).
    pub fn validate(&self) -> Result<()> {
        let (lo, hi) = crate::bounds::EXR_ZIP_LEVEL_RANGE;
        if !(lo..=hi).contains(&self.zip_level) {
            return Err(Error::invalid(format!(
                "EXR zip level {} is outside {lo}..={hi}",
                self.zip_level
            )));
        }
        Ok(())
    }
}

/// Largest finite half value.
pub const HALF_MAX: f32 = 65504.0;

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

/// Reorder the attributes of a single-part EXR header by name, in place. The header keeps
/// its length, so the offset table after it stays valid.
fn sort_header_attributes(bytes: &mut [u8]) -> Result<()> {
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

fn encode_unsorted<W: Write + Seek>(
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

/// Write a `width` x `height` EXR from its stored `blocks` (all of them, in line order, from
/// [`encode_exr_rows`] with the same `opts`) atomically at `path` (through [`ExrFile`]).
pub fn write_exr_blocks(
    width: usize,
    height: usize,
    blocks: &[Vec<u8>],
    path: &Path,
    opts: &ExrOptions,
    attributes: &[(String, String)],
    policy: &OutputPolicy,
) -> Result<()> {
    opts.validate()?;
    if width == 0 || height == 0 {
        return Err(Error::invalid("cannot write an empty EXR image"));
    }
    scanline::check_attributes(attributes)?;
    if let Some(lpb) = scanline::lines_per_block(opts.compression) {
        let nblocks = height.div_ceil(lpb);
        if blocks.len() != nblocks {
            return Err(Error::invalid(format!(
                "EXR of {height} lines needs {nblocks} blocks, got {}",
                blocks.len()
            )));
        }
    }
    let mut file = ExrFile::create(path, width, height, opts, attributes, policy)?;
    for blk in blocks {
        file.push_block(blk)?;
    }
    file.finish()
}

/// An EXR target written while it is rendered: the blocks of each band of rows
/// ([`encode_exr_rows`]) are appended as they come, in line order, so the encoded image is
/// never held whole. [`ExrFile::create`] writes the header and a zeroed offset table into
/// an [`AtomicFile`], [`ExrFile::push_rows`] appends blocks, [`ExrFile::finish`] fills in
/// the offset table and syncs and renames the file into place. The bytes are those of
/// [`write_exr`] of the whole image (tested); dropped unfinished, nothing appears at `path`.
#[derive(Debug)]
pub struct ExrFile<'p> {
    file: AtomicFile<'p>,
    stream: scanline::BlockStream,
}

impl<'p> ExrFile<'p> {
    /// Start a `width` x `height` EXR at `path` (options and attributes as for
    /// [`write_exr_blocks`]; `opts` must be one [`encodes_rows`] accepts).
    pub fn create(
        path: &Path,
        width: usize,
        height: usize,
        opts: &ExrOptions,
        attributes: &[(String, String)],
        policy: &'p OutputPolicy,
    ) -> Result<ExrFile<'p>> {
        opts.validate()?;
        if width == 0 || height == 0 {
            return Err(Error::invalid("cannot write an empty EXR image"));
        }
        scanline::check_attributes(attributes)?;
        let mut file = AtomicFile::create(path, policy)?;
        let stream = scanline::BlockStream::begin(file.writer()?, width, height, opts, attributes)
            .in_file(path)?;
        Ok(ExrFile { file, stream })
    }

    /// Append the `blocks` of the rows from image line `first_row`, which must be the first
    /// line not written yet.
    pub fn push_rows(&mut self, first_row: usize, blocks: &[Vec<u8>]) -> Result<()> {
        let next = self.stream.next_line();
        if first_row != next {
            return Err(Error::invalid(format!(
                "EXR rows from line {first_row} given while line {next} is the next to write"
            ))
            .in_file(self.file.path()));
        }
        for blk in blocks {
            self.push_block(blk)?;
        }
        Ok(())
    }

    fn push_block(&mut self, block: &[u8]) -> Result<()> {
        let r = self.file.writer().and_then(|w| self.stream.push(w, block));
        r.in_file(self.file.path())
    }

    /// Write the offset table (every block must have been pushed), then sync and rename
    /// the file into place (see [`AtomicFile::finish`]).
    pub fn finish(mut self) -> Result<()> {
        let r = self.file.writer().and_then(|w| self.stream.finish(w));
        r.in_file(self.file.path())?;
        self.file.finish()
    }
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
