//! Our own single-part scan-line OpenEXR encoder for the common compressions: none, ZIPS
//! (zlib, 1 line per block) and ZIP (zlib, 16 lines per block), half or 32-bit float
//! samples, channels B, G, R (alphabetical, as OpenEXR stores them).
//!
//! File layout (OpenEXR file layout document, "Scan Line Images"):
//! magic `76 2f 31 01`, version 2 (+ the long-names flag when a name exceeds 31 bytes),
//! the header (attributes `name\0 type\0 i32 size value`, sorted by name, ended by a 0 byte),
//! the offset table (one u64 absolute file offset per block), then the blocks in increasing
//! line order, each `i32 first line, i32 data size, data`.
//!
//! Block data: per scan line, per channel, `width` little-endian samples. ZIP/ZIPS then
//! split the bytes into even/odd halves, replace each byte by its difference to the previous
//! one (+128) and zlib-compress the result (level [`super::ExrOptions::zip_level`] 1: our own
//! run-length + Huffman encoder, [`crate::deflate`]; 2..=9: miniz_oxide at that level);
//! a block whose compressed form is not smaller than the raw bytes is stored raw, as
//! OpenEXR's own writer does (readers tell them apart by the size).
//!
//! Blocks are converted (RGB rows -> planar samples, sanitized) and compressed in parallel
//! with rayon, one block per task, and collected in order: the bytes do not depend on the
//! thread count.

use super::{ExrCompression, ExrOptions, HALF_MAX};
use crate::error::{Error, Result};
use crate::isp::RgbImage;
use rayon::prelude::*;
use std::io::{Seek, SeekFrom, Write};

/// Attribute names the encoder writes itself or that OpenEXR reserves for multi-part,
/// tiled or deep files; callers cannot set them.
pub(crate) const RESERVED: [&str; 16] = [
    "channels",
    "chromaticities",
    "chunkCount",
    "compression",
    "dataWindow",
    "displayWindow",
    "lineOrder",
    "maxSamplesPerPixel",
    "name",
    "pixelAspectRatio",
    "screenWindowCenter",
    "screenWindowWidth",
    "software",
    "tiles",
    "type",
    "version",
];

/// Longest attribute name OpenEXR accepts (with the long-names flag).
const MAX_NAME: usize = 255;

/// Scan lines per block of a compression this encoder handles, `None` for the others.
pub(crate) fn lines_per_block(c: ExrCompression) -> Option<usize> {
    match c {
        ExrCompression::None | ExrCompression::Zips => Some(1),
        ExrCompression::Zip => Some(16),
        _ => None,
    }
}

/// Check caller attribute names: not empty, no NUL, at most 255 bytes, not reserved, no
/// duplicates.
pub(crate) fn check_attributes(attributes: &[(String, String)]) -> Result<()> {
    let mut seen = std::collections::BTreeSet::new();
    for (k, _) in attributes {
        if k.is_empty() {
            return Err(Error::invalid("EXR attribute with an empty name"));
        }
        if k.contains('\0') || k.len() > MAX_NAME {
            return Err(Error::invalid(format!(
                "EXR attribute name {k:?}: NUL byte or longer than {MAX_NAME} bytes"
            )));
        }
        if RESERVED.contains(&k.as_str()) {
            return Err(Error::invalid(format!(
                "EXR attribute name {k:?} is reserved (written by the encoder)"
            )));
        }
        if !seen.insert(k.as_str()) {
            return Err(Error::invalid(format!("duplicate EXR attribute {k:?}")));
        }
    }
    Ok(())
}

fn i32_of(v: usize, what: &str) -> Result<i32> {
    i32::try_from(v).map_err(|_| Error::limits(format!("EXR {what} {v} exceeds 2^31-1")))
}

/// One header attribute: name, type name, value bytes.
type Attr = (String, &'static str, Vec<u8>);

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn i32s(v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Magic, version and the sorted header, ended by its 0 byte.
fn header(
    width: usize,
    height: usize,
    opts: &ExrOptions,
    attributes: &[(String, String)],
) -> Result<Vec<u8>> {
    let (xmax, ymax) = (i32_of(width - 1, "width")?, i32_of(height - 1, "height")?);
    let pixel_type: i32 = if opts.half { 1 } else { 2 };
    let mut chlist = Vec::with_capacity(55);
    for name in [b'B', b'G', b'R'] {
        chlist.extend_from_slice(&[name, 0]);
        chlist.extend_from_slice(&pixel_type.to_le_bytes());
        chlist.extend_from_slice(&[0, 0, 0, 0]); // pLinear, reserved
        chlist.extend_from_slice(&i32s(&[1, 1])); // x/y sampling
    }
    chlist.push(0);
    let compression = match opts.compression {
        ExrCompression::Zips => 2u8,
        ExrCompression::Zip => 3,
        _ => 0,
    };
    let window = i32s(&[0, 0, xmax, ymax]);
    let mut attrs: Vec<Attr> = vec![
        ("channels".into(), "chlist", chlist),
        (
            "chromaticities".into(),
            "chromaticities",
            // Rec.709 primaries, D65 white
            f32s(&[0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290]),
        ),
        ("compression".into(), "compression", vec![compression]),
        ("dataWindow".into(), "box2i", window.clone()),
        ("displayWindow".into(), "box2i", window),
        ("lineOrder".into(), "lineOrder", vec![0]), // increasing y
        ("pixelAspectRatio".into(), "float", f32s(&[1.0])),
        ("screenWindowCenter".into(), "v2f", f32s(&[0.0, 0.0])),
        ("screenWindowWidth".into(), "float", f32s(&[1.0])),
        (
            "software".into(),
            "string",
            crate::software_name().into_bytes(),
        ),
    ];
    for (k, v) in attributes {
        attrs.push((k.clone(), "string", v.as_bytes().to_vec()));
    }
    attrs.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    let long_names = attrs.iter().any(|a| a.0.len() > 31);
    let mut out = vec![
        0x76,
        0x2f,
        0x31,
        0x01,
        2,
        if long_names { 4 } else { 0 },
        0,
        0,
    ];
    for (name, ty, value) in &attrs {
        out.extend_from_slice(name.as_bytes());
        out.push(0);
        out.extend_from_slice(ty.as_bytes());
        out.push(0);
        out.extend_from_slice(&i32_of(value.len(), "attribute size")?.to_le_bytes());
        out.extend_from_slice(value);
    }
    out.push(0);
    Ok(out)
}

/// NaN -> 0, everything else clamped to +-`limit`.
#[inline]
fn sane(v: f32, limit: f32) -> f32 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(-limit, limit)
    }
}

/// The half bits of a finite `v` with `|v| <= HALF_MAX`, rounded to nearest even: the same
/// result as `f16::from_f32` (tested) without its general Inf/NaN paths (F. Giesen,
/// "float_to_half_fast3_rtne").
#[inline]
fn half_bits(v: f32) -> u16 {
    let bits = v.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let abs = bits & 0x7fff_ffff;
    let mag = if abs < 113 << 23 {
        // subnormal half or zero: align the 10 mantissa bits at the bottom with a magic
        // addition (round to nearest even by the FPU), then subtract the magic's bits
        const MAGIC: u32 = ((127 - 15) + (23 - 10) + 1) << 23;
        (f32::from_bits(abs) + f32::from_bits(MAGIC))
            .to_bits()
            .wrapping_sub(MAGIC)
    } else {
        // rebias the exponent and round to nearest even in the integer domain
        let odd = (abs >> 13) & 1;
        abs.wrapping_add(((15u32.wrapping_sub(127)) << 23).wrapping_add(0xfff) + odd) >> 13
    };
    sign | mag as u16
}

/// Fill `raw` with the little-endian planar samples (B, G, R per line) of the interleaved
/// RGB `rows` (`w` pixels each), sanitized ([`sane`]) to the half or f32 range.
fn fill_block(rows: &[f32], w: usize, half: bool, raw: &mut Vec<u8>) {
    let lines = rows.len() / (3 * w);
    let bps = if half { 2 } else { 4 };
    raw.clear();
    raw.resize(lines * 3 * w * bps, 0);
    let rows = rows.chunks_exact(3 * w);
    for (line, row) in raw.chunks_exact_mut(3 * w * bps).zip(rows) {
        let (b, gr) = line.split_at_mut(w * bps);
        let (g, r) = gr.split_at_mut(w * bps);
        if half {
            let planes = b
                .chunks_exact_mut(2)
                .zip(g.chunks_exact_mut(2))
                .zip(r.chunks_exact_mut(2));
            for (((b, g), r), px) in planes.zip(row.chunks_exact(3)) {
                if let [pr, pg, pb] = *px {
                    r.copy_from_slice(&half_bits(sane(pr, HALF_MAX)).to_le_bytes());
                    g.copy_from_slice(&half_bits(sane(pg, HALF_MAX)).to_le_bytes());
                    b.copy_from_slice(&half_bits(sane(pb, HALF_MAX)).to_le_bytes());
                }
            }
        } else {
            let planes = b
                .chunks_exact_mut(4)
                .zip(g.chunks_exact_mut(4))
                .zip(r.chunks_exact_mut(4));
            for (((b, g), r), px) in planes.zip(row.chunks_exact(3)) {
                if let [pr, pg, pb] = *px {
                    r.copy_from_slice(&sane(pr, f32::MAX).to_le_bytes());
                    g.copy_from_slice(&sane(pg, f32::MAX).to_le_bytes());
                    b.copy_from_slice(&sane(pb, f32::MAX).to_le_bytes());
                }
            }
        }
    }
}

/// OpenEXR's ZIP preprocessing of `raw` into `tmp`: even bytes then odd bytes, then each
/// byte replaced by `byte - previous + 128` (mod 256).
fn predict(raw: &[u8], tmp: &mut Vec<u8>) {
    tmp.clear();
    tmp.resize(raw.len(), 0);
    let (first, second) = tmp.split_at_mut(raw.len().div_ceil(2));
    for (d, s) in first.iter_mut().zip(raw.iter().step_by(2)) {
        *d = *s;
    }
    for (d, s) in second.iter_mut().zip(raw.iter().skip(1).step_by(2)) {
        *d = *s;
    }
    delta(tmp);
}

/// [`fill_block`] (half samples) followed by [`predict`]'s byte split, in one pass: the low
/// byte of planar sample `j` goes to `tmp[j]`, the high byte to `tmp[n + j]` (`n` samples),
/// exactly where the split of the little-endian planar bytes puts them. The delta step is
/// left to the caller. Compiled twice, the second time for AVX2, picked at run time (the
/// same bytes: the conversion is integer arithmetic and one f32 addition).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn fill_split_half(rows: &[f32], w: usize, tmp: &mut Vec<u8>) {
    let lines = rows.len() / (3 * w);
    let n = lines * 3 * w;
    tmp.clear();
    tmp.resize(2 * n, 0);
    let (lo, hi) = tmp.split_at_mut(n);
    let rows = rows.chunks_exact(3 * w);
    for ((lo, hi), row) in lo
        .chunks_exact_mut(3 * w)
        .zip(hi.chunks_exact_mut(3 * w))
        .zip(rows)
    {
        // planes B, G, R of this line
        let (lb, lgr) = lo.split_at_mut(w);
        let (lg, lr) = lgr.split_at_mut(w);
        let (hb, hgr) = hi.split_at_mut(w);
        let (hg, hr) = hgr.split_at_mut(w);
        let planes = lb
            .iter_mut()
            .zip(lg.iter_mut())
            .zip(lr.iter_mut())
            .zip(hb.iter_mut())
            .zip(hg.iter_mut())
            .zip(hr.iter_mut());
        for ((((((lb, lg), lr), hb), hg), hr), px) in planes.zip(row.chunks_exact(3)) {
            if let [pr, pg, pb] = *px {
                [*lr, *hr] = half_bits(sane(pr, HALF_MAX)).to_le_bytes();
                [*lg, *hg] = half_bits(sane(pg, HALF_MAX)).to_le_bytes();
                [*lb, *hb] = half_bits(sane(pb, HALF_MAX)).to_le_bytes();
            }
        }
    }
}

/// OpenEXR's delta step of [`predict`], in place.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn delta(tmp: &mut [u8]) {
    let mut prev = match tmp.first() {
        Some(&p) => p,
        None => return,
    };
    for t in tmp.iter_mut().skip(1) {
        let cur = *t;
        *t = cur.wrapping_sub(prev).wrapping_add(128);
        prev = cur;
    }
}

/// The zlib stream of `data` at `level`: 1 = day2night's own run-length + Huffman encoder
/// ([`crate::deflate`]: about 3x faster than miniz_oxide's level 1 on predicted half
/// samples, and smaller), 2..=9 = miniz_oxide at that level.
fn zlib(data: &[u8], level: u8) -> Vec<u8> {
    if level <= 1 {
        crate::deflate::compress_zlib_rle_to_vec(data)
    } else {
        miniz_oxide::deflate::compress_to_vec_zlib(data, level)
    }
}

/// The stored bytes of the block made of the interleaved RGB `rows` (`w` pixels each).
fn encode_block(
    rows: &[f32],
    w: usize,
    opts: &ExrOptions,
    scratch: &mut (Vec<u8>, Vec<u8>),
) -> Vec<u8> {
    let (raw, tmp) = scratch;
    if opts.half && opts.compression != ExrCompression::None {
        fill_split_half(rows, w, tmp);
        delta(tmp);
        let packed = zlib(tmp, opts.zip_level);
        if packed.len() < tmp.len() {
            return packed;
        }
        // incompressible: OpenEXR stores the plain samples
        fill_block(rows, w, true, raw);
        return std::mem::take(raw);
    }
    fill_block(rows, w, opts.half, raw);
    if opts.compression == ExrCompression::None {
        return std::mem::take(raw);
    }
    predict(raw, tmp);
    let packed = zlib(tmp, opts.zip_level);
    if packed.len() < raw.len() {
        packed
    } else {
        raw.clone()
    }
}

/// Encode `img` into `out` (see the module docs). `opts.compression` must be one of
/// [`lines_per_block`]'s; the attributes must have passed [`check_attributes`].
pub(crate) fn encode<W: Write>(
    img: &RgbImage,
    out: &mut W,
    opts: &ExrOptions,
    attributes: &[(String, String)],
) -> Result<()> {
    let lpb = check_blocks(img.width, img.height, opts)?;
    let w = img.width;
    let nblocks = img.height.div_ceil(lpb);
    let blocks: Vec<Vec<u8>> = (0..nblocks)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |scratch, b| {
                let y0 = b * lpb;
                let lines = lpb.min(img.height - y0);
                encode_block(
                    &img.data[3 * w * y0..3 * w * (y0 + lines)],
                    w,
                    opts,
                    scratch,
                )
            },
        )
        .collect();
    write_blocks(out, img.width, img.height, opts, attributes, &blocks)
}

/// Lines per block of `opts.compression` (own encoder only), after checking that the
/// largest block of a `w` x `h` image fits the i32 size field.
fn check_blocks(w: usize, h: usize, opts: &ExrOptions) -> Result<usize> {
    let lpb = lines_per_block(opts.compression).ok_or_else(|| {
        Error::unsupported(format!("own EXR encoder: compression {}", opts.compression))
    })?;
    let bps = if opts.half { 2 } else { 4 };
    let block_bytes = 3usize
        .checked_mul(bps * lpb.min(h))
        .and_then(|v| v.checked_mul(w))
        .ok_or_else(|| Error::limits("EXR block size overflows"))?;
    i32_of(block_bytes, "block size")?;
    Ok(lpb)
}

/// The stored blocks of the interleaved RGB `rows` (`w` pixels each) that start at image
/// line `first_row`, which must be a multiple of the compression's lines per block: the
/// same bytes [`encode`] makes for these lines of the whole image.
pub(crate) fn encode_rows(
    rows: &[f32],
    w: usize,
    first_row: usize,
    opts: &ExrOptions,
) -> Result<Vec<Vec<u8>>> {
    let lpb = lines_per_block(opts.compression).ok_or_else(|| {
        Error::unsupported(format!("own EXR encoder: compression {}", opts.compression))
    })?;
    if w == 0 || !first_row.is_multiple_of(lpb) || !rows.len().is_multiple_of(3 * w) {
        return Err(Error::invalid(format!(
            "EXR rows: first row {first_row} not a multiple of {lpb} lines, or a partial line"
        )));
    }
    let mut scratch = (Vec::new(), Vec::new());
    Ok(rows
        .chunks(3 * w * lpb)
        .map(|block| encode_block(block, w, opts, &mut scratch))
        .collect())
}

/// Write the header, offset table and `blocks` (all blocks of a `w` x `h` image, in line
/// order, as made by [`encode_rows`] or [`encode`]).
pub(crate) fn write_blocks<W: Write>(
    out: &mut W,
    w: usize,
    h: usize,
    opts: &ExrOptions,
    attributes: &[(String, String)],
    blocks: &[Vec<u8>],
) -> Result<()> {
    let lpb = check_blocks(w, h, opts)?;
    let nblocks = h.div_ceil(lpb);
    if blocks.len() != nblocks {
        return Err(Error::invalid(format!(
            "EXR of {h} lines needs {nblocks} blocks, got {}",
            blocks.len()
        )));
    }
    let head = header(w, h, opts, attributes)?;
    let mut offset = (head.len() + 8 * nblocks) as u64;
    let mut table = Vec::with_capacity(8 * nblocks);
    for blk in blocks {
        table.extend_from_slice(&offset.to_le_bytes());
        offset += 8 + blk.len() as u64;
    }
    out.write_all(&head)?;
    out.write_all(&table)?;
    for (b, blk) in blocks.iter().enumerate() {
        out.write_all(&i32_of(b * lpb, "line")?.to_le_bytes())?;
        out.write_all(&i32_of(blk.len(), "block size")?.to_le_bytes())?;
        out.write_all(blk)?;
    }
    Ok(())
}

/// A scan-line EXR written while its blocks are made, in line order, without holding them:
/// [`BlockStream::begin`] writes the header and a zeroed offset table, [`BlockStream::push`]
/// appends each block (`i32 first line, i32 size, data`) and records its offset, and
/// [`BlockStream::finish`] seeks back to fill in the table. The bytes are those of
/// [`write_blocks`] for the same blocks (tested).
#[derive(Debug)]
pub(crate) struct BlockStream {
    lpb: usize,
    height: usize,
    nblocks: usize,
    /// File offset of the offset table (= header length).
    table_at: u64,
    /// File offset of the next block.
    pos: u64,
    /// Offsets of the blocks pushed so far.
    offsets: Vec<u64>,
}

impl BlockStream {
    /// Write the header of a `w` x `h` image and a zeroed offset table into `out`, which
    /// must be at the start of the file.
    pub(crate) fn begin<W: Write>(
        out: &mut W,
        w: usize,
        h: usize,
        opts: &ExrOptions,
        attributes: &[(String, String)],
    ) -> Result<BlockStream> {
        let lpb = check_blocks(w, h, opts)?;
        let nblocks = h.div_ceil(lpb);
        let head = header(w, h, opts, attributes)?;
        out.write_all(&head)?;
        out.write_all(&vec![0u8; 8 * nblocks])?;
        Ok(BlockStream {
            lpb,
            height: h,
            nblocks,
            table_at: head.len() as u64,
            pos: (head.len() + 8 * nblocks) as u64,
            offsets: Vec::with_capacity(nblocks),
        })
    }

    /// The first image line of the next block.
    pub(crate) fn next_line(&self) -> usize {
        self.offsets.len() * self.lpb
    }

    /// Append the next block (as made by [`encode_rows`]).
    pub(crate) fn push<W: Write>(&mut self, out: &mut W, block: &[u8]) -> Result<()> {
        if self.offsets.len() == self.nblocks {
            return Err(Error::invalid(format!(
                "EXR of {} blocks given another one",
                self.nblocks
            )));
        }
        out.write_all(&i32_of(self.next_line(), "line")?.to_le_bytes())?;
        out.write_all(&i32_of(block.len(), "block size")?.to_le_bytes())?;
        out.write_all(block)?;
        self.offsets.push(self.pos);
        self.pos += 8 + block.len() as u64;
        Ok(())
    }

    /// Check that every block was pushed and write the offset table; `out` is left at the
    /// end of the file.
    pub(crate) fn finish<W: Write + Seek>(self, out: &mut W) -> Result<()> {
        if self.offsets.len() != self.nblocks {
            return Err(Error::invalid(format!(
                "EXR of {} lines needs {} blocks, got {}",
                self.height,
                self.nblocks,
                self.offsets.len()
            )));
        }
        let table: Vec<u8> = self.offsets.iter().flat_map(|o| o.to_le_bytes()).collect();
        out.seek(SeekFrom::Start(self.table_at))?;
        out.write_all(&table)?;
        out.seek(SeekFrom::Start(self.pos))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_conversion_matches_the_half_crate() {
        use exr::prelude::f16;
        let check = |v: f32| {
            let s = sane(v, HALF_MAX);
            assert_eq!(
                half_bits(s),
                f16::from_f32(s).to_bits(),
                "{v:e} ({:#x})",
                v.to_bits()
            );
        };
        // a stride over all f32 bit patterns (both signs, every exponent), plus the edges
        // of rounding: halfway cases around half's subnormal/normal boundary and the max
        for bits in (0..=u32::MAX).step_by(9973) {
            check(f32::from_bits(bits));
        }
        for e in [-26i32, -25, -24, -15, -14, -13, 0, 10, 15] {
            for k in -4i32..=4 {
                let base = 2f32.powi(e);
                check(base + k as f32 * base / 2048.0);
                check(-(base + k as f32 * base / 4096.0));
            }
        }
        for v in [
            0.0, -0.0, 65504.0, 65519.0, 65520.0, 1e-8, 5.96e-8, 2.98e-8, 6.1e-5,
        ] {
            check(v);
            check(-v);
        }
    }

    #[test]
    fn predictor_matches_openexr_reference() {
        // reference: ImfZip.cpp compress() on bytes 10 20 30 40 50
        let raw = [10u8, 20, 30, 40, 50];
        let mut tmp = Vec::new();
        predict(&raw, &mut tmp);
        // reordered: 10 30 50 20 40
        let re = [10u8, 30, 50, 20, 40];
        let mut want = vec![re[0]];
        for i in 1..5 {
            want.push((re[i] as i32 - re[i - 1] as i32 + 384) as u8);
        }
        assert_eq!(tmp, want);
    }

    #[test]
    fn fused_half_split_equals_fill_then_predict() {
        for (w, h) in [(1usize, 1usize), (7, 3), (33, 17), (4, 16)] {
            let mut img = RgbImage::new(w, h);
            for (i, v) in img.data.iter_mut().enumerate() {
                *v = match i % 11 {
                    0 => f32::NAN,
                    1 => f32::INFINITY,
                    2 => -1e9,
                    3 => 6.1e-5,
                    4 => -3.0e-8,
                    _ => ((i * 7919) % 1000) as f32 / 97.0 - 2.0,
                };
            }
            for (y0, lines) in [(0, h), (h / 2, h - h / 2)] {
                let (mut raw, mut want, mut got) = (Vec::new(), Vec::new(), Vec::new());
                let rows = &img.data[3 * w * y0..3 * w * (y0 + lines)];
                fill_block(rows, w, true, &mut raw);
                predict(&raw, &mut want);
                fill_split_half(rows, w, &mut got);
                delta(&mut got);
                assert_eq!(got, want, "{w}x{h} from {y0}");
            }
        }
    }

    #[test]
    fn header_sorts_and_flags_long_names() {
        let opts = ExrOptions::default();
        let h = header(3, 2, &opts, &[("a".into(), "x".into())]).unwrap();
        assert_eq!(&h[..8], &[0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0]);
        assert_eq!(h.last(), Some(&0));
        let long = "x".repeat(40);
        let h = header(3, 2, &opts, &[(long, "y".into())]).unwrap();
        assert_eq!(h[5], 4);
    }

    #[test]
    fn attribute_names_are_checked() {
        let ok = |k: &str| check_attributes(&[(k.to_string(), "v".to_string())]);
        assert!(ok("day2night:source").is_ok());
        assert!(ok("").is_err());
        assert!(ok("software").is_err());
        assert!(ok("chunkCount").is_err());
        assert!(ok("a\0b").is_err());
        assert!(ok(&"n".repeat(256)).is_err());
        let dup = [("k".to_string(), "1".to_string()), ("k".into(), "2".into())];
        assert!(check_attributes(&dup).is_err());
    }
}
