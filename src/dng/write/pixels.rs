//! The raw samples as stored: uncompressed strips (packed to the source's bit depth or
//! 16-bit) or lossless JPEG tiles, each with its digest for RawDataUniqueID.

use super::*;

/// Encode the samples: (chunks, their digests for RawDataUniqueID, BitsPerSample, Compression, layout tags).
pub(super) fn encode_pixels(
    img: &RawImage,
    opts: &WriteOptions,
    order: ByteOrder,
) -> Result<Pixels> {
    let (w, h) = (img.width, img.height);
    let max = crate::raw::rows::plane_max(&img.data);
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
            let tiles: Vec<(Vec<u8>, ChunkDigest)> = (0..nx * ny)
                .into_par_iter()
                .map(|i| {
                    let tile = extract_tile(img, (i % nx) * tw, (i / nx) * th, tw, th);
                    ljpeg_encode::encode(&tile, tw / 2, th, 2, precision as u8)
                        .map(|b| hashed(b, opts.unique_id))
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
                        hashed(pack_rows(&tile, tw, bits, big), opts.unique_id)
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
            let rps = super::stream::rows_per_strip(w, h, bits, opts)?;
            let strips: Vec<(Vec<u8>, ChunkDigest)> = img
                .data
                .par_chunks(rps * w)
                .map(|rows| hashed(pack_rows(rows, w, bits, big), opts.unique_id))
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
pub(super) fn extract_tile(img: &RawImage, x0: usize, y0: usize, tw: usize, th: usize) -> Vec<u16> {
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
///
/// Compiled twice, the second time for AVX2 and BMI1/2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2+bmi1+bmi2+lzcnt"))]
pub(super) fn pack_rows(samples: &[u16], w: usize, bits: u16, big: bool) -> Vec<u8> {
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
pub(super) fn pack4<const BITS: u32, const NB: usize>(
    row: &[u16],
    out: &mut [u8],
) -> (usize, usize) {
    let n = (row.len() / 4).min(out.len() / NB);
    let m = (1u64 << BITS) - 1;
    for (j, g) in row.chunks_exact(4).take(n).enumerate() {
        let v = (g[0] as u64 & m) << (3 * BITS)
            | (g[1] as u64 & m) << (2 * BITS)
            | (g[2] as u64 & m) << BITS
            | (g[3] as u64 & m);
        let o = j * NB;
        // One 8-byte store, its group's bytes first: the next group overwrites the rest
        // (one store instead of a 4- and a 1-byte one). The last groups, with fewer than
        // 8 bytes left in the row, store exactly their own.
        match out.get_mut(o..o + 8) {
            Some(d) => d.copy_from_slice(&(v << (64 - 4 * BITS)).to_be_bytes()),
            None => out[o..o + NB].copy_from_slice(&v.to_be_bytes()[8 - NB..]),
        }
    }
    (n * 4, n * NB)
}

/// Pack one row MSB-first into `out` (exactly `ceil(len * bits / 8)` bytes).
pub(super) fn pack_row(row: &[u16], out: &mut [u8], bits: u16) {
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
