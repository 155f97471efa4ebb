//! Raws from any source: `Raw.from_array(data, meta, name)` (the metadata dict of
//! `Raw.meta`, converted to the library's `RawMeta` and checked by
//! `RawImage::from_parts`), the extra keys of `Raw.meta` that make it complete enough for
//! that. Type conversion only: the checks and defaults are the library's
//! (`day2night::raw::from_parts`).

use crate::errors::{py_err, py_err_noting, value_err};
use crate::pool::on_pool;
use day2night::raw::from_parts::ColorDefault;
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, Levels, RawImage, Rect};
use day2night::synth::job::DayInput;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// Every key `from_array` reads, as `Raw.meta` returns them.
const KEYS: &[&str] = &[
    "cfa_pattern",
    "samples_per_pixel",
    "black_level",
    "black_level_repeat_dim",
    "black_level_delta_h",
    "black_level_delta_v",
    "white_level",
    "linearization_table",
    "as_shot_neutral",
    "as_shot_white_xy",
    "iso",
    "noise_profile",
    "active_area",
    "default_crop",
    "orientation",
    "make",
    "model",
    "unique_camera_model",
    "width",
    "height",
    "bits_per_sample",
    "color_matrix1",
    "color_matrix2",
    "camera_calibration1",
    "camera_calibration2",
    "forward_matrix1",
    "forward_matrix2",
    "calibration_illuminant1",
    "calibration_illuminant2",
    "analog_balance",
    "baseline_exposure",
    "exposure_time",
    "f_number",
    "date_time_original",
    "opcode_list1",
    "opcode_list2",
    "opcode_list3",
];

/// DNG tag names the library's messages use, and the key that feeds each.
const TAG_KEYS: &[(&str, &str)] = &[
    ("AsShotNeutral", "as_shot_neutral"),
    ("AsShotWhiteXY", "as_shot_white_xy"),
    ("ColorMatrix1", "color_matrix1"),
    ("ColorMatrix2", "color_matrix2"),
    ("CameraCalibration1", "camera_calibration1"),
    ("CameraCalibration2", "camera_calibration2"),
    ("ForwardMatrix1", "forward_matrix1"),
    ("ForwardMatrix2", "forward_matrix2"),
    ("AnalogBalance", "analog_balance"),
    ("BaselineExposure", "baseline_exposure"),
    ("NoiseProfile", "noise_profile"),
    ("Orientation", "orientation"),
    ("ISO", "iso"),
    ("ISOSpeedRatings", "iso"),
    ("ExposureTime", "exposure_time"),
    ("FNumber", "f_number"),
    ("LinearizationTable", "linearization_table"),
    ("DefaultCrop", "default_crop"),
    ("BitsPerSample", "bits_per_sample"),
    ("ActiveArea", "active_area"),
    ("BlackLevelDeltaH", "black_level_delta_h"),
    ("BlackLevelDeltaV", "black_level_delta_v"),
    ("BlackLevel", "black_level"),
    ("black level", "black_level"),
    ("WhiteLevel", "white_level"),
    ("white level", "white_level"),
    ("CFA", "cfa_pattern"),
    ("CFAPattern", "cfa_pattern"),
];

/// The keys `meta_dict` adds to those of the first release (so that `Raw.meta` holds
/// everything synthesis, rendering and the DNG writer use).
pub(crate) fn extra_meta(d: &Bound<'_, PyDict>, raw: &RawImage) -> PyResult<()> {
    let py = d.py();
    let m = &raw.meta;
    let c = &m.color;
    d.set_item("black_level_delta_h", m.levels.black_delta_h.clone())?;
    d.set_item("black_level_delta_v", m.levels.black_delta_v.clone())?;
    d.set_item("linearization_table", m.linearization_table.clone())?;
    d.set_item("as_shot_white_xy", m.as_shot_white_xy.map(|v| v.to_vec()))?;
    d.set_item("unique_camera_model", m.unique_camera_model.clone())?;
    d.set_item("color_matrix1", c.color_matrix1.clone())?;
    d.set_item("color_matrix2", c.color_matrix2.clone())?;
    d.set_item("camera_calibration1", c.camera_calibration1.clone())?;
    d.set_item("camera_calibration2", c.camera_calibration2.clone())?;
    d.set_item("forward_matrix1", c.forward_matrix1.clone())?;
    d.set_item("forward_matrix2", c.forward_matrix2.clone())?;
    d.set_item("calibration_illuminant1", c.calibration_illuminant1)?;
    d.set_item("calibration_illuminant2", c.calibration_illuminant2)?;
    d.set_item("analog_balance", c.analog_balance.clone())?;
    d.set_item("baseline_exposure", c.baseline_exposure)?;
    d.set_item("exposure_time", m.exif.exposure_time)?;
    d.set_item("f_number", m.exif.f_number)?;
    d.set_item("date_time_original", m.exif.date_time_original.clone())?;
    for (i, list) in m.opcode_lists.iter().enumerate() {
        d.set_item(
            format!("opcode_list{}", i + 1),
            list.as_ref().map(|b| PyBytes::new(py, b)),
        )?;
    }
    Ok(())
}

/// The dict being read: a key is missing (default), None (absent, as a DNG without the
/// tag) or a value.
struct Meta<'py> {
    d: Bound<'py, PyDict>,
}

impl<'py> Meta<'py> {
    fn has(&self, k: &str) -> PyResult<bool> {
        self.d.contains(k)
    }
    /// The value of `k`, None when missing or None.
    fn get(&self, k: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        Ok(self.d.get_item(k)?.filter(|v| !v.is_none()))
    }
    fn bad(k: &str, why: impl std::fmt::Display) -> PyErr {
        value_err(format!("meta[{k:?}]: {why}"))
    }
    fn extract<T: for<'a> FromPyObject<'a, 'py>>(
        &self,
        k: &str,
        what: &str,
    ) -> PyResult<Option<T>> {
        match self.get(k)? {
            None => Ok(None),
            Some(v) => v
                .extract::<T>()
                .map(Some)
                .map_err(|_| Self::bad(k, format!("must be {what} (got {})", short_repr(&v)))),
        }
    }
    /// Numbers, flat or nested (lists, tuples, arrays), flattened in row-major order.
    fn floats(&self, k: &str, n: Option<usize>) -> PyResult<Option<Vec<f64>>> {
        let Some(v) = self.get(k)? else {
            return Ok(None);
        };
        let flat = flat_floats(&v)
            .map_err(|_| Self::bad(k, format!("must be numbers (got {})", short_repr(&v))))?;
        if let Some(n) = n {
            if flat.len() != n {
                return Err(Self::bad(
                    k,
                    format!("has {} values, expected {n}", flat.len()),
                ));
            }
        }
        Ok(Some(flat))
    }
    fn floats_n<const N: usize>(&self, k: &str) -> PyResult<Option<[f64; N]>> {
        Ok(self
            .floats(k, Some(N))?
            .map(|v| <[f64; N]>::try_from(v.as_slice()).unwrap_or([0.0; N])))
    }
    fn ints(&self, k: &str, n: usize) -> PyResult<Option<Vec<i64>>> {
        match self.floats(k, Some(n))? {
            None => Ok(None),
            Some(v) => {
                if v.iter().any(|x| x.fract() != 0.0 || *x < 0.0 || *x > 1e12) {
                    return Err(Self::bad(k, format!("must be {n} non-negative integers")));
                }
                Ok(Some(v.into_iter().map(|x| x as i64).collect()))
            }
        }
    }
    fn required(&self, k: &str) -> PyResult<Bound<'py, PyAny>> {
        self.get(k)?.ok_or_else(|| {
            value_err(format!(
                "meta[{k:?}] is required (cfa_pattern, black_level and white_level are)"
            ))
        })
    }
}

fn short_repr(v: &Bound<'_, PyAny>) -> String {
    let s = v
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "?".into());
    if s.chars().count() > 60 {
        format!("{}...", s.chars().take(60).collect::<String>())
    } else {
        s
    }
}

/// "RGGB" (case-insensitive) or four colour indices (0 red, 1 green, 2 blue), flat or 2x2,
/// as the value `v` of `label` (`meta["cfa_pattern"]`, `cfa`).
pub(crate) fn cfa_from(v: &Bound<'_, PyAny>, label: &str) -> PyResult<Bayer> {
    let bad = |why: String| value_err(format!("{label}: {why}"));
    let codes: Vec<u8> = if let Ok(s) = v.extract::<String>() {
        s.to_ascii_uppercase()
            .chars()
            .map(|c| match c {
                'R' => Ok(0),
                'G' => Ok(1),
                'B' => Ok(2),
                _ => Err(bad(format!("{s:?}: use R, G and B (e.g. \"RGGB\")"))),
            })
            .collect::<PyResult<_>>()?
    } else {
        flat_floats(v)
            .ok()
            .filter(|c| {
                c.iter()
                    .all(|x| x.fract() == 0.0 && (0.0..=255.0).contains(x))
            })
            .ok_or_else(|| {
                bad(
                    "must be a string such as \"RGGB\" or four colour indices (0 R, 1 G, 2 B)"
                        .into(),
                )
            })?
            .into_iter()
            .map(|x| x as u8)
            .collect()
    };
    let arr: [u8; 4] = codes.as_slice().try_into().map_err(|_| {
        bad(format!(
            "has {} colours, a Bayer pattern has 4",
            codes.len()
        ))
    })?;
    Bayer::from_pattern(arr).map_err(|e| bad(e.to_string()))
}

/// Numbers, flat or nested (lists, tuples, arrays), flattened in row-major order.
pub(crate) fn flat_floats(v: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    v.py()
        .import("numpy")?
        .call_method1("asarray", (v, "float64"))
        .and_then(|a| a.call_method0("ravel"))
        .and_then(|a| a.call_method0("tolist"))
        .and_then(|a| a.extract())
}

/// The tags of the dict beyond the mosaic's layout: camera, colour, noise, Exif, opcodes.
fn parse_tags(m: &Meta<'_>, meta: &mut RawMeta) -> PyResult<()> {
    meta.make = m.extract("make", "a string")?;
    meta.model = m.extract("model", "a string")?;
    meta.unique_camera_model = m.extract("unique_camera_model", "a string")?;
    meta.as_shot_neutral = m.floats_n::<3>("as_shot_neutral")?;
    meta.as_shot_white_xy = m.floats_n::<2>("as_shot_white_xy")?;
    let c = &mut meta.color;
    c.color_matrix1 = m.floats("color_matrix1", Some(9))?;
    c.color_matrix2 = m.floats("color_matrix2", Some(9))?;
    c.camera_calibration1 = m.floats("camera_calibration1", Some(9))?;
    c.camera_calibration2 = m.floats("camera_calibration2", Some(9))?;
    c.forward_matrix1 = m.floats("forward_matrix1", Some(9))?;
    c.forward_matrix2 = m.floats("forward_matrix2", Some(9))?;
    c.calibration_illuminant1 = m.extract("calibration_illuminant1", "an EXIF LightSource code")?;
    c.calibration_illuminant2 = m.extract("calibration_illuminant2", "an EXIF LightSource code")?;
    c.analog_balance = m.floats("analog_balance", Some(3))?;
    c.baseline_exposure = m.floats("baseline_exposure", Some(1))?.map(|v| v[0]);
    meta.noise_profile = match m.floats("noise_profile", None)? {
        None => None,
        Some(v) if v.len() % 2 == 0 => Some(v.chunks_exact(2).map(|p| (p[0], p[1])).collect()),
        Some(v) => {
            return Err(Meta::bad(
                "noise_profile",
                format!("{} values: give [S, O] pairs", v.len()),
            ))
        }
    };
    meta.exif.iso = m.extract("iso", "a positive integer")?;
    meta.exif.exposure_time = m.floats("exposure_time", Some(1))?.map(|v| v[0]);
    meta.exif.f_number = m.floats("f_number", Some(1))?.map(|v| v[0]);
    meta.exif.date_time_original = m.extract("date_time_original", "a string")?;
    for i in 0..3 {
        let k = format!("opcode_list{}", i + 1);
        meta.opcode_lists[i] = m.extract::<Vec<u8>>(&k, "bytes")?;
    }
    Ok(())
}

/// The documented defaults of the colour metadata the dict does not have; their notes.
fn apply_defaults(m: &Meta<'_>, meta: &mut RawMeta) -> PyResult<Vec<String>> {
    // Colour metadata the dict does not have (the key missing; None means "absent, as in
    // a DNG without the tag"): the library's documented defaults.
    let mut notes = Vec::new();
    let mut default = |d: ColorDefault, key: &str, meta: &mut RawMeta| {
        notes.push(format!("meta[{key:?}] missing: {}", d.apply(meta)));
    };
    if !m.has("color_matrix1")? {
        default(ColorDefault::ColorMatrix, "color_matrix1", meta);
    } else if !m.has("calibration_illuminant1")? && meta.color.color_matrix1.is_some() {
        default(
            ColorDefault::CalibrationIlluminant,
            "calibration_illuminant1",
            meta,
        );
    }
    if !m.has("as_shot_neutral")? && !m.has("as_shot_white_xy")? {
        default(ColorDefault::Neutral, "as_shot_neutral", meta);
    }
    if !m.has("iso")? {
        default(ColorDefault::Iso, "iso", meta);
    }
    if !m.has("noise_profile")? {
        default(ColorDefault::NoiseProfile, "noise_profile", meta);
    }
    Ok(notes)
}

/// BlackLevel (with its repeat pattern, (1, 1) or (2, 2) by the count when not given),
/// the deltas and WhiteLevel of the dict.
fn parse_levels(m: &Meta<'_>) -> PyResult<Levels> {
    m.required("black_level")?;
    let black = m.floats("black_level", None)?.unwrap_or_default();
    let black_repeat = match m.ints("black_level_repeat_dim", 2)? {
        Some(v) => (v[0] as usize, v[1] as usize),
        None => match black.len() {
            1 => (1, 1),
            4 => (2, 2),
            n => {
                return Err(Meta::bad(
                    "black_level",
                    format!("{n} values: give black_level_repeat_dim (rows, cols)"),
                ))
            }
        },
    };
    m.required("white_level")?;
    let white = m.floats("white_level", Some(1))?.unwrap_or_default()[0];
    Ok(Levels {
        black_repeat,
        black,
        black_delta_h: m.floats("black_level_delta_h", None)?.unwrap_or_default(),
        black_delta_v: m.floats("black_level_delta_v", None)?.unwrap_or_default(),
        white,
    })
}

/// The dict's LinearizationTable (None when missing or None), as 16-bit values.
fn parse_linearization(m: &Meta<'_>) -> PyResult<Option<Vec<u16>>> {
    Ok(m.floats("linearization_table", None)?.map(|t| {
        t.into_iter()
            .map(|x| x.clamp(0.0, 65535.0) as u16)
            .collect()
    }))
}

/// What the release's network input reads of a `Raw.meta`-like dict: the CFA pattern, the
/// levels, the LinearizationTable and AsShotNeutral (other keys are not read).
pub(crate) struct InputMeta {
    pub bayer: Bayer,
    pub levels: Levels,
    pub linearization: Option<Vec<u16>>,
    pub as_shot_neutral: Option<[f64; 3]>,
}

/// [`InputMeta`] of `meta`; a dict without a CFA pattern (a LinearRaw raw's) is refused.
pub(crate) fn input_meta(meta: &Bound<'_, PyAny>) -> PyResult<InputMeta> {
    let d = meta
        .cast::<PyDict>()
        .map_err(|_| value_err("meta must be a dict (as Raw.meta returns)"))?;
    let m = Meta { d: d.clone() };
    let Some(cfa) = m.get("cfa_pattern")? else {
        return Err(value_err(
            "the raw is not a Bayer CFA mosaic (no cfa_pattern)",
        ));
    };
    Ok(InputMeta {
        bayer: cfa_from(&cfa, "meta[\"cfa_pattern\"]")?,
        levels: parse_levels(&m)?,
        linearization: parse_linearization(&m)?.filter(|t| !t.is_empty()),
        as_shot_neutral: m.floats_n::<3>("as_shot_neutral")?,
    })
}

/// Build the library's metadata from the dict; returns it with the defaults' notes.
fn parse_meta(
    m: &Meta<'_>,
    width: usize,
    height: usize,
    max_sample: u16,
) -> PyResult<(RawMeta, Vec<String>)> {
    for k in m.d.keys() {
        let k: String = k
            .extract()
            .map_err(|_| value_err("meta keys must be strings"))?;
        if !KEYS.contains(&k.as_str()) {
            return Err(value_err(format!(
                "meta[{k:?}]: unknown key (known: {})",
                KEYS.join(", ")
            )));
        }
    }
    for (k, n) in [("width", width), ("height", height)] {
        if let Some(v) = m.extract::<usize>(k, "an integer")? {
            if v != n {
                return Err(Meta::bad(k, format!("{v} but the data array has {n}")));
            }
        }
    }
    if let Some(spp) = m.extract::<u64>("samples_per_pixel", "an integer")? {
        if spp != 1 {
            return Err(Meta::bad(
                "samples_per_pixel",
                format!(
                    "{spp}: Raw.from_array builds CFA mosaics (1 sample per pixel); \
                     a LinearRaw image is read with read_dng"
                ),
            ));
        }
    }
    let bayer = cfa_from(&m.required("cfa_pattern")?, "meta[\"cfa_pattern\"]")?;
    let levels = parse_levels(m)?;
    let white = levels.white;
    let bits = match m.extract::<u16>("bits_per_sample", "an integer")? {
        Some(b) => b,
        None => {
            // The fewest bits that hold the white level and every sample, at least 8.
            let top = (white.clamp(0.0, 65535.0) as u32).max(u32::from(max_sample));
            (32 - top.leading_zeros()).clamp(8, 16) as u16
        }
    };
    let mut meta = RawMeta::bare(bayer, levels, bits);
    meta.linearization_table = parse_linearization(m)?;
    if let Some(a) = m.ints("active_area", 4)? {
        let c = |x: i64| u32::try_from(x).unwrap_or(u32::MAX);
        meta.active_area = Some(Rect {
            top: c(a[0]),
            left: c(a[1]),
            bottom: c(a[2]),
            right: c(a[3]),
        });
    }
    let a = RawImage {
        width,
        height,
        data: Vec::new(),
        meta: meta.clone(),
    }
    .active_area();
    if let Some(dc) = m.ints("default_crop", 4)? {
        let (top, left, h, w) = (dc[0], dc[1], dc[2], dc[3]);
        let whole = top == 0 && left == 0 && h as usize == a.height() && w as usize == a.width();
        if !whole {
            meta.default_crop_origin = Some([left as f64, top as f64]);
            meta.default_crop_size = Some([w as f64, h as f64]);
        }
    }
    meta.orientation = m
        .extract::<u16>("orientation", "an integer 1..8")?
        .unwrap_or(1);
    parse_tags(m, &mut meta)?;
    let notes = apply_defaults(m, &mut meta)?;
    Ok((meta, notes))
}

/// A library error about the metadata, as a ValueError naming the dict keys too: every
/// tag the message names as a whole word (`BlackLevel` is not `BlackLevelDeltaH`), in the
/// message's order (`black level 5000 >= white level 4095 (BlackLevel against WhiteLevel)`
/// names `meta["black_level"]` and `meta["white_level"]`).
fn meta_err(e: day2night::Error) -> PyErr {
    let msg = e.to_string();
    let mut found: Vec<(usize, &str)> = Vec::new();
    for (tag, key) in TAG_KEYS {
        let at = msg.match_indices(tag).find(|(i, _)| {
            let next = msg[i + tag.len()..].chars().next();
            !next.is_some_and(|c| c.is_ascii_alphanumeric())
        });
        if let Some((i, _)) = at {
            if !found.iter().any(|(_, k)| k == key) {
                found.push((i, key));
            }
        }
    }
    found.sort();
    if found.is_empty() {
        return py_err(e);
    }
    let keys: Vec<String> = found.iter().map(|(_, k)| format!("meta[{k:?}]")).collect();
    py_err_noting(e, &format!("({})", keys.join(", ")))
}

/// The stem and file name of an in-memory raw called `name` (`day` or `day.dng`).
fn names(name: &str) -> PyResult<(String, String)> {
    if name.is_empty() || name.contains(['/', '\\', '\0']) || name == "." || name == ".." {
        return Err(value_err(format!(
            "name {name:?}: give a file stem such as \"day\" (it keys the random streams and names the outputs)"
        )));
    }
    let lower = name.to_ascii_lowercase();
    Ok(match lower.strip_suffix(".dng") {
        Some(_) if name.len() > 4 => (name[..name.len() - 4].to_string(), name.to_string()),
        _ => (name.to_string(), format!("{name}.dng")),
    })
}

/// `Raw.from_array`: the raw (in memory, named after `name`) and its stem.
pub(crate) fn from_array(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    meta: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<(DayInput, String)> {
    let d = meta
        .cast::<PyDict>()
        .map_err(|_| value_err("meta must be a dict (as Raw.meta returns)"))?;
    let (stem, file_name) = names(name)?;
    let arr: PyReadonlyArray2<'_, u16> = data.extract().map_err(|_| {
        let (dtype, shape) = (
            data.getattr("dtype")
                .map(|v| short_repr(&v))
                .unwrap_or_default(),
            data.getattr("shape")
                .map(|v| short_repr(&v))
                .unwrap_or_default(),
        );
        value_err(format!(
            "data must be a 2-D uint16 numpy array (got dtype {dtype}, shape {shape})"
        ))
    })?;
    let v = arr.as_array();
    let (height, width) = v.dim();
    let samples: Vec<u16> = match v.as_slice() {
        Some(s) => s.to_vec(),
        None => v.iter().copied().collect(),
    };
    let max_sample = samples.iter().copied().max().unwrap_or(0);
    let (rmeta, notes) = parse_meta(&Meta { d: d.clone() }, width, height, max_sample)?;
    let mut raw = RawImage::from_parts(width, height, samples, rmeta).map_err(meta_err)?;
    // The DNG layer's value checks (matrix conditioning, neutral ratios, NoiseProfile, ...),
    // exactly as `read_dng` applies them to a file: corrections come back as warnings.
    day2night::dng::check::check_meta(&mut raw.meta).map_err(meta_err)?;
    let defaults = notes
        .into_iter()
        .map(|n| day2night::Warning::new(day2night::Code::MetadataDefault, n));
    let all: Vec<day2night::Warning> = defaults.chain(raw.meta.warnings.iter().cloned()).collect();
    crate::diagnostics::warn_at(py, &file_name, &all, 2)?;
    let day = py.detach(move || on_pool(move || Ok(DayInput::in_memory(raw, &file_name))));
    Ok((day.map_err(py_err)?, stem))
}
