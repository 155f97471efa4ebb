//! `day2night info`: a description of any parseable DNG, including ones synthesis cannot
//! use (and why).

use super::tags::version4;
use super::*;

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
    /// Each present list's opcodes (or why it is malformed).
    pub opcodes: Vec<crate::dng::opcodes::describe::OpcodeListInfo>,
    /// Storage of the raw.
    pub storage: Option<Storage>,
    /// Counts of carried entries (IFD0, raw IFD, Exif).
    pub carried_entries: [usize; 3],
    /// Entries of the GPS IFD (0: none), carried into written DNGs.
    pub gps_entries: usize,
    /// LinearRaw (demosaiced) images: samples per pixel and per-sample levels (absent for
    /// CFA images).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linear_raw: Option<crate::raw::meta::LinearRaw>,
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
    /// What the metadata checks corrected (each names the tag and the value used): synthesis
    /// works but warns ("ready, with warnings"). Serialized with their codes.
    pub warnings: crate::diagnostics::Diagnostics,
    /// Set when the raw data itself is unreadable (unsupported compression, malformed,
    /// over the limits): `info` reports it as an error (exit code 1).
    pub error: Option<String>,
}

pub(super) fn summarize(path: String, ifd: &Ifd, out: &mut Vec<IfdSummary>) {
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
        warnings: Default::default(),
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
    match read_dng_bytes_unchecked(bytes) {
        Ok(img) => {
            let m = &img.meta;
            let bayer = img.bayer();
            info.raw = Some(RawSummary {
                width: img.width,
                height: img.height,
                cfa: match &bayer {
                    Ok(b) => b.name(),
                    Err(_) if m.linear_raw.is_some() => format!(
                        "none: LinearRaw, {} samples per pixel (already demosaiced)",
                        m.samples_per_pixel()
                    ),
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
                    opcodes: crate::dng::opcodes::describe::describe_lists(m),
                    storage: m.storage.clone(),
                    carried_entries: [m.ifd0_extra.len(), m.raw_extra.len(), m.exif_extra.len()],
                    gps_entries: m.gps.len(),
                    linear_raw: m.linear_raw.clone(),
                },
            });
            let mut meta = img.meta.clone();
            match (bayer, crate::dng::check::check_meta(&mut meta)) {
                (_, Err(e)) => {
                    // Refused by the metadata checks: described, but an error like any other
                    // command would report.
                    info.reason = Some(e.to_string());
                    info.error = Some(e.to_string());
                }
                (Ok(_), Ok(())) => {
                    info.synth_ready = true;
                    info.warnings = meta.warnings;
                }
                (Err(e), Ok(())) => info.reason = Some(e.to_string()),
            }
            // A malformed opcode list is described (the rest of the file too) but makes the
            // file unusable for synthesis, whose targets apply the opcodes.
            if let Err(e) = crate::dng::opcodes::lists(m) {
                if info.synth_ready {
                    info.synth_ready = false;
                    info.reason = Some(e.to_string());
                }
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
