//! Pixel decoding: the raw IFD's geometry, its strips or tiles (refused when their byte
//! ranges overlap or repeat), uncompressed and packed samples, lossless JPEG; JPEG XL
//! (jxl.rs) and lossy JPEG (jpeg.rs) blocks are decoded by their own modules.

use super::*;

pub(super) struct Geometry {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) bits: u16,
    pub(super) compression: u16,
    pub(super) layout: Layout,
    /// 1 (CFA) or 3 (LinearRaw, chunky).
    pub(super) samples_per_pixel: u16,
}

pub(super) fn geometry(raw: &Ifd) -> Result<Geometry> {
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
    let linear_raw = raw.u32(PHOTOMETRIC_INTERPRETATION) == Some(u32::from(PHOTOMETRIC_LINEAR_RAW));
    if linear_raw {
        super::linear_raw::check_layout(raw, spp)?;
    } else if spp != 1 {
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
    check_compression(compression, bits)?;
    if compression == COMPRESSION_LOSSY_JPEG && !linear_raw {
        return Err(Error::malformed(
            "lossy JPEG (34892) in a CFA raw: the DNG specification allows it for LinearRaw \
             (demosaiced) images only",
        ));
    }
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
        samples_per_pixel: spp as u16,
    })
}

// ---------------------------------------------------------------------------------------
// Pixels

/// One strip or tile: its place in the image and its bytes.
pub(super) struct Block<'a> {
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    data: &'a [u8],
}

/// One strip or tile: its place in the image and where its bytes lie in the file.
pub(super) struct BlockAt {
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    off: usize,
    len: usize,
}

impl BlockAt {
    fn with<'a>(&self, data: &'a [u8]) -> Block<'a> {
        Block {
            x: self.x,
            y: self.y,
            w: self.w,
            h: self.h,
            data,
        }
    }
}

pub(super) fn blocks<'a>(bytes: &'a [u8], raw: &Ifd, g: &Geometry) -> Result<Vec<Block<'a>>> {
    Ok(block_ranges(bytes.len(), raw, g)?
        .iter()
        // block_ranges checked every range against the file's length
        .map(|b| b.with(bytes.get(b.off..b.off + b.len).unwrap_or_default()))
        .collect())
}

/// The strips or tiles of the raw IFD in a file of `file_len` bytes, each range checked to
/// lie inside the file and to share no byte with another.
pub(super) fn block_ranges(file_len: usize, raw: &Ifd, g: &Geometry) -> Result<Vec<BlockAt>> {
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
        if off.checked_add(len).is_none_or(|end| end > file_len) {
            return Err(Error::malformed(format!(
                "{} {i}: {len} bytes at offset {off} run past the end of the {file_len}-byte file (truncated?)",
                if matches!(g.layout, Layout::Strips { .. }) { "strip" } else { "tile" },
            )));
        }
        out.push(BlockAt {
            x: bx * bw,
            y: by * bh,
            w: bw,
            h: bh,
            off,
            len,
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
pub(super) fn check_disjoint(offs: &[u32], counts: &[u32], kind: &str) -> Result<()> {
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

pub(super) fn decode_pixels(
    bytes: &[u8],
    order: ByteOrder,
    raw: &Ifd,
    g: &Geometry,
) -> Result<Vec<u16>> {
    let blocks = blocks(bytes, raw, g)?;
    if matches!(g.compression, COMPRESSION_JPEG_XL | COMPRESSION_LOSSY_JPEG) {
        return decode_codec_blocks(&blocks, g);
    }
    let lens: Vec<_> = blocks
        .iter()
        .map(|b| (b.y, b.h, b.w, b.data.len()))
        .collect();
    let mut out = alloc_checked(&lens, g)?;
    let mut rowbuf = Vec::new();
    for b in &blocks {
        decode_block(b, order, g, &mut out, &mut rowbuf)?;
    }
    Ok(out)
}

/// True when [`decode_pixels_from`] can decode the blocks of `g` one at a time (the
/// uncompressed and lossless JPEG ones; JPEG XL and lossy JPEG blocks are decoded in
/// parallel from the whole file's bytes).
pub(super) fn streamable(g: &Geometry) -> bool {
    !matches!(g.compression, COMPRESSION_JPEG_XL | COMPRESSION_LOSSY_JPEG)
}

/// [`decode_pixels`] of the blocks `ranges` (from [`block_ranges`]) whose bytes `read`
/// fetches one block at a time (from the file, after its whole bytes were dropped): the
/// same samples, holding one block's bytes beside the plane. Only for [`streamable`]
/// geometries.
pub(super) fn decode_pixels_from(
    ranges: &[BlockAt],
    order: ByteOrder,
    g: &Geometry,
    mut read: impl FnMut(usize, &mut Vec<u8>) -> Result<()>,
) -> Result<Vec<u16>> {
    let lens: Vec<_> = ranges.iter().map(|b| (b.y, b.h, b.w, b.len)).collect();
    let mut out = alloc_checked(&lens, g)?;
    let (mut rowbuf, mut buf) = (Vec::new(), Vec::new());
    for r in ranges {
        buf.clear();
        buf.resize(r.len, 0);
        read(r.off, &mut buf)?;
        decode_block(&r.with(&buf), order, g, &mut out, &mut rowbuf)?;
    }
    Ok(out)
}

/// Check that the blocks (row, height, width, byte count) can hold the image, then
/// allocate it.
fn alloc_checked(blocks: &[(usize, usize, usize, usize)], g: &Geometry) -> Result<Vec<u16>> {
    // Samples per row of the image and of a block: pixels x samples per pixel (1 for CFA).
    let spp = g.samples_per_pixel as usize;
    let (w, h) = (g.width as usize * spp, g.height as usize);
    let bits = g.bits as usize;
    if g.compression == 1 {
        // Check that the data covers the image before allocating it.
        for (i, &(by, bh, bw, len)) in blocks.iter().enumerate() {
            let rows = bh.min(h - by.min(h));
            let need = row_bytes(bw * spp, bits).saturating_mul(rows);
            if len < need {
                return Err(Error::malformed(format!(
                    "{} {i} holds {len} bytes, {need} needed (truncated?)",
                    if matches!(g.layout, Layout::Strips { .. }) {
                        "strip"
                    } else {
                        "tile"
                    },
                )));
            }
        }
    } else {
        let total: usize = blocks.iter().map(|b| b.3).sum();
        if w.saturating_mul(h) > total.saturating_mul(8) {
            return Err(Error::malformed(format!(
                "{total} bytes of lossless JPEG data cannot hold a {}x{h} image (truncated?)",
                g.width
            )));
        }
    }
    crate::limits::try_filled(0u16, w * h, "the raw pixels")
}

/// Decode one uncompressed or lossless JPEG block into its place in `out`.
fn decode_block(
    b: &Block<'_>,
    order: ByteOrder,
    g: &Geometry,
    out: &mut [u16],
    rowbuf: &mut Vec<u16>,
) -> Result<()> {
    let spp = g.samples_per_pixel as usize;
    let (w, h) = (g.width as usize * spp, g.height as usize);
    let bits = g.bits as usize;
    let (bx, bw) = (b.x * spp, b.w * spp);
    let vis_w = bw.min(w.saturating_sub(bx));
    let vis_h = b.h.min(h.saturating_sub(b.y));
    if vis_w == 0 || vis_h == 0 {
        return Ok(());
    }
    if g.compression == 1 {
        let rb = row_bytes(bw, bits);
        rowbuf.resize(bw, 0);
        for (r, src) in b.data.chunks_exact(rb.max(1)).take(vis_h).enumerate() {
            let dst_start = (b.y + r) * w + bx;
            let dst = &mut out[dst_start..dst_start + vis_w];
            if vis_w == bw {
                unpack_row(src, dst, bits, order);
            } else {
                unpack_row(src, rowbuf, bits, order);
                dst.copy_from_slice(&rowbuf[..vis_w]);
            }
        }
    } else {
        let d = ljpeg::decode(b.data)?;
        if d.data.len() < bw * vis_h.min(b.h) {
            return Err(Error::malformed(format!(
                "lossless JPEG {}x{}x{} frame too small for a {}x{} block",
                d.width, d.height, d.components, b.w, b.h
            )));
        }
        for (r, src) in d.data.chunks_exact(bw).take(vis_h).enumerate() {
            let dst_start = (b.y + r) * w + bx;
            out[dst_start..dst_start + vis_w].copy_from_slice(&src[..vis_w]);
        }
    }
    Ok(())
}

/// JPEG XL or lossy JPEG blocks: each decoded on its own (rows of blocks in parallel, so
/// the result does not depend on the thread count) to exactly the block's size, then its
/// visible part copied (edge tiles are cropped).
fn decode_codec_blocks(blocks: &[Block<'_>], g: &Geometry) -> Result<Vec<u16>> {
    use rayon::prelude::*;
    let spp = g.samples_per_pixel as usize;
    let (w, h) = (g.width as usize, g.height as usize);
    let stride = w * spp;
    let kind = if matches!(g.layout, Layout::Strips { .. }) {
        "strip"
    } else {
        "tile"
    };
    // Every block has the same size; tile sizes count against the pixel limit too (a
    // tile's codestream is decoded whole, its hidden part included).
    let (bw, bh) = blocks.first().map_or((0, 0), |b| (b.w, b.h));
    crate::limits::check_pixels(kind, bw as u64, bh as u64)?;
    let mut out = crate::limits::try_filled(0u16, stride * h, "the raw pixels")?;
    let band = bh.max(1) * stride;
    let per_row = blocks.iter().filter(|b| b.y == 0).count().max(1);
    out.par_chunks_mut(band)
        .enumerate()
        .try_for_each(|(row, dst)| -> Result<()> {
            for (k, b) in blocks.iter().enumerate().skip(row * per_row).take(per_row) {
                let vis_w = b.w.min(w.saturating_sub(b.x));
                let vis_h = b.h.min(h.saturating_sub(b.y));
                if vis_w == 0 || vis_h == 0 {
                    continue;
                }
                let what = format!("{kind} {k}");
                // A tile is coded whole; the last strip holds only the image's last rows.
                let coded_h = if kind == "strip" { vis_h } else { b.h };
                let px = if g.compression == COMPRESSION_JPEG_XL {
                    super::jxl::decode(b.data, b.w, coded_h, spp, &what)?
                } else {
                    super::jpeg::decode(b.data, b.w, coded_h, spp, &what)?
                };
                for (r, src) in px.chunks_exact(b.w * spp).take(vis_h).enumerate() {
                    let start = r * stride + b.x * spp;
                    dst[start..start + vis_w * spp].copy_from_slice(&src[..vis_w * spp]);
                }
            }
            Ok(())
        })?;
    Ok(out)
}

pub(super) fn row_bytes(w: usize, bits: usize) -> usize {
    (w.saturating_mul(bits)).div_ceil(8)
}

/// Unpack one row of `dst.len()` samples: 8-bit bytes, 16-bit in file byte order, other
/// depths packed MSB-first (the DNG convention whatever the byte order).
///
/// Compiled twice, the second time for AVX2 and BMI1/2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2+bmi1+bmi2+lzcnt"))]
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
pub(super) fn unpack_quads<const BITS: usize>(src: &[u8], dst: &mut [u16]) {
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
pub(super) fn unpack_bits(src: &[u8], dst: &mut [u16], bits: usize) {
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
