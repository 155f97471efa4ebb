//! Writing a raw whose samples come from a [`RowSource`], strip by strip: a batch of strips
//! is made, packed and hashed in parallel, written, and dropped before the next batch, so
//! neither the samples nor the packed strips are ever held whole. The bytes are the same as
//! [`super::encode_dng`] of the same samples: the layout depends only on the strip sizes,
//! which are known before any sample is made, and RawDataUniqueID (which hashes every
//! strip) is written as a placeholder of its final length and filled in by a seek once the
//! last strip is written.
//!
//! Used for the default layout (uncompressed strips in IFD0). Lossless JPEG tiles, the
//! SubIFD layout with its thumbnail, fixture tiles, and a source whose sample bound does not
//! decide the stored bit depth are written from a whole plane instead ([`super::write_dng_rows`]).

use super::*;
use crate::raw::rows::RowSource;
use std::io::{Seek, SeekFrom, Write};

/// Packed bytes made in one parallel batch before they are written (about 8 strips).
const BATCH_BYTES: usize = 8 << 20;

/// The stored bit depth of uncompressed strips when every sample is at most `bound`:
/// None when the depth depends on the exact maximum (`bound` does not fit the source's
/// depth but the samples might) and `exact` is false.
pub(super) fn strip_bits(m: &RawMeta, bound: u16, exact: bool, opts: &WriteOptions) -> Option<u16> {
    let src_bits = m.bits_per_sample;
    let fit_bits = if (bound as u32) < (1u32 << src_bits) {
        src_bits
    } else if exact {
        16
    } else {
        return None;
    };
    Some(if !opts.unpacked16 {
        fit_bits
    } else if fit_bits <= 8 {
        8
    } else {
        16
    })
}

/// True when `opts` asks for the layout [`write_streamed`] writes.
pub(super) fn streams(opts: &WriteOptions) -> bool {
    opts.compression == Compression::None
        && opts.raw_ifd == RawIfd::Main
        && opts.uncompressed_tiles.is_none()
}

/// Rows per strip of a `w`-wide raw at `bits` bits (the same rule as the whole-plane path).
pub(super) fn rows_per_strip(w: usize, h: usize, bits: u16, opts: &WriteOptions) -> Result<usize> {
    let row_bytes = (w * bits as usize).div_ceil(8).max(1);
    match opts.rows_per_strip {
        Some(0) => Err(Error::invalid("rows per strip must be positive")),
        Some(r) => Ok((r as usize).min(h)),
        None => Ok(STRIP_BYTES.div_ceil(row_bytes).clamp(1, h)),
    }
}

/// Write `src` with metadata `m` as uncompressed strips of `bits` bits in IFD0 (the caller
/// has checked [`streams`] and chosen `bits` with [`strip_bits`] from `bound`, the source's
/// [`RowSource::max_bound`]).
pub(super) fn write_streamed(
    m: &RawMeta,
    src: &dyn RowSource,
    (bits, bound): (u16, u16),
    path: &Path,
    opts: &WriteOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    let (w, h) = (src.width(), src.height());
    let order = byte_order(opts);
    let big = order == ByteOrder::Big;
    let rps = rows_per_strip(w, h, bits, opts)?;
    let row_bytes = (w * bits as usize).div_ceil(8).max(1);
    let nstrips = h.div_ceil(rps);
    let sizes: Vec<u32> = (0..nstrips)
        .map(|i| {
            let rows = rps.min(h - i * rps);
            u32::try_from(packed_len(w, rows, bits, row_bytes))
                .map_err(|_| Error::limits("strip larger than 4 GiB"))
        })
        .collect::<Result<_>>()?;
    let part = RawPart {
        width: w,
        height: h,
        chunks: Chunks::StreamedStrips(sizes),
        bits,
        compression: 1,
        layout_tags: vec![(t::ROWS_PER_STRIP, Value::Long(vec![rps as u32]))],
    };
    // RawDataUniqueID hashes every strip: a placeholder of its length for now.
    let ifd0 = assemble(m, part, vec![0; UNIQUE_ID_LEN], None);
    let per_batch = (BATCH_BYTES / (rps * row_bytes).max(1)).max(1);
    let make = |first: usize| -> Result<Vec<(Vec<u8>, ChunkDigest)>> {
        (first..(first + per_batch).min(nstrips))
            .into_par_iter()
            .map(|s| make_strip(src, s, (rps, bits, big, bound), opts.unique_id))
            .collect()
    };
    crate::output::write_atomic(path, policy, |f| {
        let tail = write_tiff_head(order, &[ifd0], f)?;
        if tail.strips.len() != nstrips {
            return Err(Error::invalid("the streamed strips were not laid out"));
        }
        let mut digests: Vec<ChunkDigest> = Vec::with_capacity(nstrips);
        let mut pos = tail.written;
        // Batch k is written while batch k + 1 is made.
        let mut batch = make(0)?;
        let mut first = 0;
        while !batch.is_empty() {
            let next_first = first + batch.len();
            let (written, next) = rayon::join(
                || -> Result<u64> {
                    let mut p = pos;
                    for ((bytes, _), &(off, len)) in batch.iter().zip(&tail.strips[first..]) {
                        if bytes.len() as u64 != len {
                            return Err(Error::invalid("a streamed strip has the wrong size"));
                        }
                        f.write_all(&vec![0u8; off.saturating_sub(p) as usize])?;
                        f.write_all(bytes)?;
                        p = off + len;
                    }
                    Ok(p)
                },
                || {
                    if next_first < nstrips {
                        make(next_first)
                    } else {
                        Ok(Vec::new())
                    }
                },
            );
            pos = written?;
            digests.extend(batch.into_iter().map(|(_, d)| d));
            batch = next?;
            first = next_first;
        }
        f.write_all(&vec![0u8; tail.end.saturating_sub(pos) as usize])?;
        // The ID hashes every strip: written now over its placeholder.
        let at = tail
            .ifd0_value_offset(t::RAW_DATA_UNIQUE_ID)
            .ok_or_else(|| Error::invalid("RawDataUniqueID was not written out of line"))?;
        let id = raw_data_unique_id(m, (w, h), false, &digests, opts.unique_id);
        f.seek(SeekFrom::Start(at))?;
        f.write_all(&id)?;
        f.seek(SeekFrom::Start(tail.end))?;
        Ok(())
    })
}

/// Strip `s` (rows from `s * rps`) of `src`, packed at `bits` bits, with its digest.
fn make_strip(
    src: &dyn RowSource,
    s: usize,
    (rps, bits, big, bound): (usize, u16, bool, u16),
    hash: UniqueIdHash,
) -> Result<(Vec<u8>, ChunkDigest)> {
    let (w, h) = (src.width(), src.height());
    let y0 = s * rps;
    let rows = rps.min(h - y0);
    let packed = match src.plane() {
        Some(p) => pack_rows(&p[y0 * w..(y0 + rows) * w], w, bits, big),
        None => {
            let mut buf = crate::limits::try_filled(0u16, rows * w, "a strip")?;
            src.fill_rows(y0, &mut buf);
            // The depth was chosen from the bound before any row existed: a sample above
            // it would be packed wrong, so it is an error, not a silently different file.
            // (the maximum first: a loop of whole-register maxima, where a search stops
            // at every sample to test it)
            let max = buf.iter().fold(0u16, |m, &v| m.max(v));
            if max > bound {
                return Err(Error::invalid(format!(
                    "sample {max} in rows {y0}.. exceeds the source's bound {bound}"
                )));
            }
            pack_rows(&buf, w, bits, big)
        }
    };
    Ok(hashed(packed, hash))
}

/// Bytes of `rows` packed rows of `w` samples (as [`pack_rows`] makes them).
fn packed_len(w: usize, rows: usize, bits: u16, row_bytes: usize) -> usize {
    match bits {
        16 => w * rows * 2,
        8 => w * rows,
        _ => row_bytes * rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::rows::PlaneRows;
    use crate::raw::Bayer;

    use super::super::tests::sample_image_upto as image;

    /// The rows of a plane without the plane (made on demand) and with a chosen bound.
    struct Made<'a>(&'a RawImage, u16);
    impl RowSource for Made<'_> {
        fn width(&self) -> usize {
            self.0.width
        }
        fn height(&self) -> usize {
            self.0.height
        }
        fn max_bound(&self) -> u16 {
            self.1
        }
        fn fill_rows(&self, y0: usize, out: &mut [u16]) {
            PlaneRows::new(self.0).fill_rows(y0, out)
        }
    }

    #[test]
    fn streamed_files_equal_the_encoded_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let policy = OutputPolicy::default();
        let mut n = 0;
        for (w, h) in [(1, 1), (3, 5), (37, 29), (64, 300)] {
            for bits in [8u16, 10, 12, 14, 16] {
                for max in [(1u32 << bits) - 1, 65535] {
                    let img = image(w, h, bits, max);
                    for (big, unpacked16, rps) in [
                        (false, false, None),
                        (true, false, Some(7)),
                        (false, true, Some(1)),
                    ] {
                        let opts = WriteOptions {
                            big_endian: big,
                            unpacked16,
                            rows_per_strip: rps,
                            ..WriteOptions::default()
                        };
                        let want = encode_dng(&img, &opts).unwrap();
                        let p = dir.path().join(format!("{n}.dng"));
                        n += 1;
                        write_dng(&img, &p, &opts, &policy).unwrap();
                        assert_eq!(std::fs::read(&p).unwrap(), want, "{w}x{h} {bits} {max}");
                        // Made on demand: streamed when the bound decides the depth, else
                        // from a plane; the same bytes either way.
                        for bound in [max.min(65535) as u16, 65535] {
                            let p = dir.path().join(format!("{n}.dng"));
                            n += 1;
                            write_dng_rows(&img.meta, &Made(&img, bound), &p, &opts, &policy)
                                .unwrap();
                            assert_eq!(std::fs::read(&p).unwrap(), want, "rows {w}x{h} {bits}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_bound_above_the_depth_is_decided_by_the_exact_maximum() {
        let m = RawMeta::new_bayer(Bayer::RGGB, 10, 0.0, 1023.0);
        let o = WriteOptions::default();
        assert_eq!(strip_bits(&m, 1023, false, &o), Some(10));
        assert_eq!(strip_bits(&m, 1024, false, &o), None);
        assert_eq!(strip_bits(&m, 1024, true, &o), Some(16));
        let u = WriteOptions {
            unpacked16: true,
            ..o
        };
        assert_eq!(strip_bits(&m, 1023, false, &u), Some(16));
    }

    #[test]
    fn a_failing_streamed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let img = image(16, 300, 10, 1023);
        let p = dir.path().join("x.dng");
        let policy = OutputPolicy::default();
        let opts = WriteOptions {
            rows_per_strip: Some(8),
            ..WriteOptions::default()
        };
        // refused before anything is written: an ActiveArea outside the image
        let mut bad = img.meta.clone();
        bad.active_area = Some(crate::raw::Rect {
            top: 0,
            left: 0,
            bottom: 301,
            right: 16,
        });
        assert!(write_dng_rows(&bad, &Made(&img, 1023), &p, &opts, &policy).is_err());
        // failing after the header and some strips: a source exceeding its bound
        let err = write_dng_rows(&img.meta, &Made(&img, 5), &p, &opts, &policy).unwrap_err();
        assert!(
            err.to_string().contains("exceeds the source's bound"),
            "{err}"
        );
        assert!(err.to_string().contains("x.dng"), "{err}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
