//! The noise model a plan uses, and where it came from (SYNTHESIS.md 7; issue 24 points 2
//! and 3). The first of these that applies:
//!
//! 1. `--noise-model FILE` (a warning when the file records another camera);
//! 2. the input's own NoiseProfile, at its Exif ISO;
//! 3. the embedded table when it is this camera's own (the paper's phone, the Samsung
//!    Galaxy S20 FE: [`CameraId::is_s20_fe`]), or under `--compat release` (the release
//!    applies it to every input; a warning unless the input is the S20 FE);
//! 4. an estimate from the day image itself at its Exif ISO ([`crate::noise::estimate`]),
//!    when it can be trusted;
//! 5. the embedded table, with a warning that names it as another camera's noise, says why
//!    (unknown ISO, or a fit that cannot be trusted and why) and how to calibrate.
//!
//! A model at one ISO (2 and 4) is scaled to the requested ISOs as docs/noise.md says
//! (`S` in proportion to ISO, `O` to ISO^2).

use super::dictionaries::embedded;
use super::{Calibration, SynthOptions};
use crate::error::Result;
use crate::noise::provenance::s20_fe_camera;
use crate::noise::{IsoPoint, NoiseEstimate, NoiseModel, NoiseProvenance, NoiseSource};
use crate::raw::camera::CameraId;
use crate::raw::{Bayer, RawImage};

/// A plan's noise model, its provenance and the warnings it raises.
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseChoice {
    /// The model.
    pub model: NoiseModel,
    /// Where it came from and whose camera it is.
    pub provenance: NoiseProvenance,
    /// Warnings for the plan (another camera's calibration, an untrusted estimate...).
    pub warnings: Vec<String>,
}

/// How to calibrate a camera, for the warnings.
pub const HOW_TO_CALIBRATE: &str = "calibrate this camera: `day2night calibrate noise \
--from-image DAY.dng [--assume-iso N] -o noise.json` (from day images; or --burst FRAMES... / \
--pair CLEAN NOISY for a full calibration), then `synth --noise-model noise.json` \
(docs/calibration.md)";

/// The embedded table as another camera's noise: model, provenance and the warning.
fn embedded_elsewhere(cam: &CameraId, why: &str, note: &str) -> NoiseChoice {
    let model = embedded::noise_model();
    NoiseChoice {
        warnings: vec![format!(
            "noise: {why}; using the embedded noise table of the paper's phone (Samsung Galaxy \
             S20 FE): another camera's noise, not {}'s; {HOW_TO_CALIBRATE}",
            cam.label()
        )],
        provenance: NoiseProvenance {
            source: NoiseSource::EmbeddedS20Fe,
            camera: Some(s20_fe_camera()),
            note: format!("{note} ({})", model.source),
        },
        model,
    }
}

/// The noise model of a plan for `img` (see the module documentation). `estimate` is called
/// only when the chain gets to the image estimate (it reads every pixel).
pub fn choose_noise_model(
    img: &RawImage,
    cal: &Calibration,
    opts: &SynthOptions,
    bayer: Bayer,
    estimate: &dyn Fn() -> Result<NoiseEstimate>,
) -> Result<NoiseChoice> {
    let cam = CameraId::of(&img.meta);
    if let Some(m) = &cal.noise {
        let file = m.file.as_deref().unwrap_or("the noise model file");
        let mut warnings = vec![];
        if let Some(mc) = &m.camera {
            if mc.same_camera(&cam) == Some(false) {
                warnings.push(format!(
                    "noise: {file} was calibrated on {}, not on this camera ({}): its noise \
                     may not match this camera's; {HOW_TO_CALIBRATE}",
                    mc.label(),
                    cam.label()
                ));
            }
        }
        let kind = if m.physics.is_some() {
            "physics noise model"
        } else {
            "noise model"
        };
        return Ok(NoiseChoice {
            model: m.clone(),
            provenance: NoiseProvenance {
                source: NoiseSource::File,
                camera: m.camera.clone(),
                note: format!(
                    "{kind} {file}{}: {}",
                    if m.camera.is_none() {
                        " (records no camera)"
                    } else {
                        ""
                    },
                    m.source
                ),
            },
            warnings,
        });
    }
    let iso = img.meta.exif.iso.filter(|&i| i > 0);
    let mut profile_problem = None;
    if let (Some(p), Some(iso)) = (&img.meta.noise_profile, iso) {
        match NoiseModel::from_dng_profile(p, bayer, iso) {
            Ok(m) => {
                return Ok(NoiseChoice {
                    provenance: NoiseProvenance {
                        source: NoiseSource::NoiseProfile,
                        camera: Some(cam),
                        note: m.source.clone(),
                    },
                    model: m,
                    warnings: vec![],
                })
            }
            Err(e) => profile_problem = Some(format!("its NoiseProfile is unusable ({e})")),
        }
    }
    let profile_words = profile_problem
        .clone()
        .unwrap_or_else(|| "the input has no NoiseProfile".into());
    if cam.is_s20_fe() {
        let model = embedded::noise_model();
        return Ok(NoiseChoice {
            provenance: NoiseProvenance {
                source: NoiseSource::EmbeddedS20Fe,
                camera: Some(s20_fe_camera()),
                note: format!(
                    "{profile_words} and it is the paper's phone, the camera of the embedded \
                     table ({})",
                    model.source
                ),
            },
            model,
            warnings: vec![],
        });
    }
    if opts.compat.embedded_noise {
        return Ok(embedded_elsewhere(
            &cam,
            &format!("{profile_words} and --compat release keeps the release's noise table"),
            "--compat release: the release's table",
        ));
    }
    let Some(iso) = iso else {
        return Ok(embedded_elsewhere(
            &cam,
            &format!(
                "{profile_words} and its ISO is unknown (Exif ISO 0 or absent), so its noise \
                 cannot be estimated from the image"
            ),
            "unknown ISO: no estimate from the image",
        ));
    };
    let est = estimate()?;
    match est.trusted() {
        Ok(params) => {
            let mut model = NoiseModel::new(
                format!(
                    "estimated from the day image at ISO {iso} (Poisson-Gaussian fit per 2x2 \
                     position, {} smooth blocks, docs/noise.md)",
                    est.smooth_blocks()
                ),
                vec![IsoPoint {
                    iso,
                    positions: params.positions,
                }],
            )?;
            model.camera = Some(cam.clone());
            Ok(NoiseChoice {
                provenance: NoiseProvenance {
                    source: NoiseSource::ImageEstimate,
                    camera: Some(cam),
                    note: format!("{profile_words}; {}", model.source),
                },
                model,
                warnings: vec![],
            })
        }
        Err(why) => Ok(embedded_elsewhere(
            &cam,
            &format!(
                "{profile_words} and the noise estimated from the image (ISO {iso}) cannot \
                 be trusted: {why}"
            ),
            &format!("untrusted image estimate: {why}"),
        )),
    }
}
