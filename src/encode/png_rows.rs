//! 8-bit RGB PNG files written from row groups that are filtered and compressed
//! independently (PNG specification, 3rd edition: chunks, filtering, and the zlib stream of
//! IDAT). Why not the `png` crate: its encoder takes the whole image and deflates it on one
//! thread, so for `synth` it was the single-threaded tail of the run; here each group of
//! rows is filtered and compressed where it is produced (a band of the render, while it is
//! in cache, on any thread), and the file is the concatenation of the pieces.
//!
//! - Filtering: per row, the filter type (None, Sub, Up, Average, Paeth) whose output has
//!   the smallest sum of absolute values as signed bytes (the usual heuristic); the first row
//!   of a group has no previous row in the group, so it chooses between None and Sub only.
//! - Compression: each group is one segment of a raw DEFLATE stream
//!   ([`crate::deflate::Encoder::compress_segment`]: non-final blocks, byte-aligned end);
//!   the file's zlib stream is the header `78 01`, the segments in order, a final empty
//!   block and the Adler-32 combined from the groups' ([`crate::deflate::adler32_combine`]).
//! - Chunks: IHDR (8-bit RGB, no interlace), `sRGB` (rendering intent perceptual) for sRGB
//!   output or `gAMA` 1/2.2 for gamma 2.2 output, one IDAT per group, IEND.
//!
//! The bytes depend only on the pixels and the group height (tests/it/png_rows.rs checks the
//! files in OpenImageIO and scikit-image); [`write_png_rgb8`] uses groups of
//! [`crate::isp::render::BAND`] rows, as the band-wise synth targets do, so both give the
//! same file for the same image.

use crate::deflate::{adler32, adler32_combine, Encoder, FINAL_EMPTY_BLOCK};
use crate::error::{Error, Result, ResultExt};
use crate::isp::tone::DisplayTone;
use crate::output::{write_atomic, AtomicFile, OutputPolicy};
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;

/// Bytes per pixel (8-bit RGB).
const BPP: usize = 3;

/// One group of rows, filtered and compressed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PngRows {
    /// Raw DEFLATE segment of the filtered rows.
    deflate: Vec<u8>,
    /// Adler-32 of the filtered rows.
    adler: u32,
    /// Length of the filtered rows (1 + 3 * width bytes per row).
    len: u64,
    /// Rows in the group.
    rows: usize,
}

impl PngRows {
    /// Filter and compress `rgb` (whole rows of `width` 8-bit RGB pixels); `enc` is
    /// reusable scratch. An empty `rgb` gives an empty group.
    pub fn encode(rgb: &[u8], width: usize, enc: &mut Encoder) -> Result<PngRows> {
        let stride = width.checked_mul(BPP).unwrap_or(0);
        if stride == 0 || !rgb.len().is_multiple_of(stride) {
            return Err(Error::invalid(format!(
                "PNG rows of {width} RGB pixels need a multiple of {stride} bytes, got {}",
                rgb.len()
            )));
        }
        let rows = rgb.len() / stride;
        let mut filtered = Vec::with_capacity(rows * (stride + 1));
        let mut scratch = Scratch::new(stride);
        let mut prev: Option<&[u8]> = None;
        for row in rgb.chunks_exact(stride) {
            scratch.filter(row, prev, &mut filtered);
            prev = Some(row);
        }
        let mut deflate = Vec::with_capacity(filtered.len() / 3 + 64);
        enc.compress_segment(&filtered, &mut deflate);
        Ok(PngRows {
            adler: adler32(&filtered),
            len: filtered.len() as u64,
            deflate,
            rows,
        })
    }

    /// Rows in the group.
    pub fn rows(&self) -> usize {
        self.rows
    }
}

/// The five candidate filtered rows of one image row.
struct Scratch {
    cand: [Vec<u8>; 5],
}

impl Scratch {
    fn new(stride: usize) -> Scratch {
        Scratch {
            cand: std::array::from_fn(|_| vec![0; stride]),
        }
    }

    /// Append the filter type byte and the filtered `row` with the best filter.
    fn filter(&mut self, row: &[u8], prev: Option<&[u8]>, out: &mut Vec<u8>) {
        filter_row(&mut self.cand, row, prev, out);
    }
}

/// [`Scratch::filter`]: written as zipped slices without per-byte branches so that the
/// compiler vectorizes it, and compiled twice, the second time for AVX2, picked at run
/// time (the same bytes: integer arithmetic only).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn filter_row(cand: &mut [Vec<u8>; 5], row: &[u8], prev: Option<&[u8]>, out: &mut Vec<u8>) {
    let [none, sub, up, avg, paeth] = &mut *cand;
    let n = row.len().min(BPP);
    none.copy_from_slice(row);
    sub[..n].copy_from_slice(&row[..n]);
    for ((o, &x), &a) in sub[n..].iter_mut().zip(&row[n..]).zip(row) {
        *o = x.wrapping_sub(a);
    }
    let kinds: &[u8] = match prev {
        None => &[0, 1],
        Some(p) => {
            for ((o, &x), &b) in up.iter_mut().zip(row).zip(p) {
                *o = x.wrapping_sub(b);
            }
            // the first pixel: left and upper-left are 0
            for i in 0..n {
                avg[i] = row[i].wrapping_sub(p[i] >> 1);
                paeth[i] = row[i].wrapping_sub(p[i]);
            }
            for ((((o, &x), &a), &b), (q, &c)) in avg[n..]
                .iter_mut()
                .zip(&row[n..])
                .zip(row)
                .zip(&p[n..])
                .zip(paeth[n..].iter_mut().zip(p))
            {
                *o = x.wrapping_sub(((u16::from(a) + u16::from(b)) >> 1) as u8);
                *q = x.wrapping_sub(paeth_predictor(a, b, c));
            }
            &[0, 1, 2, 3, 4]
        }
    };
    let mut best = 0u8;
    let mut best_cost = u64::MAX;
    for &k in kinds {
        let c = filter_cost(&cand[usize::from(k)]);
        if c < best_cost {
            best = k;
            best_cost = c;
        }
    }
    out.push(best);
    out.extend_from_slice(&cand[usize::from(best)]);
}

/// The sum of the absolute values of the filtered bytes read as i8 (the minimum-sum
/// heuristic), in u32 sums of 4,096 bytes. A function, not a closure, so that it is
/// inlined into [`filter_row`]'s AVX2 copy (a closure there was compiled apart and ran
/// slower than the plain build).
#[inline(always)]
fn filter_cost(v: &[u8]) -> u64 {
    let mut total = 0u64;
    for c in v.chunks(4096) {
        let mut sum = 0u32;
        for &b in c {
            sum += u32::from((b as i8).unsigned_abs());
        }
        total += u64::from(sum);
    }
    total
}

/// The Paeth predictor of PNG filter type 4.
#[inline(always)]
fn paeth_predictor(a: u8, b: u8, c: u8) -> u8 {
    let (ia, ib, ic) = (i16::from(a), i16::from(b), i16::from(c));
    // p - a = b - c, p - b = a - c, p - c = a + b - 2c
    let (pa, pb, pc) = ((ib - ic).abs(), (ia - ic).abs(), (ia + ib - 2 * ic).abs());
    let bc = if pb <= pc { b } else { c };
    if pa <= pb && pa <= pc {
        a
    } else {
        bc
    }
}

/// Write one chunk: length, type, data, CRC-32 of type and data.
fn chunk<W: Write>(w: &mut W, kind: &[u8; 4], parts: &[&[u8]]) -> Result<()> {
    let len: usize = parts.iter().map(|p| p.len()).sum();
    let len = u32::try_from(len)
        .ok()
        .filter(|&l| l <= 0x7FFF_FFFF)
        .ok_or_else(|| Error::limits("PNG chunk over 2^31 - 1 bytes"))?;
    let mut crc = crc32fast::Hasher::new();
    crc.update(kind);
    w.write_all(&len.to_be_bytes())?;
    w.write_all(kind)?;
    for p in parts {
        crc.update(p);
        w.write_all(p)?;
    }
    w.write_all(&crc.finalize().to_be_bytes())?;
    Ok(())
}

/// Write the PNG of `width` x `height` pixels made of `groups` (in row order) into `w`;
/// `tone` selects the colour-space chunk (see the module documentation).
pub fn encode_png_rows<W: Write>(
    groups: &[PngRows],
    width: usize,
    height: usize,
    tone: DisplayTone,
    w: &mut W,
) -> Result<()> {
    dims(width, height)?;
    let rows: usize = groups.iter().map(|g| g.rows).sum();
    if rows != height {
        return Err(rows_mismatch(height, rows));
    }
    let mut s = PngStream::begin(w, width, height, tone)?;
    for g in groups {
        s.push(w, g)?;
    }
    s.end(w)
}

/// Width and height as the u32s of IHDR (1 ..= 2^31 - 1).
fn dims(width: usize, height: usize) -> Result<(u32, u32)> {
    let too_big = || Error::limits("PNG dimensions over 2^31 - 1");
    let wu = u32::try_from(width)
        .ok()
        .filter(|&v| v > 0 && v <= 0x7FFF_FFFF)
        .ok_or_else(too_big)?;
    let hu = u32::try_from(height)
        .ok()
        .filter(|&v| v > 0 && v <= 0x7FFF_FFFF)
        .ok_or_else(too_big)?;
    Ok((wu, hu))
}

fn rows_mismatch(height: usize, rows: usize) -> Error {
    Error::invalid(format!("PNG of {height} rows given {rows} rows of data"))
}

/// The file of [`encode_png_rows`] written group by group: [`PngStream::begin`] writes the
/// signature and the header chunks, [`PngStream::push`] one IDAT per non-empty group (the
/// zlib header before the first; the final empty block and the Adler-32, combined group by
/// group, after the last: the group that completes the height), [`PngStream::end`] IEND.
#[derive(Debug)]
struct PngStream {
    height: usize,
    /// Rows written so far.
    rows: usize,
    /// Adler-32 of the filtered rows written so far.
    adler: u32,
}

impl PngStream {
    fn begin<W: Write>(
        w: &mut W,
        width: usize,
        height: usize,
        tone: DisplayTone,
    ) -> Result<PngStream> {
        let (wu, hu) = dims(width, height)?;
        w.write_all(b"\x89PNG\r\n\x1a\n")?;
        let mut ihdr = Vec::with_capacity(13);
        ihdr.extend_from_slice(&wu.to_be_bytes());
        ihdr.extend_from_slice(&hu.to_be_bytes());
        // bit depth 8, colour type 2 (RGB), deflate, adaptive filtering, no interlace
        ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
        chunk(w, b"IHDR", &[&ihdr])?;
        match tone {
            DisplayTone::Srgb => chunk(w, b"sRGB", &[&[0]])?,
            // 1 / 2.2 in units of 1e-5
            DisplayTone::Gamma22 => chunk(w, b"gAMA", &[&45455u32.to_be_bytes()])?,
            DisplayTone::Release => {}
        }
        Ok(PngStream {
            height,
            rows: 0,
            adler: 1,
        })
    }

    fn push<W: Write>(&mut self, w: &mut W, g: &PngRows) -> Result<()> {
        if g.rows == 0 {
            return Ok(());
        }
        let rows = self.rows + g.rows;
        if rows > self.height {
            return Err(rows_mismatch(self.height, rows));
        }
        self.adler = adler32_combine(self.adler, g.adler, g.len);
        let head: &[u8] = if self.rows == 0 { &[0x78, 0x01] } else { &[] };
        if rows == self.height {
            let tail = [&FINAL_EMPTY_BLOCK[..], &self.adler.to_be_bytes()[..]].concat();
            chunk(w, b"IDAT", &[head, &g.deflate, &tail])?;
        } else {
            chunk(w, b"IDAT", &[head, &g.deflate])?;
        }
        self.rows = rows;
        Ok(())
    }

    fn end<W: Write>(self, w: &mut W) -> Result<()> {
        if self.rows != self.height {
            return Err(rows_mismatch(self.height, self.rows));
        }
        chunk(w, b"IEND", &[])
    }
}

/// A PNG target written while it is rendered: each group of rows ([`PngRows`], in row
/// order) is appended as one IDAT as it comes, so the compressed image is never held
/// whole. The bytes are those of [`write_png_groups`] of the same groups (tested); dropped
/// unfinished, nothing appears at `path` ([`AtomicFile`]).
#[derive(Debug)]
pub struct PngFile<'p> {
    file: AtomicFile<'p>,
    stream: PngStream,
}

impl<'p> PngFile<'p> {
    /// Start a `width` x `height` PNG at `path`.
    pub fn create(
        path: &Path,
        width: usize,
        height: usize,
        tone: DisplayTone,
        policy: &'p OutputPolicy,
    ) -> Result<PngFile<'p>> {
        let mut file = AtomicFile::create(path, policy)?;
        let stream = PngStream::begin(file.writer()?, width, height, tone).in_file(path)?;
        Ok(PngFile { file, stream })
    }

    /// Append the next group of rows.
    pub fn push(&mut self, group: &PngRows) -> Result<()> {
        let r = self.file.writer().and_then(|w| self.stream.push(w, group));
        r.in_file(self.file.path())
    }

    /// Write IEND (every row must have been pushed), then sync and rename the file into
    /// place (see [`AtomicFile::finish`]).
    pub fn finish(mut self) -> Result<()> {
        let r = self.file.writer().and_then(|w| self.stream.end(w));
        r.in_file(self.file.path())?;
        self.file.finish()
    }
}

/// Write the PNG made of `groups` (see [`encode_png_rows`]) atomically.
pub fn write_png_groups(
    groups: &[PngRows],
    width: usize,
    height: usize,
    tone: DisplayTone,
    path: &Path,
    policy: &OutputPolicy,
) -> Result<()> {
    write_atomic(path, policy, |out| {
        encode_png_rows(groups, width, height, tone, out)
    })
}

/// Write interleaved 8-bit RGB samples (`width` x `height`) as a PNG atomically, in groups
/// of [`crate::isp::render::BAND`] rows filtered and compressed in parallel.
pub fn write_png_rgb8(
    bytes: &[u8],
    width: usize,
    height: usize,
    tone: DisplayTone,
    path: &Path,
    policy: &OutputPolicy,
) -> Result<()> {
    let groups = rgb8_groups(bytes, width, height)?;
    write_png_groups(&groups, width, height, tone, path, policy)
}

/// The bytes of the PNG file [`write_png_rgb8`] writes for these samples, in memory (the
/// Python package's `day2night.png.png_bytes`).
pub fn png_rgb8_bytes(
    bytes: &[u8],
    width: usize,
    height: usize,
    tone: DisplayTone,
) -> Result<Vec<u8>> {
    let groups = rgb8_groups(bytes, width, height)?;
    let mut out =
        Vec::with_capacity(groups.iter().map(|g| g.deflate.len() + 12).sum::<usize>() + 64);
    encode_png_rows(&groups, width, height, tone, &mut out)?;
    Ok(out)
}

/// Interleaved 8-bit RGB samples (`width` x `height`) in groups of
/// [`crate::isp::render::BAND`] rows, filtered and compressed in parallel.
fn rgb8_groups(bytes: &[u8], width: usize, height: usize) -> Result<Vec<PngRows>> {
    let need = width.checked_mul(BPP).and_then(|s| s.checked_mul(height));
    if width == 0 || height == 0 || Some(bytes.len()) != need {
        return Err(Error::invalid(format!(
            "PNG of {width}x{height} RGB needs {} bytes, got {}",
            3u128 * width as u128 * height as u128,
            bytes.len()
        )));
    }
    // bytes.len() = 3 * width * height did not overflow, so neither does this (BAND > 0)
    let group = BPP * width * crate::isp::render::BAND.min(height);
    bytes
        .par_chunks(group)
        .map_init(Encoder::new, |enc, rows| PngRows::encode(rows, width, enc))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Undo the filters (reference decoder, straight from the specification).
    fn unfilter(data: &[u8], width: usize) -> Vec<u8> {
        let stride = 3 * width;
        let mut out: Vec<u8> = Vec::new();
        for (r, row) in data.chunks_exact(stride + 1).enumerate() {
            let kind = row[0];
            for i in 0..stride {
                let x = row[1 + i];
                let a = if i >= 3 { out[r * stride + i - 3] } else { 0 };
                let b = if r > 0 { out[(r - 1) * stride + i] } else { 0 };
                let c = if r > 0 && i >= 3 {
                    out[(r - 1) * stride + i - 3]
                } else {
                    0
                };
                let p = match kind {
                    0 => 0,
                    1 => a,
                    2 => b,
                    3 => ((u16::from(a) + u16::from(b)) / 2) as u8,
                    4 => paeth_predictor(a, b, c),
                    _ => panic!("filter type {kind}"),
                };
                out.push(x.wrapping_add(p));
            }
        }
        out
    }

    /// Parse chunks, check CRCs, return (type, data) pairs.
    fn chunks(png: &[u8]) -> Vec<([u8; 4], Vec<u8>)> {
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        let mut p = 8;
        let mut out = Vec::new();
        while p < png.len() {
            let len = u32::from_be_bytes(png[p..p + 4].try_into().unwrap()) as usize;
            let kind: [u8; 4] = png[p + 4..p + 8].try_into().unwrap();
            let data = png[p + 8..p + 8 + len].to_vec();
            let crc = u32::from_be_bytes(png[p + 8 + len..p + 12 + len].try_into().unwrap());
            let mut h = crc32fast::Hasher::new();
            h.update(&kind);
            h.update(&data);
            assert_eq!(crc, h.finalize());
            out.push((kind, data));
            p += 12 + len;
        }
        out
    }

    fn image(w: usize, h: usize, seed: u32) -> Vec<u8> {
        let mut s = seed | 1;
        (0..3 * w * h)
            .map(|i| {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                let x = i / 3 % w;
                let y = i / (3 * w);
                // smooth gradient plus a little noise, a flat region
                if x < w / 4 {
                    40
                } else {
                    ((x * 3 + y * 2 + (i % 3) * 50) as u32 + (s >> 29)) as u8
                }
            })
            .collect()
    }

    #[test]
    fn decodes_to_the_pixels_with_every_group_size() {
        for (w, h) in [(1, 1), (1, 5), (5, 1), (7, 33), (64, 70), (301, 64)] {
            let img = image(w, h, (w * 31 + h) as u32);
            for group in [1, 2, 32, 1000] {
                let mut enc = Encoder::new();
                let groups: Vec<PngRows> = img
                    .chunks(3 * w * group)
                    .map(|r| PngRows::encode(r, w, &mut enc).unwrap())
                    .collect();
                let mut png = Vec::new();
                encode_png_rows(&groups, w, h, DisplayTone::Srgb, &mut png).unwrap();
                let ch = chunks(&png);
                assert_eq!(&ch[0].0, b"IHDR");
                assert_eq!(
                    ch[0].1[..8],
                    [(w as u32).to_be_bytes(), (h as u32).to_be_bytes()].concat()
                );
                assert_eq!(&ch[1].0, b"sRGB");
                assert_eq!(&ch.last().unwrap().0, b"IEND");
                let z: Vec<u8> = ch
                    .iter()
                    .filter(|c| &c.0 == b"IDAT")
                    .flat_map(|c| c.1.clone())
                    .collect();
                let filtered = miniz_oxide::inflate::decompress_to_vec_zlib(&z).unwrap();
                assert_eq!(unfilter(&filtered, w), img, "{w}x{h} group {group}");
                // and an independent decoder agrees
                let dec = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
                    .unwrap()
                    .to_rgb8();
                assert_eq!(dec.into_raw(), img);
            }
        }
    }

    /// The filters of PNG's specification byte by byte, and the minimum-sum choice (the
    /// first of equal sums): what [`filter_row`] must give, in whichever copy runs.
    fn filter_by_hand(row: &[u8], prev: Option<&[u8]>) -> Vec<u8> {
        let up = |i: usize| prev.map_or(0, |p| p[i]);
        let left = |i: usize| if i >= BPP { row[i - BPP] } else { 0 };
        let corner = |i: usize| if i >= BPP { up(i - BPP) } else { 0 };
        let kinds: &[u8] = if prev.is_some() {
            &[0, 1, 2, 3, 4]
        } else {
            &[0, 1]
        };
        let mut best: Option<(u64, Vec<u8>)> = None;
        for &k in kinds {
            let mut out = vec![k];
            for (i, &x) in row.iter().enumerate() {
                let (a, b, c) = (left(i), up(i), corner(i));
                let pred = match k {
                    0 => 0,
                    1 => a,
                    2 => b,
                    3 => ((u16::from(a) + u16::from(b)) / 2) as u8,
                    _ => {
                        let p = i16::from(a) + i16::from(b) - i16::from(c);
                        let (pa, pb, pc) = (
                            (p - i16::from(a)).abs(),
                            (p - i16::from(b)).abs(),
                            (p - i16::from(c)).abs(),
                        );
                        if pa <= pb && pa <= pc {
                            a
                        } else if pb <= pc {
                            b
                        } else {
                            c
                        }
                    }
                };
                out.push(x.wrapping_sub(pred));
            }
            let sum: u64 = out[1..]
                .iter()
                .map(|&v| u64::from((v as i8).unsigned_abs()))
                .sum();
            if best.as_ref().is_none_or(|(s, _)| sum < *s) {
                best = Some((sum, out));
            }
        }
        best.map(|(_, v)| v).unwrap_or_default()
    }

    #[test]
    fn filtered_rows_are_the_specifications() {
        for w in [1usize, 2, 5, 33, 1000, 4097] {
            let img = image(w, 3, w as u32 * 7 + 1);
            let noisy: Vec<u8> = img
                .iter()
                .enumerate()
                .map(|(i, &v)| v ^ ((i * 2_654_435_761) >> 7) as u8)
                .collect();
            for src in [&img, &noisy] {
                let stride = 3 * w;
                let mut cand: [Vec<u8>; 5] = std::array::from_fn(|_| vec![0; stride]);
                let mut prev: Option<&[u8]> = None;
                for row in src.chunks_exact(stride) {
                    let mut out = Vec::new();
                    filter_row(&mut cand, row, prev, &mut out);
                    assert_eq!(out, filter_by_hand(row, prev), "width {w}");
                    prev = Some(row);
                }
            }
        }
    }

    #[test]
    fn filters_are_chosen_and_first_rows_use_none_or_sub() {
        let (w, h) = (64, 40);
        let img = image(w, h, 5);
        let mut enc = Encoder::new();
        let g = PngRows::encode(&img, w, &mut enc).unwrap();
        let mut z = vec![0x78, 0x01];
        z.extend_from_slice(&g.deflate);
        z.extend_from_slice(&FINAL_EMPTY_BLOCK);
        z.extend_from_slice(&g.adler.to_be_bytes());
        let f = miniz_oxide::inflate::decompress_to_vec_zlib(&z).unwrap();
        let kinds: Vec<u8> = f.chunks_exact(3 * w + 1).map(|r| r[0]).collect();
        assert!(kinds[0] <= 1);
        // a smooth gradient: some row uses a filter that looks at the previous row
        assert!(kinds[1..].iter().any(|&k| k >= 2), "{kinds:?}");
    }

    #[test]
    fn tone_chunks_and_bad_sizes() {
        let img = image(3, 2, 1);
        let mut enc = Encoder::new();
        let g = [PngRows::encode(&img, 3, &mut enc).unwrap()];
        for (tone, kind) in [
            (DisplayTone::Srgb, Some(*b"sRGB")),
            (DisplayTone::Gamma22, Some(*b"gAMA")),
            (DisplayTone::Release, None),
        ] {
            let mut png = Vec::new();
            encode_png_rows(&g, 3, 2, tone, &mut png).unwrap();
            let ch = chunks(&png);
            match kind {
                Some(k) => assert_eq!(ch[1].0, k),
                None => assert_eq!(&ch[1].0, b"IDAT"),
            }
        }
        let mut sink = Vec::new();
        assert!(encode_png_rows(&g, 3, 3, DisplayTone::Srgb, &mut sink).is_err());
        assert!(encode_png_rows(&g, 0, 2, DisplayTone::Srgb, &mut sink).is_err());
        assert!(PngRows::encode(&img[..5], 3, &mut enc).is_err());
        assert!(PngRows::encode(&img, 0, &mut enc).is_err());
        // sizes whose byte counts overflow are errors, not panics
        assert!(PngRows::encode(&img, usize::MAX / 2, &mut enc).is_err());
        let dir0 = tempfile::tempdir().unwrap();
        let q = dir0.path().join("y.png");
        let pol = OutputPolicy::default();
        assert!(write_png_rgb8(&img, usize::MAX / 2, 3, DisplayTone::Srgb, &q, &pol).is_err());
        assert!(write_png_rgb8(&img, 3, usize::MAX / 4, DisplayTone::Srgb, &q, &pol).is_err());
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.png");
        let r = write_png_rgb8(&img, 3, 3, DisplayTone::Srgb, &p, &OutputPolicy::default());
        assert!(r.is_err() && !p.exists());
    }
}
