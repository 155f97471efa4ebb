//! Reading OpenEXR files safely and in bands: the chunk offset table is checked before any
//! decoding (chunks that share an offset or overlap are refused, as OpenEXR does: a small
//! file could otherwise make the decoder fill a huge image from one repeated chunk), and
//! single-part scan-line files can be read a band of rows at a time, so memory grows with
//! the band, not the image.

use super::error::{chunk_err, compression_name, exr_err, guarded, ChunkPlace};
use crate::error::{Error, Result};
use exr::meta::attribute::SampleType;
use exr::meta::{BlockDescription, MetaData};
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

fn io_eof(e: std::io::Error) -> Error {
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        Error::malformed("EXR: the file ends early (truncated?)")
    } else {
        Error::Io(e)
    }
}

fn read_u32(r: &mut impl Read) -> Result<u32> {
    let mut b = [0u8; 4];
    r.read_exact(&mut b).map_err(io_eof)?;
    Ok(u32::from_le_bytes(b))
}

/// A NUL-terminated attribute name or type (at most 255 bytes).
fn read_cstr(r: &mut impl Read) -> Result<usize> {
    let mut n = 0usize;
    loop {
        let mut b = [0u8; 1];
        r.read_exact(&mut b).map_err(io_eof)?;
        if b[0] == 0 {
            return Ok(n);
        }
        n += 1;
        if n > 255 {
            return Err(Error::malformed(
                "EXR: an attribute name of the header is longer than 255 bytes",
            ));
        }
    }
}

/// Byte position just after the header(s), where the offset tables start.
fn header_end(r: &mut (impl Read + Seek), multipart: bool) -> Result<u64> {
    r.seek(SeekFrom::Start(8))?;
    loop {
        let mut attributes = 0usize;
        loop {
            if read_cstr(r)? == 0 {
                break;
            }
            read_cstr(r)?;
            let size = read_u32(r)? as i32;
            if size < 0 {
                return Err(Error::malformed(
                    "EXR: an attribute of the header has a negative size",
                ));
            }
            r.seek(SeekFrom::Current(i64::from(size)))?;
            attributes += 1;
        }
        // Single part: one header. Multi-part: headers until an empty one.
        if !multipart || attributes == 0 {
            break;
        }
    }
    Ok(r.stream_position()?)
}

/// Check the chunk offset tables of an EXR file against its headers: every offset inside the
/// file after the tables, no two chunks at the same offset, no chunk overlapping the next.
/// Reads only the tables and each chunk's few-byte prefix.
pub fn check_chunk_table(path: &Path, meta: &MetaData) -> Result<()> {
    let mut f = BufReader::new(File::open(path)?);
    let file_len = f.get_ref().metadata()?.len();
    f.seek(SeekFrom::Start(4))?;
    let version = read_u32(&mut f)?;
    let multipart = version & 0x1000 != 0;
    if version & 0x800 != 0 {
        return Err(Error::unsupported(
            "EXR: the file holds deep data, which eval cannot read",
        ));
    }
    let start = header_end(&mut f, multipart)?;
    let total: usize = meta.headers.iter().map(|h| h.chunk_count).sum();
    let table_end = (total as u64)
        .checked_mul(8)
        .and_then(|t| t.checked_add(start))
        .filter(|&e| e <= file_len)
        .ok_or_else(|| {
            Error::malformed(format!(
                "EXR: offset table of {total} chunks runs past the end of the {file_len}-byte file"
            ))
        })?;
    let mut offsets = crate::limits::try_with_capacity::<(u64, usize)>(total, "EXR offsets")?;
    for i in 0..total {
        let mut b = [0u8; 8];
        f.read_exact(&mut b).map_err(io_eof)?;
        let off = u64::from_le_bytes(b);
        if off < table_end || off >= file_len {
            return Err(Error::malformed(format!(
                "EXR: chunk {i} starts at byte {off}, outside the chunk data (bytes \
                 {table_end}..{file_len} of the file; truncated?)"
            )));
        }
        offsets.push((off, i));
    }
    offsets.sort_unstable();
    for pair in offsets.windows(2) {
        if pair[0].0 == pair[1].0 {
            let (a, b) = (pair[0].1.min(pair[1].1), pair[0].1.max(pair[1].1));
            return Err(Error::malformed(format!(
                "EXR: chunks {a} and {b} share the offset {} (each chunk must have its own \
                 data; a decompression bomb?)",
                pair[0].0
            )));
        }
    }
    // Each chunk: [part number if multi-part] then [y] (scan lines) or [tx, ty, lx, ly]
    // (tiles) then the data size; it must end before the next chunk starts.
    let tiled = meta
        .headers
        .first()
        .is_some_and(|h| matches!(h.blocks, BlockDescription::Tiles(_)));
    let prefix = u64::from(multipart) * 4 + if tiled { 16 } else { 4 };
    if multipart
        && meta
            .headers
            .iter()
            .any(|h| matches!(h.blocks, BlockDescription::Tiles(_)) != tiled)
    {
        // Mixed parts: chunk prefixes differ per part; the offsets are still distinct.
        return Ok(());
    }
    for (k, &(off, i)) in offsets.iter().enumerate() {
        f.seek(SeekFrom::Start(off + prefix))?;
        let size = read_u32(&mut f)? as i32;
        let end = off + prefix + 4 + u64::try_from(size).unwrap_or(u64::MAX / 2);
        let next = offsets.get(k + 1).map_or(file_len, |n| n.0);
        if size < 0 {
            return Err(Error::malformed(format!(
                "EXR: chunk {i} at offset {off} says its data has a negative size ({size} bytes)"
            )));
        }
        if end > next {
            return Err(Error::malformed(format!(
                "EXR: chunk {i} ({size} bytes at offset {off}) overlaps the next chunk or \
                 runs past the end of the file"
            )));
        }
    }
    Ok(())
}

/// The first chunk of `path` that does not decode, as an error naming it (number, rows or
/// tile, compression) in plain words; `None` when every chunk decodes. Run after a whole-file
/// read failed, to say where.
pub fn damaged_chunk(path: &Path) -> Option<Error> {
    use exr::block::chunk::CompressedBlock;
    use exr::block::UncompressedBlock;
    let file = BufReader::new(File::open(path).ok()?);
    let reader = exr::block::read(file, false).ok()?;
    let chunks = reader.all_chunks(false).ok()?;
    let meta = exr::block::reader::ChunksReader::meta_data(&chunks).clone();
    for (n, chunk) in chunks.enumerate() {
        let Ok(chunk) = chunk else {
            return None;
        };
        let header = meta.headers.get(chunk.layer_index)?;
        let lines = header.compression.scan_lines_per_block().max(1);
        let (index, pixels) = match &chunk.compressed_block {
            CompressedBlock::ScanLine(b) => {
                let y =
                    i64::from(b.y_coordinate) - i64::from(header.own_attributes.layer_position.y());
                if (0..header.layer_size.1 as i64).contains(&y) {
                    let first = y as usize / lines * lines;
                    let last = (first + lines).min(header.layer_size.1);
                    (Some(first / lines), format!("rows {first}..{last}"))
                } else {
                    (
                        None,
                        format!("first row {}, outside the data window", b.y_coordinate),
                    )
                }
            }
            CompressedBlock::Tile(t) => {
                let c = &t.coordinates;
                (
                    Some(n),
                    format!(
                        "tile ({}, {}) of level ({}, {})",
                        c.tile_index.0, c.tile_index.1, c.level_index.0, c.level_index.1
                    ),
                )
            }
            _ => (Some(n), "deep data".into()),
        };
        let place = ChunkPlace {
            index,
            count: header.chunk_count,
            pixels,
            compression: compression_name(header.compression),
        };
        let failed = || {
            Error::malformed(format!(
                "EXR: {} is damaged: the decoder failed on it",
                place.describe()
            ))
        };
        let r = guarded(
            || {
                UncompressedBlock::decompress_chunk(chunk, &meta, false)
                    .map(|_| ())
                    .map_err(|e| chunk_err(e, &place))
            },
            failed,
        );
        if let Err(e) = r {
            return Some(e);
        }
    }
    None
}

/// A single-part scan-line EXR read a band of rows at a time (RGB f32, as
/// [`crate::encode::read::read_image`] would give them).
pub struct ExrBands {
    path: std::path::PathBuf,
    /// Width of the data window.
    pub width: usize,
    /// Height of the data window.
    pub height: usize,
    /// Index of the R, G, B channels in the channel list (the same index thrice for grey).
    picked: [usize; 3],
    /// (bytes per sample, type) of each channel, in file order.
    channels: Vec<(usize, SampleType)>,
}

impl ExrBands {
    /// Prepare banded reading of `path`, or None when the file is not a single-part
    /// scan-line image with full-resolution channels (read it whole instead).
    /// `pick` chooses the R, G, B channel indices from the channel names.
    pub fn open(
        path: &Path,
        meta: &MetaData,
        pick: impl Fn(&[String]) -> Result<[usize; 3]>,
    ) -> Result<Option<ExrBands>> {
        if meta.headers.len() != 1 {
            return Ok(None);
        }
        let h = &meta.headers[0];
        if h.deep || !matches!(h.blocks, BlockDescription::ScanLines) {
            return Ok(None);
        }
        let list = &h.channels.list;
        if list.iter().any(|c| c.sampling != exr::math::Vec2(1, 1)) {
            return Ok(None);
        }
        let names: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
        let picked = pick(&names)?;
        let channels = list
            .iter()
            .map(|c| (c.sample_type.bytes_per_sample(), c.sample_type))
            .collect();
        Ok(Some(ExrBands {
            path: path.to_path_buf(),
            width: h.layer_size.0,
            height: h.layer_size.1,
            picked,
            channels,
        }))
    }

    /// The file read.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows `y0..y1` of the data window as interleaved RGB f32 (`3 * width` per row). A
    /// chunk that does not decode is an error naming it (number, rows, compression) in plain
    /// words; a panic of the decoder on damaged data is one too.
    pub fn rows(&self, y0: usize, y1: usize) -> Result<Vec<f32>> {
        guarded(
            || self.rows_unguarded(y0, y1),
            || {
                damaged_chunk(&self.path).unwrap_or_else(|| {
                    Error::malformed(format!(
                        "EXR: the decoder failed on damaged data in rows {y0}..{y1}"
                    ))
                })
            },
        )
    }

    fn rows_unguarded(&self, y0: usize, y1: usize) -> Result<Vec<f32>> {
        use exr::block::chunk::CompressedBlock;
        use exr::block::UncompressedBlock;
        let w = self.width;
        let n = (y1 - y0) * w * 3;
        let mut out = crate::limits::try_filled(0f32, n, "an EXR band")?;
        let file = BufReader::new(File::open(&self.path)?);
        let reader = exr::block::read(file, false).map_err(exr_err)?;
        let chunks = reader
            .filter_chunks(false, |_, _, b| {
                b.layer == 0
                    && b.level == exr::math::Vec2(0, 0)
                    && b.pixel_position.1 < y1
                    && b.pixel_position.1 + b.pixel_size.1 > y0
            })
            .map_err(exr_err)?;
        let meta = exr::block::reader::ChunksReader::meta_data(&chunks).clone();
        let header = meta
            .headers
            .first()
            .ok_or_else(|| Error::malformed("EXR: the file has no image part"))?;
        let lines = header.compression.scan_lines_per_block().max(1);
        let top = i64::from(header.own_attributes.layer_position.y());
        let place = |y: i32| {
            let first = i64::from(y) - top;
            let inside = (0..self.height as i64).contains(&first);
            let index = first.max(0) as usize / lines;
            let last = (index * lines + lines).min(self.height);
            ChunkPlace {
                index: inside.then_some(index),
                count: header.chunk_count,
                pixels: if inside {
                    format!("rows {}..{last}", index * lines)
                } else {
                    format!("first row {y}, outside the data window")
                },
                compression: compression_name(header.compression),
            }
        };
        let row_bytes: usize = self.channels.iter().map(|c| c.0 * w).sum();
        let mut starts = Vec::with_capacity(self.channels.len());
        let mut acc = 0;
        for c in &self.channels {
            starts.push(acc);
            acc += c.0 * w;
        }
        let mut seen = 0usize;
        for chunk in chunks {
            let chunk = chunk.map_err(exr_err)?;
            let at = match &chunk.compressed_block {
                CompressedBlock::ScanLine(b) => place(b.y_coordinate),
                _ => {
                    return Err(Error::malformed(
                        "EXR: a chunk of the scan-line image is a tile",
                    ))
                }
            };
            let block = UncompressedBlock::decompress_chunk(chunk, &meta, false)
                .map_err(|e| chunk_err(e, &at))?;
            let (bx, by) = (block.index.pixel_position.0, block.index.pixel_position.1);
            let (bw, bh) = (block.index.pixel_size.0, block.index.pixel_size.1);
            if bx != 0 || bw != w || block.data.len() != row_bytes * bh {
                return Err(Error::malformed(format!(
                    "EXR: {} does not match the data window",
                    at.describe()
                )));
            }
            for r in 0..bh {
                let y = by + r;
                if y < y0 || y >= y1 {
                    continue;
                }
                seen += 1;
                let line = &block.data[r * row_bytes..(r + 1) * row_bytes];
                let dst = &mut out[(y - y0) * 3 * w..(y - y0 + 1) * 3 * w];
                for (k, &ci) in self.picked.iter().enumerate() {
                    let (bps, ty) = self.channels[ci];
                    let src = &line[starts[ci]..starts[ci] + bps * w];
                    for (x, s) in src.chunks_exact(bps).enumerate() {
                        dst[3 * x + k] = match ty {
                            SampleType::F16 => {
                                exr::prelude::f16::from_bits(u16::from_ne_bytes([s[0], s[1]]))
                                    .to_f32()
                            }
                            SampleType::F32 => f32::from_ne_bytes([s[0], s[1], s[2], s[3]]),
                            SampleType::U32 => u32::from_ne_bytes([s[0], s[1], s[2], s[3]]) as f32,
                        };
                    }
                }
            }
        }
        if seen != y1 - y0 {
            return Err(Error::malformed(format!(
                "EXR: rows {y0}..{y1}: {seen} of {} rows found (missing or repeated chunks)",
                y1 - y0
            )));
        }
        Ok(out)
    }
}
