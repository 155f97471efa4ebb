//! Which night-illuminant dictionary an input is sampled from, and where it came from
//! (docs/synthesis.md, "4. Night illuminants", "Night lamps in CIE xy").
//!
//! A dictionary of `[r/g, b/g]` gray-card neutrals is in one camera's raw colours. The
//! default therefore depends on the input:
//!
//! * a camera with an embedded calibration ([`embedded::for_camera`]: the paper's phone,
//!   Samsung Galaxy S20 FE): the embedded dictionary measured on it, as before;
//! * every other camera: the CIE 015:2018 night lamps ([`XyDict::cie_night`]), converted to
//!   this camera's neutrals through the file's own colour matrices by the DNG specification's
//!   chapter 6 ([`CameraColor::xy_to_neutral`]: xy -> XYZ -> ColorMatrix interpolated at the
//!   lamp's CCT, CameraCalibration, AnalogBalance), then fitted (weighted) as a camera
//!   dictionary.
//!
//! `--illuminants paper` (and the `--compat release` preset) uses the phone's dictionary for
//! every input, `--illuminants cie` the lamps for every input, `--illuminants FILE` a file
//! (camera neutrals, xy, or both: the neutrals for the camera they were measured on, the xy
//! through the input's matrices for any other). A camera's neutrals applied to another camera
//! are a warning naming both.

use super::dictionaries::embedded::{self, CameraCalibration};
use super::dictionaries::xy::{load_illuminant_file, IlluminantFile, XyDict, XyLamp};
use super::dictionaries::{IlluminantDict, MAX_NEUTRAL_RATIO};
use super::illuminant::{Covariance, Gaussian2};
use crate::diagnostics::{Code, Diagnostics};
use crate::error::{Error, Result, ResultExt};
use crate::isp::color::CameraColor;
use crate::raw::camera::CameraId;
use crate::raw::meta::ColorInfo;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The job's choice of night-illuminant dictionary (`--illuminants`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum IlluminantChoice {
    /// The default: the paper's dictionary for the paper's phone, the CIE lamps through the
    /// file's colour matrices for every other camera.
    Auto,
    /// The paper phone's embedded dictionary for every input (`--illuminants paper`, the
    /// `--compat release` preset).
    Paper,
    /// The CIE night lamps for every input, the paper's phone included (`--illuminants cie`).
    Cie,
    /// An illuminant file.
    File(IlluminantFile),
    /// A fitted Gaussian used as is for every input, with its recorded provenance (a
    /// sidecar's on `--replay`; library callers).
    Gaussian(Gaussian2, Option<IlluminantProvenance>),
}

/// Where an input's dictionary came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IlluminantOrigin {
    /// The paper phone's embedded gray-card neutrals.
    EmbeddedS20fe,
    /// The embedded CIE 015:2018 night lamps through this input's colour matrices.
    CieLamps,
    /// A file's camera neutrals (or Gaussian).
    FileCameraRgb,
    /// A file's xy lamps through this input's colour matrices.
    FileXy,
    /// A Gaussian given by the library caller.
    Given,
}

/// The provenance of an input's illuminant dictionary (sidecar `calibration.provenance`,
/// `info`, `synth`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IlluminantProvenance {
    /// Where it came from.
    pub source: IlluminantOrigin,
    /// The file, for file sources.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// The camera whose raw colours the sampled neutrals are in: the S20 FE for the embedded
    /// dictionary, the measuring camera for a file's neutrals (null when the file does not
    /// say), this input's camera for xy lamps converted through its matrices.
    pub camera: Option<CameraId>,
    /// One sentence for people.
    pub note: String,
}

impl IlluminantProvenance {
    /// One line for `synth` and `info`: what the dictionary is and whose colours.
    pub fn summary(&self) -> String {
        let camera = self
            .camera
            .as_ref()
            .map_or("an unnamed camera".to_string(), |c| c.label());
        let file = self.file.as_deref().unwrap_or("?");
        match self.source {
            IlluminantOrigin::EmbeddedS20fe => {
                "embedded paper phone gray cards (Samsung Galaxy S20 FE camera RGB)".to_string()
            }
            IlluminantOrigin::CieLamps => {
                format!("CIE 015:2018 night lamps through this file's colour matrices ({camera})")
            }
            IlluminantOrigin::FileCameraRgb => format!("{file}, camera RGB of {camera}"),
            IlluminantOrigin::FileXy => {
                format!("{file}, xy lamps through this file's colour matrices ({camera})")
            }
            IlluminantOrigin::Given => "a given Gaussian".to_string(),
        }
    }
}

/// An input's dictionary: the Gaussian to sample, its provenance and the warnings to give.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedIlluminants {
    /// The fitted Gaussian over this camera's `[r/g, b/g]`.
    pub gaussian: Gaussian2,
    /// Where it came from.
    pub provenance: IlluminantProvenance,
    /// Another camera's colours applied to this one, said once per plan.
    pub warnings: Diagnostics,
}

/// How to avoid another camera's colours (appended to warnings and errors).
const FIXES: &str = "--illuminants cie (CIE lamps through this file's colour matrices) or \
--illuminants FILE (this camera's gray cards, from `day2night calibrate illuminants`)";

/// An embedded dictionary, fitted exactly as before this choice existed.
fn fit_embedded(cal: &CameraCalibration, est: Covariance) -> Result<Gaussian2> {
    Gaussian2::fit(&cal.illuminants, est)
}

/// A lamp's camera channel below this fraction of green is degenerate (an error); between
/// it and [`MIN_LAMP_RATIO`] it is clamped to [`MIN_LAMP_RATIO`].
pub const MAX_NEGATIVE_RATIO: f64 = -0.1;
/// Smallest channel / green of a lamp's neutral (the neutral bound, `1 / MAX_NEUTRAL_RATIO`).
pub const MIN_LAMP_RATIO: f64 = 1.0 / MAX_NEUTRAL_RATIO;

/// A lamp's camera neutral `[r/g, b/g]` through `color` (DNG chapter 6), and whether a
/// channel was clamped: a colour matrix is a linear fit of the sensor, and just outside its
/// gamut (e.g. sodium light through an sRGB-like matrix) a channel the sensor sees as nearly
/// nothing comes out slightly negative; it is clamped to [`MIN_LAMP_RATIO`]. A green <= 0, a
/// channel below [`MAX_NEGATIVE_RATIO`] of green or above `MAX_NEUTRAL_RATIO` is an error.
pub fn lamp_neutral(color: &CameraColor, xy: [f64; 2]) -> Result<([f64; 2], bool)> {
    let n = color.xy_to_camera(xy);
    if !(n.iter().all(|v| v.is_finite()) && n[1] > 0.0) {
        return Err(Error::malformed(format!(
            "camera response {} has no positive green",
            crate::bounds::short_list(&n)
        )));
    }
    let mut clamped = false;
    let mut c = [n[0] / n[1], n[2] / n[1]];
    for v in &mut c {
        if *v < MAX_NEGATIVE_RATIO {
            return Err(Error::malformed(format!(
                "camera neutral {} has a channel below {} of green",
                crate::bounds::short_list(&[n[0] / n[1], 1.0, n[2] / n[1]]),
                MAX_NEGATIVE_RATIO
            )));
        }
        if *v < MIN_LAMP_RATIO {
            *v = MIN_LAMP_RATIO;
            clamped = true;
        }
    }
    crate::bounds::ratios("camera neutral (r/g, b/g)", &c, MAX_NEUTRAL_RATIO)?;
    Ok((c, clamped))
}

/// Convert an xy dictionary to `camera`'s neutrals through `color` (DNG chapter 6,
/// [`lamp_neutral`]). Lamps of weight 0 are left out; with weight 1 each the dictionary is
/// unweighted (a single lamp is then always drawn). Returns the names of clamped lamps too.
/// Errors name the lamp when the matrices are degenerate.
pub fn xy_to_camera(
    xy: &XyDict,
    color: &CameraColor,
    camera: &CameraId,
) -> Result<(IlluminantDict, Vec<String>)> {
    let mut clamped = Vec::new();
    let dict = weighted(xy, |l| {
        let (c, cut) = lamp_neutral(color, l.xy).map_err(|e| {
            Error::malformed(format!(
                "the colour matrices of this {camera} file map lamp {} (x {}, y {}) of {} to no \
                 usable camera neutral ({}): they are degenerate; give --illuminants paper or \
                 a camera-RGB dictionary of this camera",
                l.name,
                l.xy[0],
                l.xy[1],
                xy.name,
                message(&e)
            ))
        })?;
        if cut {
            clamped.push(l.name.clone());
        }
        Ok(c)
    })?;
    let dict = IlluminantDict {
        name: format!(
            "{} through the colour matrices of this {camera} file",
            xy.name
        ),
        ..dict
    };
    Ok((dict, clamped))
}

/// The lamps of non-zero weight mapped by `f`, weighted (unweighted when every weight is 1).
fn weighted(xy: &XyDict, mut f: impl FnMut(&XyLamp) -> Result<[f64; 2]>) -> Result<IlluminantDict> {
    let mut chroma = Vec::with_capacity(xy.lamps.len());
    let mut weights = Vec::with_capacity(xy.lamps.len());
    for l in xy.lamps.iter().filter(|l| l.weight > 0.0) {
        chroma.push(f(l)?);
        weights.push(l.weight);
    }
    if weights.iter().all(|&w| w == 1.0) {
        weights.clear();
    }
    Ok(IlluminantDict {
        name: xy.name.clone(),
        source: xy.source.clone(),
        chromaticities: chroma,
        weights,
    })
}

/// An error's message without its kind prefix.
fn message(e: &Error) -> String {
    match e.root() {
        Error::Malformed(m) | Error::Unsupported(m) | Error::Limits(m) | Error::InvalidParam(m) => {
            m.clone()
        }
        other => other.to_string(),
    }
}

fn camera_color(color: &ColorInfo, why: &str) -> Result<CameraColor> {
    CameraColor::new(color).map_err(|e| {
        Error::unsupported(format!(
            "{}: {why} need this file's colour matrices; give --illuminants paper (the paper \
             phone's neutrals, another camera's colours) or --illuminants FILE (a camera-RGB \
             dictionary of this camera)",
            message(&e)
        ))
    })
}

impl IlluminantChoice {
    /// The default of a job: [`IlluminantChoice::Paper`] under the release preset's
    /// `paper_illuminants` switch, [`IlluminantChoice::Auto`] otherwise.
    pub fn default_for(paper_illuminants: bool) -> IlluminantChoice {
        if paper_illuminants {
            IlluminantChoice::Paper
        } else {
            IlluminantChoice::Auto
        }
    }

    /// `--illuminants`: `paper`, `cie`, or a file (loaded and its fits checked with the
    /// estimator `est`, so that a bad file is refused before any input is read; a file
    /// named `paper` or `cie` is given as `./paper`).
    pub fn from_arg(arg: &Path, est: Covariance) -> Result<IlluminantChoice> {
        match arg.to_str() {
            Some("paper") => return Ok(IlluminantChoice::Paper),
            Some("cie") => return Ok(IlluminantChoice::Cie),
            _ => {}
        }
        let f = load_illuminant_file(arg)?;
        if let Some(rgb) = &f.rgb {
            Gaussian2::from_source(rgb, est).in_file(arg)?;
        }
        if let Some(xy) = &f.xy {
            Gaussian2::fit(&weighted(xy, |l| Ok(l.xy))?, est).in_file(arg)?;
        }
        Ok(IlluminantChoice::File(f))
    }

    /// The dictionary of an input of camera `camera` with colour tags `color`.
    pub fn resolve(
        &self,
        camera: &CameraId,
        color: &ColorInfo,
        est: Covariance,
    ) -> Result<ResolvedIlluminants> {
        let mut warnings = Diagnostics::new();
        let own = embedded::for_camera(camera);
        let (gaussian, provenance) = match (self, own) {
            (IlluminantChoice::Auto, Some(own)) => {
                (fit_embedded(own, est)?, embedded_provenance(own, camera))
            }
            (IlluminantChoice::Paper, _) => {
                let paper = embedded::paper();
                if own.map(|c| c.key) != Some(paper.key) {
                    warnings.warn(
                        Code::IlluminantsOtherCamera,
                        format!(
                        "night illuminants: the paper phone's dictionary (Samsung Galaxy S20 FE \
                         camera RGB) applied to {camera}: its lamp colours are another camera's \
                         (--illuminants paper or --compat release); for this camera's colours \
                         use {FIXES}"
                    ),
                    );
                }
                (
                    fit_embedded(paper, est)?,
                    embedded_provenance(paper, camera),
                )
            }
            (IlluminantChoice::Auto, None) | (IlluminantChoice::Cie, _) => {
                let cc = camera_color(color, "the CIE night lamps")?;
                let xy = XyDict::cie_night();
                let (dict, clamped) = xy_to_camera(&xy, &cc, camera)?;
                let g = Gaussian2::fit(&dict, est)?;
                let prov = IlluminantProvenance {
                    source: IlluminantOrigin::CieLamps,
                    file: None,
                    camera: Some(camera.clone()),
                    note: format!(
                        "{} ({} lamps, {}) converted to this camera's neutrals through its \
                         colour matrices (DNG spec chapter 6){}",
                        xy.name,
                        xy.lamps.len(),
                        xy.source,
                        clamped_note(&clamped)
                    ),
                };
                (g, prov)
            }
            (IlluminantChoice::File(f), _) => file(f, camera, color, est, &mut warnings)?,
            (IlluminantChoice::Gaussian(g, p), _) => {
                let prov = p.clone().unwrap_or_else(|| IlluminantProvenance {
                    source: IlluminantOrigin::Given,
                    file: None,
                    camera: None,
                    note: format!("the Gaussian {} given as is", g.name),
                });
                (g.clone(), prov)
            }
        };
        Ok(ResolvedIlluminants {
            gaussian,
            provenance,
            warnings,
        })
    }

    /// Whether this choice reads colour matrices for `camera` (for `info`'s readiness).
    pub fn needs_matrices(&self, camera: &CameraId) -> bool {
        match self {
            IlluminantChoice::Auto => embedded::for_camera(camera).is_none(),
            IlluminantChoice::Cie => true,
            IlluminantChoice::File(f) => {
                f.xy.is_some()
                    && !(f.rgb.is_some()
                        && f.camera.as_ref().and_then(|c| c.same_camera(camera)) == Some(true))
            }
            IlluminantChoice::Paper | IlluminantChoice::Gaussian(..) => false,
        }
    }
}

/// The provenance's words for lamps clamped by [`lamp_neutral`].
fn clamped_note(clamped: &[String]) -> String {
    if clamped.is_empty() {
        return String::new();
    }
    format!(
        "; outside this camera's matrix gamut, a channel clamped to {MIN_LAMP_RATIO} of green: {}",
        clamped.join(", ")
    )
}

/// The provenance of `cal`'s embedded dictionary sampled for `camera`.
fn embedded_provenance(cal: &CameraCalibration, camera: &CameraId) -> IlluminantProvenance {
    let n = cal.illuminants.chromaticities.len();
    let note = if embedded::for_camera(camera).map(|c| c.key) == Some(cal.key) {
        format!("the paper's {n} gray-card neutrals, measured on this camera model")
    } else {
        format!("the paper's {n} gray-card neutrals, measured on another camera than this {camera}")
    };
    IlluminantProvenance {
        source: IlluminantOrigin::EmbeddedS20fe,
        file: None,
        camera: Some(cal.illuminants_camera.clone()),
        note: format!("{note} ({})", cal.illuminants.source),
    }
}

/// A file's dictionary for `camera`: its neutrals when measured on this camera, else its xy
/// through the input's matrices, else its neutrals with a warning when measured on another
/// camera.
fn file(
    f: &IlluminantFile,
    camera: &CameraId,
    color: &ColorInfo,
    est: Covariance,
    warnings: &mut Diagnostics,
) -> Result<(Gaussian2, IlluminantProvenance)> {
    let same = f.camera.as_ref().and_then(|c| c.same_camera(camera));
    let measured_on = f
        .camera
        .as_ref()
        .map_or("an unnamed camera".to_string(), |c| c.label());
    let rgb_prov = |note: String| IlluminantProvenance {
        source: IlluminantOrigin::FileCameraRgb,
        file: Some(f.name.clone()),
        camera: f.camera.clone(),
        note,
    };
    match (&f.rgb, &f.xy, same) {
        (Some(rgb), _, Some(true)) => Ok((
            Gaussian2::from_source(rgb, est)?,
            rgb_prov(format!(
                "camera neutrals measured on this camera model ({measured_on})"
            )),
        )),
        (_, Some(xy), _) => {
            let cc = camera_color(color, "the file's xy lamps")?;
            let (dict, clamped) = xy_to_camera(xy, &cc, camera)?;
            let g = Gaussian2::fit(&dict, est)?;
            Ok((
                g,
                IlluminantProvenance {
                    source: IlluminantOrigin::FileXy,
                    file: Some(f.name.clone()),
                    camera: Some(camera.clone()),
                    note: format!(
                        "{} xy lamps (measured on {measured_on}) converted to this camera's \
                         neutrals through its colour matrices (DNG spec chapter 6){}",
                        xy.lamps.len(),
                        clamped_note(&clamped)
                    ),
                },
            ))
        }
        (Some(rgb), None, Some(false)) => {
            warnings.warn(
                Code::IlluminantsOtherCamera,
                format!(
                "night illuminants: {} holds camera neutrals measured on {measured_on}, applied \
                 to {camera}: its lamp colours are another camera's; for this camera's colours \
                 use {FIXES}",
                f.name
            ),
            );
            Ok((
                Gaussian2::from_source(rgb, est)?,
                rgb_prov(format!(
                    "camera neutrals measured on another camera ({measured_on}) than this \
                     {camera}"
                )),
            ))
        }
        (Some(rgb), None, None) => Ok((
            Gaussian2::from_source(rgb, est)?,
            rgb_prov(if f.camera.is_none() {
                "camera neutrals; the file does not say which camera they were measured on"
                    .to_string()
            } else {
                format!(
                    "camera neutrals measured on {measured_on}; this file's camera names do \
                     not tell whether it is the same camera"
                )
            }),
        )),
        (None, None, _) => Err(Error::malformed(format!(
            "{}: holds no illuminants",
            f.name
        ))),
    }
}

#[cfg(test)]
#[path = "illuminant_choice_tests.rs"]
mod tests;
