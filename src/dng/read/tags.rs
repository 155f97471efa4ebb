//! Mapping the tags of a DNG into the raw image model: levels (BlackLevel, deltas,
//! LinearizationTable, WhiteLevel), CFA, colour matrices and neutrals, EXIF, and the
//! entries carried unchanged for a faithful rewrite.

use super::*;

/// Tags that describe the file's structure (offsets, sizes, pointers): never carried.
pub const STRUCTURAL_TAGS: &[u16] = &[
    NEW_SUBFILE_TYPE,
    IMAGE_WIDTH,
    IMAGE_LENGTH,
    BITS_PER_SAMPLE,
    COMPRESSION,
    PHOTOMETRIC_INTERPRETATION,
    STRIP_OFFSETS,
    SAMPLES_PER_PIXEL,
    ROWS_PER_STRIP,
    STRIP_BYTE_COUNTS,
    PLANAR_CONFIGURATION,
    PREDICTOR,
    TILE_WIDTH,
    TILE_LENGTH,
    TILE_OFFSETS,
    TILE_BYTE_COUNTS,
    SUB_IFDS,
    SAMPLE_FORMAT,
    JPEG_TABLES,
    EXIF_IFD,
    GPS_IFD,
    JPEG_IF_OFFSET, // thumbnail offset
    JPEG_IF_LENGTH,
    INTEROP_IFD, // Exif InteroperabilityIFD pointer
];

/// Tags decoded into typed [`RawMeta`] fields (so not carried as extras).
pub const MODELLED_TAGS: &[u16] = &[
    DNG_VERSION,
    DNG_BACKWARD_VERSION,
    MAKE,
    MODEL,
    UNIQUE_CAMERA_MODEL,
    ACTIVE_AREA,
    DEFAULT_CROP_ORIGIN,
    DEFAULT_CROP_SIZE,
    CFA_REPEAT_PATTERN_DIM,
    CFA_PATTERN,
    CFA_PLANE_COLOR,
    CFA_LAYOUT,
    LINEARIZATION_TABLE,
    BLACK_LEVEL_REPEAT_DIM,
    BLACK_LEVEL,
    BLACK_LEVEL_DELTA_H,
    BLACK_LEVEL_DELTA_V,
    WHITE_LEVEL,
    AS_SHOT_NEUTRAL,
    AS_SHOT_WHITE_XY,
    COLOR_MATRIX1,
    COLOR_MATRIX2,
    CAMERA_CALIBRATION1,
    CAMERA_CALIBRATION2,
    FORWARD_MATRIX1,
    FORWARD_MATRIX2,
    CALIBRATION_ILLUMINANT1,
    CALIBRATION_ILLUMINANT2,
    ANALOG_BALANCE,
    BASELINE_EXPOSURE,
    NOISE_PROFILE,
    ORIENTATION,
    OPCODE_LIST1,
    OPCODE_LIST2,
    OPCODE_LIST3,
];

/// Modelled tags whose stored form is kept in [`RawMeta::stored`] (written back unchanged
/// while their value is).
pub const STORED_TAGS: &[u16] = &[
    AS_SHOT_NEUTRAL,
    AS_SHOT_WHITE_XY,
    COLOR_MATRIX1,
    COLOR_MATRIX2,
    CAMERA_CALIBRATION1,
    CAMERA_CALIBRATION2,
    FORWARD_MATRIX1,
    FORWARD_MATRIX2,
    ANALOG_BALANCE,
    BASELINE_EXPOSURE,
];

/// Exif tags decoded into [`ExifInfo`].
pub const MODELLED_EXIF_TAGS: &[u16] = &[
    ISO_SPEED_RATINGS,
    EXPOSURE_TIME,
    F_NUMBER,
    DATE_TIME_ORIGINAL,
];

pub(super) fn carried(ifd: &Ifd, skip_extra: &[u16]) -> Vec<Entry> {
    ifd.entries
        .iter()
        .filter(|e| {
            !STRUCTURAL_TAGS.contains(&e.tag)
                && !MODELLED_TAGS.contains(&e.tag)
                && !skip_extra.contains(&e.tag)
        })
        .cloned()
        .collect()
}

/// Look a tag up in the raw IFD first, then IFD0.
pub(super) fn lookup<'a>(d: &Located<'a>, tag: u16) -> Option<&'a Value> {
    d.raw.get(tag).or_else(|| d.ifd0.get(tag))
}

pub(super) fn floats(v: &Value, tag: u16) -> Result<Vec<f64>> {
    let f = v.to_f64_vec().ok_or_else(|| {
        Error::malformed(format!(
            "{} (tag {tag}) is not numeric or has a zero denominator",
            tag_name(tag)
        ))
    })?;
    if f.iter().any(|x| !x.is_finite()) {
        return Err(Error::malformed(format!(
            "{} (tag {tag}) holds a non-finite value",
            tag_name(tag)
        )));
    }
    Ok(f)
}

pub(super) fn opt_floats(d: &Located<'_>, tag: u16) -> Result<Option<Vec<f64>>> {
    lookup(d, tag).map(|v| floats(v, tag)).transpose()
}

pub(super) fn opt_matrix(
    d: &Located<'_>,
    tag: u16,
    rows: usize,
    cols: usize,
) -> Result<Option<Vec<f64>>> {
    match opt_floats(d, tag)? {
        Some(m) if m.len() != rows * cols => Err(Error::malformed(format!(
            "{} has {} values, expected {}x{}",
            tag_name(tag),
            m.len(),
            rows,
            cols
        ))),
        m => Ok(m),
    }
}

pub(super) fn version4(v: Option<&Value>) -> Option<[u8; 4]> {
    let b = v?.to_u32_vec()?;
    let g = |i: usize| b.get(i).map(|&x| x as u8).unwrap_or(0);
    Some([g(0), g(1), g(2), g(3)])
}

/// The CFA tags of a CFA raw IFD.
fn cfa_pattern(raw: &Ifd) -> Result<CfaPattern> {
    let dim = raw
        .require(CFA_REPEAT_PATTERN_DIM)?
        .to_u32_vec()
        .filter(|v| v.len() == 2)
        .ok_or_else(|| Error::malformed("CFARepeatPatternDim must be two SHORTs"))?;
    let (cr, cc) = (dim[0] as usize, dim[1] as usize);
    if cr == 0 || cc == 0 || cr > MAX_CFA_DIM || cc > MAX_CFA_DIM {
        return Err(Error::malformed(format!(
            "CFARepeatPatternDim {cr}x{cc} (1..{MAX_CFA_DIM} per side)"
        )));
    }
    let pattern: Vec<u8> = raw
        .require(CFA_PATTERN)?
        .to_u32_vec()
        .ok_or_else(|| Error::malformed("CFAPattern must be BYTEs"))?
        .into_iter()
        .map(|x| x.min(255) as u8)
        .collect();
    if pattern.len() != cr * cc {
        return Err(Error::malformed(format!(
            "CFAPattern has {} values for a {cr}x{cc} repeat",
            pattern.len()
        )));
    }
    let plane_color: Vec<u8> = match raw.get(CFA_PLANE_COLOR) {
        Some(v) => v
            .to_u32_vec()
            .ok_or_else(|| Error::malformed("CFAPlaneColor must be BYTEs"))?
            .into_iter()
            .map(|x| x.min(255) as u8)
            .collect(),
        None => vec![0, 1, 2],
    };
    if plane_color.is_empty() || plane_color.len() > 8 {
        return Err(Error::malformed(format!(
            "CFAPlaneColor has {} planes",
            plane_color.len()
        )));
    }
    let planes = plane_color.len();
    if let Some(&bad) = pattern.iter().find(|&&p| p as usize >= planes) {
        return Err(Error::malformed(format!(
            "CFAPattern value {bad} is not a colour plane (the CFA has {planes} planes: 0..{})",
            planes - 1
        )));
    }
    Ok(CfaPattern {
        rows: cr,
        cols: cc,
        pattern,
        plane_color,
        layout: raw.u32(CFA_LAYOUT).unwrap_or(1) as u16,
    })
}

pub(super) fn build_meta(tiff: &Tiff, d: &Located<'_>, g: &Geometry) -> Result<RawMeta> {
    let raw = d.raw;
    let ifd0 = d.ifd0;
    let (w, h) = (g.width, g.height);

    // CFA (a LinearRaw image has none: linear_raw.rs).
    let cfa = match g.samples_per_pixel {
        1 => cfa_pattern(raw)?,
        spp => super::linear_raw::no_cfa(spp),
    };
    let planes = cfa.plane_color.len();

    // Geometry tags.
    let active_area = active_area(raw, (w, h))?;
    let (aw, ah) = match active_area {
        Some(r) => (r.width(), r.height()),
        None => (w as usize, h as usize),
    };
    let (default_crop_origin, default_crop_size) = default_crop(raw)?;

    // Levels.
    let (linearization_table, levels, linear_raw) = levels(raw, g, (aw, ah))?;

    // Colour.
    let ColorTags {
        as_shot_neutral,
        as_shot_white_xy,
        color,
        noise_profile,
    } = color_tags(d, planes)?;
    let orientation = ifd0.u32(ORIENTATION).unwrap_or(1);
    let orientation = if (1..=8).contains(&orientation) {
        orientation as u16
    } else {
        1
    };

    let exif = exif_info(ifd0);
    let exif_ifd = ifd0.exif.as_deref();

    let opcode = |tag: u16| raw.get(tag).and_then(|v| v.as_bytes()).map(|b| b.to_vec());
    let dng_version = version4(ifd0.get(DNG_VERSION)).unwrap_or([1, 0, 0, 0]);
    let raw_in_sub = d.path.is_some();
    // TIFF/EP copies of the Exif fields in IFD0 are modelled too (the writer puts the
    // current values in the Exif IFD; a stale IFD0 copy would contradict them).
    let ifd0_extra = carried(ifd0, MODELLED_EXIF_TAGS);
    let raw_extra = if raw_in_sub {
        carried(raw, &[])
    } else {
        Vec::new()
    };
    let exif_extra = exif_ifd
        .map(|e| carried(e, MODELLED_EXIF_TAGS))
        .unwrap_or_default();
    // GPS tags (0..=31) have their own numbering: every readable entry is carried.
    let gps = ifd0
        .gps
        .as_deref()
        .map(|g| g.entries.clone())
        .unwrap_or_default();
    Ok(RawMeta {
        dng_version,
        dng_backward_version: version4(ifd0.get(DNG_BACKWARD_VERSION)),
        make: ifd0.string(MAKE),
        model: ifd0.string(MODEL),
        unique_camera_model: ifd0.string(UNIQUE_CAMERA_MODEL),
        bits_per_sample: g.bits,
        active_area,
        default_crop_origin,
        default_crop_size,
        cfa,
        linearization_table,
        levels,
        as_shot_neutral,
        as_shot_white_xy,
        color,
        noise_profile,
        orientation,
        exif,
        opcode_lists: [
            opcode(OPCODE_LIST1),
            opcode(OPCODE_LIST2),
            opcode(OPCODE_LIST3),
        ],
        ifd0_extra,
        raw_extra,
        exif_extra,
        gps,
        storage: Some(Storage {
            byte_order: tiff.byte_order,
            sub_ifd: d.path.clone(),
            layout: g.layout,
            compression: g.compression,
            predictor: raw.u32(PREDICTOR).map(|p| p as u16),
        }),
        linear_raw,
        stored: STORED_TAGS
            .iter()
            .filter_map(|&tag| {
                lookup(d, tag).map(|v| Entry {
                    tag,
                    value: v.clone(),
                })
            })
            .collect(),
        warnings: Default::default(),
        noise_profile_problem: None,
    })
}

/// ActiveArea, checked inside the `w x h` image.
fn active_area(raw: &Ifd, (w, h): (u32, u32)) -> Result<Option<Rect>> {
    Ok(match raw.get(ACTIVE_AREA) {
        Some(v) => {
            let a = v
                .to_u32_vec()
                .filter(|a| a.len() == 4)
                .ok_or_else(|| Error::malformed("ActiveArea must be four integers"))?;
            let r = Rect {
                top: a[0],
                left: a[1],
                bottom: a[2],
                right: a[3],
            };
            if r.top >= r.bottom || r.left >= r.right || r.bottom > h || r.right > w {
                return Err(Error::malformed(format!(
                    "ActiveArea {},{},{},{} is empty or outside the {w}x{h} image",
                    r.top, r.left, r.bottom, r.right
                )));
            }
            Some(r)
        }
        None => None,
    })
}

/// DefaultCropOrigin and DefaultCropSize (non-negative pairs; a zero size is an error).
#[allow(clippy::type_complexity)]
fn default_crop(raw: &Ifd) -> Result<(Option<[f64; 2]>, Option<[f64; 2]>)> {
    let pair = |tag: u16| -> Result<Option<[f64; 2]>> {
        match raw.get(tag).map(|v| floats(v, tag)).transpose()? {
            Some(p) if p.len() == 2 && p.iter().all(|&x| x >= 0.0) => Ok(Some([p[0], p[1]])),
            Some(p) => Err(Error::malformed(format!(
                "{} must be two non-negative numbers (got {:?})",
                tag_name(tag),
                p
            ))),
            None => Ok(None),
        }
    };
    let default_crop_origin = pair(DEFAULT_CROP_ORIGIN)?;
    let default_crop_size = pair(DEFAULT_CROP_SIZE)?;
    if let Some(s) = default_crop_size {
        if s[0] <= 0.0 || s[1] <= 0.0 {
            return Err(Error::malformed("DefaultCropSize is zero"));
        }
    }
    Ok((default_crop_origin, default_crop_size))
}

/// The levels of an `aw x ah` active area: LinearizationTable, black (with its repeat and
/// deltas) and white, split for LinearRaw images (`linear_raw.rs`).
fn levels(
    raw: &Ifd,
    g: &Geometry,
    (aw, ah): (usize, usize),
) -> Result<(
    Option<Vec<u16>>,
    Levels,
    Option<crate::raw::meta::LinearRaw>,
)> {
    let linearization_table = match raw.get(LINEARIZATION_TABLE) {
        Some(v) => {
            let t: Vec<u16> = v
                .to_u32_vec()
                .ok_or_else(|| Error::malformed("LinearizationTable must be SHORTs"))?
                .into_iter()
                .map(|x| x.min(65535) as u16)
                .collect();
            if t.is_empty() || t.len() > 65536 {
                return Err(Error::malformed(format!(
                    "LinearizationTable has {} entries (1..65536)",
                    t.len()
                )));
            }
            Some(t)
        }
        None => None,
    };
    let black_repeat = match raw.get(BLACK_LEVEL_REPEAT_DIM) {
        Some(v) => {
            let r = v
                .to_u32_vec()
                .filter(|a| a.len() == 2)
                .ok_or_else(|| Error::malformed("BlackLevelRepeatDim must be two integers"))?;
            let (a, b) = (r[0] as usize, r[1] as usize);
            if a == 0 || b == 0 || a > MAX_CFA_DIM || b > MAX_CFA_DIM {
                return Err(Error::malformed(format!(
                    "BlackLevelRepeatDim {a}x{b} (1..{MAX_CFA_DIM} per side)"
                )));
            }
            (a, b)
        }
        None => (1, 1),
    };
    let spp = usize::from(g.samples_per_pixel);
    let black = match raw.get(BLACK_LEVEL) {
        Some(v) => floats(v, BLACK_LEVEL)?,
        None => vec![0.0; black_repeat.0 * black_repeat.1 * spp],
    };
    if black.len() != black_repeat.0 * black_repeat.1 * spp {
        return Err(Error::malformed(format!(
            "BlackLevel has {} values for BlackLevelRepeatDim {}x{}{}",
            black.len(),
            black_repeat.0,
            black_repeat.1,
            super::linear_raw::times_samples(spp)
        )));
    }
    let delta = |tag: u16, n: usize| -> Result<Vec<f64>> {
        match raw.get(tag) {
            Some(v) => {
                let d = floats(v, tag)?;
                if d.len() != n {
                    return Err(Error::malformed(format!(
                        "{} has {} values, the active area needs {n}",
                        tag_name(tag),
                        d.len()
                    )));
                }
                Ok(d)
            }
            None => Ok(Vec::new()),
        }
    };
    let black_delta_h = delta(BLACK_LEVEL_DELTA_H, aw)?;
    let black_delta_v = delta(BLACK_LEVEL_DELTA_V, ah)?;
    let white = match raw.get(WHITE_LEVEL) {
        Some(v) => *floats(v, WHITE_LEVEL)?
            .first()
            .ok_or_else(|| Error::malformed("WhiteLevel is empty"))?,
        None => match &linearization_table {
            Some(t) => t.iter().copied().max().map_or(65535.0, f64::from),
            None => ((1u32 << g.bits) - 1) as f64,
        },
    };
    let (black, white, linear_raw) =
        super::linear_raw::split_levels(raw, black, white, black_repeat, spp)?;
    let levels = Levels {
        black_repeat,
        black,
        black_delta_h,
        black_delta_v,
        white,
    };
    levels.validate(aw, ah)?;
    Ok((linearization_table, levels, linear_raw))
}

/// The colour tags of a CFA of `planes` colour planes.
struct ColorTags {
    as_shot_neutral: Option<[f64; 3]>,
    as_shot_white_xy: Option<[f64; 2]>,
    color: ColorInfo,
    noise_profile: Option<Vec<(f64, f64)>>,
}

/// AsShotNeutral, AsShotWhiteXY, the colour matrices and NoiseProfile.
fn color_tags(d: &Located<'_>, planes: usize) -> Result<ColorTags> {
    let n3 = planes;
    let as_shot_neutral = match lookup(d, AS_SHOT_NEUTRAL) {
        Some(v) => {
            let n = floats(v, AS_SHOT_NEUTRAL)?;
            if n.len() != n3 {
                return Err(Error::malformed(format!(
                    "AsShotNeutral has {} values for {n3} colour planes",
                    n.len()
                )));
            }
            if let Some(bad) = n.iter().find(|&&x| x <= 0.0 || !x.is_finite()) {
                return Err(Error::malformed(format!(
                    "AsShotNeutral component {bad} is not positive"
                )));
            }
            if n3 == 3 {
                Some([n[0] / n[1], 1.0, n[2] / n[1]])
            } else {
                None
            }
        }
        None => None,
    };
    let as_shot_white_xy = match lookup(d, AS_SHOT_WHITE_XY) {
        Some(v) => {
            let p = floats(v, AS_SHOT_WHITE_XY)?;
            if p.len() != 2 {
                return Err(Error::malformed("AsShotWhiteXY must hold two values"));
            }
            Some([p[0], p[1]])
        }
        None => None,
    };
    let illum = |tag: u16| {
        lookup(d, tag)
            .and_then(|v| v.get_u32(0))
            .map(|x| x.min(65535) as u16)
    };
    let analog_balance = opt_floats(d, ANALOG_BALANCE)?;
    if let Some(a) = &analog_balance {
        if a.len() != n3 {
            return Err(Error::malformed(format!(
                "AnalogBalance has {} values for {n3} planes",
                a.len()
            )));
        }
    }
    let color = ColorInfo {
        color_matrix1: opt_matrix(d, COLOR_MATRIX1, n3, 3)?,
        color_matrix2: opt_matrix(d, COLOR_MATRIX2, n3, 3)?,
        camera_calibration1: opt_matrix(d, CAMERA_CALIBRATION1, n3, n3)?,
        camera_calibration2: opt_matrix(d, CAMERA_CALIBRATION2, n3, n3)?,
        forward_matrix1: opt_matrix(d, FORWARD_MATRIX1, 3, n3)?,
        forward_matrix2: opt_matrix(d, FORWARD_MATRIX2, 3, n3)?,
        calibration_illuminant1: illum(CALIBRATION_ILLUMINANT1),
        calibration_illuminant2: illum(CALIBRATION_ILLUMINANT2),
        analog_balance,
        // Some writers (Magic Lantern) store 0/0 here: treated as absent (= 0 EV).
        baseline_exposure: lookup(d, BASELINE_EXPOSURE)
            .and_then(|v| v.get_f64(0))
            .filter(|x| x.is_finite()),
    };
    let noise_profile = match opt_floats(d, NOISE_PROFILE)? {
        Some(v) => {
            if v.len() != 2 && v.len() != 2 * n3 {
                return Err(Error::malformed(format!(
                    "NoiseProfile has {} values (expected 2 or {})",
                    v.len(),
                    2 * n3
                )));
            }
            Some(v.chunks_exact(2).map(|p| (p[0], p[1])).collect())
        }
        None => None,
    };
    Ok(ColorTags {
        as_shot_neutral,
        as_shot_white_xy,
        color,
        noise_profile,
    })
}

/// Exif fields (Exif IFD, falling back to TIFF/EP tags in IFD0).
fn exif_info(ifd0: &Ifd) -> ExifInfo {
    let exif_ifd = ifd0.exif.as_deref();
    let ex = |tag: u16| exif_ifd.and_then(|e| e.get(tag)).or_else(|| ifd0.get(tag));
    ExifInfo {
        iso: ex(ISO_SPEED_RATINGS)
            .and_then(|v| v.get_u32(0))
            .filter(|&i| i > 0),
        exposure_time: ex(EXPOSURE_TIME)
            .and_then(|v| v.get_f64(0))
            .filter(|&t| t > 0.0 && t.is_finite()),
        f_number: ex(F_NUMBER)
            .and_then(|v| v.get_f64(0))
            .filter(|&f| f > 0.0 && f.is_finite()),
        date_time_original: ex(DATE_TIME_ORIGINAL)
            .and_then(|v| v.as_string())
            .filter(|s| !s.is_empty()),
    }
}

// ---------------------------------------------------------------------------------------
// Inspection (for `day2night info`)
