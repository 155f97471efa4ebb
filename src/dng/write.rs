//! DNG writer: a [`RawImage`] -> a DNG 1.4 file (backward version 1.1, or 1.3 when opcode
//! lists are written) through the hand-written TIFF layer in [`crate::tiff::write`].
//!
//! Layouts: raw in IFD0 (default) or in a SubIFD behind a small RGB thumbnail rendered from
//! the raw being written ([`RawIfd::Sub`]); uncompressed strips (default; 16-bit container
//! or packed samples) or lossless-JPEG tiles ([`Compression::Ljpeg`], 256x256,
//! two-component half-width encoding, precision = BitsPerSample). Uncompressed samples keep
//! the source's BitsPerSample (10/12/14-bit packed MSB-first, as camera firmwares write);
//! `unpacked16` stores them in a 16-bit container instead. Fixture-only options: big-endian
//! files, uncompressed tiles, chosen strip height.
//!
//! What is carried and what is dropped is documented in docs/dng-writing.md and in
//! [`is_dropped`].

use crate::dng::ljpeg_encode;
use crate::dng::thumbnail;
use crate::error::{Error, Result};
use crate::output::OutputPolicy;
use crate::raw::meta::{ByteOrder, RawMeta};
use crate::raw::RawImage;
use crate::tiff::tags as t;
use crate::tiff::value::{Entry, Value};
use crate::tiff::write::{encode_tiff, write_tiff, Chunks, Ifd};
use rayon::prelude::*;
use sha2::{Digest, Sha256};
use std::path::Path;

/// Tile edge of lossless-JPEG tiles (as Adobe's converter writes).
const LJPEG_TILE: usize = 256;
/// Target size of one uncompressed strip.
const STRIP_BYTES: usize = 1 << 20;

/// Raw image compression of written DNGs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Compression {
    /// Uncompressed strips (default: readable by every raw tool).
    #[default]
    None,
    /// Lossless JPEG (compression 7) tiles.
    Ljpeg,
}

/// Where the raw image goes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum RawIfd {
    /// Raw in IFD0 (default).
    #[default]
    Main,
    /// Raw in a SubIFD behind a small RGB thumbnail in IFD0.
    Sub,
}

/// DNG writing options.
#[derive(Debug, Clone, Default)]
pub struct WriteOptions {
    /// Compression of the raw image.
    pub compression: Compression,
    /// IFD holding the raw image.
    pub raw_ifd: RawIfd,
    /// Fixture option: write a big-endian ("MM") file.
    pub big_endian: bool,
    /// Write uncompressed 9..15-bit samples in a 16-bit container instead of packing them
    /// at `meta.bits_per_sample` bits (MSB first, rows padded to a byte; the default, which
    /// keeps BitsPerSample as the source had it, as Magic Lantern and camera firmwares do).
    pub unpacked16: bool,
    /// Fixture option: uncompressed tiles of this size (multiple of 16) instead of strips.
    pub uncompressed_tiles: Option<(u32, u32)>,
    /// Fixture option: rows per uncompressed strip (default: about 1 MiB per strip).
    pub rows_per_strip: Option<u32>,
}

/// Encode a DNG into memory.
pub fn encode_dng(img: &RawImage, opts: &WriteOptions) -> Result<Vec<u8>> {
    let (order, ifd0) = build(img, opts)?;
    encode_tiff(order, &[ifd0])
}

/// Encode and write a DNG atomically under `policy` (strips/tiles are streamed to the
/// temporary file, not assembled in memory first).
pub fn write_dng(
    img: &RawImage,
    path: &Path,
    opts: &WriteOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    policy.check(path)?;
    let (order, ifd0) = build(img, opts).map_err(|e| e.in_file(path))?;
    crate::output::write_atomic(path, policy, |w| write_tiff(order, &[ifd0], w))
}

/// The IFD tree of a DNG: byte order and IFD0 (with its SubIFD/Exif children and data).
fn build(img: &RawImage, opts: &WriteOptions) -> Result<(ByteOrder, Ifd)> {
    img.validate()?;
    let m = &img.meta;
    check_meta(img)?;
    let order = if opts.big_endian {
        ByteOrder::Big
    } else {
        ByteOrder::Little
    };

    let (raw_chunks, digests, bits, compression, layout_tags) = encode_pixels(img, opts, order)?;
    let tiled = matches!(raw_chunks, Chunks::Tiles(_));
    let unique_id = raw_data_unique_id(img, tiled, &digests);

    let mut raw = Ifd::new();
    raw.set(t::NEW_SUBFILE_TYPE, Value::Long(vec![0]));
    raw.set(t::IMAGE_WIDTH, Value::Long(vec![img.width as u32]));
    raw.set(t::IMAGE_LENGTH, Value::Long(vec![img.height as u32]));
    raw.set(t::BITS_PER_SAMPLE, Value::Short(vec![bits]));
    raw.set(t::COMPRESSION, Value::Short(vec![compression]));
    raw.set(t::PHOTOMETRIC_INTERPRETATION, Value::Short(vec![32803]));
    raw.set(t::SAMPLES_PER_PIXEL, Value::Short(vec![1]));
    raw.set(t::PLANAR_CONFIGURATION, Value::Short(vec![1]));
    for (tag, v) in layout_tags {
        raw.set(tag, v);
    }
    raw.set_chunks(raw_chunks);
    set_raw_tags(&mut raw, m);

    let mut ifd0 = match opts.raw_ifd {
        RawIfd::Main => {
            for e in &m.raw_extra {
                if !is_dropped(e.tag) {
                    raw.set_if_absent(e.tag, e.value.clone());
                }
            }
            raw
        }
        RawIfd::Sub => {
            let th = thumbnail::render(img, 256)?;
            let mut ifd0 = Ifd::new();
            ifd0.set(t::NEW_SUBFILE_TYPE, Value::Long(vec![1]));
            ifd0.set(t::IMAGE_WIDTH, Value::Long(vec![th.width as u32]));
            ifd0.set(t::IMAGE_LENGTH, Value::Long(vec![th.height as u32]));
            ifd0.set(t::BITS_PER_SAMPLE, Value::Short(vec![8, 8, 8]));
            ifd0.set(t::COMPRESSION, Value::Short(vec![1]));
            ifd0.set(t::PHOTOMETRIC_INTERPRETATION, Value::Short(vec![2]));
            ifd0.set(t::SAMPLES_PER_PIXEL, Value::Short(vec![3]));
            ifd0.set(t::PLANAR_CONFIGURATION, Value::Short(vec![1]));
            ifd0.set(t::ROWS_PER_STRIP, Value::Long(vec![th.height as u32]));
            ifd0.set_chunks(Chunks::Strips(vec![th.rgb]));
            let mut raw = raw;
            // Raw-IFD tags that a source with its raw in IFD0 carried in `ifd0_extra`
            // belong with the raw image, not with the preview.
            let raw_tags = m
                .ifd0_extra
                .iter()
                .filter(|e| RAW_IFD_TAGS.contains(&e.tag));
            for e in m.raw_extra.iter().chain(raw_tags) {
                if !is_dropped(e.tag) {
                    raw.set_if_absent(e.tag, e.value.clone());
                }
            }
            ifd0.set_children(t::SUB_IFDS, vec![raw]);
            ifd0
        }
    };
    set_ifd0_tags(&mut ifd0, img, unique_id, opts.raw_ifd == RawIfd::Sub);
    ifd0.set_children(t::EXIF_IFD, vec![exif_ifd(m)]);
    if !m.gps.is_empty() {
        let mut gps = Ifd::new();
        for en in &m.gps {
            gps.set(en.tag, en.value.clone());
        }
        ifd0.set_children(t::GPS_IFD, vec![gps]);
    }
    Ok((order, ifd0))
}

/// Carried tags that describe the raw image itself (DNG spec: "IFD: Raw IFD"); with the raw
/// in a SubIFD they are written there even when the source had them in IFD0.
const RAW_IFD_TAGS: &[u16] = &[
    t::DEFAULT_SCALE,
    t::BAYER_GREEN_SPLIT,
    t::CHROMA_BLUR_RADIUS,
    t::ANTI_ALIAS_STRENGTH,
    t::BEST_QUALITY_SCALE,
    t::MASKED_AREAS,
    t::NOISE_REDUCTION_APPLIED,
    t::SUB_TILE_BLOCK_SIZE,
    t::ROW_INTERLEAVE_FACTOR,
    t::DEFAULT_USER_CROP,
];

/// Tags never copied from the source's carried entries: structural tags the writer
/// generates, and tags that become false or dangling once the file is re-laid out or its
/// pixels change (see docs/dng-writing.md).
pub fn is_dropped(tag: u16) -> bool {
    matches!(
        tag,
        // Structure, regenerated for the new layout.
        t::NEW_SUBFILE_TYPE
            | t::SUBFILE_TYPE
            | t::IMAGE_WIDTH
            | t::IMAGE_LENGTH
            | t::BITS_PER_SAMPLE
            | t::COMPRESSION
            | t::PHOTOMETRIC_INTERPRETATION
            | t::STRIP_OFFSETS
            | t::SAMPLES_PER_PIXEL
            | t::ROWS_PER_STRIP
            | t::STRIP_BYTE_COUNTS
            | t::PLANAR_CONFIGURATION
            | t::PREDICTOR
            | t::TILE_WIDTH
            | t::TILE_LENGTH
            | t::TILE_OFFSETS
            | t::TILE_BYTE_COUNTS
            | t::SUB_IFDS
            | t::SAMPLE_FORMAT
            | t::JPEG_TABLES
            | t::JPEG_IF_OFFSET
            | t::JPEG_IF_LENGTH
            | t::EXIF_IFD
            | t::GPS_IFD
            | t::INTEROP_IFD
            // Regenerated from the typed metadata / by this writer.
            | t::SOFTWARE
            | t::RAW_DATA_UNIQUE_ID
            // Stale once pixels or layout change.
            | t::RAW_IMAGE_DIGEST
            | t::NEW_RAW_IMAGE_DIGEST
            | t::ORIGINAL_RAW_FILE_DATA
            | t::ORIGINAL_RAW_FILE_DIGEST
            | t::MAKER_NOTE
            | t::DNG_PRIVATE_DATA
            | t::MAKER_NOTE_SAFETY
            | t::XMP
            | t::ICC_PROFILE
            | t::PREVIEW_APPLICATION_NAME
            | t::PREVIEW_APPLICATION_VERSION
            | t::PREVIEW_SETTINGS_NAME
            | t::PREVIEW_SETTINGS_DIGEST
            | t::PREVIEW_COLOR_SPACE
            | t::PREVIEW_DATE_TIME
            | t::RAW_TO_PREVIEW_GAIN
            // Exif exposure/sensitivity fields that are rewritten from (or derived from) the
            // typed exposure metadata, or that describe the scene brightness.
            | t::ISO_SPEED_RATINGS
            | t::SENSITIVITY_TYPE
            | t::RECOMMENDED_EXPOSURE_INDEX
            | t::STANDARD_OUTPUT_SENSITIVITY
            | t::ISO_SPEED
            | t::EXPOSURE_TIME
            | t::F_NUMBER
            | t::DATE_TIME_ORIGINAL
            | t::EXIF_VERSION
            | t::SHUTTER_SPEED_VALUE
            | t::APERTURE_VALUE
            | t::BRIGHTNESS_VALUE
            | t::PIXEL_X_DIMENSION
            | t::PIXEL_Y_DIMENSION
            // Typed fields of RawMeta: written from the typed value, never twice.
            | t::MAKE
            | t::MODEL
            | t::ORIENTATION
            | t::CFA_REPEAT_PATTERN_DIM
            | t::CFA_PATTERN
            | t::DNG_VERSION
            | t::DNG_BACKWARD_VERSION
            | t::UNIQUE_CAMERA_MODEL
            | t::CFA_PLANE_COLOR
            | t::CFA_LAYOUT
            | t::LINEARIZATION_TABLE
            | t::BLACK_LEVEL_REPEAT_DIM
            | t::BLACK_LEVEL
            | t::BLACK_LEVEL_DELTA_H
            | t::BLACK_LEVEL_DELTA_V
            | t::WHITE_LEVEL
            | t::DEFAULT_CROP_ORIGIN
            | t::DEFAULT_CROP_SIZE
            | t::COLOR_MATRIX1
            | t::COLOR_MATRIX2
            | t::CAMERA_CALIBRATION1
            | t::CAMERA_CALIBRATION2
            | t::FORWARD_MATRIX1
            | t::FORWARD_MATRIX2
            | t::CALIBRATION_ILLUMINANT1
            | t::CALIBRATION_ILLUMINANT2
            | t::ANALOG_BALANCE
            | t::AS_SHOT_NEUTRAL
            | t::AS_SHOT_WHITE_XY
            | t::BASELINE_EXPOSURE
            | t::ACTIVE_AREA
            | t::OPCODE_LIST1
            | t::OPCODE_LIST2
            | t::OPCODE_LIST3
            | t::NOISE_PROFILE
    )
}

fn check_meta(img: &RawImage) -> Result<()> {
    let m = &img.meta;
    if !(1..=16).contains(&m.bits_per_sample) {
        return Err(Error::invalid(format!(
            "BitsPerSample {} outside 1..=16",
            m.bits_per_sample
        )));
    }
    let c = &m.cfa;
    if c.rows == 0 || c.cols == 0 || c.rows * c.cols != c.pattern.len() || c.rows > 255 {
        return Err(Error::invalid(format!(
            "CFA pattern of {} values for a {}x{} repeat",
            c.pattern.len(),
            c.rows,
            c.cols
        )));
    }
    if img.width > u32::MAX as usize || img.height > u32::MAX as usize {
        return Err(Error::limits("image dimensions exceed 32 bits"));
    }
    Ok(())
}

type Pixels = (Chunks, Vec<Digest32>, u16, u16, Vec<(u16, Value)>);
type Digest32 = Vec<u8>;

/// A chunk with its SHA-256 (hashed while it is still in cache).
fn hashed(bytes: Vec<u8>) -> (Vec<u8>, Digest32) {
    let d = Sha256::digest(&bytes).to_vec();
    (bytes, d)
}

/// Encode the samples: (chunks, their SHA-256s, BitsPerSample, Compression, layout tags).
fn encode_pixels(img: &RawImage, opts: &WriteOptions, order: ByteOrder) -> Result<Pixels> {
    let (w, h) = (img.width, img.height);
    let max = img
        .data
        .par_chunks(1 << 16)
        .map(|c| c.iter().copied().max().unwrap_or(0))
        .max()
        .unwrap_or(0);
    let src_bits = img.meta.bits_per_sample;
    // Bits actually written: the source depth unless a sample does not fit in it.
    let fit_bits = if (max as u32) < (1u32 << src_bits) {
        src_bits
    } else {
        16
    };
    match opts.compression {
        Compression::Ljpeg => {
            let precision = fit_bits.max(2);
            let tw = if w >= LJPEG_TILE {
                LJPEG_TILE
            } else {
                w.div_ceil(16) * 16
            };
            let th = if h >= LJPEG_TILE {
                LJPEG_TILE
            } else {
                h.div_ceil(16) * 16
            };
            let (nx, ny) = (w.div_ceil(tw), h.div_ceil(th));
            let tiles: Vec<(Vec<u8>, Digest32)> = (0..nx * ny)
                .into_par_iter()
                .map(|i| {
                    let tile = extract_tile(img, (i % nx) * tw, (i / nx) * th, tw, th);
                    ljpeg_encode::encode(&tile, tw / 2, th, 2, precision as u8).map(hashed)
                })
                .collect::<Result<_>>()?;
            let (tiles, digests) = tiles.into_iter().unzip();
            Ok((
                Chunks::Tiles(tiles),
                digests,
                precision,
                7,
                vec![
                    (t::TILE_WIDTH, Value::Long(vec![tw as u32])),
                    (t::TILE_LENGTH, Value::Long(vec![th as u32])),
                ],
            ))
        }
        Compression::None => {
            let bits = if !opts.unpacked16 {
                fit_bits
            } else if fit_bits <= 8 {
                8
            } else {
                16
            };
            let big = order == ByteOrder::Big;
            if let Some((tw, th)) = opts.uncompressed_tiles {
                let (tw, th) = (tw as usize, th as usize);
                if tw == 0 || th == 0 || tw % 16 != 0 || th % 16 != 0 {
                    return Err(Error::invalid(format!(
                        "tile size {tw}x{th} is not a positive multiple of 16"
                    )));
                }
                let (nx, ny) = (w.div_ceil(tw), h.div_ceil(th));
                let (tiles, digests) = (0..nx * ny)
                    .map(|i| {
                        let tile = extract_tile(img, (i % nx) * tw, (i / nx) * th, tw, th);
                        hashed(pack_rows(&tile, tw, bits, big))
                    })
                    .unzip();
                return Ok((
                    Chunks::Tiles(tiles),
                    digests,
                    bits,
                    1,
                    vec![
                        (t::TILE_WIDTH, Value::Long(vec![tw as u32])),
                        (t::TILE_LENGTH, Value::Long(vec![th as u32])),
                    ],
                ));
            }
            let row_bytes = (w * bits as usize).div_ceil(8).max(1);
            let rps = match opts.rows_per_strip {
                Some(0) => return Err(Error::invalid("rows per strip must be positive")),
                Some(r) => (r as usize).min(h),
                None => STRIP_BYTES.div_ceil(row_bytes).clamp(1, h),
            };
            let strips: Vec<(Vec<u8>, Digest32)> = img
                .data
                .par_chunks(rps * w)
                .map(|rows| hashed(pack_rows(rows, w, bits, big)))
                .collect();
            let (strips, digests) = strips.into_iter().unzip();
            Ok((
                Chunks::Strips(strips),
                digests,
                bits,
                1,
                vec![(t::ROWS_PER_STRIP, Value::Long(vec![rps as u32]))],
            ))
        }
    }
}

/// A `tw x th` tile at (x0, y0), edges padded by replicating the last column/row of the
/// same CFA parity (so predictors keep running over one colour).
fn extract_tile(img: &RawImage, x0: usize, y0: usize, tw: usize, th: usize) -> Vec<u16> {
    let clamp = |v: usize, n: usize| -> usize {
        let last = n - 1;
        if v <= last {
            v
        } else if (v - last).is_multiple_of(2) {
            last
        } else {
            last.saturating_sub(1)
        }
    };
    let mut out = Vec::with_capacity(tw * th);
    for y in 0..th {
        let sy = clamp(y0 + y, img.height);
        let row = &img.data[sy * img.width..(sy + 1) * img.width];
        let inside = img.width.saturating_sub(x0).min(tw);
        out.extend_from_slice(&row[x0.min(img.width)..x0.min(img.width) + inside]);
        for x in inside..tw {
            out.push(row[clamp(x0 + x, img.width)]);
        }
    }
    out
}

/// Rows of `w` samples at `bits` bits: 8 -> bytes, 16 -> 16-bit words in file byte order,
/// other depths -> MSB-first packed, each row padded to a byte boundary.
fn pack_rows(samples: &[u16], w: usize, bits: u16, big: bool) -> Vec<u8> {
    match bits {
        16 => {
            let mut out = vec![0u8; samples.len() * 2];
            if big {
                for (o, &s) in out.chunks_exact_mut(2).zip(samples) {
                    o.copy_from_slice(&s.to_be_bytes());
                }
            } else {
                for (o, &s) in out.chunks_exact_mut(2).zip(samples) {
                    o.copy_from_slice(&s.to_le_bytes());
                }
            }
            out
        }
        8 => samples.iter().map(|&s| s as u8).collect(),
        _ => {
            let w = w.max(1);
            let row_bytes = (w * bits as usize).div_ceil(8);
            let rows = samples.len().div_ceil(w);
            let mut out = vec![0u8; row_bytes * rows];
            for (row, orow) in samples.chunks(w).zip(out.chunks_mut(row_bytes)) {
                pack_row(row, orow, bits);
            }
            out
        }
    }
}

/// Pack groups of 4 samples of `BITS` bits into `NB` bytes; returns (samples, bytes) done.
fn pack4<const BITS: u32, const NB: usize>(row: &[u16], out: &mut [u8]) -> (usize, usize) {
    let n = row.len() / 4;
    let m = (1u64 << BITS) - 1;
    for (o, g) in out.chunks_exact_mut(NB).zip(row.chunks_exact(4)) {
        let v = (g[0] as u64 & m) << (3 * BITS)
            | (g[1] as u64 & m) << (2 * BITS)
            | (g[2] as u64 & m) << BITS
            | (g[3] as u64 & m);
        let be = v.to_be_bytes();
        o.copy_from_slice(&be[8 - NB..]);
    }
    (n * 4, n * NB)
}

/// Pack one row MSB-first into `out` (exactly `ceil(len * bits / 8)` bytes).
fn pack_row(row: &[u16], out: &mut [u8], bits: u16) {
    // Fast paths: whole groups of samples that end on a byte boundary.
    let (done_s, done_b) = match bits {
        12 => {
            let n = row.len() / 2;
            for (o, g) in out.chunks_exact_mut(3).zip(row.chunks_exact(2)) {
                let v = ((g[0] as u32 & 0xFFF) << 12) | (g[1] as u32 & 0xFFF);
                o[0] = (v >> 16) as u8;
                o[1] = (v >> 8) as u8;
                o[2] = v as u8;
            }
            (n * 2, n * 3)
        }
        10 => pack4::<10, 5>(row, out),
        14 => pack4::<14, 7>(row, out),
        _ => (0, 0),
    };
    let mut pos = done_b;
    let mut acc: u64 = 0;
    let mut n = 0u32;
    for &s in &row[done_s..] {
        acc = (acc << bits) | (s as u64 & ((1u64 << bits) - 1));
        n += bits as u32;
        while n >= 8 {
            n -= 8;
            if let Some(b) = out.get_mut(pos) {
                *b = (acc >> n) as u8;
            }
            pos += 1;
        }
        acc &= (1u64 << n) - 1;
    }
    if n > 0 {
        if let Some(b) = out.get_mut(pos) {
            *b = (acc << (8 - n)) as u8;
        }
    }
}

/// Best rational approximation of `x >= 0` with numerator and denominator <= `max`
/// (continued fractions; exact for values that were read from rationals).
fn cf_rational(x: f64, max: u64) -> (u64, u64) {
    if !x.is_finite() || x <= 0.0 {
        return (0, 1);
    }
    if x >= max as f64 {
        return (max, 1);
    }
    let (mut h0, mut h1) = (0u64, 1u64);
    let (mut k0, mut k1) = (1u64, 0u64);
    let mut best = (0u64, 1u64);
    let mut r = x;
    for _ in 0..64 {
        let a = r.floor();
        if a > max as f64 {
            break;
        }
        let a = a as u64;
        let h = a.checked_mul(h1).and_then(|v| v.checked_add(h0));
        let k = a.checked_mul(k1).and_then(|v| v.checked_add(k0));
        let (h, k) = match (h, k) {
            (Some(h), Some(k)) if h <= max && k <= max => (h, k),
            _ => break,
        };
        best = (h, k);
        if h as f64 / k as f64 == x {
            break;
        }
        (h0, h1, k0, k1) = (h1, h, k1, k);
        let frac = r - a as f64;
        if frac <= 0.0 {
            break;
        }
        r = 1.0 / frac;
    }
    if best.1 == 0 {
        (0, 1)
    } else {
        best
    }
}

fn urational(values: &[f64]) -> Value {
    Value::Rational(
        values
            .iter()
            .map(|&x| {
                let (n, d) = cf_rational(x, u32::MAX as u64);
                (n as u32, d as u32)
            })
            .collect(),
    )
}

fn srational(values: &[f64]) -> Value {
    Value::SRational(
        values
            .iter()
            .map(|&x| {
                let (n, d) = cf_rational(x.abs(), i32::MAX as u64);
                let n = n as i32;
                (if x < 0.0 { -n } else { n }, d as i32)
            })
            .collect(),
    )
}

/// The source's stored entry of `tag` when it still decodes to `current` exactly (the value
/// was not changed): written back as the source stored it, type and value.
fn kept(m: &RawMeta, tag: u16, current: &[f64]) -> Option<Value> {
    let v = m.stored_value(tag)?;
    (v.to_f64_vec()?.as_slice() == current).then(|| v.clone())
}

/// [`kept`] for AsShotNeutral, which the reader normalizes to green = 1.
fn kept_neutral(m: &RawMeta, n: [f64; 3]) -> Option<Value> {
    let v = m.stored_value(t::AS_SHOT_NEUTRAL)?;
    match v.to_f64_vec()?.as_slice() {
        [r, g, b] if *g > 0.0 && [r / g, 1.0, b / g] == n => Some(v.clone()),
        _ => None,
    }
}

/// AsShotNeutral as RATIONALs that can never round to 0: green = 1 when every component is
/// representable within 1e-9 (the usual case), else the neutral rescaled by the geometric
/// mean of its extremes (AsShotNeutral is defined up to scale; readers divide by green),
/// which keeps ratios up to ~1.8e19 non-zero and finite.
pub fn neutral_value(n: [f64; 3]) -> Value {
    let close = |v: &Value, want: &[f64]| {
        v.to_f64_vec().is_some_and(|got| {
            got.iter()
                .zip(want)
                .all(|(g, w)| *g > 0.0 && ((g - w) / w).abs() <= 1e-9)
        })
    };
    let plain = urational(&n);
    if close(&plain, &n) || n.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return plain;
    }
    let (lo, hi) = n.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| {
        (lo.min(x), hi.max(x))
    });
    let s = (lo.sqrt()) * (hi.sqrt());
    let scaled = n.map(|x| x / s);
    let v = urational(&scaled);
    match &v {
        Value::Rational(r) if r.iter().all(|&(num, den)| num > 0 && den > 0) => v,
        // Beyond what RATIONAL holds: the smallest positive value instead of 0.
        Value::Rational(r) => Value::Rational(
            r.iter()
                .map(|&(num, den)| {
                    if num == 0 || den == 0 {
                        (1, u32::MAX)
                    } else {
                        (num, den)
                    }
                })
                .collect(),
        ),
        _ => v,
    }
}

/// Integers as SHORT/LONG when exact, otherwise RATIONAL.
fn levels_value(values: &[f64]) -> Value {
    let ints = values
        .iter()
        .all(|&v| v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64);
    if ints && values.iter().all(|&v| v <= u16::MAX as f64) {
        Value::Short(values.iter().map(|&v| v as u16).collect())
    } else if ints {
        Value::Long(values.iter().map(|&v| v as u32).collect())
    } else {
        urational(values)
    }
}

fn ascii_or_default(s: &Option<String>, default: &str) -> Value {
    match s.as_deref().map(str::trim) {
        Some(s) if !s.is_empty() => Value::ascii(s),
        _ => Value::ascii(default),
    }
}

/// Tags that describe the raw image (raw IFD).
fn set_raw_tags(ifd: &mut Ifd, m: &RawMeta) {
    let c = &m.cfa;
    ifd.set(
        t::CFA_REPEAT_PATTERN_DIM,
        Value::Short(vec![c.rows as u16, c.cols as u16]),
    );
    ifd.set(t::CFA_PATTERN, Value::Byte(c.pattern.clone()));
    let planes = if c.plane_color.is_empty() {
        vec![0, 1, 2]
    } else {
        c.plane_color.clone()
    };
    ifd.set(t::CFA_PLANE_COLOR, Value::Byte(planes));
    ifd.set(t::CFA_LAYOUT, Value::Short(vec![c.layout.max(1)]));
    if let Some(lt) = &m.linearization_table {
        ifd.set(t::LINEARIZATION_TABLE, Value::Short(lt.clone()));
    }
    let l = &m.levels;
    if l.black_repeat != (1, 1) {
        ifd.set(
            t::BLACK_LEVEL_REPEAT_DIM,
            Value::Short(vec![l.black_repeat.0 as u16, l.black_repeat.1 as u16]),
        );
    }
    ifd.set(t::BLACK_LEVEL, levels_value(&l.black));
    if !l.black_delta_h.is_empty() {
        ifd.set(t::BLACK_LEVEL_DELTA_H, srational(&l.black_delta_h));
    }
    if !l.black_delta_v.is_empty() {
        ifd.set(t::BLACK_LEVEL_DELTA_V, srational(&l.black_delta_v));
    }
    let white = if l.white.fract() == 0.0 && l.white >= 0.0 && l.white <= u32::MAX as f64 {
        Value::Long(vec![l.white as u32])
    } else {
        urational(&[l.white])
    };
    ifd.set(t::WHITE_LEVEL, white);
    if let Some(a) = m.active_area {
        ifd.set(
            t::ACTIVE_AREA,
            Value::Long(vec![a.top, a.left, a.bottom, a.right]),
        );
    }
    if let Some(o) = m.default_crop_origin {
        ifd.set(t::DEFAULT_CROP_ORIGIN, levels_value(&o));
    }
    if let Some(s) = m.default_crop_size {
        ifd.set(t::DEFAULT_CROP_SIZE, levels_value(&s));
    }
    for (i, tag) in [t::OPCODE_LIST1, t::OPCODE_LIST2, t::OPCODE_LIST3]
        .into_iter()
        .enumerate()
    {
        if let Some(Some(bytes)) = m.opcode_lists.get(i) {
            ifd.set(tag, Value::Undefined(bytes.clone()));
        }
    }
    if let Some(np) = &m.noise_profile {
        ifd.set(
            t::NOISE_PROFILE,
            Value::Double(np.iter().flat_map(|&(s, o)| [s, o]).collect()),
        );
    }
}

/// Tags of IFD0 (camera, colour, version, provenance).
fn set_ifd0_tags(ifd: &mut Ifd, img: &RawImage, unique_id: Vec<u8>, raw_in_sub: bool) {
    let m = &img.meta;
    let has_opcodes = m.opcode_lists.iter().any(|o| o.is_some());
    ifd.set(t::DNG_VERSION, Value::Byte(vec![1, 4, 0, 0]));
    ifd.set(
        t::DNG_BACKWARD_VERSION,
        Value::Byte(if has_opcodes {
            vec![1, 3, 0, 0]
        } else {
            vec![1, 1, 0, 0]
        }),
    );
    let ucm = m
        .unique_camera_model
        .clone()
        .filter(|s| !s.trim().is_empty())
        .or_else(|| match (&m.make, &m.model) {
            (Some(a), Some(b)) => Some(format!("{a} {b}")),
            (None, Some(b)) => Some(b.clone()),
            _ => None,
        });
    ifd.set(t::UNIQUE_CAMERA_MODEL, ascii_or_default(&ucm, "Unknown"));
    ifd.set(t::MAKE, ascii_or_default(&m.make, "Unknown"));
    ifd.set(t::MODEL, ascii_or_default(&m.model, "Unknown"));
    ifd.set(
        t::ORIENTATION,
        Value::Short(vec![m.orientation.clamp(1, 8)]),
    );
    ifd.set(t::SOFTWARE, Value::ascii(&crate::software_name()));
    let c = &m.color;
    // ColorMatrix1 is required: an identity-like default only when the source had none.
    let cm1 = c
        .color_matrix1
        .clone()
        .unwrap_or_else(|| vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    ifd.set(
        t::COLOR_MATRIX1,
        kept(m, t::COLOR_MATRIX1, &cm1).unwrap_or_else(|| srational(&cm1)),
    );
    let mats = [
        (t::COLOR_MATRIX2, &c.color_matrix2),
        (t::CAMERA_CALIBRATION1, &c.camera_calibration1),
        (t::CAMERA_CALIBRATION2, &c.camera_calibration2),
        (t::FORWARD_MATRIX1, &c.forward_matrix1),
        (t::FORWARD_MATRIX2, &c.forward_matrix2),
    ];
    for (tag, v) in mats {
        if let Some(v) = v {
            ifd.set(tag, kept(m, tag, v).unwrap_or_else(|| srational(v)));
        }
    }
    if let Some(i) = c.calibration_illuminant1 {
        ifd.set(t::CALIBRATION_ILLUMINANT1, Value::Short(vec![i]));
    }
    if let Some(i) = c.calibration_illuminant2 {
        ifd.set(t::CALIBRATION_ILLUMINANT2, Value::Short(vec![i]));
    }
    if let Some(ab) = &c.analog_balance {
        ifd.set(
            t::ANALOG_BALANCE,
            kept(m, t::ANALOG_BALANCE, ab).unwrap_or_else(|| urational(ab)),
        );
    }
    if let Some(be) = c.baseline_exposure {
        ifd.set(
            t::BASELINE_EXPOSURE,
            kept(m, t::BASELINE_EXPOSURE, &[be]).unwrap_or_else(|| srational(&[be])),
        );
    }
    if let Some(n) = m.as_shot_neutral {
        ifd.set(
            t::AS_SHOT_NEUTRAL,
            kept_neutral(m, n).unwrap_or_else(|| neutral_value(n)),
        );
    } else if let Some(xy) = m.as_shot_white_xy {
        ifd.set(
            t::AS_SHOT_WHITE_XY,
            kept(m, t::AS_SHOT_WHITE_XY, &xy).unwrap_or_else(|| urational(&xy)),
        );
    }
    ifd.set(t::RAW_DATA_UNIQUE_ID, Value::Byte(unique_id));
    for e in &m.ifd0_extra {
        let belongs_to_raw = raw_in_sub && RAW_IFD_TAGS.contains(&e.tag);
        if !is_dropped(e.tag) && !belongs_to_raw {
            ifd.set_if_absent(e.tag, e.value.clone());
        }
    }
    ifd.set_if_absent(t::X_RESOLUTION, Value::Rational(vec![(72, 1)]));
    ifd.set_if_absent(t::Y_RESOLUTION, Value::Rational(vec![(72, 1)]));
    ifd.set_if_absent(t::RESOLUTION_UNIT, Value::Short(vec![2]));
}

fn exif_ifd(m: &RawMeta) -> Ifd {
    let mut ifd = Ifd::new();
    ifd.set(t::EXIF_VERSION, Value::Undefined(b"0230".to_vec()));
    let e = &m.exif;
    if let Some(iso) = e.iso.filter(|&i| i > 0) {
        ifd.set(
            t::ISO_SPEED_RATINGS,
            Value::Short(vec![iso.min(65535) as u16]),
        );
        ifd.set(t::SENSITIVITY_TYPE, Value::Short(vec![3]));
        ifd.set(t::ISO_SPEED, Value::Long(vec![iso]));
    }
    if let Some(et) = e.exposure_time.filter(|&x| x > 0.0 && x.is_finite()) {
        ifd.set(t::EXPOSURE_TIME, urational(&[et]));
    }
    if let Some(f) = e.f_number.filter(|&x| x > 0.0 && x.is_finite()) {
        ifd.set(t::F_NUMBER, urational(&[f]));
    }
    if let Some(d) = &e.date_time_original {
        ifd.set(t::DATE_TIME_ORIGINAL, Value::ascii(d));
    }
    for en in &m.exif_extra {
        if !is_dropped(en.tag) {
            ifd.set_if_absent(en.tag, en.value.clone());
        }
    }
    ifd
}

/// RawDataUniqueID: the first 16 bytes of SHA-256 over the dimensions, the SHA-256 of every
/// encoded strip/tile (computed in parallel right after encoding each, combined in order:
/// independent of the thread count) and the metadata as written (JSON; no storage description, no regenerated or
/// dropped entries). Deterministic: the same image written the same way always gets the
/// same ID, a change of pixels or meaning a new one. Hashing the encoded (packed or
/// compressed) data rather than the `u16` samples keeps it cheap.
fn raw_data_unique_id(img: &RawImage, tiled: bool, digests: &[Digest32]) -> Vec<u8> {
    let mut h = Sha256::new();
    h.update(b"day2night RawDataUniqueID v2\0");
    h.update((img.width as u64).to_le_bytes());
    h.update((img.height as u64).to_le_bytes());
    h.update([tiled as u8]);
    for d in digests {
        h.update(d);
    }
    // Canonical metadata: what this writer actually writes, so that re-writing a file it
    // wrote reproduces the same ID (a fixed point) while any change of meaning changes it.
    let mut meta = img.meta.clone();
    meta.storage = None;
    meta.dng_version = [1, 4, 0, 0];
    meta.dng_backward_version = None;
    let keep = |e: &Entry| {
        !is_dropped(e.tag)
            && !matches!(
                e.tag,
                t::X_RESOLUTION | t::Y_RESOLUTION | t::RESOLUTION_UNIT
            )
    };
    meta.ifd0_extra.retain(keep);
    meta.raw_extra.retain(keep);
    meta.exif_extra.retain(keep);
    if let Ok(json) = serde_json::to_vec(&meta) {
        h.update(&json);
    }
    h.finalize()[..16].to_vec()
}

/// Entries of an IFD that the writer will carry (helper for docs/tests).
pub fn carried(entries: &[Entry]) -> Vec<&Entry> {
    entries.iter().filter(|e| !is_dropped(e.tag)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::Bayer;

    fn sample_image(w: usize, h: usize, bits: u16) -> RawImage {
        let meta = RawMeta::new_bayer(Bayer::RGGB, bits, 64.0, ((1u32 << bits) - 1) as f64);
        let max = (1u32 << bits) - 1;
        let data = (0..w * h)
            .map(|i| (((i as u32).wrapping_mul(2654435761u32) >> 7) & max) as u16)
            .collect();
        RawImage {
            width: w,
            height: h,
            data,
            meta,
        }
    }

    #[test]
    fn rationals_are_exact_for_simple_fractions() {
        assert_eq!(cf_rational(1.0 / 60.0, u32::MAX as u64), (1, 60));
        assert_eq!(cf_rational(2.477, u32::MAX as u64), (2477, 1000));
        assert_eq!(cf_rational(0.6461, i32::MAX as u64), (6461, 10000));
        assert_eq!(cf_rational(0.0, 100), (0, 1));
        assert_eq!(cf_rational(1e12, u32::MAX as u64), (u32::MAX as u64, 1));
        let v = srational(&[-0.3825]);
        assert_eq!(v, Value::SRational(vec![(-153, 400)]));
        for x in [std::f64::consts::PI, 1e-7, 12345.678] {
            let (n, d) = cf_rational(x, u32::MAX as u64);
            assert!((n as f64 / d as f64 - x).abs() / x < 1e-9);
        }
    }

    #[test]
    fn packing_is_msb_first_and_row_padded() {
        // Two 12-bit samples 0xABC, 0xDEF -> AB CD EF.
        assert_eq!(
            pack_rows(&[0xABC, 0xDEF], 2, 12, false),
            vec![0xAB, 0xCD, 0xEF]
        );
        // 10-bit, width 1: 0x3FF -> 11111111 11000000, each row padded.
        assert_eq!(
            pack_rows(&[0x3FF, 0x001], 1, 10, false),
            vec![0xFF, 0xC0, 0x00, 0x40]
        );
        assert_eq!(pack_rows(&[0x0102], 1, 16, true), vec![1, 2]);
        // Fast paths agree with the generic packer (odd widths leave a generic tail).
        for bits in [10u16, 12, 14] {
            let row: Vec<u16> = (0..13u32)
                .map(|i| ((i * 977) % (1 << bits)) as u16)
                .collect();
            let fast = pack_rows(&row, 13, bits, false);
            let mut slow = vec![];
            let (mut acc, mut n) = (0u64, 0u32);
            for &s in &row {
                acc = (acc << bits) | s as u64;
                n += bits as u32;
                while n >= 8 {
                    n -= 8;
                    slow.push((acc >> n) as u8);
                }
                acc &= (1 << n) - 1;
            }
            if n > 0 {
                slow.push((acc << (8 - n)) as u8);
            }
            assert_eq!(fast, slow, "{bits}");
        }
        assert_eq!(pack_rows(&[0x0102], 1, 16, false), vec![2, 1]);
    }

    #[test]
    fn encodes_deterministically_in_all_modes() {
        let img = sample_image(40, 30, 12);
        for compression in [Compression::None, Compression::Ljpeg] {
            for raw_ifd in [RawIfd::Main, RawIfd::Sub] {
                let o = WriteOptions {
                    compression,
                    raw_ifd,
                    ..Default::default()
                };
                let a = encode_dng(&img, &o).unwrap();
                let b = encode_dng(&img, &o).unwrap();
                assert_eq!(a, b);
                assert_eq!(&a[..4], b"II*\0");
            }
        }
        let o = WriteOptions {
            big_endian: true,
            uncompressed_tiles: Some((16, 16)),
            ..Default::default()
        };
        let a = encode_dng(&img, &o).unwrap();
        assert_eq!(&a[..4], b"MM\0*");
    }

    #[test]
    fn tiles_pad_with_same_parity() {
        let img = sample_image(5, 3, 12);
        let t = extract_tile(&img, 0, 0, 8, 4);
        // Columns 5,6,7 repeat columns 3,4,3; row 3 repeats row 1.
        for y in 0..4 {
            let sy = [0, 1, 2, 1][y];
            let want: Vec<u16> = [0, 1, 2, 3, 4, 3, 4, 3]
                .iter()
                .map(|&x| img.data[sy * 5 + x])
                .collect();
            assert_eq!(&t[y * 8..y * 8 + 8], &want[..], "row {y}");
        }
    }

    #[test]
    fn unique_id_changes_with_pixels_and_meta() {
        let id = |img: &RawImage| {
            let (_, ifd0) = build(img, &WriteOptions::default()).unwrap();
            ifd0.get(t::RAW_DATA_UNIQUE_ID).cloned().unwrap()
        };
        let a = sample_image(8, 8, 12);
        let mut b = a.clone();
        b.data[5] ^= 1;
        let mut c = a.clone();
        c.meta.exif.iso = Some(3200);
        assert_ne!(id(&a), id(&b));
        assert_ne!(id(&a), id(&c));
        assert_eq!(id(&a), id(&a.clone()));
        assert_eq!(id(&a).count(), 16);
    }

    #[test]
    fn raw_ifd_tags_follow_the_raw_into_the_subifd() {
        let mut img = sample_image(16, 16, 12);
        img.meta.ifd0_extra.push(Entry {
            tag: t::DEFAULT_SCALE,
            value: Value::Rational(vec![(1, 1), (1, 1)]),
        });
        img.meta.ifd0_extra.push(Entry {
            tag: t::COPYRIGHT,
            value: Value::ascii("x"),
        });
        let sub = WriteOptions {
            raw_ifd: RawIfd::Sub,
            ..Default::default()
        };
        let (_, ifd0) = build(&img, &sub).unwrap();
        assert!(ifd0.get(t::DEFAULT_SCALE).is_none());
        assert!(ifd0.get(t::COPYRIGHT).is_some());
        let back = crate::dng::read::read_dng_bytes(&encode_dng(&img, &sub).unwrap()).unwrap();
        assert!(back
            .meta
            .raw_extra
            .iter()
            .any(|e| e.tag == t::DEFAULT_SCALE));
        let (_, main) = build(&img, &WriteOptions::default()).unwrap();
        assert!(main.get(t::DEFAULT_SCALE).is_some());
    }

    #[test]
    fn drop_list_covers_stale_tags() {
        for tag in [
            t::RAW_IMAGE_DIGEST,
            t::NEW_RAW_IMAGE_DIGEST,
            t::ORIGINAL_RAW_FILE_DATA,
            t::MAKER_NOTE,
            t::STRIP_OFFSETS,
            t::SUB_IFDS,
        ] {
            assert!(is_dropped(tag));
        }
        assert!(!is_dropped(t::COPYRIGHT));
        assert!(!is_dropped(t::BASELINE_NOISE));
    }
}
