//! `RawMeta`: everything the pipeline and a faithful re-write need to know about a raw
//! image, in the model's terms (the DNG layer, [`crate::dng`], maps tags into it and back).
//!
//! Tags the pipeline uses are decoded into typed fields; every other entry is carried as a
//! decoded [`Entry`] in `ifd0_extra`, `raw_extra` or `exif_extra` so that the writer can put
//! it back. The reader fills this struct, the writer consumes it; synthesis changes only the
//! fields whose meaning changes (neutral, ISO, NoiseProfile, ...).

use crate::error::{Error, Result};
use crate::raw::{Bayer, Levels, Rect};
use crate::tiff::value::Entry;
use serde::Serialize;

/// Why a LinearRaw image cannot be used where a CFA mosaic is needed (synthesis,
/// calibration, merging, writing).
pub const LINEAR_RAW_NOT_CFA: &str =
    "LinearRaw: already demosaiced; the night synthesis works on the CFA mosaic";

pub use crate::tiff::ByteOrder;

/// Where and how the raw image was (or will be) stored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Storage {
    /// Byte order of the file.
    pub byte_order: ByteOrder,
    /// `None` = raw in IFD0; `Some(path)` = SubIFD path from IFD0 (e.g. `[0]` = first SubIFD).
    pub sub_ifd: Option<Vec<usize>>,
    /// Tiles (with TileWidth, TileLength) or strips (rows per strip).
    pub layout: Layout,
    /// TIFF Compression code (1 none, 7 lossless JPEG, ...).
    pub compression: u16,
    /// Predictor tag, if present.
    pub predictor: Option<u16>,
}

/// Strip or tile layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Layout {
    /// Strips of `rows_per_strip` rows.
    Strips {
        /// RowsPerStrip.
        rows_per_strip: u32,
    },
    /// Tiles of `width x height`.
    Tiles {
        /// TileWidth.
        width: u32,
        /// TileLength.
        height: u32,
    },
}

/// The CFA description as stored (may be a non-Bayer or non-2x2 pattern; see [`RawMeta::bayer`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CfaPattern {
    /// CFARepeatPatternDim (rows, cols).
    pub rows: usize,
    /// CFARepeatPatternDim cols.
    pub cols: usize,
    /// CFAPattern, `rows * cols` colour indices into `plane_color`.
    pub pattern: Vec<u8>,
    /// CFAPlaneColor (default [0, 1, 2] = R, G, B).
    pub plane_color: Vec<u8>,
    /// CFALayout (1 = rectangular).
    pub layout: u16,
}

/// What a LinearRaw image (PhotometricInterpretation 34892: already demosaiced, several
/// samples per pixel) has beyond a CFA image: its samples per pixel and the per-sample
/// levels. `None` in [`RawMeta::linear_raw`] for CFA images, which keep every CFA path as is.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinearRaw {
    /// SamplesPerPixel (3: one per colour plane).
    pub samples_per_pixel: u16,
    /// BlackLevel, `black_repeat rows x cols x samples_per_pixel` values in the DNG's
    /// row-column-sample order (BlackLevelDeltaH/V apply to every sample).
    pub black: Vec<f64>,
    /// WhiteLevel per sample.
    pub white: Vec<f64>,
}

impl LinearRaw {
    /// Black level of sample `s` at active-area (row, col), deltas included.
    #[inline]
    pub fn black_at(&self, levels: &Levels, s: usize, row: usize, col: usize) -> f64 {
        let (rr, rc) = levels.black_repeat;
        let spp = self.samples_per_pixel as usize;
        let mut b = self.black[((row % rr) * rc + (col % rc)) * spp + s];
        if let Some(d) = levels.black_delta_h.get(col) {
            b += d;
        }
        if let Some(d) = levels.black_delta_v.get(row) {
            b += d;
        }
        b
    }

    /// Error unless the per-sample arrays fit the repeat pattern and every sample's
    /// largest black (deltas included) is below its white, all finite.
    pub fn validate(&self, levels: &Levels) -> Result<()> {
        let spp = self.samples_per_pixel as usize;
        let (rr, rc) = levels.black_repeat;
        if spp == 0 || self.black.len() != rr * rc * spp || self.white.len() != spp {
            return Err(Error::malformed(format!(
                "LinearRaw levels: {} BlackLevel values for BlackLevelRepeatDim {rr}x{rc} and \
                 {spp} samples, {} WhiteLevel values",
                self.black.len(),
                self.white.len()
            )));
        }
        if self.black.iter().chain(&self.white).any(|v| !v.is_finite()) {
            return Err(Error::malformed(
                "black or white level is not a finite number",
            ));
        }
        let dh = levels.black_delta_h.iter().cloned().fold(0.0, f64::max);
        let dv = levels.black_delta_v.iter().cloned().fold(0.0, f64::max);
        for s in 0..spp {
            let bmax = self
                .black
                .iter()
                .skip(s)
                .step_by(spp)
                .cloned()
                .fold(f64::NEG_INFINITY, f64::max)
                + dh
                + dv;
            if bmax >= self.white[s] {
                return Err(Error::malformed(format!(
                    "black level {bmax} >= white level {} (sample {s})",
                    self.white[s]
                )));
            }
        }
        Ok(())
    }
}

/// Exif fields the pipeline reads or rewrites.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ExifInfo {
    /// ISOSpeedRatings / PhotographicSensitivity (0 in some files = unknown -> None).
    pub iso: Option<u32>,
    /// ExposureTime in seconds (<= 0 -> None).
    pub exposure_time: Option<f64>,
    /// FNumber.
    pub f_number: Option<f64>,
    /// DateTimeOriginal ("YYYY:MM:DD HH:MM:SS").
    pub date_time_original: Option<String>,
}

/// Colour calibration tags (DNG chapter 6). Matrices are row-major, `3 x 3` for a
/// three-colour CFA (ColorMatrix/ForwardMatrix/CameraCalibration).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ColorInfo {
    /// ColorMatrix1 (XYZ -> camera) for CalibrationIlluminant1.
    pub color_matrix1: Option<Vec<f64>>,
    /// ColorMatrix2 for CalibrationIlluminant2.
    pub color_matrix2: Option<Vec<f64>>,
    /// CameraCalibration1.
    pub camera_calibration1: Option<Vec<f64>>,
    /// CameraCalibration2.
    pub camera_calibration2: Option<Vec<f64>>,
    /// ForwardMatrix1 (white-balanced camera -> XYZ D50).
    pub forward_matrix1: Option<Vec<f64>>,
    /// ForwardMatrix2.
    pub forward_matrix2: Option<Vec<f64>>,
    /// CalibrationIlluminant1 (EXIF LightSource code).
    pub calibration_illuminant1: Option<u16>,
    /// CalibrationIlluminant2.
    pub calibration_illuminant2: Option<u16>,
    /// AnalogBalance.
    pub analog_balance: Option<Vec<f64>>,
    /// BaselineExposure (EV).
    pub baseline_exposure: Option<f64>,
}

/// All metadata of a DNG raw image.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RawMeta {
    /// DNGVersion (e.g. [1, 4, 0, 0]).
    pub dng_version: [u8; 4],
    /// DNGBackwardVersion, if present.
    pub dng_backward_version: Option<[u8; 4]>,
    /// Make.
    pub make: Option<String>,
    /// Model.
    pub model: Option<String>,
    /// UniqueCameraModel.
    pub unique_camera_model: Option<String>,
    /// BitsPerSample of the raw image (8..=16).
    pub bits_per_sample: u16,
    /// ActiveArea (None = whole image).
    pub active_area: Option<Rect>,
    /// DefaultCropOrigin (x, y), relative to the active area.
    pub default_crop_origin: Option<[f64; 2]>,
    /// DefaultCropSize (width, height).
    pub default_crop_size: Option<[f64; 2]>,
    /// CFA description.
    pub cfa: CfaPattern,
    /// LinearizationTable, if present.
    pub linearization_table: Option<Vec<u16>>,
    /// Black and white levels.
    pub levels: Levels,
    /// AsShotNeutral, normalised so that green = 1 (as the reader stores it).
    pub as_shot_neutral: Option<[f64; 3]>,
    /// AsShotWhiteXY, if present.
    pub as_shot_white_xy: Option<[f64; 2]>,
    /// Colour calibration.
    pub color: ColorInfo,
    /// NoiseProfile: (S, O) pairs, one per colour plane or a single pair for all.
    pub noise_profile: Option<Vec<(f64, f64)>>,
    /// Orientation (1..=8; 1 when absent).
    pub orientation: u16,
    /// Exif fields used by the pipeline.
    pub exif: ExifInfo,
    /// OpcodeList1/2/3 as opaque bytes (big-endian by the DNG spec).
    pub opcode_lists: [Option<Vec<u8>>; 3],
    /// Other IFD0 entries carried verbatim (not modelled above, not structural).
    pub ifd0_extra: Vec<Entry>,
    /// Other raw-IFD entries carried verbatim (when the raw lives in a SubIFD).
    pub raw_extra: Vec<Entry>,
    /// Other Exif entries carried verbatim.
    pub exif_extra: Vec<Entry>,
    /// The GPS IFD's entries, carried verbatim (a night raw is a drop-in replacement of
    /// the capture, location included). Not serialized when empty.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gps: Vec<Entry>,
    /// How the source stored the raw (for `info`; the writer chooses its own layout).
    pub storage: Option<Storage>,
    /// Set for a LinearRaw (demosaiced) image: then `cfa` is empty, the pixel buffer holds
    /// `samples_per_pixel` interleaved samples per pixel and `levels` holds sample 0's
    /// black (per repeat cell) and white (the per-sample values are here). Not serialized
    /// when `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linear_raw: Option<LinearRaw>,
    /// The modelled colour tags (AsShotNeutral, AsShotWhiteXY, matrices, AnalogBalance,
    /// BaselineExposure) exactly as the source stored them (type and value). The writer
    /// re-uses an entry while the modelled field still equals what the reader decoded from
    /// it, so that values nobody changed round-trip unchanged. Empty for generated images.
    #[serde(skip)]
    pub stored: Vec<Entry>,
    /// What [`crate::dng::check::check_meta`] corrected, one message per correction naming
    /// the tag and the value used, without a subject (printed by the CLI as
    /// `warning[CODE]: <file>: ...`, recorded in synth sidecars, raised as Python warnings).
    /// Not written to files.
    #[serde(skip)]
    pub warnings: crate::diagnostics::Diagnostics,
    /// Why [`crate::dng::check::check_meta`] dropped the NoiseProfile (its values and the
    /// rule they break), so that the noise chain reports an invalid NoiseProfile as one,
    /// not as a missing one. Not written to files.
    #[serde(skip)]
    pub noise_profile_problem: Option<String>,
}

impl RawMeta {
    /// The source's stored entry of `tag`, if any (see [`RawMeta::stored`]).
    pub fn stored_value(&self, tag: u16) -> Option<&crate::tiff::value::Value> {
        self.stored.iter().find(|e| e.tag == tag).map(|e| &e.value)
    }

    /// A minimal valid metadata set for a Bayer image: used by generators and tests.
    pub fn new_bayer(bayer: Bayer, bits: u16, black: f64, white: f64) -> RawMeta {
        let levels = Levels {
            black_repeat: (1, 1),
            black: vec![black],
            black_delta_h: vec![],
            black_delta_v: vec![],
            white,
        };
        RawMeta {
            dng_backward_version: Some([1, 1, 0, 0]),
            make: Some("day2night".into()),
            model: Some("Synthetic".into()),
            unique_camera_model: Some("day2night Synthetic".into()),
            as_shot_neutral: Some([0.5, 1.0, 0.6]),
            color: ColorInfo {
                // A plausible sRGB-like camera: XYZ(D65) -> camera is the inverse of the
                // sRGB primaries matrix; illuminant 21 = D65.
                color_matrix1: Some(crate::color::xyz::XYZ_TO_SRGB.to_vec()),
                calibration_illuminant1: Some(21),
                ..ColorInfo::default()
            },
            ..RawMeta::bare(bayer, levels, bits)
        }
    }

    /// Metadata of a Bayer raw with only its levels and bit depth known: no colour
    /// metadata, no neutral, no ISO, no make or model, no ActiveArea or DefaultCrop.
    pub fn bare(bayer: Bayer, levels: Levels, bits_per_sample: u16) -> RawMeta {
        RawMeta {
            dng_version: [1, 4, 0, 0],
            dng_backward_version: None,
            make: None,
            model: None,
            unique_camera_model: None,
            bits_per_sample,
            active_area: None,
            default_crop_origin: None,
            default_crop_size: None,
            cfa: CfaPattern {
                rows: 2,
                cols: 2,
                pattern: bayer.0.to_vec(),
                plane_color: vec![0, 1, 2],
                layout: 1,
            },
            linearization_table: None,
            levels,
            as_shot_neutral: None,
            as_shot_white_xy: None,
            color: ColorInfo::default(),
            noise_profile: None,
            orientation: 1,
            exif: ExifInfo::default(),
            opcode_lists: [None, None, None],
            ifd0_extra: vec![],
            raw_extra: vec![],
            exif_extra: vec![],
            gps: vec![],
            storage: None,
            stored: Vec::new(),
            linear_raw: None,
            warnings: Default::default(),
            noise_profile_problem: None,
        }
    }

    /// The 2x2 Bayer pattern with colours mapped through CFAPlaneColor to R=0, G=1, B=2,
    /// or an error naming why this CFA is not one (non-2x2 repeat, non-RGB planes, layout).
    pub fn bayer(&self) -> Result<Bayer> {
        if self.linear_raw.is_some() {
            return Err(Error::unsupported(LINEAR_RAW_NOT_CFA));
        }
        let c = &self.cfa;
        if c.rows != 2 || c.cols != 2 || c.pattern.len() != 4 {
            return Err(Error::unsupported(format!(
                "{}x{} CFA pattern is not a 2x2 Bayer mosaic",
                c.rows, c.cols
            )));
        }
        if c.layout != 1 {
            return Err(Error::unsupported(format!(
                "CFALayout {} (non-rectangular sensor layout) is not supported",
                c.layout
            )));
        }
        let mut p = [0u8; 4];
        for (i, &idx) in c.pattern.iter().enumerate() {
            let plane = *c.plane_color.get(idx as usize).ok_or_else(|| {
                Error::malformed(format!(
                    "CFAPattern value {} has no CFAPlaneColor entry ({} planes)",
                    idx,
                    c.plane_color.len()
                ))
            })?;
            if plane > 2 {
                return Err(Error::unsupported(format!(
                    "CFA plane colour {} (not red, green or blue) is not supported",
                    plane
                )));
            }
            p[i] = plane;
        }
        Bayer::from_pattern(p)
    }

    /// Samples per pixel of the pixel buffer: 1 (CFA) or LinearRaw's.
    pub fn samples_per_pixel(&self) -> usize {
        self.linear_raw
            .as_ref()
            .map_or(1, |l| usize::from(l.samples_per_pixel))
    }

    /// ISO for writing a clean output: the Exif ISO, or 50 when unknown.
    pub fn iso_or_default(&self) -> u32 {
        self.exif.iso.filter(|&i| i > 0).unwrap_or(50)
    }
}
