//! Typed warnings: one [`Warning`] type with a stable [`Code`], the thing it is about (its
//! subject) and the human message, collected in a [`Diagnostics`] sink (docs/warnings.md).
//!
//! Every part of the library that has something to say without failing pushes a
//! [`Warning`] into the `Diagnostics` of the value it returns (a file's metadata, a plan, a
//! calibration, a run's summary); the command line prints each one once as
//! `warning[CODE]: SUBJECT: MESSAGE`, the `--json` outputs and the sidecar carry the code,
//! and Python raises the `day2night.Day2NightWarning` subclass of the code. The library
//! itself prints nothing.
//!
//! The subject names what the warning is about: the input file, a scene, an option, a
//! calibration image. Code that makes a warning without knowing the file (the metadata
//! checks, the opcode checks) leaves it empty; the caller that knows the file fills it in
//! with [`Diagnostics::about`].
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// Declares [`Code`] with its name and summary, once.
macro_rules! codes {
    ($( $(#[$doc:meta])* $variant:ident = $name:literal, $summary:literal; )*) => {
        /// The stable identifier of a kind of warning (kebab-case; listed in
        /// docs/warnings.md with its summary).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Code {
            $( $(#[$doc])* $variant, )*
        }

        impl Code {
            /// Every code, in documentation order.
            pub const ALL: &'static [Code] = &[$(Code::$variant,)*];

            /// The code as printed and serialized (`noise-extrapolated`).
            pub fn as_str(self) -> &'static str {
                match self {
                    $(Code::$variant => $name,)*
                }
            }

            /// One line on what the warning means (docs/warnings.md).
            pub fn summary(self) -> &'static str {
                match self {
                    $(Code::$variant => $summary,)*
                }
            }

            /// The code named `name`.
            pub fn from_name(name: &str) -> Option<Code> {
                match name {
                    $($name => Some(Code::$variant),)*
                    _ => None,
                }
            }
        }
    };
}

codes! {
    /// A CalibrationIlluminant outside the EXIF LightSource table.
    CalibrationIlluminantUnknown = "calibration-illuminant-unknown",
        "a CalibrationIlluminant is not an EXIF LightSource code: the colour matrices are not interpolated (ColorMatrix1 is used)";
    /// A NoiseProfile that is not a noise model, dropped.
    NoiseProfileInvalid = "noise-profile-invalid",
        "the input's NoiseProfile is not a noise model (S <= 0, O < 0, non-finite or too large): ignored";
    /// An Exif ISO outside the supported range, dropped.
    IsoOutOfRange = "iso-out-of-range",
        "the input's ISOSpeedRatings is outside the supported range: ignored (ISO unknown)";
    /// An optional opcode a render cannot apply.
    OpcodeSkipped = "opcode-skipped",
        "an optional DNG opcode cannot be applied: skipped";
    /// A malformed opcode list in a job that renders nothing.
    OpcodeListMalformed = "opcode-list-malformed",
        "an opcode list is malformed; nothing is rendered, so it is not used (a render would fail)";
    /// A mandatory opcode that cannot be applied, in a job that renders nothing.
    OpcodeNotApplied = "opcode-not-applied",
        "a mandatory opcode cannot be applied; nothing is rendered, so nothing fails (a render would)";
    /// An opcode whose parameters make every sample it touches one value.
    OpcodeFlattens = "opcode-flattens",
        "an opcode's parameters make every sample it touches one value";
    /// An OpcodeList3 TrimBounds that changes the rendered size.
    OpcodeTrim = "opcode-trim",
        "an OpcodeList3 TrimBounds makes rendered images smaller than the raw's crop";
    /// An opcode list dropped by `convert --bad-opcode-lists drop`.
    OpcodeListDropped = "opcode-list-dropped",
        "convert --bad-opcode-lists drop left out an opcode list it cannot read";
    /// A render that came out constant.
    RenderConstant = "render-constant",
        "a render (target, network input, render output) is constant, or has a constant plane";
    /// A noise model file calibrated on another camera.
    NoiseOtherCamera = "noise-other-camera",
        "the noise model file was calibrated on another camera";
    /// A noise model file with negative parameters.
    NoiseNegativeClamped = "noise-negative-clamped",
        "the noise model file has negative parameters: synth clamps them to 0";
    /// `--compat release` keeps the paper phone's noise table.
    NoiseCompatTable = "noise-compat-table",
        "the input has no NoiseProfile and --compat release uses the paper phone's noise table";
    /// No NoiseProfile and no ISO: the paper phone's table.
    UnknownIso = "unknown-iso",
        "the input has no NoiseProfile and no ISO: its noise cannot be estimated (the paper phone's table is used)";
    /// No NoiseProfile and an estimate from the image that cannot be trusted.
    NoiseEstimateUntrusted = "noise-estimate-untrusted",
        "the input has no NoiseProfile and the noise estimated from the image cannot be trusted (the paper phone's table is used)";
    /// An ISO outside the noise model's calibrated range.
    NoiseExtrapolated = "noise-extrapolated",
        "an output ISO is outside the noise model's calibrated range: its noise is extrapolated";
    /// `info`: no noise model for this input.
    NoiseUnavailable = "noise-unavailable",
        "info: no noise model can be chosen for this input with the default options";
    /// Night illuminants of another camera.
    IlluminantsOtherCamera = "illuminants-other-camera",
        "the night illuminant dictionary holds another camera's colours";
    /// Burst frames whose valid area is small or empty.
    BurstValidArea = "burst-valid-area",
        "burst frames keep a valid area under half of the active area (or none)";
    /// `calibrate noise --physics`: an odd flat left out.
    CalibrateOddFlats = "calibrate-odd-flats",
        "calibrate noise --physics: odd number of flats at an ISO, the brightest left out";
    /// `calibrate noise --from-image`: an image whose estimate cannot be trusted.
    CalibrateImageUntrusted = "calibrate-image-untrusted",
        "calibrate noise --from-image: an image's noise estimate cannot be trusted: left out";
    /// `calibrate noise --from-image`: images of one ISO with other levels.
    CalibrateLevelsDiffer = "calibrate-levels-differ",
        "calibrate noise --from-image: images of one ISO have different black or white levels";
    /// `calibrate noise`: two sources for one ISO.
    CalibrateIsoOverlap = "calibrate-iso-overlap",
        "calibrate noise: two sources calibrate one ISO; the measured one takes precedence";
    /// `calibrate noise`: a fit with a negative parameter.
    CalibrateNegativeParameter = "calibrate-negative-parameter",
        "calibrate noise: a fitted parameter is negative (synth clamps variances at 0)";
    /// `calibrate noise`: inputs of several cameras.
    CalibrateMixedCameras = "calibrate-mixed-cameras",
        "calibrate: an input comes from another camera than the first input";
    /// `calibrate illuminants`: many saturated sites on the gray card.
    GrayCardSaturated = "gray-card-saturated",
        "calibrate illuminants: many saturated sites on the gray card: the mean is biased low";
    /// `calibrate illuminants`: no xy for a gray card.
    GrayCardNoXy = "gray-card-no-xy",
        "calibrate illuminants: no CIE xy for a gray card: the dictionary serves this camera only";
    /// `calibrate illuminants`: a dictionary fit on too few lights.
    IlluminantsDegenerate = "illuminants-degenerate",
        "calibrate illuminants: one or two lights give a zero or degenerate covariance";
    /// `calibrate illuminants`: a note on how the dictionary was built.
    IlluminantsDictionary = "illuminants-dictionary",
        "calibrate illuminants: a note on the inputs of the dictionary (mixed cameras, missing xy)";
    /// `calibrate brightness`: a dictionary of one image.
    BrightnessSingleImage = "brightness-single-image",
        "calibrate brightness: one image gives std 0";
    /// `eval --nonfinite zero`: NaN/Inf replaced.
    NonfiniteReplaced = "nonfinite-replaced",
        "eval --nonfinite zero: NaN/Inf samples replaced by 0";
    /// `report`: a plot or image that could not be made.
    ReportNotAvailable = "report-not-available",
        "report: a sample image or plot could not be made (the page says not available)";
    /// `real-pairs`: a noisy frame with other levels than the clean burst.
    RealLevelsDiffer = "real-levels-differ",
        "real-pairs: a noisy frame's black/white levels differ from the clean burst's";
    /// `real-pairs`: a frame whose DNG ISO is not its name's.
    RealIsoMismatch = "real-iso-mismatch",
        "real-pairs: a frame's DNG ISO differs from the ISO in its name or folder";
    /// `real-pairs`: a scene without a high-ISO frame.
    RealNoNoisyFrame = "real-no-noisy-frame",
        "real-pairs: the scene has no high-ISO frame (clean task only)";
    /// `real-pairs`: a frame whose motion cannot be measured (featureless).
    RealMotionUnmeasured = "real-motion-unmeasured",
        "real-pairs: a frame's motion cannot be measured (no signal, or no structure to align)";
    /// Python `Raw.from_array`: a metadata default used.
    MetadataDefault = "metadata-default",
        "Python Raw.from_array: a metadata value was not given and a default is used";
    /// A warning read from a file written before warnings had codes (a plain string).
    Legacy = "legacy",
        "a warning read from a sidecar or calibration file written before warnings had codes";
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for Code {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for Code {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Code::from_name(&name)
            .ok_or_else(|| de::Error::custom(format!("unknown warning code {name:?}")))
    }
}

/// One warning: what kind ([`Code`]), about what (`subject`: a file, scene, option...; empty
/// until the caller that knows it fills it in) and the human text.
///
/// Serialized as `{"code", "subject", "message"}`. A plain string (how sidecars and
/// calibration files held warnings before codes) reads as a [`Code::Legacy`] warning with
/// no subject, and such a warning is written back as the same string, so that old files
/// replay byte for byte.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Warning {
    /// The kind.
    pub code: Code,
    /// What it is about (the input file, a scene, an option); may be empty.
    pub subject: String,
    /// The human text.
    pub message: String,
}

impl Warning {
    /// A warning without a subject (the caller fills it in, [`Diagnostics::about`]).
    pub fn new(code: Code, message: impl Into<String>) -> Warning {
        Warning {
            code,
            subject: String::new(),
            message: message.into(),
        }
    }

    /// This warning about `subject`.
    pub fn about(mut self, subject: impl Into<String>) -> Warning {
        self.subject = subject.into();
        self
    }

    /// The subject, or `fallback` when the warning has none.
    pub fn subject_or<'a>(&'a self, fallback: &'a str) -> &'a str {
        if self.subject.is_empty() {
            fallback
        } else {
            &self.subject
        }
    }

    /// `warning[CODE]: SUBJECT: MESSAGE`, with `fallback` as the subject when the warning
    /// has none (the command line's line).
    pub fn line(&self, fallback: &str) -> String {
        match self.subject_or(fallback) {
            "" => format!("warning[{}]: {}", self.code, self.message),
            s => format!("warning[{}]: {s}: {}", self.code, self.message),
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.line(""))
    }
}

/// The serialized fields of a [`Warning`].
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Fields<S> {
    code: Code,
    #[serde(default)]
    subject: S,
    message: S,
}

impl Serialize for Warning {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.code == Code::Legacy && self.subject.is_empty() {
            return s.serialize_str(&self.message);
        }
        Fields {
            code: self.code,
            subject: self.subject.as_str(),
            message: self.message.as_str(),
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Warning {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Warning;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a warning: {\"code\", \"subject\", \"message\"} or a string")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Warning, E> {
                Ok(Warning::new(Code::Legacy, v))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Warning, A::Error> {
                let f: Fields<String> =
                    Deserialize::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(Warning {
                    code: f.code,
                    subject: f.subject,
                    message: f.message,
                })
            }
        }
        d.deserialize_any(V)
    }
}

/// The warnings of one value (a file's metadata, a plan, a run), in the order they were
/// raised. Serialized as a list of [`Warning`]s.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Diagnostics(Vec<Warning>);

impl Diagnostics {
    /// No warning.
    pub fn new() -> Diagnostics {
        Diagnostics(Vec::new())
    }

    /// Add a warning of `code` without a subject.
    pub fn warn(&mut self, code: Code, message: impl Into<String>) {
        self.0.push(Warning::new(code, message));
    }

    /// Add a warning.
    pub fn push(&mut self, w: Warning) {
        self.0.push(w);
    }

    /// Give every warning without a subject the subject `subject`.
    pub fn about(&mut self, subject: &str) {
        for w in self.0.iter_mut().filter(|w| w.subject.is_empty()) {
            w.subject = subject.to_string();
        }
    }

    /// These warnings, each without a subject given `subject`.
    pub fn about_owned(mut self, subject: &str) -> Diagnostics {
        self.about(subject);
        self
    }

    /// Whether a warning of `code` is here.
    pub fn has(&self, code: Code) -> bool {
        self.0.iter().any(|w| w.code == code)
    }

    /// The messages, in order.
    pub fn messages(&self) -> Vec<&str> {
        self.0.iter().map(|w| w.message.as_str()).collect()
    }

    /// The warnings as a vector.
    pub fn into_vec(self) -> Vec<Warning> {
        self.0
    }
}

impl std::ops::Deref for Diagnostics {
    type Target = [Warning];
    fn deref(&self) -> &[Warning] {
        &self.0
    }
}

impl From<Vec<Warning>> for Diagnostics {
    fn from(v: Vec<Warning>) -> Diagnostics {
        Diagnostics(v)
    }
}

impl FromIterator<Warning> for Diagnostics {
    fn from_iter<I: IntoIterator<Item = Warning>>(it: I) -> Diagnostics {
        Diagnostics(it.into_iter().collect())
    }
}

impl Extend<Warning> for Diagnostics {
    fn extend<I: IntoIterator<Item = Warning>>(&mut self, it: I) {
        self.0.extend(it);
    }
}

impl IntoIterator for Diagnostics {
    type Item = Warning;
    type IntoIter = std::vec::IntoIter<Warning>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl<'a> IntoIterator for &'a Diagnostics {
    type Item = &'a Warning;
    type IntoIter = std::slice::Iter<'a, Warning>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_kebab_case_and_round_trip() {
        let mut seen = std::collections::HashSet::new();
        for &c in Code::ALL {
            let n = c.as_str();
            assert!(seen.insert(n), "{n} twice");
            assert!(
                !n.is_empty()
                    && n.bytes().all(|b| b.is_ascii_lowercase() || b == b'-')
                    && !n.starts_with('-')
                    && !n.ends_with('-'),
                "{n}"
            );
            assert_eq!(Code::from_name(n), Some(c));
            assert!(!c.summary().is_empty());
        }
        assert_eq!(Code::from_name("no-such-code"), None);
    }

    #[test]
    fn a_warning_serializes_as_an_object_and_reads_back() {
        let w = Warning::new(Code::NoiseExtrapolated, "ISO 25 ...").about("day.dng");
        let text = serde_json::to_string(&w).unwrap();
        assert_eq!(
            text,
            r#"{"code":"noise-extrapolated","subject":"day.dng","message":"ISO 25 ..."}"#
        );
        assert_eq!(serde_json::from_str::<Warning>(&text).unwrap(), w);
        assert_eq!(
            w.to_string(),
            "warning[noise-extrapolated]: day.dng: ISO 25 ..."
        );
        assert_eq!(
            Warning::new(Code::UnknownIso, "m").line("x.dng"),
            "warning[unknown-iso]: x.dng: m"
        );
    }

    #[test]
    fn a_plain_string_is_a_legacy_warning_written_back_as_the_same_string() {
        let text = r#"["ISO 25 is outside ...","b"]"#;
        let d: Diagnostics = serde_json::from_str(text).unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!((d[0].code, d[0].subject.as_str()), (Code::Legacy, ""));
        assert_eq!(d[0].message, "ISO 25 is outside ...");
        assert_eq!(serde_json::to_string(&d).unwrap(), text);
    }

    #[test]
    fn unknown_codes_and_fields_are_refused() {
        let e = serde_json::from_str::<Warning>(r#"{"code":"nope","message":"m"}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown warning code \"nope\""), "{e}");
        assert!(
            serde_json::from_str::<Warning>(r#"{"code":"legacy","message":"m","x":1}"#).is_err()
        );
        assert!(serde_json::from_str::<Warning>("3").is_err());
    }

    #[test]
    fn about_fills_only_empty_subjects() {
        let mut d = Diagnostics::new();
        d.warn(Code::OpcodeSkipped, "a");
        d.push(Warning::new(Code::OpcodeTrim, "b").about("scene 1"));
        d.about("day.dng");
        assert_eq!(d[0].subject, "day.dng");
        assert_eq!(d[1].subject, "scene 1");
        assert!(d.has(Code::OpcodeTrim) && !d.has(Code::UnknownIso));
        assert_eq!(d.messages(), ["a", "b"]);
    }
}
