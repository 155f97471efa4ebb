//! DNG reader: finds the raw IFD (NewSubFileType 0, in IFD0 or any SubIFD; CFA, else
//! LinearRaw), decodes its pixels (uncompressed 8-16 bit incl. packed 10/12/14-bit, lossless
//! JPEG, JPEG XL, lossy JPEG; strips or tiles) and fills [`RawMeta`] completely. See docs/dng-support.md ("Reading").

use crate::dng::ljpeg;
use crate::error::{Error, Result, ResultExt};
use crate::raw::meta::{ByteOrder, CfaPattern, ColorInfo, ExifInfo, Layout, RawMeta, Storage};
use crate::raw::{Levels, RawImage, Rect};
use crate::tiff::read::{parse, Ifd, Tiff};
use crate::tiff::tags::*;
use crate::tiff::value::{Entry, Value};
use serde::Serialize;
use std::path::Path;

mod inspect;
mod jpeg;
mod jxl;
mod linear_raw;
mod pixels;
mod tags;

pub use inspect::{inspect, inspect_bytes, DngInfo, IfdSummary, MetaSummary, RawSummary};
pub use pixels::unpack_row;
use pixels::{block_ranges, decode_pixels, decode_pixels_from, geometry, streamable, Geometry};
use tags::build_meta;
pub use tags::{MODELLED_EXIF_TAGS, MODELLED_TAGS, STORED_TAGS, STRUCTURAL_TAGS};

/// Default largest stored image (width * height samples); the limit in force is
/// [`crate::limits::Limits::current`] (`--max-pixels`, `D2N_MAX_PIXELS`).
pub const MAX_PIXELS: usize = crate::limits::DEFAULT_MAX_PIXELS as usize;
/// Largest width or height accepted.
pub const MAX_DIMENSION: u32 = 65535;
/// Largest CFA repeat pattern (rows or columns).
pub const MAX_CFA_DIM: usize = 16;

/// Compression values decoded by jxl.rs and jpeg.rs.
const COMPRESSION_LOSSY_JPEG: u16 = 34892;
const COMPRESSION_JPEG_XL: u16 = 52546;

/// PhotometricInterpretation values.
const PHOTOMETRIC_CFA: u16 = 32803;
const PHOTOMETRIC_LINEAR_RAW: u16 = 34892;

/// Read the raw image (a CFA mosaic, or a demosaiced LinearRaw image: see
/// [`RawMeta::linear_raw`]) and the metadata of a DNG file.
pub fn read_dng(path: &Path) -> Result<RawImage> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io(e).in_file(path))?;
    read_dng_bytes(&bytes).in_file(path)
}

/// [`read_dng`] that also hands the file's bytes to `whole` (e.g. to hash them), run in
/// parallel with the parsing. A file of at least `stream_from` bytes whose raw blocks are
/// uncompressed or lossless JPEG has its bytes dropped once its structure is parsed and
/// its blocks read again from the file one at a time: the same image, without the file's
/// bytes and the decoded samples in memory at once (docs/benchmarks.md, 109 MP peak).
pub fn read_dng_with<T: Send>(
    path: &Path,
    stream_from: u64,
    whole: impl FnOnce(&[u8]) -> T + Send,
) -> Result<(RawImage, T)> {
    use std::io::{Read, Seek, SeekFrom};
    let io = |e: std::io::Error| Error::Io(e).in_file(path);
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes).map_err(io)?;
    if (bytes.len() as u64) < stream_from {
        let (t, raw) = rayon::join(|| whole(&bytes), || read_dng_bytes(&bytes));
        return Ok((raw.in_file(path)?, t));
    }
    let (t, head) = rayon::join(|| whole(&bytes), || structure(&bytes));
    let Some((order, meta, geom, ranges)) = head.in_file(path)? else {
        return Ok((read_dng_bytes(&bytes).in_file(path)?, t));
    };
    drop(bytes);
    // The same open file: a file renamed over `path` meanwhile is not read.
    let data = decode_pixels_from(&ranges, order, &geom, |off, buf| {
        file.seek(SeekFrom::Start(off as u64)).map_err(Error::Io)?;
        file.read_exact(buf).map_err(Error::Io)
    })
    .in_file(path)?;
    let mut img = RawImage {
        width: geom.width as usize,
        height: geom.height as usize,
        data,
        meta,
    };
    img.validate().in_file(path)?;
    crate::dng::check::check_meta(&mut img.meta).in_file(path)?;
    Ok((img, t))
}

/// What [`structure`] finds: byte order, metadata, geometry and block ranges.
type Structure = (ByteOrder, RawMeta, Geometry, Vec<pixels::BlockAt>);

/// The byte order, metadata, geometry and block ranges of a DNG whose blocks can be
/// decoded one at a time (None for the others).
fn structure(bytes: &[u8]) -> Result<Option<Structure>> {
    let tiff = parse(bytes)?;
    let dng = locate(&tiff)?;
    let raw = dng.raw;
    check_photometric(raw.u32(PHOTOMETRIC_INTERPRETATION).unwrap_or(0) as u16)?;
    let geom = geometry(raw)?;
    if !streamable(&geom) {
        return Ok(None);
    }
    let meta = build_meta(&tiff, &dng, &geom)?;
    let ranges = block_ranges(bytes.len(), raw, &geom)?;
    Ok(Some((tiff.byte_order, meta, geom, ranges)))
}

/// Read the raw CFA image and metadata of a DNG held in memory. The metadata passed
/// [`crate::dng::check::check_meta`]: corrections are listed in `meta.warnings`.
pub fn read_dng_bytes(bytes: &[u8]) -> Result<RawImage> {
    let mut img = read_dng_bytes_unchecked(bytes)?;
    crate::dng::check::check_meta(&mut img.meta)?;
    Ok(img)
}

/// [`read_dng_bytes`] without the metadata checks (for `info`, which describes a file the
/// checks refuse).
fn read_dng_bytes_unchecked(bytes: &[u8]) -> Result<RawImage> {
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
        PHOTOMETRIC_CFA | PHOTOMETRIC_LINEAR_RAW => Ok(()),
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

fn check_compression(c: u16, bits: u32) -> Result<()> {
    match c {
        1 | 7 | COMPRESSION_JPEG_XL => Ok(()),
        COMPRESSION_LOSSY_JPEG if bits == 8 => Ok(()),
        COMPRESSION_LOSSY_JPEG => Err(Error::unsupported(format!(
            "lossy JPEG (34892) with {bits}-bit samples (8-bit baseline JPEG supported)"
        ))),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streamed_read_gives_the_same_image_for_every_fixture() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
        let mut n = 0;
        for e in std::fs::read_dir(&dir).unwrap() {
            let path = e.unwrap().path();
            if path.extension().is_none_or(|x| x != "dng") {
                continue;
            }
            let Ok(want) = read_dng(&path) else { continue };
            let len = std::fs::metadata(&path).unwrap().len() as usize;
            for from in [0, u64::MAX] {
                let (got, seen) = read_dng_with(&path, from, |b| b.len()).unwrap();
                assert_eq!(seen, len, "{}", path.display());
                assert_eq!(got.data, want.data, "{} from {from}", path.display());
                assert_eq!(got.meta, want.meta, "{}", path.display());
                assert_eq!((got.width, got.height), (want.width, want.height));
            }
            n += 1;
        }
        assert!(n >= 8, "{n} fixtures read");
    }

    #[test]
    fn streamed_read_reports_a_truncated_strip() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/rggb_16bit_le_strips.dng");
        let bytes = std::fs::read(&src).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let cut = dir.path().join("cut.dng");
        // a cut tail: both reads refuse the file with the same message
        std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
        let whole = read_dng(&cut).unwrap_err().to_string();
        let streamed = read_dng_with(&cut, 0, |_| ()).unwrap_err().to_string();
        assert_eq!(streamed, whole);
        assert!(whole.contains("cut.dng"), "{whole}");
    }

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
