//! A raw image from parts held outside a DNG file: a CFA array and its metadata as another
//! reader (LibRaw through rawpy, a simulator, a Python array) gives them.
//!
//! [`RawMeta::bare`] starts a metadata set from what every raw has (Bayer pattern, levels,
//! bits); the caller fills what it knows; [`ColorDefault::apply`] fills each piece of colour
//! metadata it lacks with the documented default (and says what it used, for a warning);
//! [`RawImage::from_parts`] checks the whole as the DNG reader checks a file's tags (plus
//! [`RawImage::validate`]) before anything uses it. Nothing here reads or writes a file.

use super::meta::RawMeta;
use super::RawImage;
use crate::error::{Error, Result};

/// The XYZ (D65) -> linear sRGB matrix (IEC 61966-2-1), row-major: the default
/// ColorMatrix1 of a raw without colour metadata (a camera whose raw RGB is linear sRGB).
pub const SRGB_COLOR_MATRIX: [f64; 9] = crate::color::xyz::XYZ_TO_SRGB;
/// EXIF LightSource code of D65: the default CalibrationIlluminant1.
pub const D65_ILLUMINANT: u16 = 21;
/// CIE 1931 xy of D65: the default white (AsShotWhiteXY) of a raw without a neutral.
pub const D65_WHITE_XY: [f64; 2] = crate::color::xyz::D65_XY;

/// Largest width or height (the DNG reader's limit, `dng::read::MAX_DIMENSION`).
pub const MAX_SIDE: usize = 65535;

/// Colour metadata a source may lack, each with a documented default.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorDefault {
    /// No ColorMatrix1: [`SRGB_COLOR_MATRIX`] with CalibrationIlluminant1 D65.
    ColorMatrix,
    /// A ColorMatrix1 without CalibrationIlluminant1: D65 (LibRaw's and Adobe's single
    /// matrices are D65 matrices).
    CalibrationIlluminant,
    /// No AsShotNeutral (nor AsShotWhiteXY): the white is D65 ([`D65_WHITE_XY`]), mapped to
    /// a camera neutral through the colour matrix.
    Neutral,
    /// No ISO: unknown (the built-in noise model gives the clean raw's noise; a clean night
    /// DNG says ISO 50).
    Iso,
    /// No NoiseProfile: none (the built-in noise model gives the clean raw's noise).
    NoiseProfile,
}

impl ColorDefault {
    /// Fill `meta` with this default; returns what was used, for a warning.
    pub fn apply(self, meta: &mut RawMeta) -> String {
        match self {
            ColorDefault::ColorMatrix => {
                meta.color.color_matrix1 = Some(SRGB_COLOR_MATRIX.to_vec());
                meta.color.calibration_illuminant1 = Some(D65_ILLUMINANT);
                "no colour matrix: using the XYZ->sRGB matrix (the camera's raw RGB taken as \
                 linear sRGB) with calibration illuminant 21 (D65); colours are approximate"
                    .into()
            }
            ColorDefault::CalibrationIlluminant => {
                meta.color.calibration_illuminant1 = Some(D65_ILLUMINANT);
                "no calibration illuminant for colour matrix 1: using 21 (D65)".into()
            }
            ColorDefault::Neutral => {
                meta.as_shot_neutral = None;
                meta.as_shot_white_xy = Some(D65_WHITE_XY);
                format!(
                    "no as-shot neutral: using white point D65 (AsShotWhiteXY {}, {}) through \
                     the colour matrix",
                    D65_WHITE_XY[0], D65_WHITE_XY[1]
                )
            }
            ColorDefault::Iso => {
                meta.exif.iso = None;
                "no ISO: unknown (the built-in noise model gives the clean raw's noise; clean \
                 night DNGs say ISO 50)"
                    .into()
            }
            ColorDefault::NoiseProfile => {
                meta.noise_profile = None;
                "no noise profile: the built-in noise model gives the clean raw's noise".into()
            }
        }
    }
}

fn bad(what: impl std::fmt::Display) -> Error {
    Error::invalid(what.to_string())
}

fn finite(name: &str, v: &[f64]) -> Result<()> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(bad(format!("{name} holds a non-finite value ({x})"))),
        None => Ok(()),
    }
}

fn matrix(name: &str, m: &Option<Vec<f64>>) -> Result<()> {
    if let Some(m) = m {
        if m.len() != 9 {
            return Err(bad(format!("{name} has {} values, expected 3x3", m.len())));
        }
        finite(name, m)?;
    }
    Ok(())
}

fn positive(name: &str, v: &[f64]) -> Result<()> {
    match v.iter().find(|&&x| !(x.is_finite() && x > 0.0)) {
        Some(x) => Err(bad(format!("{name} component {x} is not positive"))),
        None => Ok(()),
    }
}

/// The checks the DNG reader applies to a file's tags, on typed metadata (see the module
/// documentation); normalizes AsShotNeutral to green = 1 as the reader does.
fn check_meta(meta: &mut RawMeta, width: usize, height: usize) -> Result<()> {
    let m = meta;
    if !(8..=16).contains(&m.bits_per_sample) {
        return Err(bad(format!(
            "BitsPerSample {} outside 8..=16",
            m.bits_per_sample
        )));
    }
    m.bayer()?;
    if let Some(t) = &m.linearization_table {
        if t.is_empty() || t.len() > 65536 {
            return Err(bad(format!(
                "LinearizationTable has {} entries (1..65536)",
                t.len()
            )));
        }
    }
    for (name, v) in [
        ("DefaultCropOrigin", m.default_crop_origin),
        ("DefaultCropSize", m.default_crop_size),
    ] {
        if let Some(p) = v {
            if p.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(bad(format!(
                    "{name} must be two non-negative numbers (got {p:?})"
                )));
            }
        }
    }
    if let Some(s) = m.default_crop_size {
        if s[0] <= 0.0 || s[1] <= 0.0 {
            return Err(bad("DefaultCropSize is zero"));
        }
    }
    if let Some(n) = m.as_shot_neutral {
        positive("AsShotNeutral", &n)?;
        m.as_shot_neutral = Some([n[0] / n[1], 1.0, n[2] / n[1]]);
    }
    if let Some(xy) = m.as_shot_white_xy {
        if !(xy.iter().all(|v| v.is_finite() && *v > 0.0) && xy[0] + xy[1] < 1.0) {
            return Err(bad(format!(
                "AsShotWhiteXY {xy:?} is not a chromaticity (x, y > 0, x + y < 1)"
            )));
        }
    }
    let c = &m.color;
    matrix("ColorMatrix1", &c.color_matrix1)?;
    matrix("ColorMatrix2", &c.color_matrix2)?;
    matrix("CameraCalibration1", &c.camera_calibration1)?;
    matrix("CameraCalibration2", &c.camera_calibration2)?;
    matrix("ForwardMatrix1", &c.forward_matrix1)?;
    matrix("ForwardMatrix2", &c.forward_matrix2)?;
    if let Some(ab) = &c.analog_balance {
        if ab.len() != 3 {
            return Err(bad(format!(
                "AnalogBalance has {} values for 3 planes",
                ab.len()
            )));
        }
        positive("AnalogBalance", ab)?;
    }
    if let Some(b) = c.baseline_exposure {
        finite("BaselineExposure", &[b])?;
    }
    if let Some(p) = &m.noise_profile {
        if p.len() != 1 && p.len() != 3 {
            return Err(bad(format!(
                "NoiseProfile has {} (S, O) pairs (expected 1 or 3)",
                p.len()
            )));
        }
        let flat: Vec<f64> = p.iter().flat_map(|&(s, o)| [s, o]).collect();
        finite("NoiseProfile", &flat)?;
    }
    if !(1..=8).contains(&m.orientation) {
        return Err(bad(format!("Orientation {} outside 1..=8", m.orientation)));
    }
    let e = &m.exif;
    if e.iso == Some(0) {
        return Err(bad("ISO 0 (leave it out when unknown)"));
    }
    for (name, v) in [("ExposureTime", e.exposure_time), ("FNumber", e.f_number)] {
        if let Some(v) = v {
            positive(name, &[v])?;
        }
    }
    let max = MAX_SIDE;
    if width > max || height > max {
        return Err(Error::limits(format!(
            "{width}x{height} image: at most {max} samples per side"
        )));
    }
    let limit = crate::limits::Limits::current()?.max_pixels;
    if (width as u64).saturating_mul(height as u64) > limit {
        return Err(Error::limits(format!(
            "{width}x{height} image exceeds the pixel limit {limit} (--max-pixels, D2N_MAX_PIXELS)"
        )));
    }
    Ok(())
}

impl RawImage {
    /// A raw image from a CFA plane (`width x height` stored samples, row-major, masked
    /// border included) and its metadata, checked as the DNG reader checks a file: the
    /// metadata values (lengths, finite and positive numbers, CFA, orientation, ISO,
    /// limits; AsShotNeutral normalized to green = 1), [`RawImage::validate`] (buffer,
    /// ActiveArea, levels) and every sample within `BitsPerSample`.
    pub fn from_parts(
        width: usize,
        height: usize,
        data: Vec<u16>,
        mut meta: RawMeta,
    ) -> Result<RawImage> {
        check_meta(&mut meta, width, height)?;
        let img = RawImage {
            width,
            height,
            data,
            meta,
        };
        img.validate()?;
        let top = (1u32 << img.meta.bits_per_sample) - 1;
        if let Some(i) = img.data.iter().position(|&v| u32::from(v) > top) {
            return Err(bad(format!(
                "sample {} at row {}, column {} exceeds BitsPerSample {} (largest {top})",
                img.data[i],
                i / width,
                i % width,
                img.meta.bits_per_sample
            )));
        }
        Ok(img)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::{Bayer, Levels, Rect};

    fn levels(black: f64, white: f64) -> Levels {
        Levels {
            black_repeat: (1, 1),
            black: vec![black],
            black_delta_h: vec![],
            black_delta_v: vec![],
            white,
        }
    }

    fn parts() -> (Vec<u16>, RawMeta) {
        let mut m = RawMeta::bare(Bayer::GRBG, levels(64.0, 4095.0), 12);
        ColorDefault::ColorMatrix.apply(&mut m);
        m.as_shot_neutral = Some([1.0, 2.0, 1.5]);
        ((0..8 * 6).map(|i| (i * 80) as u16).collect(), m)
    }

    #[test]
    fn a_good_raw_is_built_and_its_neutral_normalized() {
        let (d, m) = parts();
        let img = RawImage::from_parts(8, 6, d.clone(), m).unwrap();
        assert_eq!(img.meta.as_shot_neutral, Some([0.5, 1.0, 0.75]));
        assert_eq!(img.bayer().unwrap(), Bayer::GRBG);
        assert_eq!(img.data, d);
        // The DNG writer accepts it and the reader gives back the same pixels and levels.
        let bytes =
            crate::dng::write::encode_dng(&img, &crate::dng::write::WriteOptions::default())
                .unwrap();
        let back = crate::dng::read::read_dng_bytes(&bytes).unwrap();
        assert_eq!(back.data, img.data);
        assert_eq!(back.meta.levels, img.meta.levels);
        assert_eq!(back.meta.color.color_matrix1, img.meta.color.color_matrix1);
    }

    #[test]
    fn each_bad_value_is_refused_with_its_name() {
        type Change = Box<dyn Fn(&mut RawMeta)>;
        let cases: Vec<(&str, Change)> = vec![
            (
                "AsShotNeutral",
                Box::new(|m| m.as_shot_neutral = Some([1.0, 0.0, 1.0])),
            ),
            (
                "AsShotWhiteXY",
                Box::new(|m| m.as_shot_white_xy = Some([0.7, 0.5])),
            ),
            (
                "ColorMatrix1",
                Box::new(|m| m.color.color_matrix1 = Some(vec![1.0; 8])),
            ),
            (
                "ForwardMatrix2",
                Box::new(|m| m.color.forward_matrix2 = Some(vec![f64::NAN; 9])),
            ),
            (
                "AnalogBalance",
                Box::new(|m| m.color.analog_balance = Some(vec![1.0, -1.0, 1.0])),
            ),
            (
                "NoiseProfile",
                Box::new(|m| m.noise_profile = Some(vec![(1.0, 0.0); 2])),
            ),
            ("Orientation", Box::new(|m| m.orientation = 9)),
            ("ISO 0", Box::new(|m| m.exif.iso = Some(0))),
            (
                "ExposureTime",
                Box::new(|m| m.exif.exposure_time = Some(-1.0)),
            ),
            (
                "LinearizationTable",
                Box::new(|m| m.linearization_table = Some(vec![])),
            ),
            (
                "DefaultCropSize",
                Box::new(|m| m.default_crop_size = Some([0.0, 4.0])),
            ),
            ("BitsPerSample", Box::new(|m| m.bits_per_sample = 17)),
            ("Bayer", Box::new(|m| m.cfa.pattern = vec![0, 0, 1, 2])),
            ("black level", Box::new(|m| m.levels.black = vec![5000.0])),
            (
                "ActiveArea",
                Box::new(|m| {
                    m.active_area = Some(Rect {
                        top: 0,
                        left: 0,
                        bottom: 7,
                        right: 8,
                    })
                }),
            ),
        ];
        for (want, f) in cases {
            let (d, mut m) = parts();
            f(&mut m);
            let e = RawImage::from_parts(8, 6, d, m).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    #[test]
    fn samples_beyond_the_bit_depth_and_bad_shapes_are_refused() {
        let (mut d, m) = parts();
        d[13] = 4096;
        let e = RawImage::from_parts(8, 6, d, m.clone())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("row 1, column 5") && e.contains("BitsPerSample 12"),
            "{e}"
        );
        let e = RawImage::from_parts(8, 5, vec![0; 48], m.clone()).unwrap_err();
        assert!(e.to_string().contains("48 samples"), "{e}");
        let e = RawImage::from_parts(0, 0, vec![], m).unwrap_err();
        assert!(e.to_string().contains("zero"), "{e}");
    }

    #[test]
    fn defaults_fill_what_they_name() {
        let mut m = RawMeta::bare(Bayer::RGGB, levels(0.0, 255.0), 8);
        let notes: Vec<String> = [
            ColorDefault::ColorMatrix,
            ColorDefault::Neutral,
            ColorDefault::Iso,
            ColorDefault::NoiseProfile,
        ]
        .iter()
        .map(|d| d.apply(&mut m))
        .collect();
        assert!(notes[0].contains("D65") && notes[1].contains("0.3127"));
        assert_eq!(m.color.calibration_illuminant1, Some(D65_ILLUMINANT));
        assert_eq!(m.as_shot_white_xy, Some(D65_WHITE_XY));
        // The defaulted raw renders: the D65 white through the sRGB matrix is neutral.
        let img = RawImage::from_parts(4, 4, vec![100; 16], m).unwrap();
        let n = crate::isp::render::resolve_neutral(&img.meta, None).unwrap();
        for c in n {
            assert!((c - 1.0).abs() < 1e-3, "{n:?}");
        }
    }
}
