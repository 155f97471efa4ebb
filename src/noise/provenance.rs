//! Where a noise model came from and which camera it belongs to (issue 24 point 3): the
//! `noise` entry of a sidecar's `calibration.provenance`, the plan's `noise_provenance`,
//! and the `camera` of noise model files.

use crate::raw::camera::CameraId;
use serde::{Deserialize, Deserializer, Serialize};

/// The source of the noise model a plan uses (docs/noise.md, "Where the model comes from", in the chain's order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseSource {
    /// A model file (`--noise-model`).
    File,
    /// The input DNG's own NoiseProfile, at its Exif ISO.
    NoiseProfile,
    /// Estimated from the day image itself at its Exif ISO (`noise::estimate`).
    ImageEstimate,
    /// An embedded table (`synth::dictionaries::embedded`): the paper's phone's, the
    /// Samsung Galaxy S20 FE (the only one today, whence the name).
    #[serde(rename = "embedded_s20fe")]
    EmbeddedS20Fe,
}

impl NoiseSource {
    /// The name written in sidecars: `file`, `noise_profile`, `image_estimate`,
    /// `embedded_s20fe`.
    pub fn name(self) -> &'static str {
        match self {
            NoiseSource::File => "file",
            NoiseSource::NoiseProfile => "noise_profile",
            NoiseSource::ImageEstimate => "image_estimate",
            NoiseSource::EmbeddedS20Fe => "embedded_s20fe",
        }
    }
}

/// Where a plan's noise model came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseProvenance {
    /// The source.
    pub source: NoiseSource,
    /// The camera the model belongs to (null when unknown, e.g. a model file that does not
    /// record it).
    pub camera: Option<CameraId>,
    /// In words: which file, ISO, fit, and why this source was taken.
    pub note: String,
}

/// The `camera` of a model file: an object `{make, model, unique_camera_model}` (what
/// `calibrate noise` writes), or, in files written before it was one, a string (the
/// UniqueCameraModel, else `Make Model`), read as a UniqueCameraModel; null or absent =
/// unknown.
pub fn deserialize_camera<'de, D: Deserializer<'de>>(d: D) -> Result<Option<CameraId>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Field {
        Id(CameraId),
        Name(String),
    }
    Ok(match Option::<Field>::deserialize(d)? {
        None => None,
        Some(Field::Id(c)) => Some(c),
        Some(Field::Name(n)) => Some(CameraId::new(None, None, Some(n))),
    }
    .filter(|c| !c.is_unknown()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct Doc {
        #[serde(default, deserialize_with = "deserialize_camera")]
        camera: Option<CameraId>,
    }

    #[test]
    fn camera_field_forms() {
        let read = |s: &str| serde_json::from_str::<Doc>(s).unwrap().camera;
        assert_eq!(read("{}"), None);
        assert_eq!(read(r#"{"camera": null}"#), None);
        assert_eq!(read(r#"{"camera": ""}"#), None);
        let legacy = read(r#"{"camera": "Canon EOS 5D"}"#).unwrap();
        assert_eq!(legacy.unique_camera_model.as_deref(), Some("Canon EOS 5D"));
        let id = read(
            r#"{"camera": {"make": "Canon", "model": "EOS 5D", "unique_camera_model": null}}"#,
        )
        .unwrap();
        assert_eq!(id.make.as_deref(), Some("Canon"));
        assert!(serde_json::from_str::<Doc>(r#"{"camera": 3}"#).is_err());
    }

    #[test]
    fn source_names_match_serde() {
        for s in [
            NoiseSource::File,
            NoiseSource::NoiseProfile,
            NoiseSource::ImageEstimate,
            NoiseSource::EmbeddedS20Fe,
        ] {
            assert_eq!(
                serde_json::to_string(&s).unwrap(),
                format!("\"{}\"", s.name())
            );
        }
    }
}
