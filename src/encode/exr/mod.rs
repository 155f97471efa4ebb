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
mod tests {
    use super::*;

    #[test]
    fn rows_and_blocks_give_the_whole_image_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (13usize, 70usize);
        let mut img = RgbImage::new(w, h);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = match i % 13 {
                0 => f32::NAN,
                1 => 1e9,
                _ => ((i * 7919) % 1000) as f32 / 997.0,
            };
        }
        let attrs = [("day2night:x".to_string(), "y".to_string())];
        let policy = OutputPolicy::default();
        for compression in [
            ExrCompression::None,
            ExrCompression::Zips,
            ExrCompression::Zip,
        ] {
            for half in [true, false] {
                let opts = ExrOptions {
                    half,
                    compression,
                    ..ExrOptions::default()
                };
                assert!(encodes_rows(&opts));
                let a = dir.path().join(format!("a{compression}{half}.exr"));
                write_exr(&img, &a, &opts, &attrs, &policy).unwrap();
                // bands of 32 rows (the render's), the last one short
                let mut blocks = Vec::new();
                for (k, rows) in img.data.chunks(3 * w * 32).enumerate() {
                    blocks.extend(encode_exr_rows(rows, w, 32 * k, &opts).unwrap());
                }
                let b = dir.path().join(format!("b{compression}{half}.exr"));
                write_exr_blocks(w, h, &blocks, &b, &opts, &attrs, &policy).unwrap();
                assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
                // a missing block and a misaligned band are errors, not bad files
                let c = dir.path().join(format!("c{compression}{half}.exr"));
                assert!(write_exr_blocks(w, h, &blocks[1..], &c, &opts, &attrs, &policy).is_err());
                assert!(!c.exists());
            }
        }
        let zip = ExrOptions::default();
        assert!(encode_exr_rows(&img.data[..3 * w * 16], w, 8, &zip).is_err());
        assert!(encode_exr_rows(&img.data[..3 * w * 16 + 1], w, 0, &zip).is_err());
        assert!(!encodes_rows(&ExrOptions {
            compression: ExrCompression::Piz,
            ..ExrOptions::default()
        }));
    }
    use std::io::Cursor;

    #[test]
    fn writes_and_reads_back_sanitized() {
        let mut img = RgbImage::new(5, 3);
        img.data[0] = f32::NAN;
        img.data[1] = f32::INFINITY;
        img.data[2] = -1e9;
        img.data[3] = 0.25;
        for c in ExrCompression::ALL {
            for half in [true, false] {
                let mut buf = Cursor::new(Vec::new());
                let opts = ExrOptions {
                    half,
                    compression: c,
                    ..ExrOptions::default()
                };
                encode_exr(&img, &mut buf, &opts, &[("a:b".into(), "x".into())]).unwrap();
                let bytes = buf.into_inner();
                let image = exr::prelude::read()
                    .no_deep_data()
                    .largest_resolution_level()
                    .rgba_channels(
                        |r, _| vec![[0f32; 3]; r.area()],
                        |v: &mut Vec<[f32; 3]>,
                         p: Vec2<usize>,
                         (r, g, b, _a): (f32, f32, f32, f32)| {
                            v[p.1 * 5 + p.0] = [r, g, b]
                        },
                    )
                    .first_valid_layer()
                    .all_attributes()
                    .from_buffered(Cursor::new(bytes))
                    .unwrap();
                let px = &image.layer_data.channel_data.pixels;
                let lim = if half { HALF_MAX } else { f32::MAX };
                assert_eq!(px[0][0], 0.0, "{c}");
                if c == ExrCompression::Pxr24 && !half {
                    // 24-bit floats: finite and near the limit
                    assert!(px[0][1].is_finite() && px[0][1] > 3.0e38, "{c}");
                    continue;
                }
                assert_eq!(px[0][1], lim, "{c}");
                assert_eq!(px[0][2], if half { -lim } else { -1e9 }, "{c}");
                if !matches!(c, ExrCompression::B44 | ExrCompression::B44a) || !half {
                    assert_eq!(px[1][0], 0.25, "{c}");
                }
                assert!(image.attributes.chromaticities.is_some());
            }
        }
    }

    #[test]
    fn header_is_deterministic_with_many_attributes() {
        let img = RgbImage::new(3, 2);
        let attrs: Vec<(String, String)> = (0..12)
            .map(|i| (format!("k{i}"), format!("v{i}")))
            .collect();
        let enc = || {
            let mut buf = Cursor::new(Vec::new());
            encode_exr(&img, &mut buf, &ExrOptions::default(), &attrs).unwrap();
            buf.into_inner()
        };
        let first = enc();
        // HashMap order is random per map: many encodings in one process must still agree
        for _ in 0..20 {
            assert_eq!(enc(), first);
        }
        let back = exr::meta::MetaData::read_from_buffered(Cursor::new(&first), true).unwrap();
        assert_eq!(back.headers[0].own_attributes.other.len(), 12);
    }

    #[test]
    fn parallel_compression_is_deterministic() {
        let mut img = RgbImage::new(97, 83);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = ((i * 7919) % 1000) as f32 / 997.0;
        }
        let enc = || {
            let mut buf = Cursor::new(Vec::new());
            encode_exr(&img, &mut buf, &ExrOptions::default(), &[]).unwrap();
            buf.into_inner()
        };
        let a = enc();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(enc);
        assert_eq!(a, b);
        assert_eq!(a, enc());
    }

    /// Decode EXR bytes with the `exr` crate: (width, height, RGB samples as f32).
    fn read_back(bytes: &[u8]) -> (usize, usize, Vec<[f32; 3]>) {
        let image = exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .rgba_channels(
                |r, _| (r.0, vec![[0f32; 3]; r.area()]),
                |v: &mut (usize, Vec<[f32; 3]>),
                 p: Vec2<usize>,
                 (r, g, b, _a): (f32, f32, f32, f32)| {
                    v.1[p.1 * v.0 + p.0] = [r, g, b]
                },
            )
            .first_valid_layer()
            .all_attributes()
            .from_buffered(Cursor::new(bytes.to_vec()))
            .unwrap();
        let size = image.layer_data.size;
        (size.0, size.1, image.layer_data.channel_data.pixels.1)
    }

    /// A deterministic image with distinct, varied values (some negative, some large).
    fn ramp(w: usize, h: usize) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        let mut s = 0x9e37_79b9_u32;
        for v in img.data.iter_mut() {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            *v = ((s >> 8) as f32 / (1u32 << 24) as f32 - 0.1) * 3.0;
        }
        img
    }

    /// (first line, data size) of every block, parsed from the offset table.
    fn chunks(bytes: &[u8]) -> Vec<(i32, usize)> {
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), true).unwrap();
        let h = &meta.headers[0];
        let n = h.chunk_count;
        // header end: the offset table is the n u64 before the first chunk
        let first = {
            let mut pos = 8;
            while bytes[pos] != 0 {
                let name_end = pos + bytes[pos..].iter().position(|&b| b == 0).unwrap();
                let ty_end =
                    name_end + 1 + bytes[name_end + 1..].iter().position(|&b| b == 0).unwrap();
                let size = i32::from_le_bytes(bytes[ty_end + 1..ty_end + 5].try_into().unwrap());
                pos = ty_end + 5 + size as usize;
            }
            pos + 1
        };
        (0..n)
            .map(|i| {
                let o =
                    u64::from_le_bytes(bytes[first + 8 * i..first + 8 * i + 8].try_into().unwrap())
                        as usize;
                let y = i32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
                let len = i32::from_le_bytes(bytes[o + 4..o + 8].try_into().unwrap());
                assert!(o + 8 + len as usize <= bytes.len());
                (y, len as usize)
            })
            .collect()
    }

    #[test]
    fn own_encoder_round_trips_odd_sizes() {
        for (w, h) in [(1, 1), (1, 7), (9, 1), (17, 33), (5, 16), (4, 17)] {
            let img = ramp(w, h);
            for c in [
                ExrCompression::None,
                ExrCompression::Zips,
                ExrCompression::Zip,
            ] {
                for half in [true, false] {
                    for zip_level in [1, 6, 9] {
                        let opts = ExrOptions {
                            half,
                            compression: c,
                            zip_level,
                        };
                        let mut buf = Cursor::new(Vec::new());
                        encode_exr(&img, &mut buf, &opts, &[("k".into(), "v".into())]).unwrap();
                        let bytes = buf.into_inner();
                        let (rw, rh, px) = read_back(&bytes);
                        assert_eq!((rw, rh), (w, h));
                        for (i, p) in px.iter().enumerate() {
                            for (k, &got) in p.iter().enumerate() {
                                let v = img.data[3 * i + k];
                                let want = if half { f16::from_f32(v).to_f32() } else { v };
                                assert_eq!(got, want, "{c} half={half} {w}x{h} at {i}/{k}");
                            }
                        }
                        let lpb = if c == ExrCompression::Zip { 16 } else { 1 };
                        let ch = chunks(&bytes);
                        assert_eq!(ch.len(), h.div_ceil(lpb));
                        for (b, (y, _)) in ch.iter().enumerate() {
                            assert_eq!(*y as usize, b * lpb);
                        }
                        let meta =
                            exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes), true)
                                .unwrap();
                        assert_eq!(meta.headers[0].compression, c.to_exr());
                    }
                }
            }
        }
    }

    #[test]
    fn incompressible_blocks_are_stored_raw() {
        // a 1x1 block (6 or 12 bytes) cannot shrink under zlib's 6-byte framing + deflate
        for half in [true, false] {
            let mut img = RgbImage::new(1, 1);
            img.data.copy_from_slice(&[0.5, -2.0, 7.25]);
            let opts = ExrOptions {
                half,
                ..ExrOptions::default()
            };
            let mut buf = Cursor::new(Vec::new());
            encode_exr(&img, &mut buf, &opts, &[]).unwrap();
            let bytes = buf.into_inner();
            assert_eq!(chunks(&bytes), vec![(0, if half { 6 } else { 12 })]);
            assert_eq!(read_back(&bytes).2, vec![[0.5, -2.0, 7.25]]);
        }
        // a compressible image is compressed
        let img = RgbImage::new(64, 16);
        let mut buf = Cursor::new(Vec::new());
        encode_exr(&img, &mut buf, &ExrOptions::default(), &[]).unwrap();
        assert!(chunks(buf.get_ref())[0].1 < 64 * 16 * 6 / 10);
    }

    #[test]
    fn zip_levels_trade_size_and_are_checked() {
        // a smooth image with texture: higher levels find more matches
        let mut img = RgbImage::new(64, 48);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = (i / 3 % 64 + i / 192) as f32 * 0.01 + ((i * 7) % 5) as f32 * 0.001;
        }
        let size = |zip_level| {
            let mut buf = Cursor::new(Vec::new());
            let opts = ExrOptions {
                zip_level,
                ..ExrOptions::default()
            };
            encode_exr(&img, &mut buf, &opts, &[]).map(|_| buf.into_inner().len())
        };
        let (s1, s9) = (size(1).unwrap(), size(9).unwrap());
        assert!(s9 < s1, "level 9: {s9} bytes, level 1: {s1}");
        assert!(size(0).is_err());
        assert!(size(10).is_err());
    }

    #[test]
    fn reserved_and_duplicate_attributes_are_rejected() {
        let img = RgbImage::new(2, 2);
        for c in [ExrCompression::Zip, ExrCompression::Piz] {
            let opts = ExrOptions {
                compression: c,
                ..ExrOptions::default()
            };
            for bad in [
                vec![("software".to_string(), "x".to_string())],
                vec![("a".into(), "1".into()), ("a".into(), "2".into())],
                vec![("".into(), "1".into())],
            ] {
                let r = encode_exr(&img, Cursor::new(Vec::new()), &opts, &bad);
                assert!(matches!(r, Err(Error::InvalidParam(_))), "{c} {bad:?}");
            }
        }
    }

    #[test]
    fn own_encoder_is_deterministic_across_thread_counts() {
        let img = ramp(97, 83);
        for c in [
            ExrCompression::None,
            ExrCompression::Zips,
            ExrCompression::Zip,
        ] {
            let opts = ExrOptions {
                compression: c,
                ..ExrOptions::default()
            };
            let enc = || {
                let mut buf = Cursor::new(Vec::new());
                encode_exr(
                    &img,
                    &mut buf,
                    &opts,
                    &[("z".into(), "1".into()), ("a".into(), "2".into())],
                )
                .unwrap();
                buf.into_inner()
            };
            let pool = |n| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap()
            };
            let one = pool(1).install(enc);
            let two = pool(2).install(enc);
            assert_eq!(one, two, "{c}");
            assert_eq!(one, enc(), "{c}");
        }
    }

    #[test]
    fn compression_names_parse() {
        for c in ExrCompression::ALL {
            assert_eq!(c.name().parse::<ExrCompression>().unwrap(), c);
        }
        assert!("dwaa".parse::<ExrCompression>().is_err());
    }
}
