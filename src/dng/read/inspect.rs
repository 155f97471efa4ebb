//! `day2night info`: a description of any parseable DNG, including ones synthesis cannot
//! use (and why).

use super::tags::version4;
use super::*;
use crate::dng::opcodes::describe::{describe_lists, OpcodeListInfo};

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

/// The modelled metadata, as `info` reports it: the reader's own [`RawMeta`] (a view of it,
/// not a copy of its fields), without the entries carried verbatim (counted instead), the
/// LinearizationTable by its length and the opcode lists by number and description.
#[derive(Debug, Clone)]
pub struct MetaSummary {
    /// The metadata read (pixel-free).
    pub meta: RawMeta,
    /// Each present list's opcodes (or why it is malformed).
    pub opcodes: Vec<OpcodeListInfo>,
}

impl MetaSummary {
    /// The summary of `meta` (its opcode lists described).
    pub fn new(meta: RawMeta) -> MetaSummary {
        let opcodes = describe_lists(&meta);
        MetaSummary { meta, opcodes }
    }

    /// Which OpcodeLists are present (1, 2, 3).
    pub fn opcode_lists(&self) -> Vec<u8> {
        (1..=3u8)
            .filter(|&i| self.meta.opcode_lists[i as usize - 1].is_some())
            .collect()
    }

    /// LinearizationTable length.
    pub fn linearization_table_len(&self) -> Option<usize> {
        self.meta.linearization_table.as_ref().map(|t| t.len())
    }

    /// Counts of carried entries (IFD0, raw IFD, Exif).
    pub fn carried_entries(&self) -> [usize; 3] {
        let m = &self.meta;
        [m.ifd0_extra.len(), m.raw_extra.len(), m.exif_extra.len()]
    }

    /// Entries of the GPS IFD (0: none), carried into written DNGs.
    pub fn gps_entries(&self) -> usize {
        self.meta.gps.len()
    }
}

impl Serialize for MetaSummary {
    /// The fields `info --json` reports, in its order; `linear_raw` only for LinearRaw
    /// images.
    fn serialize<S: serde::Serializer>(&self, ser: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let m = &self.meta;
        let mut st = ser.serialize_struct("MetaSummary", 19)?;
        st.serialize_field("bits_per_sample", &m.bits_per_sample)?;
        st.serialize_field("active_area", &m.active_area)?;
        st.serialize_field("default_crop_origin", &m.default_crop_origin)?;
        st.serialize_field("default_crop_size", &m.default_crop_size)?;
        st.serialize_field("cfa_pattern", &m.cfa)?;
        st.serialize_field("linearization_table_len", &self.linearization_table_len())?;
        st.serialize_field("levels", &m.levels)?;
        st.serialize_field("as_shot_neutral", &m.as_shot_neutral)?;
        st.serialize_field("as_shot_white_xy", &m.as_shot_white_xy)?;
        st.serialize_field("color", &m.color)?;
        st.serialize_field("noise_profile", &m.noise_profile)?;
        st.serialize_field("orientation", &m.orientation)?;
        st.serialize_field("exif", &m.exif)?;
        st.serialize_field("opcode_lists", &self.opcode_lists())?;
        st.serialize_field("opcodes", &self.opcodes)?;
        st.serialize_field("storage", &m.storage)?;
        st.serialize_field("carried_entries", &self.carried_entries())?;
        st.serialize_field("gps_entries", &self.gps_entries())?;
        match &m.linear_raw {
            Some(l) => st.serialize_field("linear_raw", l)?,
            None => st.skip_field("linear_raw")?,
        }
        st.end()
    }
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
                meta: MetaSummary::new(m.clone()),
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
