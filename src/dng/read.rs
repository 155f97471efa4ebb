//! DNG reader: finds the CFA raw IFD (NewSubFileType 0, in IFD0 or any SubIFD), decodes its
//! pixels (uncompressed 8-16 bit incl. packed 10/12/14-bit, or lossless JPEG; strips or
//! tiles) and fills [`RawMeta`] completely. See docs/dng-support.md ("Reading").

use crate::dng::ljpeg;
use crate::dng::meta::{ByteOrder, CfaPattern, ColorInfo, ExifInfo, Layout, RawMeta, Storage};
use crate::error::{Error, Result, ResultExt};
use crate::raw::{Levels, RawImage, Rect};
use crate::tiff::read::{parse, Ifd, Tiff};
use crate::tiff::tags::*;
use crate::tiff::value::{Entry, Value};
use serde::Serialize;
use std::path::Path;

/// Default largest stored image (width * height samples); the limit in force is
/// [`crate::limits::Limits::current`] (`--max-pixels`, `D2N_MAX_PIXELS`).
pub const MAX_PIXELS: usize = crate::limits::DEFAULT_MAX_PIXELS as usize;
/// Largest width or height accepted.
pub const MAX_DIMENSION: u32 = 65535;
/// Largest CFA repeat pattern (rows or columns).
pub const MAX_CFA_DIM: usize = 16;

/// PhotometricInterpretation values.
const PHOTOMETRIC_CFA: u16 = 32803;
const PHOTOMETRIC_LINEAR_RAW: u16 = 34892;

/// Read the raw CFA image and metadata of a DNG file.
pub fn read_dng(path: &Path) -> Result<RawImage> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io(e).in_file(path))?;
    read_dng_bytes(&bytes).in_file(path)
}

/// Read the raw CFA image and metadata of a DNG held in memory.
pub fn read_dng_bytes(bytes: &[u8]) -> Result<RawImage> {
    let tiff = parse(bytes)?;
    let dng = locate(&tiff)?;
    let raw = dng.raw;
    let photometric = raw.u32(PHOTOMETRIC_INTERPRETATION).unwrap_or(0) as u16;
    check_photometric(photometric)?;
    let geom = geometry(raw)?;
    let meta = build_meta(&tiff, &dng, &geom)?;
    let data = decode_pixels(bytes, tiff.byte_order, raw, &geom)?;
    let img = RawImage {
        width: geom.width as usize,
        height: geom.height as usize,
        data,
        meta,
    };
    img.validate()?;
    Ok(img)
}

fn check_photometric(p: u16) -> Result<()> {
    match p {
        PHOTOMETRIC_CFA => Ok(()),
        PHOTOMETRIC_LINEAR_RAW => Err(Error::unsupported(
            "LinearRaw DNG is not a CFA raw (already demosaiced)",
        )),
        other => Err(Error::unsupported(format!(
            "PhotometricInterpretation {other} ({}) is not a CFA raw",
            photometric_name(other)
        ))),
    }
}

/// Name of a PhotometricInterpretation value.
pub fn photometric_name(p: u16) -> &'static str {
    match p {
        0 => "WhiteIsZero",
        1 => "BlackIsZero",
        2 => "RGB",
        6 => "YCbCr",
        PHOTOMETRIC_CFA => "CFA",
        PHOTOMETRIC_LINEAR_RAW => "LinearRaw",
        51177 => "Depth",
        _ => "unknown",
    }
}

/// Name of a TIFF/DNG Compression value.
pub fn compression_name(c: u16) -> &'static str {
    match c {
        1 => "uncompressed",
        7 => "lossless JPEG",
        8 | 32946 => "deflate",
        9 => "VC-5",
        34892 => "lossy JPEG",
        52546 => "JPEG XL",
        6 => "old-style JPEG",
        5 => "LZW",
        32773 => "PackBits",
        _ => "unknown",
    }
}

fn check_compression(c: u16) -> Result<()> {
    match c {
        1 | 7 => Ok(()),
        _ => Err(Error::unsupported(format!(
            "compression {c} ({}) is not supported",
            compression_name(c)
        ))),
    }
}

/// Where the raw IFD is.
struct Located<'a> {
    ifd0: &'a Ifd,
    raw: &'a Ifd,
    /// SubIFD path (None = IFD0).
    path: Option<Vec<usize>>,
}

fn is_main_image(ifd: &Ifd) -> bool {
    ifd.u32(NEW_SUBFILE_TYPE).unwrap_or(0) == 0
}

fn collect_main<'a>(ifd: &'a Ifd, path: &mut Vec<usize>, out: &mut Vec<(&'a Ifd, Vec<usize>)>) {
    for (i, s) in ifd.sub_ifds.iter().enumerate() {
        path.push(i);
        if is_main_image(s) {
            out.push((s, path.clone()));
        }
        collect_main(s, path, out);
        path.pop();
    }
}

/// The raw IFD: among IFD0 and its SubIFD tree (depth first) the IFDs with NewSubFileType 0,
/// the first one with CFA photometric, else the first one (e.g. LinearRaw, reported later).
fn locate(tiff: &Tiff) -> Result<Located<'_>> {
    let ifd0 = tiff.ifd0();
    if ifd0.get(DNG_VERSION).is_none() {
        return Err(Error::unsupported("not a DNG: IFD0 has no DNGVersion tag"));
    }
    let mut candidates = Vec::new();
    if is_main_image(ifd0) {
        candidates.push((ifd0, Vec::new()));
    }
    collect_main(ifd0, &mut Vec::new(), &mut candidates);
    let is_cfa = |i: &Ifd| i.u32(PHOTOMETRIC_INTERPRETATION) == Some(u32::from(PHOTOMETRIC_CFA));
    let chosen = candidates
        .iter()
        .find(|(i, _)| is_cfa(i))
        .or_else(|| candidates.first());
    match chosen {
        Some((raw, path)) => Ok(Located {
            ifd0,
            raw,
            path: if path.is_empty() {
                None
            } else {
                Some(path.clone())
            },
        }),
        None => Err(Error::malformed(
            "no raw image: no IFD with NewSubFileType 0 (IFD0 or SubIFDs)",
        )),
    }
}

struct Geometry {
    width: u32,
    height: u32,
    bits: u16,
    compression: u16,
    layout: Layout,
}

fn geometry(raw: &Ifd) -> Result<Geometry> {
    let width = raw.require_u32(IMAGE_WIDTH)?;
    let height = raw.require_u32(IMAGE_LENGTH)?;
    if width == 0 || height == 0 {
        return Err(Error::malformed(format!(
            "raw image has zero size ({width}x{height})"
        )));
    }
    if width > MAX_DIMENSION || height > MAX_DIMENSION {
        return Err(Error::limits(format!(
            "raw image {width}x{height} exceeds the limit of {MAX_DIMENSION} pixels per side"
        )));
    }
    crate::limits::check_pixels("raw image", u64::from(width), u64::from(height))?;
    let spp = raw.u32(SAMPLES_PER_PIXEL).unwrap_or(1);
    if spp != 1 {
        return Err(Error::unsupported(format!(
            "CFA raw with {spp} samples per pixel (only 1)"
        )));
    }
    let bits_v = raw.get(BITS_PER_SAMPLE);
    let bits = bits_v.and_then(|v| v.get_u32(0)).unwrap_or(1);
    if !(8..=16).contains(&bits) {
        return Err(Error::unsupported(format!(
            "{bits}-bit samples (8..16 supported)"
        )));
    }
    if let Some(f) = raw.u32(SAMPLE_FORMAT) {
        if f != 1 {
            return Err(Error::unsupported(format!(
                "SampleFormat {f} (floating point or signed raw data) is not supported"
            )));
        }
    }
    let compression = raw.u32(COMPRESSION).unwrap_or(1) as u16;
    check_compression(compression)?;
    let layout = if raw.has(TILE_OFFSETS) || raw.has(TILE_WIDTH) {
        let tw = raw.require_u32(TILE_WIDTH)?;
        let th = raw.require_u32(TILE_LENGTH)?;
        if tw == 0 || th == 0 || tw > MAX_DIMENSION || th > MAX_DIMENSION {
            return Err(Error::malformed(format!("bad tile size {tw}x{th}")));
        }
        Layout::Tiles {
            width: tw,
            height: th,
        }
    } else {
        let rps = raw.u32(ROWS_PER_STRIP).unwrap_or(height).clamp(1, height);
        Layout::Strips {
            rows_per_strip: rps,
        }
    };
    Ok(Geometry {
        width,
        height,
        bits: bits as u16,
        compression,
        layout,
    })
}

// ---------------------------------------------------------------------------------------
// Pixels

/// One strip or tile: its place in the image and its bytes.
struct Block<'a> {
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    data: &'a [u8],
}

fn blocks<'a>(bytes: &'a [u8], raw: &Ifd, g: &Geometry) -> Result<Vec<Block<'a>>> {
    let (w, h) = (g.width as usize, g.height as usize);
    let (off_tag, cnt_tag, bw, bh, across) = match g.layout {
        Layout::Strips { rows_per_strip } => (
            STRIP_OFFSETS,
            STRIP_BYTE_COUNTS,
            w,
            rows_per_strip as usize,
            1,
        ),
        Layout::Tiles { width, height } => (
            TILE_OFFSETS,
            TILE_BYTE_COUNTS,
            width as usize,
            height as usize,
            w.div_ceil(width as usize),
        ),
    };
    let down = h.div_ceil(bh);
    let n = across * down;
    let offs = raw
        .require(off_tag)?
        .to_u32_vec()
        .ok_or_else(|| Error::malformed(format!("{} is not LONG/SHORT", tag_name(off_tag))))?;
    let counts = raw
        .require(cnt_tag)?
        .to_u32_vec()
        .ok_or_else(|| Error::malformed(format!("{} is not LONG/SHORT", tag_name(cnt_tag))))?;
    if offs.len() < n || counts.len() < n {
        return Err(Error::malformed(format!(
            "{} {} and {} {} for {} {} needed by a {}x{} image",
            offs.len(),
            tag_name(off_tag),
            counts.len(),
            tag_name(cnt_tag),
            n,
            if across == 1 && matches!(g.layout, Layout::Strips { .. }) {
                "strips"
            } else {
                "tiles"
            },
            w,
            h
        )));
    }
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (bx, by) = (i % across, i / across);
        let off = offs[i] as usize;
        let len = counts[i] as usize;
        let data = off
            .checked_add(len)
            .and_then(|end| bytes.get(off..end))
            .ok_or_else(|| {
                Error::malformed(format!(
                    "{} {i}: {len} bytes at offset {off} run past the end of the {}-byte file (truncated?)",
                    if matches!(g.layout, Layout::Strips { .. }) { "strip" } else { "tile" },
                    bytes.len()
                ))
            })?;
        out.push(Block {
            x: bx * bw,
            y: by * bh,
            w: bw,
            h: bh,
            data,
        });
    }
    let kind = if matches!(g.layout, Layout::Strips { .. }) {
        "strip"
    } else {
        "tile"
    };
    check_disjoint(&offs[..n], &counts[..n], kind)?;
    Ok(out)
}

/// Error when two strips or tiles share bytes: each must have its own data. Repeated or
/// overlapping ranges are how a tiny file claims a huge image (a decompression bomb), so
/// they are refused before anything is allocated for the pixels. Empty ranges share nothing.
fn check_disjoint(offs: &[u32], counts: &[u32], kind: &str) -> Result<()> {
    let mut order: Vec<usize> = (0..offs.len()).filter(|&i| counts[i] > 0).collect();
    order.sort_unstable_by_key(|&i| (offs[i], i));
    for pair in order.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let a_end = u64::from(offs[a]) + u64::from(counts[a]);
        if u64::from(offs[b]) < a_end {
            let (first, second) = (a.min(b), a.max(b));
            return Err(Error::malformed(format!(
                "{kind}s {first} and {second} overlap ({kind} {a}: bytes {}..{a_end}, \
                 {kind} {b}: from byte {}): each {kind} must have its own data \
                 (a decompression bomb?)",
                offs[a], offs[b]
            )));
        }
    }
    Ok(())
}

fn decode_pixels(bytes: &[u8], order: ByteOrder, raw: &Ifd, g: &Geometry) -> Result<Vec<u16>> {
    let (w, h) = (g.width as usize, g.height as usize);
    let blocks = blocks(bytes, raw, g)?;
    let bits = g.bits as usize;
    if g.compression == 1 {
        // Check that the data covers the image before allocating it.
        for (i, b) in blocks.iter().enumerate() {
            let rows = b.h.min(h - b.y.min(h));
            let need = row_bytes(b.w, bits).saturating_mul(rows);
            if b.data.len() < need {
                return Err(Error::malformed(format!(
                    "{} {i} holds {} bytes, {need} needed (truncated?)",
                    if matches!(g.layout, Layout::Strips { .. }) {
                        "strip"
                    } else {
                        "tile"
                    },
                    b.data.len()
                )));
            }
        }
    } else {
        let total: usize = blocks.iter().map(|b| b.data.len()).sum();
        if w.saturating_mul(h) > total.saturating_mul(8) {
            return Err(Error::malformed(format!(
                "{total} bytes of lossless JPEG data cannot hold a {w}x{h} image (truncated?)"
            )));
        }
    }
    let mut out = crate::limits::try_filled(0u16, w * h, "the raw pixels")?;
    let mut rowbuf = Vec::new();
    for b in &blocks {
        let vis_w = b.w.min(w.saturating_sub(b.x));
        let vis_h = b.h.min(h.saturating_sub(b.y));
        if vis_w == 0 || vis_h == 0 {
            continue;
        }
        if g.compression == 1 {
            let rb = row_bytes(b.w, bits);
            rowbuf.resize(b.w, 0);
            for (r, src) in b.data.chunks_exact(rb.max(1)).take(vis_h).enumerate() {
                let dst_start = (b.y + r) * w + b.x;
                let dst = &mut out[dst_start..dst_start + vis_w];
                if vis_w == b.w {
                    unpack_row(src, dst, bits, order);
                } else {
                    unpack_row(src, &mut rowbuf, bits, order);
                    dst.copy_from_slice(&rowbuf[..vis_w]);
                }
            }
        } else {
            let d = ljpeg::decode(b.data)?;
            if d.data.len() < b.w * vis_h.min(b.h) {
                return Err(Error::malformed(format!(
                    "lossless JPEG {}x{}x{} frame too small for a {}x{} block",
                    d.width, d.height, d.components, b.w, b.h
                )));
            }
            for (r, src) in d.data.chunks_exact(b.w).take(vis_h).enumerate() {
                let dst_start = (b.y + r) * w + b.x;
                out[dst_start..dst_start + vis_w].copy_from_slice(&src[..vis_w]);
            }
        }
    }
    Ok(out)
}

fn row_bytes(w: usize, bits: usize) -> usize {
    (w.saturating_mul(bits)).div_ceil(8)
}

/// Unpack one row of `dst.len()` samples: 8-bit bytes, 16-bit in file byte order, other
/// depths packed MSB-first (the DNG convention whatever the byte order).
pub fn unpack_row(src: &[u8], dst: &mut [u16], bits: usize, order: ByteOrder) {
    match bits {
        8 => {
            for (d, &s) in dst.iter_mut().zip(src) {
                *d = s as u16;
            }
        }
        16 => match order {
            ByteOrder::Little => {
                for (d, s) in dst.iter_mut().zip(src.chunks_exact(2)) {
                    *d = u16::from_le_bytes([s[0], s[1]]);
                }
            }
            ByteOrder::Big => {
                for (d, s) in dst.iter_mut().zip(src.chunks_exact(2)) {
                    *d = u16::from_be_bytes([s[0], s[1]]);
                }
            }
        },
        12 => {
            let pairs = dst.len() / 2;
            for (d, s) in dst.chunks_exact_mut(2).zip(src.chunks_exact(3)) {
                d[0] = (u16::from(s[0]) << 4) | (u16::from(s[1]) >> 4);
                d[1] = (u16::from(s[1] & 0x0F) << 8) | u16::from(s[2]);
            }
            if dst.len() % 2 == 1 {
                let i = pairs * 3;
                let a = src.get(i).copied().unwrap_or(0);
                let b = src.get(i + 1).copied().unwrap_or(0);
                if let Some(last) = dst.last_mut() {
                    *last = (u16::from(a) << 4) | (u16::from(b) >> 4);
                }
            }
        }
        10 => unpack_quads::<10>(src, dst),
        14 => unpack_quads::<14>(src, dst),
        _ => {
            // Eight samples of `bits` bits fill exactly `bits` bytes: decode whole groups
            // from a 128-bit big-endian word, then the tail bit by bit.
            let groups = (dst.len() / 8).min(src.len() / bits);
            let mask = (1u128 << bits) - 1;
            for (d, s) in dst
                .chunks_exact_mut(8)
                .zip(src.chunks_exact(bits))
                .take(groups)
            {
                let mut word = [0u8; 16];
                word[..bits].copy_from_slice(s);
                let v = u128::from_be_bytes(word);
                for (k, o) in d.iter_mut().enumerate() {
                    *o = ((v >> (128 - bits * (k + 1))) & mask) as u16;
                }
            }
            unpack_bits(
                &src[(groups * bits).min(src.len())..],
                &mut dst[groups * 8..],
                bits,
            );
        }
    }
}

/// Four `BITS`-bit samples fill exactly BITS/2 bytes (BITS even): decode whole groups from
/// a 64-bit big-endian word (constant-size copies, no per-sample branches), then the tail.
fn unpack_quads<const BITS: usize>(src: &[u8], dst: &mut [u16]) {
    let gb = BITS / 2;
    let groups = (dst.len() / 4).min(src.len() / gb);
    let mask = (1u64 << BITS) - 1;
    for (d, s) in dst
        .chunks_exact_mut(4)
        .zip(src.chunks_exact(gb))
        .take(groups)
    {
        let mut word = [0u8; 8];
        for (w, b) in word.iter_mut().zip(s) {
            *w = *b;
        }
        let v = u64::from_be_bytes(word);
        d[0] = ((v >> (64 - BITS)) & mask) as u16;
        d[1] = ((v >> (64 - 2 * BITS)) & mask) as u16;
        d[2] = ((v >> (64 - 3 * BITS)) & mask) as u16;
        d[3] = ((v >> (64 - 4 * BITS)) & mask) as u16;
    }
    let (s_done, d_done) = (groups * gb, groups * 4);
    unpack_bits(
        src.get(s_done..).unwrap_or(&[]),
        dst.get_mut(d_done..).unwrap_or(&mut []),
        BITS,
    );
}

/// Generic MSB-first unpacking (missing source bytes read as zero).
fn unpack_bits(src: &[u8], dst: &mut [u16], bits: usize) {
    let mut acc: u64 = 0;
    let mut n = 0usize;
    let mut it = src.iter();
    let mask = (1u64 << bits) - 1;
    for d in dst.iter_mut() {
        while n < bits {
            acc = (acc << 8) | u64::from(it.next().copied().unwrap_or(0));
            n += 8;
        }
        n -= bits;
        *d = ((acc >> n) & mask) as u16;
    }
}

// ---------------------------------------------------------------------------------------
// Metadata

/// Tags that describe the file's structure (offsets, sizes, pointers): never carried.
pub const STRUCTURAL_TAGS: &[u16] = &[
    NEW_SUBFILE_TYPE,
    IMAGE_WIDTH,
    IMAGE_LENGTH,
    BITS_PER_SAMPLE,
    COMPRESSION,
    PHOTOMETRIC_INTERPRETATION,
    STRIP_OFFSETS,
    SAMPLES_PER_PIXEL,
    ROWS_PER_STRIP,
    STRIP_BYTE_COUNTS,
    PLANAR_CONFIGURATION,
    PREDICTOR,
    TILE_WIDTH,
    TILE_LENGTH,
    TILE_OFFSETS,
    TILE_BYTE_COUNTS,
    SUB_IFDS,
    SAMPLE_FORMAT,
    JPEG_TABLES,
    EXIF_IFD,
    GPS_IFD,
    JPEG_IF_OFFSET, // thumbnail offset
    JPEG_IF_LENGTH,
    INTEROP_IFD, // Exif InteroperabilityIFD pointer
];

/// Tags decoded into typed [`RawMeta`] fields (so not carried as extras).
pub const MODELLED_TAGS: &[u16] = &[
    DNG_VERSION,
    DNG_BACKWARD_VERSION,
    MAKE,
    MODEL,
    UNIQUE_CAMERA_MODEL,
    ACTIVE_AREA,
    DEFAULT_CROP_ORIGIN,
    DEFAULT_CROP_SIZE,
    CFA_REPEAT_PATTERN_DIM,
    CFA_PATTERN,
    CFA_PLANE_COLOR,
    CFA_LAYOUT,
    LINEARIZATION_TABLE,
    BLACK_LEVEL_REPEAT_DIM,
    BLACK_LEVEL,
    BLACK_LEVEL_DELTA_H,
    BLACK_LEVEL_DELTA_V,
    WHITE_LEVEL,
    AS_SHOT_NEUTRAL,
    AS_SHOT_WHITE_XY,
    COLOR_MATRIX1,
    COLOR_MATRIX2,
    CAMERA_CALIBRATION1,
    CAMERA_CALIBRATION2,
    FORWARD_MATRIX1,
    FORWARD_MATRIX2,
    CALIBRATION_ILLUMINANT1,
    CALIBRATION_ILLUMINANT2,
    ANALOG_BALANCE,
    BASELINE_EXPOSURE,
    NOISE_PROFILE,
    ORIENTATION,
    OPCODE_LIST1,
    OPCODE_LIST2,
    OPCODE_LIST3,
];

/// Modelled tags whose stored form is kept in [`RawMeta::stored`] (written back unchanged
/// while their value is).
pub const STORED_TAGS: &[u16] = &[
    AS_SHOT_NEUTRAL,
    AS_SHOT_WHITE_XY,
    COLOR_MATRIX1,
    COLOR_MATRIX2,
    CAMERA_CALIBRATION1,
    CAMERA_CALIBRATION2,
    FORWARD_MATRIX1,
    FORWARD_MATRIX2,
    ANALOG_BALANCE,
    BASELINE_EXPOSURE,
];

/// Exif tags decoded into [`ExifInfo`].
pub const MODELLED_EXIF_TAGS: &[u16] = &[
    ISO_SPEED_RATINGS,
    EXPOSURE_TIME,
    F_NUMBER,
    DATE_TIME_ORIGINAL,
];

fn carried(ifd: &Ifd, skip_extra: &[u16]) -> Vec<Entry> {
    ifd.entries
        .iter()
        .filter(|e| {
            !STRUCTURAL_TAGS.contains(&e.tag)
                && !MODELLED_TAGS.contains(&e.tag)
                && !skip_extra.contains(&e.tag)
        })
        .cloned()
        .collect()
}

/// Look a tag up in the raw IFD first, then IFD0.
fn lookup<'a>(d: &Located<'a>, tag: u16) -> Option<&'a Value> {
    d.raw.get(tag).or_else(|| d.ifd0.get(tag))
}

fn floats(v: &Value, tag: u16) -> Result<Vec<f64>> {
    let f = v.to_f64_vec().ok_or_else(|| {
        Error::malformed(format!(
            "{} (tag {tag}) is not numeric or has a zero denominator",
            tag_name(tag)
        ))
    })?;
    if f.iter().any(|x| !x.is_finite()) {
        return Err(Error::malformed(format!(
            "{} (tag {tag}) holds a non-finite value",
            tag_name(tag)
        )));
    }
    Ok(f)
}

fn opt_floats(d: &Located<'_>, tag: u16) -> Result<Option<Vec<f64>>> {
    lookup(d, tag).map(|v| floats(v, tag)).transpose()
}

fn opt_matrix(d: &Located<'_>, tag: u16, rows: usize, cols: usize) -> Result<Option<Vec<f64>>> {
    match opt_floats(d, tag)? {
        Some(m) if m.len() != rows * cols => Err(Error::malformed(format!(
            "{} has {} values, expected {}x{}",
            tag_name(tag),
            m.len(),
            rows,
            cols
        ))),
        m => Ok(m),
    }
}

fn version4(v: Option<&Value>) -> Option<[u8; 4]> {
    let b = v?.to_u32_vec()?;
    let g = |i: usize| b.get(i).map(|&x| x as u8).unwrap_or(0);
    Some([g(0), g(1), g(2), g(3)])
}

fn build_meta(tiff: &Tiff, d: &Located<'_>, g: &Geometry) -> Result<RawMeta> {
    let raw = d.raw;
    let ifd0 = d.ifd0;
    let (w, h) = (g.width, g.height);

    // CFA.
    let dim = raw
        .require(CFA_REPEAT_PATTERN_DIM)?
        .to_u32_vec()
        .filter(|v| v.len() == 2)
        .ok_or_else(|| Error::malformed("CFARepeatPatternDim must be two SHORTs"))?;
    let (cr, cc) = (dim[0] as usize, dim[1] as usize);
    if cr == 0 || cc == 0 || cr > MAX_CFA_DIM || cc > MAX_CFA_DIM {
        return Err(Error::malformed(format!(
            "CFARepeatPatternDim {cr}x{cc} (1..{MAX_CFA_DIM} per side)"
        )));
    }
    let pattern: Vec<u8> = raw
        .require(CFA_PATTERN)?
        .to_u32_vec()
        .ok_or_else(|| Error::malformed("CFAPattern must be BYTEs"))?
        .into_iter()
        .map(|x| x.min(255) as u8)
        .collect();
    if pattern.len() != cr * cc {
        return Err(Error::malformed(format!(
            "CFAPattern has {} values for a {cr}x{cc} repeat",
            pattern.len()
        )));
    }
    let plane_color: Vec<u8> = match raw.get(CFA_PLANE_COLOR) {
        Some(v) => v
            .to_u32_vec()
            .ok_or_else(|| Error::malformed("CFAPlaneColor must be BYTEs"))?
            .into_iter()
            .map(|x| x.min(255) as u8)
            .collect(),
        None => vec![0, 1, 2],
    };
    if plane_color.is_empty() || plane_color.len() > 8 {
        return Err(Error::malformed(format!(
            "CFAPlaneColor has {} planes",
            plane_color.len()
        )));
    }
    let planes = plane_color.len();
    if let Some(&bad) = pattern.iter().find(|&&p| p as usize >= planes) {
        return Err(Error::malformed(format!(
            "CFAPattern value {bad} is not a colour plane (the CFA has {planes} planes: 0..{})",
            planes - 1
        )));
    }
    let layout = raw.u32(CFA_LAYOUT).unwrap_or(1) as u16;

    // Geometry tags.
    let active_area = match raw.get(ACTIVE_AREA) {
        Some(v) => {
            let a = v
                .to_u32_vec()
                .filter(|a| a.len() == 4)
                .ok_or_else(|| Error::malformed("ActiveArea must be four integers"))?;
            let r = Rect {
                top: a[0],
                left: a[1],
                bottom: a[2],
                right: a[3],
            };
            if r.top >= r.bottom || r.left >= r.right || r.bottom > h || r.right > w {
                return Err(Error::malformed(format!(
                    "ActiveArea {},{},{},{} is empty or outside the {w}x{h} image",
                    r.top, r.left, r.bottom, r.right
                )));
            }
            Some(r)
        }
        None => None,
    };
    let (aw, ah) = match active_area {
        Some(r) => (r.width(), r.height()),
        None => (w as usize, h as usize),
    };
    let pair = |tag: u16| -> Result<Option<[f64; 2]>> {
        match raw.get(tag).map(|v| floats(v, tag)).transpose()? {
            Some(p) if p.len() == 2 && p.iter().all(|&x| x >= 0.0) => Ok(Some([p[0], p[1]])),
            Some(p) => Err(Error::malformed(format!(
                "{} must be two non-negative numbers (got {:?})",
                tag_name(tag),
                p
            ))),
            None => Ok(None),
        }
    };
    let default_crop_origin = pair(DEFAULT_CROP_ORIGIN)?;
    let default_crop_size = pair(DEFAULT_CROP_SIZE)?;
    if let Some(s) = default_crop_size {
        if s[0] <= 0.0 || s[1] <= 0.0 {
            return Err(Error::malformed("DefaultCropSize is zero"));
        }
    }

    // Levels.
    let linearization_table = match raw.get(LINEARIZATION_TABLE) {
        Some(v) => {
            let t: Vec<u16> = v
                .to_u32_vec()
                .ok_or_else(|| Error::malformed("LinearizationTable must be SHORTs"))?
                .into_iter()
                .map(|x| x.min(65535) as u16)
                .collect();
            if t.is_empty() || t.len() > 65536 {
                return Err(Error::malformed(format!(
                    "LinearizationTable has {} entries (1..65536)",
                    t.len()
                )));
            }
            Some(t)
        }
        None => None,
    };
    let black_repeat = match raw.get(BLACK_LEVEL_REPEAT_DIM) {
        Some(v) => {
            let r = v
                .to_u32_vec()
                .filter(|a| a.len() == 2)
                .ok_or_else(|| Error::malformed("BlackLevelRepeatDim must be two integers"))?;
            let (a, b) = (r[0] as usize, r[1] as usize);
            if a == 0 || b == 0 || a > MAX_CFA_DIM || b > MAX_CFA_DIM {
                return Err(Error::malformed(format!(
                    "BlackLevelRepeatDim {a}x{b} (1..{MAX_CFA_DIM} per side)"
                )));
            }
            (a, b)
        }
        None => (1, 1),
    };
    let black = match raw.get(BLACK_LEVEL) {
        Some(v) => floats(v, BLACK_LEVEL)?,
        None => vec![0.0; black_repeat.0 * black_repeat.1],
    };
    if black.len() != black_repeat.0 * black_repeat.1 {
        return Err(Error::malformed(format!(
            "BlackLevel has {} values for BlackLevelRepeatDim {}x{}",
            black.len(),
            black_repeat.0,
            black_repeat.1
        )));
    }
    let delta = |tag: u16, n: usize| -> Result<Vec<f64>> {
        match raw.get(tag) {
            Some(v) => {
                let d = floats(v, tag)?;
                if d.len() != n {
                    return Err(Error::malformed(format!(
                        "{} has {} values, the active area needs {n}",
                        tag_name(tag),
                        d.len()
                    )));
                }
                Ok(d)
            }
            None => Ok(Vec::new()),
        }
    };
    let black_delta_h = delta(BLACK_LEVEL_DELTA_H, aw)?;
    let black_delta_v = delta(BLACK_LEVEL_DELTA_V, ah)?;
    let white = match raw.get(WHITE_LEVEL) {
        Some(v) => *floats(v, WHITE_LEVEL)?
            .first()
            .ok_or_else(|| Error::malformed("WhiteLevel is empty"))?,
        None => match &linearization_table {
            Some(t) => t.iter().copied().max().map_or(65535.0, f64::from),
            None => ((1u32 << g.bits) - 1) as f64,
        },
    };
    let levels = Levels {
        black_repeat,
        black,
        black_delta_h,
        black_delta_v,
        white,
    };
    levels.validate(aw, ah)?;

    // Colour.
    let n3 = planes;
    let as_shot_neutral = match lookup(d, AS_SHOT_NEUTRAL) {
        Some(v) => {
            let n = floats(v, AS_SHOT_NEUTRAL)?;
            if n.len() != n3 {
                return Err(Error::malformed(format!(
                    "AsShotNeutral has {} values for {n3} colour planes",
                    n.len()
                )));
            }
            if let Some(bad) = n.iter().find(|&&x| x <= 0.0 || !x.is_finite()) {
                return Err(Error::malformed(format!(
                    "AsShotNeutral component {bad} is not positive"
                )));
            }
            if n3 == 3 {
                Some([n[0] / n[1], 1.0, n[2] / n[1]])
            } else {
                None
            }
        }
        None => None,
    };
    let as_shot_white_xy = match lookup(d, AS_SHOT_WHITE_XY) {
        Some(v) => {
            let p = floats(v, AS_SHOT_WHITE_XY)?;
            if p.len() != 2 {
                return Err(Error::malformed("AsShotWhiteXY must hold two values"));
            }
            Some([p[0], p[1]])
        }
        None => None,
    };
    let illum = |tag: u16| {
        lookup(d, tag)
            .and_then(|v| v.get_u32(0))
            .map(|x| x.min(65535) as u16)
    };
    let analog_balance = opt_floats(d, ANALOG_BALANCE)?;
    if let Some(a) = &analog_balance {
        if a.len() != n3 {
            return Err(Error::malformed(format!(
                "AnalogBalance has {} values for {n3} planes",
                a.len()
            )));
        }
    }
    let color = ColorInfo {
        color_matrix1: opt_matrix(d, COLOR_MATRIX1, n3, 3)?,
        color_matrix2: opt_matrix(d, COLOR_MATRIX2, n3, 3)?,
        camera_calibration1: opt_matrix(d, CAMERA_CALIBRATION1, n3, n3)?,
        camera_calibration2: opt_matrix(d, CAMERA_CALIBRATION2, n3, n3)?,
        forward_matrix1: opt_matrix(d, FORWARD_MATRIX1, 3, n3)?,
        forward_matrix2: opt_matrix(d, FORWARD_MATRIX2, 3, n3)?,
        calibration_illuminant1: illum(CALIBRATION_ILLUMINANT1),
        calibration_illuminant2: illum(CALIBRATION_ILLUMINANT2),
        analog_balance,
        // Some writers (Magic Lantern) store 0/0 here: treated as absent (= 0 EV).
        baseline_exposure: lookup(d, BASELINE_EXPOSURE)
            .and_then(|v| v.get_f64(0))
            .filter(|x| x.is_finite()),
    };
    let noise_profile = match opt_floats(d, NOISE_PROFILE)? {
        Some(v) => {
            if v.len() != 2 && v.len() != 2 * n3 {
                return Err(Error::malformed(format!(
                    "NoiseProfile has {} values (expected 2 or {})",
                    v.len(),
                    2 * n3
                )));
            }
            Some(v.chunks_exact(2).map(|p| (p[0], p[1])).collect())
        }
        None => None,
    };
    let orientation = ifd0.u32(ORIENTATION).unwrap_or(1);
    let orientation = if (1..=8).contains(&orientation) {
        orientation as u16
    } else {
        1
    };

    // Exif (Exif IFD, falling back to TIFF/EP tags in IFD0).
    let exif_ifd = ifd0.exif.as_deref();
    let ex = |tag: u16| exif_ifd.and_then(|e| e.get(tag)).or_else(|| ifd0.get(tag));
    let exif = ExifInfo {
        iso: ex(ISO_SPEED_RATINGS)
            .and_then(|v| v.get_u32(0))
            .filter(|&i| i > 0),
        exposure_time: ex(EXPOSURE_TIME)
            .and_then(|v| v.get_f64(0))
            .filter(|&t| t > 0.0 && t.is_finite()),
        f_number: ex(F_NUMBER)
            .and_then(|v| v.get_f64(0))
            .filter(|&f| f > 0.0 && f.is_finite()),
        date_time_original: ex(DATE_TIME_ORIGINAL)
            .and_then(|v| v.as_string())
            .filter(|s| !s.is_empty()),
    };

    let opcode = |tag: u16| raw.get(tag).and_then(|v| v.as_bytes()).map(|b| b.to_vec());
    let dng_version = version4(ifd0.get(DNG_VERSION)).unwrap_or([1, 0, 0, 0]);
    let raw_in_sub = d.path.is_some();
    // TIFF/EP copies of the Exif fields in IFD0 are modelled too (the writer puts the
    // current values in the Exif IFD; a stale IFD0 copy would contradict them).
    let ifd0_extra = carried(ifd0, MODELLED_EXIF_TAGS);
    let raw_extra = if raw_in_sub {
        carried(raw, &[])
    } else {
        Vec::new()
    };
    let exif_extra = exif_ifd
        .map(|e| carried(e, MODELLED_EXIF_TAGS))
        .unwrap_or_default();
    // GPS tags (0..=31) have their own numbering: every readable entry is carried.
    let gps = ifd0
        .gps
        .as_deref()
        .map(|g| g.entries.clone())
        .unwrap_or_default();
    Ok(RawMeta {
        dng_version,
        dng_backward_version: version4(ifd0.get(DNG_BACKWARD_VERSION)),
        make: ifd0.string(MAKE),
        model: ifd0.string(MODEL),
        unique_camera_model: ifd0.string(UNIQUE_CAMERA_MODEL),
        bits_per_sample: g.bits,
        active_area,
        default_crop_origin,
        default_crop_size,
        cfa: CfaPattern {
            rows: cr,
            cols: cc,
            pattern,
            plane_color,
            layout,
        },
        linearization_table,
        levels,
        as_shot_neutral,
        as_shot_white_xy,
        color,
        noise_profile,
        orientation,
        exif,
        opcode_lists: [
            opcode(OPCODE_LIST1),
            opcode(OPCODE_LIST2),
            opcode(OPCODE_LIST3),
        ],
        ifd0_extra,
        raw_extra,
        exif_extra,
        gps,
        storage: Some(Storage {
            byte_order: tiff.byte_order,
            sub_ifd: d.path.clone(),
            layout: g.layout,
            compression: g.compression,
            predictor: raw.u32(PREDICTOR).map(|p| p as u16),
        }),
        stored: STORED_TAGS
            .iter()
            .filter_map(|&tag| {
                lookup(d, tag).map(|v| Entry {
                    tag,
                    value: v.clone(),
                })
            })
            .collect(),
    })
}

// ---------------------------------------------------------------------------------------
// Inspection (for `day2night info`)

/// Summary of one image IFD (IFD0, a SubIFD, a chained IFD).
#[derive(Debug, Clone, Serialize)]
pub struct IfdSummary {
    /// "IFD0", "IFD0/SubIFD1", "IFD1", ...
    pub path: String,
    /// NewSubFileType (0 = main image, 1 = preview).
    pub new_subfile_type: u32,
    /// ImageWidth.
    pub width: Option<u32>,
    /// ImageLength.
    pub height: Option<u32>,
    /// BitsPerSample (first).
    pub bits_per_sample: Option<u32>,
    /// SamplesPerPixel.
    pub samples_per_pixel: u32,
    /// Compression code.
    pub compression: u16,
    /// Compression name.
    pub compression_name: &'static str,
    /// PhotometricInterpretation code.
    pub photometric: Option<u16>,
    /// Its name.
    pub photometric_name: &'static str,
    /// "strips" or "tiles WxH".
    pub layout: String,
    /// Number of entries.
    pub entries: usize,
}

/// Summary of a readable raw image.
#[derive(Debug, Clone, Serialize)]
pub struct RawSummary {
    /// Stored width.
    pub width: usize,
    /// Stored height.
    pub height: usize,
    /// Bayer pattern name ("RGGB") or the raw pattern description.
    pub cfa: String,
    /// Everything else (pixel-free).
    pub meta: MetaSummary,
}

/// The modelled metadata (RawMeta without the carried entries).
#[derive(Debug, Clone, Serialize)]
pub struct MetaSummary {
    /// Bits per sample.
    pub bits_per_sample: u16,
    /// ActiveArea.
    pub active_area: Option<Rect>,
    /// DefaultCropOrigin.
    pub default_crop_origin: Option<[f64; 2]>,
    /// DefaultCropSize.
    pub default_crop_size: Option<[f64; 2]>,
    /// CFA description.
    pub cfa_pattern: CfaPattern,
    /// LinearizationTable length.
    pub linearization_table_len: Option<usize>,
    /// Levels.
    pub levels: Levels,
    /// AsShotNeutral (green = 1).
    pub as_shot_neutral: Option<[f64; 3]>,
    /// AsShotWhiteXY.
    pub as_shot_white_xy: Option<[f64; 2]>,
    /// Colour tags.
    pub color: ColorInfo,
    /// NoiseProfile pairs.
    pub noise_profile: Option<Vec<(f64, f64)>>,
    /// Orientation.
    pub orientation: u16,
    /// Exif fields.
    pub exif: ExifInfo,
    /// Which OpcodeLists are present (1, 2, 3).
    pub opcode_lists: Vec<u8>,
    /// Storage of the raw.
    pub storage: Option<Storage>,
    /// Counts of carried entries (IFD0, raw IFD, Exif).
    pub carried_entries: [usize; 3],
    /// Entries of the GPS IFD (0: none), carried into written DNGs.
    pub gps_entries: usize,
}

/// What `day2night info` reports about a file.
#[derive(Debug, Clone, Serialize)]
pub struct DngInfo {
    /// "little-endian" or "big-endian".
    pub byte_order: &'static str,
    /// DNGVersion as "1.4.0.0", if present.
    pub dng_version: Option<String>,
    /// Make.
    pub make: Option<String>,
    /// Model.
    pub model: Option<String>,
    /// UniqueCameraModel.
    pub unique_camera_model: Option<String>,
    /// Every image IFD found.
    pub ifds: Vec<IfdSummary>,
    /// Path of the main (NewSubFileType 0) IFD, if any.
    pub raw_ifd: Option<String>,
    /// The decoded raw, when it could be read.
    pub raw: Option<RawSummary>,
    /// True when `synth` can use this file (a readable 2x2 Bayer CFA raw).
    pub synth_ready: bool,
    /// Why not, when `synth_ready` is false.
    pub reason: Option<String>,
    /// Set when the raw data itself is unreadable (unsupported compression, malformed,
    /// over the limits): `info` reports it as an error (exit code 1).
    pub error: Option<String>,
}

fn summarize(path: String, ifd: &Ifd, out: &mut Vec<IfdSummary>) {
    let compression = ifd.u32(COMPRESSION).unwrap_or(1) as u16;
    let photometric = ifd.u32(PHOTOMETRIC_INTERPRETATION).map(|p| p as u16);
    let raw_kind = matches!(photometric, Some(PHOTOMETRIC_CFA | PHOTOMETRIC_LINEAR_RAW));
    let compression_name = if compression == 7 && !raw_kind {
        "JPEG"
    } else {
        compression_name(compression)
    };
    let layout = match (ifd.u32(TILE_WIDTH), ifd.u32(TILE_LENGTH)) {
        (Some(w), Some(h)) => format!("tiles {w}x{h}"),
        _ => "strips".to_string(),
    };
    out.push(IfdSummary {
        path: path.clone(),
        new_subfile_type: ifd.u32(NEW_SUBFILE_TYPE).unwrap_or(0),
        width: ifd.u32(IMAGE_WIDTH),
        height: ifd.u32(IMAGE_LENGTH),
        bits_per_sample: ifd.u32(BITS_PER_SAMPLE),
        samples_per_pixel: ifd.u32(SAMPLES_PER_PIXEL).unwrap_or(1),
        compression,
        compression_name,
        photometric,
        photometric_name: photometric.map_or("none", photometric_name),
        layout,
        entries: ifd.entries.len(),
    });
    for (i, s) in ifd.sub_ifds.iter().enumerate() {
        summarize(format!("{path}/SubIFD{i}"), s, out);
    }
}

/// Describe any parseable DNG (or TIFF), including ones synthesis cannot use.
/// Errors only when the file is not a parseable TIFF.
pub fn inspect_bytes(bytes: &[u8]) -> Result<DngInfo> {
    let tiff = parse(bytes)?;
    let ifd0 = tiff.ifd0();
    let mut ifds = Vec::new();
    for (i, ifd) in tiff.ifds.iter().enumerate() {
        summarize(format!("IFD{i}"), ifd, &mut ifds);
    }
    let mut info = DngInfo {
        byte_order: match tiff.byte_order {
            ByteOrder::Little => "little-endian",
            ByteOrder::Big => "big-endian",
        },
        dng_version: version4(ifd0.get(DNG_VERSION))
            .map(|v| format!("{}.{}.{}.{}", v[0], v[1], v[2], v[3])),
        make: ifd0.string(MAKE),
        model: ifd0.string(MODEL),
        unique_camera_model: ifd0.string(UNIQUE_CAMERA_MODEL),
        ifds,
        raw_ifd: None,
        raw: None,
        synth_ready: false,
        reason: None,
        error: None,
    };
    let located = match locate(&tiff) {
        Ok(l) => l,
        Err(e) => {
            info.reason = Some(e.to_string());
            info.error = Some(e.to_string());
            return Ok(info);
        }
    };
    info.raw_ifd = Some(match &located.path {
        None => "IFD0".to_string(),
        Some(p) => {
            let mut s = "IFD0".to_string();
            for i in p {
                s.push_str(&format!("/SubIFD{i}"));
            }
            s
        }
    });
    let photometric = located.raw.u32(PHOTOMETRIC_INTERPRETATION).unwrap_or(0) as u16;
    if let Err(e) = check_photometric(photometric) {
        // A well-formed DNG of another kind (LinearRaw, ...): described, not an error.
        info.reason = Some(e.to_string());
        return Ok(info);
    }
    match read_dng_bytes(bytes) {
        Ok(img) => {
            let m = &img.meta;
            let bayer = img.bayer();
            info.raw = Some(RawSummary {
                width: img.width,
                height: img.height,
                cfa: match &bayer {
                    Ok(b) => b.name(),
                    Err(_) => format!(
                        "{}x{} pattern {:?} planes {:?}",
                        m.cfa.rows, m.cfa.cols, m.cfa.pattern, m.cfa.plane_color
                    ),
                },
                meta: MetaSummary {
                    bits_per_sample: m.bits_per_sample,
                    active_area: m.active_area,
                    default_crop_origin: m.default_crop_origin,
                    default_crop_size: m.default_crop_size,
                    cfa_pattern: m.cfa.clone(),
                    linearization_table_len: m.linearization_table.as_ref().map(|t| t.len()),
                    levels: m.levels.clone(),
                    as_shot_neutral: m.as_shot_neutral,
                    as_shot_white_xy: m.as_shot_white_xy,
                    color: m.color.clone(),
                    noise_profile: m.noise_profile.clone(),
                    orientation: m.orientation,
                    exif: m.exif.clone(),
                    opcode_lists: (1..=3u8)
                        .filter(|&i| m.opcode_lists[i as usize - 1].is_some())
                        .collect(),
                    storage: m.storage.clone(),
                    carried_entries: [m.ifd0_extra.len(), m.raw_extra.len(), m.exif_extra.len()],
                    gps_entries: m.gps.len(),
                },
            });
            match bayer {
                Ok(_) => info.synth_ready = true,
                Err(e) => info.reason = Some(e.to_string()),
            }
        }
        Err(e) => {
            info.reason = Some(e.to_string());
            info.error = Some(e.to_string());
        }
    }
    Ok(info)
}

/// [`inspect_bytes`] on a file (errors name the file).
pub fn inspect(path: &Path) -> Result<DngInfo> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io(e).in_file(path))?;
    inspect_bytes(&bytes).in_file(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unpack_packed_depths() {
        // 12-bit: 0xABC, 0x123, 0x456 -> AB C1 23 45 6(0)
        let src = [0xAB, 0xC1, 0x23, 0x45, 0x60];
        let mut d = [0u16; 3];
        unpack_row(&src, &mut d, 12, ByteOrder::Little);
        assert_eq!(d, [0xABC, 0x123, 0x456]);
        // 10-bit: 0x3FF, 0x001 -> 11111111 11000000 0001(0000)
        let src = [0xFF, 0xC0, 0x10];
        let mut d = [0u16; 2];
        unpack_row(&src, &mut d, 10, ByteOrder::Big);
        assert_eq!(d, [0x3FF, 0x001]);
        // 11-bit (generic path), 8 samples + 1 tail
        let vals: Vec<u16> = (0..9).map(|i| (i * 229 + 5) as u16 & 0x7FF).collect();
        let mut packed = Vec::new();
        let (mut acc, mut n) = (0u64, 0);
        for &v in &vals {
            acc = (acc << 11) | v as u64;
            n += 11;
            while n >= 8 {
                packed.push((acc >> (n - 8)) as u8);
                n -= 8;
            }
        }
        packed.push((acc << (8 - n)) as u8);
        let mut d = [0u16; 9];
        unpack_row(&packed, &mut d, 11, ByteOrder::Little);
        assert_eq!(&d[..], &vals[..]);
        // 14-bit: 0x2AAA, 0x1555 -> 10101010 10101001 01010101 0101(0000)
        let src = [0xAA, 0xA9, 0x55, 0x50];
        let mut d = [0u16; 2];
        unpack_row(&src, &mut d, 14, ByteOrder::Little);
        assert_eq!(d, [0x2AAA, 0x1555]);
        let mut d = [0u16; 1];
        unpack_row(&[0x12, 0x34], &mut d, 16, ByteOrder::Big);
        assert_eq!(d, [0x1234]);
        unpack_row(&[0x12, 0x34], &mut d, 16, ByteOrder::Little);
        assert_eq!(d, [0x3412]);
    }
}
