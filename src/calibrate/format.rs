//! JSON formats written by `day2night calibrate`. Each is a SUPERSET of what `synth` reads
//! (`crate::synth::dictionaries::{parse_illuminants, parse_brightness}`,
//! `crate::noise::model::NoiseModel`): the keys synth uses come first and carry the same
//! meaning; the extra keys (per-file measurements, fit quality, DN forms, ISO laws) are for
//! people and are ignored by synth. Tests parse every written file with synth's readers.

use crate::raw::camera::CameraId;
use serde::{Deserialize, Serialize};

/// Format tag of illuminant dictionaries.
pub const ILLUMINANTS_FORMAT: &str = "day2night-illuminants/1";
/// Format tag of brightness dictionaries.
pub const BRIGHTNESS_FORMAT: &str = "day2night-brightness/1";
/// Format tag of noise models (synth's).
pub const NOISE_FORMAT: &str = crate::noise::model::NOISE_MODEL_FORMAT;

/// A fitted 2-D Gaussian over `[r/g, b/g]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Gaussian2Fit {
    /// Mean `[r/g, b/g]`.
    pub mean: [f64; 2],
    /// Covariance, row-major 2x2.
    pub covariance: [[f64; 2]; 2],
    /// Number of chromaticities fitted.
    pub count: usize,
    /// "unbiased" (1/(M-1), the released code and the default) or "maximum_likelihood"
    /// (1/M, the paper's eq. 2): synth's `Covariance` names.
    pub estimator: crate::synth::illuminant::Covariance,
}

/// Per-file measurement of a gray card.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GrayCardMeasurement {
    /// Input file.
    pub file: String,
    /// ROI in active-area pixels: [x, y, width, height].
    pub roi: [usize; 4],
    /// Robust (10 %-trimmed) mean of the black-subtracted, normalized samples of R, G, B.
    pub means: [f64; 3],
    /// Samples used per colour (unsaturated sites in the ROI).
    pub pixels: [usize; 3],
    /// Saturated sites excluded, per colour.
    pub saturated: [usize; 3],
    /// `[r/g, 1, b/g]`.
    pub chromaticity: [f64; 3],
    /// CIE 1931 xy of the card's light through the capture's own colour matrices (DNG
    /// chapter 6); absent when the capture has none (the reason is in `warnings`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub xy: Option<[f64; 2]>,
    /// The capture's camera (Make, Model, UniqueCameraModel).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraId>,
    /// Things the user should know (e.g. many saturated sites).
    #[serde(default, skip_serializing_if = "<[_]>::is_empty")]
    pub warnings: crate::diagnostics::Diagnostics,
}

/// `calibrate illuminants` output (`synth --illuminants` input).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IlluminantDictionary {
    /// [`ILLUMINANTS_FORMAT`].
    pub format: String,
    /// Human description of the contents.
    pub what: String,
    /// Number of illuminants.
    pub count: usize,
    /// The dictionary: `[r/g, 1, b/g]` per illuminant (same key as the shared s20fe file),
    /// in the raw colours of `camera`.
    pub illuminants_rgb_over_g: Vec<[f64; 3]>,
    /// The camera the gray cards were shot with (null when unknown or when they come from
    /// several cameras): synth uses the camera neutrals for this camera, the xy for others.
    pub camera: Option<CameraId>,
    /// "CIE 1931 2 degree" when `xy` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observer: Option<String>,
    /// CIE 1931 xy of each illuminant through its capture's own colour matrices (same order
    /// as `illuminants_rgb_over_g`); absent unless every illuminant has one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub xy: Vec<[f64; 2]>,
    /// The fitted Gaussian over `[r/g, b/g]`.
    pub fit: Gaussian2Fit,
    /// Per gray-card file measurements (empty for refits of a list).
    #[serde(default)]
    pub files: Vec<GrayCardMeasurement>,
}

/// Fitted distribution of night brightness: the normal distribution synth samples target
/// means from (`synth::dictionaries::parse_brightness`, draws kept in (0, 1]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BrightnessFit {
    /// "normal, truncated to (0, 1]".
    pub distribution: String,
    /// Mean of the values.
    pub mean: f64,
    /// Sample standard deviation (1/(M-1); 0 for a single image).
    pub std: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Number of images.
    pub count: usize,
}

/// One night image's brightness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BrightnessMeasurement {
    /// Input file.
    pub file: String,
    /// Normalized mean intensity over the active area (docs/synthesis.md, "1. Normalize"; negatives clipped).
    pub mean: f64,
    /// Exif ISO, if known.
    pub iso: Option<u32>,
    /// Exposure time in seconds, if known.
    pub exposure_time: Option<f64>,
}

/// `calibrate brightness` output (`synth --brightness` input).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BrightnessDictionary {
    /// [`BRIGHTNESS_FORMAT`].
    pub format: String,
    /// Human description of the contents.
    pub what: String,
    /// The dictionary D: normalized mean intensities.
    pub values: Vec<f64>,
    /// Fitted distribution to sample target means from.
    pub fit: BrightnessFit,
    /// Per file.
    #[serde(default)]
    pub files: Vec<BrightnessMeasurement>,
}

/// Fit of one 2x2 CFA position at one ISO.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PositionFit {
    /// 2x2 position, row-major: 0=(0,0), 1=(0,1), 2=(1,0), 3=(1,1) of the active area.
    pub position: usize,
    /// CFA colour at that position ("R", "G", "B").
    pub color: String,
    /// Shot parameter, normalized units: `var(y) = S * y + O`.
    #[serde(rename = "S")]
    pub s: f64,
    /// Read parameter, normalized units.
    #[serde(rename = "O")]
    pub o: f64,
    /// Standard error of S (None for NoiseProfile sources).
    pub s_stderr: Option<f64>,
    /// Standard error of O.
    pub o_stderr: Option<f64>,
    /// In DN with x including black: `var(x) = beta1 * x + beta2`.
    pub beta1: f64,
    /// See `beta1`.
    pub beta2: f64,
    /// Weighted R^2 of the binned fit.
    pub r2: Option<f64>,
    /// Reduced chi-square (about 1 when the model fits and the weights are right).
    pub chi2_reduced: Option<f64>,
    /// Intensity bins used.
    pub bins: usize,
    /// Pixels used (sites, not samples).
    pub pixels: u64,
    /// Pixels excluded because a sample was clipped (0 or >= white).
    pub clipped_pixels: u64,
}

/// Model at one ISO: synth's `IsoPoint` (`iso`, `positions`) plus calibration details.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IsoModel {
    /// Exif ISO of the frames.
    pub iso: u32,
    /// `[[S, O]; 4]` per 2x2 position (normalized units): what synth reads.
    pub positions: [[f64; 2]; 4],
    /// "burst", "pair", "burst+pair", "noise_profile" or "image_estimate".
    pub source: String,
    /// Black level (max over the plane, DN) used for the DN conversion.
    pub black: f64,
    /// White level (DN).
    pub white: f64,
    /// Bursts, pairs or files that contributed.
    pub inputs: usize,
    /// Variance subtracted from O for the rounding of raw values, normalized units
    /// (`1 / (12 (white - black)^2)`; 0 for NoiseProfile sources).
    pub quantization_variance_removed: f64,
    /// Details of the four 2x2 positions (same S, O as `positions`).
    pub fits: Vec<PositionFit>,
}

/// Cross-ISO laws (docs/calibration.md, "ISO laws"): `S = c * ISO`, `O = a + b * ISO^2`, per position.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IsoLaws {
    /// `c` per 2x2 position.
    pub s_per_iso: [f64; 4],
    /// `a` per 2x2 position.
    pub o_at_iso0: [f64; 4],
    /// `b` per 2x2 position.
    pub o_per_iso2: [f64; 4],
    /// ISOs the laws were fitted over.
    pub isos: Vec<u32>,
}

/// `calibrate noise` output (`synth --noise-model` input): synth's `NoiseModel` (`format`,
/// `units`, `source`, `isos[].iso/positions`) plus calibration details.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseModelFile {
    /// [`NOISE_FORMAT`].
    pub format: String,
    /// Units and model statement.
    pub units: String,
    /// Provenance.
    pub source: String,
    /// The camera of the first input (Make, Model, UniqueCameraModel): synth warns when the
    /// model is applied to another camera. (Files written before this held a string; synth
    /// still reads them.)
    pub camera: Option<crate::raw::camera::CameraId>,
    /// One entry per ISO, ascending.
    pub isos: Vec<IsoModel>,
    /// Laws across ISOs (None with fewer than two ISOs).
    pub iso_laws: Option<IsoLaws>,
}

/// The `units` statement written into noise models.
pub const NOISE_UNITS: &str = "positions [[S, O]; 4] and fits[].S/O: variance of the normalized signal y = (x - black(site)) / (white - black_max), linear (post-LinearizationTable) values: var(y) = S * y + O (DNG NoiseProfile form); positions are the 2x2 CFA tile relative to the ActiveArea origin, row-major (0=(0,0), 1=(0,1), 2=(1,0), 3=(1,1)). fits[].beta1/beta2: DN with the black/white levels given per ISO, var(x) = beta1*x + beta2 where x is the raw value INCLUDING the black level (beta1 = S*(white-black), beta2 = O*(white-black)^2 - black*beta1).";
