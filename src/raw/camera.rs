//! `CameraId`: which camera a raw (or a calibration) belongs to, from the Make, Model and
//! UniqueCameraModel tags, and the comparison that decides whether a calibration measured on
//! one camera is being applied to another.
//!
//! Names are compared after trimming, collapsing runs of white space and ASCII lower-casing;
//! an empty name or `Unknown` (what the DNG writer stores when the source had none) counts
//! as absent. UniqueCameraModel decides when both sides have it (the DNG spec's identifier
//! of a camera model); otherwise Make and Model decide when both sides have both; otherwise
//! the two cannot be compared ([`CameraId::same_camera`] returns `None`), except that a
//! UniqueCameraModel equal to the other side's `Make Model` or `Model` (how writers,
//! ours included, build one) is the same camera.

use crate::raw::RawMeta;
use serde::{Deserialize, Serialize};

/// Make, Model and UniqueCameraModel of a camera, as the file stored them (trimmed).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CameraId {
    /// Make.
    #[serde(default)]
    pub make: Option<String>,
    /// Model.
    #[serde(default)]
    pub model: Option<String>,
    /// UniqueCameraModel.
    #[serde(default)]
    pub unique_camera_model: Option<String>,
}

/// Trimmed name, `None` when empty or `Unknown`.
fn clean(s: &Option<String>) -> Option<String> {
    let t = s.as_deref()?.trim();
    (!t.is_empty() && !t.eq_ignore_ascii_case("unknown")).then(|| t.to_string())
}

/// Comparison key of a name: white space collapsed, ASCII lower case.
fn key(s: &str) -> String {
    s.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_ascii_lowercase()
}

impl CameraId {
    /// From the three names (trimmed; empty or `Unknown` = absent).
    pub fn new(
        make: Option<String>,
        model: Option<String>,
        unique_camera_model: Option<String>,
    ) -> CameraId {
        CameraId {
            make: clean(&make),
            model: clean(&model),
            unique_camera_model: clean(&unique_camera_model),
        }
    }

    /// The camera of a raw's metadata.
    pub fn of(meta: &RawMeta) -> CameraId {
        CameraId::new(
            meta.make.clone(),
            meta.model.clone(),
            meta.unique_camera_model.clone(),
        )
    }

    /// True when no name is known.
    pub fn is_unknown(&self) -> bool {
        self.make.is_none() && self.model.is_none() && self.unique_camera_model.is_none()
    }

    /// `Some(true)` for the same camera model, `Some(false)` for different ones, `None`
    /// when the names do not allow a comparison (see the module docs).
    pub fn same_camera(&self, other: &CameraId) -> Option<bool> {
        let k = |s: &Option<String>| s.as_deref().map(key);
        let (u1, u2) = (k(&self.unique_camera_model), k(&other.unique_camera_model));
        if let (Some(a), Some(b)) = (&u1, &u2) {
            return Some(a == b);
        }
        let (m1, m2) = (
            (k(&self.make), k(&self.model)),
            (k(&other.make), k(&other.model)),
        );
        if let ((Some(a1), Some(b1)), (Some(a2), Some(b2))) = (&m1, &m2) {
            return Some(a1 == a2 && b1 == b2);
        }
        // One side has only a UniqueCameraModel: it matches a `Make Model` or `Model`.
        let mixed = |u: &Option<String>, (make, model): &(Option<String>, Option<String>)| {
            let u = u.as_ref()?;
            let model = model.as_ref()?;
            let full = make.as_ref().map(|m| format!("{m} {model}"));
            (u == model || full.as_ref() == Some(u)).then_some(true)
        };
        mixed(&u1, &m2).or_else(|| mixed(&u2, &m1))
    }

    /// True when the Make is `make` and the Model begins with one of `model_prefixes`,
    /// both compared as names are (white space collapsed, ASCII case ignored): how an
    /// embedded calibration recognizes its camera (`synth::dictionaries::embedded`).
    pub fn make_and_model_prefix(&self, make: &str, model_prefixes: &[&str]) -> bool {
        let model = self.model.as_deref().map(key);
        self.make.as_deref().map(key) == Some(key(make))
            && model.is_some_and(|m| model_prefixes.iter().any(|p| m.starts_with(&key(p))))
    }

    /// A name for messages: UniqueCameraModel, else `Make Model`, else `unknown camera`.
    pub fn label(&self) -> String {
        if let Some(u) = &self.unique_camera_model {
            return u.clone();
        }
        match (&self.make, &self.model) {
            (Some(a), Some(b)) => format!("{a} {b}"),
            (Some(a), None) | (None, Some(a)) => a.clone(),
            (None, None) => "unknown camera".into(),
        }
    }
}

impl std::fmt::Display for CameraId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.label())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(make: Option<&str>, model: Option<&str>, ucm: Option<&str>) -> CameraId {
        let s = |v: Option<&str>| v.map(String::from);
        CameraId::new(s(make), s(model), s(ucm))
    }

    #[test]
    fn unique_camera_model_decides_when_both_have_it() {
        let a = id(Some("Canon"), Some("EOS 5D"), Some("Canon EOS 5D"));
        let b = id(Some("canon"), Some("eos 5d"), Some("  canon   EOS 5D "));
        assert_eq!(a.same_camera(&b), Some(true));
        let c = id(Some("Canon"), Some("EOS 5D"), Some("Canon EOS 5D Mark II"));
        assert_eq!(a.same_camera(&c), Some(false));
    }

    #[test]
    fn make_and_model_decide_without_unique_camera_model() {
        let a = id(Some("Canon"), Some("EOS 5D"), None);
        assert_eq!(
            a.same_camera(&id(Some("CANON"), Some("EOS  5D"), None)),
            Some(true)
        );
        assert_eq!(
            a.same_camera(&id(Some("Nikon"), Some("EOS 5D"), None)),
            Some(false)
        );
        // A writer-made UniqueCameraModel matches its Make Model.
        assert_eq!(
            a.same_camera(&id(None, None, Some("canon eos 5d"))),
            Some(true)
        );
        assert_eq!(id(None, None, Some("EOS 5D")).same_camera(&a), Some(true));
        // Otherwise cannot tell.
        assert_eq!(a.same_camera(&id(None, None, Some("Nikon D3"))), None);
        assert_eq!(a.same_camera(&id(Some("Canon"), None, None)), None);
        assert_eq!(a.same_camera(&CameraId::default()), None);
    }

    #[test]
    fn empty_and_unknown_names_are_absent() {
        let u = id(Some(""), Some("Unknown"), Some("  "));
        assert!(u.is_unknown());
        assert_eq!(u.label(), "unknown camera");
        assert_eq!(u, CameraId::default());
    }

    #[test]
    fn make_and_model_prefix_rule() {
        let phone = |c: &CameraId| c.make_and_model_prefix("samsung", &["SM-G780", "SM-G781"]);
        for (make, model) in [
            ("samsung", "SM-G780F"),
            ("SAMSUNG", "SM-G781B"),
            ("Samsung", "sm-g780g"),
            (" samsung ", "SM-G781U1"),
        ] {
            assert!(phone(&id(Some(make), Some(model), None)), "{make} {model}");
        }
        for (make, model) in [
            (Some("samsung"), Some("SM-G991B")),
            (Some("Google"), Some("SM-G780F")),
            (None, Some("SM-G780F")),
            (Some("samsung"), None),
            (Some("samsung"), Some("G780")),
        ] {
            assert!(!phone(&id(make, model, None)), "{make:?} {model:?}");
        }
    }

    #[test]
    fn from_meta_and_label() {
        let m = RawMeta::new_bayer(crate::raw::Bayer::RGGB, 12, 0.0, 4095.0);
        let c = CameraId::of(&m);
        assert_eq!(c.make.as_deref(), Some("day2night"));
        assert_eq!(c.label(), "day2night Synthetic");
        assert_eq!(id(Some("A"), Some("B"), None).to_string(), "A B");
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(serde_json::from_str::<CameraId>(&json).unwrap(), c);
        assert_eq!(
            serde_json::from_str::<CameraId>("{}").unwrap(),
            CameraId::default()
        );
    }
}
