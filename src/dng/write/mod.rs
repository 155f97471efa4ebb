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
use crate::raw::rows::{PlaneRows, RowSource};
use crate::raw::RawImage;
use crate::tiff::tags as t;
use crate::tiff::value::{Entry, Value};
use crate::tiff::write::{encode_tiff, write_tiff, write_tiff_head, Chunks, Ifd};
use rayon::prelude::*;
use std::path::Path;

mod pixels;
mod stream;
mod tags;
mod unique_id;

use pixels::*;
pub use tags::neutral_value;
use tags::*;
pub use unique_id::UniqueIdHash;
use unique_id::*;

/// Tile edge of lossless-JPEG tiles (as Adobe's converter writes).
const LJPEG_TILE: usize = 256;
/// Target size of one uncompressed strip.
const STRIP_BYTES: usize = 1 << 20;
/// Bytes of RawDataUniqueID.
const UNIQUE_ID_LEN: usize = 16;

/// Raw image compression of written DNGs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Compression {
    /// Uncompressed strips (default: readable by every raw tool).
    #[default]
    None,
    /// Lossless JPEG (compression 7) tiles.
    Ljpeg,
}

crate::choices! {
    Compression, ignore_case: false,
    unknown: |s| Error::invalid(format!(
        "{s:?} (use {})",
        crate::choice::listed::<Compression>(", ", " or ")
    )),
    None => "none": "Uncompressed",
    Ljpeg => "ljpeg": "Lossless JPEG",
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
    /// The hash of RawDataUniqueID (XXH3-128; SHA-256 replays sidecars written before it).
    pub unique_id: UniqueIdHash,
}

/// Encode a DNG into memory.
pub fn encode_dng(img: &RawImage, opts: &WriteOptions) -> Result<Vec<u8>> {
    let (order, ifd0) = build(img, opts)?;
    encode_tiff(order, &[ifd0])
}

/// Encode and write a DNG atomically under `policy`: the same bytes as [`encode_dng`]. In
/// the default layout the strips are packed and written a batch at a time
/// ([`write_dng_rows`]); otherwise the tiles/strips are encoded first and streamed to the
/// temporary file.
pub fn write_dng(
    img: &RawImage,
    path: &Path,
    opts: &WriteOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    policy.check(path)?;
    if stream::streams(opts) {
        check_written(img).map_err(|e| e.in_file(path))?;
        return write_dng_rows(&img.meta, &PlaneRows::new(img), path, opts, policy);
    }
    let (order, ifd0) = build(img, opts).map_err(|e| e.in_file(path))?;
    crate::output::write_atomic(path, policy, |w| write_tiff(order, &[ifd0], w))
}

/// Write the raw whose rows `src` makes, with metadata `meta`, atomically under `policy`:
/// the same bytes as [`write_dng`] of the plane of those rows. In the default layout
/// (uncompressed strips in IFD0) and when `src`'s sample bound decides the stored bit depth,
/// the rows are made, packed and written a batch of strips at a time and never held whole;
/// otherwise the plane is made first ([`crate::raw::rows::to_plane`]).
pub fn write_dng_rows(
    meta: &RawMeta,
    src: &dyn RowSource,
    path: &Path,
    opts: &WriteOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    policy.check(path)?;
    let (w, h) = (src.width(), src.height());
    let checked = (|| {
        refuse_linear_raw(meta)?;
        if meta.samples_per_pixel() != 1 {
            return Err(Error::invalid("a streamed raw has one sample per pixel"));
        }
        crate::raw::check_layout(w, h, meta)?;
        check_meta(meta, w, h)
    })();
    checked.map_err(|e| e.in_file(path))?;
    let streamed = stream::streams(opts)
        .then(|| {
            let bound = src.max_bound();
            stream::strip_bits(meta, bound, src.plane().is_some(), opts).map(|b| (b, bound))
        })
        .flatten();
    match streamed {
        Some(bits) => stream::write_streamed(meta, src, bits, path, opts, policy),
        None => {
            let img = RawImage {
                width: w,
                height: h,
                data: crate::raw::rows::to_plane(src).map_err(|e| e.in_file(path))?,
                meta: meta.clone(),
            };
            let (order, ifd0) = build(&img, opts).map_err(|e| e.in_file(path))?;
            crate::output::write_atomic(path, policy, |w| write_tiff(order, &[ifd0], w))
        }
    }
}

/// The checks [`build`] makes before encoding, for a raw written from its plane.
fn check_written(img: &RawImage) -> Result<()> {
    refuse_linear_raw(&img.meta)?;
    img.validate()?;
    check_meta(&img.meta, img.width, img.height)
}

/// The IFD tree of a DNG: byte order and IFD0 (with its SubIFD/Exif children and data).
fn build(img: &RawImage, opts: &WriteOptions) -> Result<(ByteOrder, Ifd)> {
    check_written(img)?;
    let order = byte_order(opts);
    let (raw_chunks, digests, bits, compression, layout_tags) = encode_pixels(img, opts, order)?;
    let tiled = matches!(raw_chunks, Chunks::Tiles(_));
    let unique_id = raw_data_unique_id(
        &img.meta,
        (img.width, img.height),
        tiled,
        &digests,
        opts.unique_id,
    );
    let thumb = match opts.raw_ifd {
        RawIfd::Main => None,
        RawIfd::Sub => Some(thumbnail::render(img, 256)?),
    };
    let raw = RawPart {
        width: img.width,
        height: img.height,
        chunks: raw_chunks,
        bits,
        compression,
        layout_tags,
    };
    Ok((order, assemble(&img.meta, raw, unique_id, thumb)))
}

/// The writer writes CFA mosaics; a LinearRaw source is read and rendered only.
fn refuse_linear_raw(m: &RawMeta) -> Result<()> {
    if m.linear_raw.is_some() {
        return Err(crate::error::Error::unsupported(
            "LinearRaw: already demosaiced; the DNG writer writes CFA mosaics",
        ));
    }
    Ok(())
}

fn byte_order(opts: &WriteOptions) -> ByteOrder {
    if opts.big_endian {
        ByteOrder::Big
    } else {
        ByteOrder::Little
    }
}

/// The raw image's IFD parts that depend on how its samples are stored.
struct RawPart {
    width: usize,
    height: usize,
    chunks: Chunks,
    bits: u16,
    compression: u16,
    layout_tags: Vec<(u16, Value)>,
}

/// IFD0 (with the raw in it or in a SubIFD behind `thumb`, and the Exif/GPS children).
fn assemble(
    m: &RawMeta,
    part: RawPart,
    unique_id: Vec<u8>,
    thumb: Option<thumbnail::Thumbnail>,
) -> Ifd {
    let mut raw = Ifd::new();
    raw.set(t::NEW_SUBFILE_TYPE, Value::Long(vec![0]));
    raw.set(t::IMAGE_WIDTH, Value::Long(vec![part.width as u32]));
    raw.set(t::IMAGE_LENGTH, Value::Long(vec![part.height as u32]));
    raw.set(t::BITS_PER_SAMPLE, Value::Short(vec![part.bits]));
    raw.set(t::COMPRESSION, Value::Short(vec![part.compression]));
    raw.set(t::PHOTOMETRIC_INTERPRETATION, Value::Short(vec![32803]));
    raw.set(t::SAMPLES_PER_PIXEL, Value::Short(vec![1]));
    raw.set(t::PLANAR_CONFIGURATION, Value::Short(vec![1]));
    for (tag, v) in part.layout_tags {
        raw.set(tag, v);
    }
    raw.set_chunks(part.chunks);
    set_raw_tags(&mut raw, m);

    let raw_in_sub = thumb.is_some();
    let mut ifd0 = match thumb {
        None => {
            for e in &m.raw_extra {
                if !is_dropped(e.tag) {
                    raw.set_if_absent(e.tag, e.value.clone());
                }
            }
            raw
        }
        Some(th) => {
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
    set_ifd0_tags(&mut ifd0, m, unique_id, raw_in_sub);
    ifd0.set_children(t::EXIF_IFD, vec![exif_ifd(m)]);
    if !m.gps.is_empty() {
        let mut gps = Ifd::new();
        for en in &m.gps {
            gps.set(en.tag, en.value.clone());
        }
        ifd0.set_children(t::GPS_IFD, vec![gps]);
    }
    ifd0
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

fn check_meta(m: &RawMeta, width: usize, height: usize) -> Result<()> {
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
    if width > u32::MAX as usize || height > u32::MAX as usize {
        return Err(Error::limits("image dimensions exceed 32 bits"));
    }
    Ok(())
}

type Pixels = (Chunks, Vec<ChunkDigest>, u16, u16, Vec<(u16, Value)>);

/// Entries of an IFD that the writer will carry (a helper for the docs and the tests).
pub fn carried(entries: &[Entry]) -> Vec<&Entry> {
    entries.iter().filter(|e| !is_dropped(e.tag)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::Bayer;

    fn sample_image(w: usize, h: usize, bits: u16) -> RawImage {
        sample_image_upto(w, h, bits, (1u32 << bits) - 1)
    }

    /// A `bits`-bit image of hashed samples `& max` (`max` = 2^k - 1; above the depth's
    /// range for the 16-bit fallback).
    pub(in crate::dng::write) fn sample_image_upto(
        w: usize,
        h: usize,
        bits: u16,
        max: u32,
    ) -> RawImage {
        let meta = RawMeta::new_bayer(Bayer::RGGB, bits, 64.0, ((1u32 << bits) - 1) as f64);
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
