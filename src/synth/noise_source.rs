//! The noise model a plan uses, and where it came from (docs/noise.md, "Where the model comes from"; issue 24 points 2
//! and 3). The first of these that applies:
//!
//! 1. `--noise-model FILE` (a warning when the file records another camera);
//! 2. the input's own NoiseProfile, at its Exif ISO (not under `--compat release`);
//! 3. the embedded table when it is this camera's own (the paper's phone, the Samsung
//!    Galaxy S20 FE: [`embedded::for_camera`]), or under `--compat release` (the release
//!    applies it to every input, whatever its NoiseProfile; a warning unless the input is
//!    the S20 FE);
//! 4. an estimate from the day image itself at its Exif ISO ([`crate::noise::estimate`](mod@crate::noise::estimate)),
//!    when it can be trusted;
//! 5. the embedded table, with a warning that names it as another camera's noise, says why
//!    (unknown ISO, or a fit that cannot be trusted and why) and how to calibrate.
//!
//! A model at one ISO (2 and 4) is scaled to the requested ISOs as docs/noise.md says
//! (`S` in proportion to ISO, `O` to ISO^2).

use super::dictionaries::embedded;
use super::{Calibration, SynthOptions};
use crate::diagnostics::{Code, Diagnostics};
use crate::error::Result;
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
    pub warnings: Diagnostics,
}

/// How to calibrate a camera, for the warnings.
pub const HOW_TO_CALIBRATE: &str = "calibrate this camera: `day2night calibrate noise \
--from-image DAY.dng [--assume-iso N] -o noise.json` (or --burst/--pair), then `synth \
--noise-model noise.json` (docs/calibration.md)";

/// The embedded table as another camera's noise: model, provenance and the warning.
fn embedded_elsewhere(cam: &CameraId, code: Code, why: &str, note: &str) -> NoiseChoice {
    let model = embedded::noise_model();
    let mut warnings = Diagnostics::new();
    warnings.warn(
        code,
        format!(
            "noise: {why}; using the embedded noise table of the paper's phone (Samsung Galaxy \
             S20 FE): another camera's noise, not {}'s; {HOW_TO_CALIBRATE}",
            cam.label()
        ),
    );
    NoiseChoice {
        warnings,
        provenance: NoiseProvenance {
            source: NoiseSource::EmbeddedS20Fe,
            camera: model.camera.clone(),
            note: format!("{note} ({})", model.source),
        },
        model,
    }
}

/// The choice of a `--noise-model` file `m` for the camera `cam`: warnings when it was
/// calibrated on another camera or holds negative parameters.
fn from_file(m: &NoiseModel, cam: &CameraId) -> NoiseChoice {
    let file = m.file.as_deref().unwrap_or("the noise model file");
    let mut warnings = Diagnostics::new();
    if let Some(mc) = &m.camera {
        if mc.same_camera(cam) == Some(false) {
            warnings.warn(
                Code::NoiseOtherCamera,
                format!(
                    "noise: {file} was calibrated on {}, not on this camera ({}): its noise \
                 may not match this camera's; {HOW_TO_CALIBRATE}",
                    mc.label(),
                    cam.label()
                ),
            );
        }
    }
    let negative = m.negative_points();
    if !negative.is_empty() {
        warnings.warn(
            Code::NoiseNegativeClamped,
            format!(
                "noise: {file} has negative parameters at {}: a variance cannot be negative, \
             so synth clamps them to 0 (no noise from that term); recalibrate, or fix the \
             file (docs/noise.md, \"Negative parameters\")",
                negative.join(", ")
            ),
        );
    }
    let kind = if m.physics.is_some() {
        "physics noise model"
    } else {
        "noise model"
    };
    NoiseChoice {
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
        return Ok(from_file(m, &cam));
    }
    let iso = img.meta.exif.iso.filter(|&i| i > 0);
    let release = opts.compat.embedded_noise;
    let mut profile_problem = None;
    let mut unused_profile = None;
    if let (Some(p), Some(iso)) = (&img.meta.noise_profile, iso) {
        match NoiseModel::from_dng_profile(p, bayer, iso) {
            // `--compat release`: the release's table whatever the input says (the
            // release never reads a NoiseProfile).
            Ok(_) if release => unused_profile = Some(iso),
            Ok(m) => {
                return Ok(NoiseChoice {
                    provenance: NoiseProvenance {
                        source: NoiseSource::NoiseProfile,
                        camera: Some(cam),
                        note: m.source.clone(),
                    },
                    model: m,
                    warnings: Diagnostics::new(),
                })
            }
            Err(e) => profile_problem = Some(format!("its NoiseProfile is unusable ({e})")),
        }
    }
    // What became of the input's NoiseProfile, in words: refused when read (its values
    // given), present but unusable, present without an ISO to scale it by, set aside by
    // --compat release, or absent.
    let profile_words = match (&profile_problem, unused_profile, &img.meta.noise_profile) {
        (Some(p), _, _) => p.clone(),
        (None, Some(iso), _) => format!(
            "--compat release keeps the release's noise table rather than the input's \
             NoiseProfile (at ISO {iso})"
        ),
        (None, None, Some(_)) => "its NoiseProfile cannot be scaled without its ISO".into(),
        (None, None, None) => match &img.meta.noise_profile_problem {
            Some(why) => format!("the input's NoiseProfile is not used ({why})"),
            None => "the input has no NoiseProfile".into(),
        },
    };
    if let Some(own) = embedded::for_camera(&cam) {
        let model = own.noise.clone();
        return Ok(NoiseChoice {
            provenance: NoiseProvenance {
                source: NoiseSource::EmbeddedS20Fe,
                camera: model.camera.clone(),
                note: format!(
                    "{profile_words} and it is the paper's phone, the camera of the embedded \
                     table ({})",
                    model.source
                ),
            },
            model,
            warnings: Diagnostics::new(),
        });
    }
    if release {
        let (why, note) = match unused_profile {
            Some(iso) => (
                profile_words,
                format!(
                    "--compat release: the release's table, not the input's NoiseProfile \
                     (at ISO {iso})"
                ),
            ),
            None => (
                format!("{profile_words} and --compat release keeps the release's noise table"),
                "--compat release: the release's table".into(),
            ),
        };
        return Ok(embedded_elsewhere(
            &cam,
            Code::NoiseCompatTable,
            &why,
            &note,
        ));
    }
    let Some(iso) = iso else {
        return Ok(embedded_elsewhere(
            &cam,
            Code::UnknownIso,
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
                warnings: Diagnostics::new(),
            })
        }
        Err(why) => Ok(embedded_elsewhere(
            &cam,
            Code::NoiseEstimateUntrusted,
            &format!(
                "{profile_words} and the noise estimated from the image (ISO {iso}) cannot \
                 be trusted: {why}"
            ),
            &format!("untrusted image estimate: {why}"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::estimate::{EstimateOptions, PositionEstimate};
    use crate::raw::meta::RawMeta;
    use std::cell::Cell;

    fn img(iso: Option<u32>, profile: bool, make: &str, model: &str) -> RawImage {
        let mut meta = RawMeta::new_bayer(Bayer::RGGB, 12, 64.0, 4095.0);
        meta.exif.iso = iso;
        meta.make = Some(make.into());
        meta.model = Some(model.into());
        meta.unique_camera_model = None;
        if profile {
            meta.noise_profile = Some(vec![(2e-5, 4e-7)]);
        }
        RawImage {
            width: 8,
            height: 8,
            data: vec![500; 64],
            meta,
        }
    }

    fn trusted_estimate() -> NoiseEstimate {
        let p = |position: usize, s: f64| PositionEstimate {
            position,
            color: "G".into(),
            s,
            o: 1e-7,
            intercept: 1e-7,
            s_stderr: 1e-7,
            o_stderr: 1e-9,
            blocks: 5000,
            smooth_blocks: 4000,
            clipped_blocks: 0,
            bins: 40,
            span: [0.05, 0.8],
            problem: None,
            level_sets: vec![],
        };
        NoiseEstimate {
            step: 1,
            quantization_variance_removed: 0.0,
            positions: vec![p(0, 1e-4), p(1, 1.1e-4), p(2, 1.2e-4), p(3, 1.3e-4)],
        }
    }

    struct Run {
        choice: NoiseChoice,
        estimated: bool,
    }

    fn choose(i: &RawImage, file: Option<NoiseModel>, release: bool, est: NoiseEstimate) -> Run {
        let opts = if release {
            SynthOptions::default().release_compat().unwrap()
        } else {
            SynthOptions::default()
        };
        let mut cal = Calibration::embedded(&opts).unwrap();
        cal.noise = file;
        let called = Cell::new(false);
        let f = || {
            called.set(true);
            Ok(est.clone())
        };
        let choice = choose_noise_model(i, &cal, &opts, Bayer::RGGB, &f).unwrap();
        Run {
            choice,
            estimated: called.get(),
        }
    }

    fn file_model(camera: Option<CameraId>) -> NoiseModel {
        let mut m = NoiseModel::new(
            "test calibration",
            vec![IsoPoint {
                iso: 800,
                positions: [[3e-4, 2e-6]; 4],
            }],
        )
        .unwrap();
        m.camera = camera;
        m.file = Some("cal.json".into());
        m
    }

    #[test]
    fn a_negative_parameter_in_a_model_file_is_said_not_clamped_in_silence() {
        let i = img(Some(100), true, "Canon", "EOS 5D");
        let mut m = file_model(Some(CameraId::of(&i.meta)));
        m.isos[0].positions[2][1] = -1.0;
        let r = choose(&i, Some(m), false, trusted_estimate());
        assert_eq!(r.choice.warnings.len(), 1, "{:?}", r.choice.warnings);
        let w = &r.choice.warnings[0].message;
        assert!(
            w.contains("cal.json has negative parameters at ISO 800 position 2 (S 3e-4, O -1)")
                && w.contains("clamps them to 0"),
            "{w}"
        );
    }

    #[test]
    fn an_invalid_noise_profile_is_reported_as_one() {
        let mut i = img(Some(100), true, "Canon", "EOS 5D");
        i.meta.noise_profile = Some(vec![(-1e-4, 1e-6)]);
        crate::dng::check::check_meta(&mut i.meta).unwrap();
        let mut est = trusted_estimate();
        est.positions[0].problem = Some("too flat".into());
        let r = choose(&i, None, false, est);
        let w = &r.choice.warnings[0].message;
        assert!(
            w.contains("NoiseProfile is not used (invalid NoiseProfile pair 0 (S -1e-4, O 1e-6)"),
            "{w}"
        );
        assert!(!w.contains("no NoiseProfile"), "{w}");
        // A valid profile without an ISO is not "no NoiseProfile" either.
        let r = choose(
            &img(None, true, "Canon", "EOS 5D"),
            None,
            false,
            trusted_estimate(),
        );
        let w = &r.choice.warnings[0].message;
        assert!(
            w.contains("NoiseProfile cannot be scaled without its ISO"),
            "{w}"
        );
    }

    #[test]
    fn a_model_file_comes_first_and_warns_only_for_another_camera() {
        let i = img(Some(100), true, "Canon", "EOS 5D");
        let same = CameraId::new(Some("canon".into()), Some("EOS 5D".into()), None);
        let other = CameraId::new(Some("Nikon".into()), Some("D3".into()), None);
        let r = choose(
            &i,
            Some(file_model(Some(same.clone()))),
            false,
            trusted_estimate(),
        );
        assert_eq!(r.choice.provenance.source, NoiseSource::File);
        assert_eq!(r.choice.provenance.camera, Some(same));
        assert!(r.choice.warnings.is_empty(), "{:?}", r.choice.warnings);
        assert!(!r.estimated);
        let r = choose(&i, Some(file_model(Some(other))), false, trusted_estimate());
        assert_eq!(r.choice.warnings.len(), 1);
        let w = &r.choice.warnings[0].message;
        assert!(
            w.starts_with(
                "noise: cal.json was calibrated on Nikon D3, not on this camera (Canon EOS 5D)"
            ),
            "{w}"
        );
        assert!(w.contains("day2night calibrate noise"), "{w}");
        // A file that records no camera cannot be compared: no warning, said in the note.
        let r = choose(&i, Some(file_model(None)), false, trusted_estimate());
        assert!(r.choice.warnings.is_empty());
        assert_eq!(r.choice.provenance.camera, None);
        assert!(
            r.choice.provenance.note.contains("records no camera"),
            "{}",
            r.choice.provenance.note
        );
    }

    #[test]
    fn the_noise_profile_comes_second() {
        let i = img(Some(200), true, "Canon", "EOS 5D");
        let r = choose(&i, None, false, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::NoiseProfile);
        assert_eq!(r.choice.provenance.camera, Some(CameraId::of(&i.meta)));
        assert!(r.choice.warnings.is_empty() && !r.estimated);
        assert_eq!(r.choice.model.iso_range(), (200, 200));
        // Without an ISO the profile cannot be scaled: the embedded table, said why.
        let i = img(None, true, "Canon", "EOS 5D");
        let r = choose(&i, None, false, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
        assert!(r.choice.warnings[0].message.contains("ISO is unknown"));
        assert!(!r.estimated);
    }

    #[test]
    fn the_paper_phone_keeps_its_own_table_without_a_word() {
        for model in ["SM-G780F", "SM-G781B"] {
            let i = img(Some(100), false, "samsung", model);
            let r = choose(&i, None, false, trusted_estimate());
            assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
            assert!(r.choice.warnings.is_empty(), "{:?}", r.choice.warnings);
            assert!(!r.estimated, "no estimate for the table's own camera");
            assert_eq!(r.choice.model.isos, embedded::noise_model().isos);
            assert_eq!(r.choice.provenance.camera, embedded::noise_model().camera);
            assert_eq!(
                r.choice.provenance.camera.unwrap().label(),
                "samsung SM-G780/SM-G781 (Galaxy S20 FE)"
            );
        }
    }

    #[test]
    fn release_compat_keeps_the_release_table_and_says_so() {
        let i = img(Some(100), false, "Canon", "EOS 5D");
        let r = choose(&i, None, true, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
        assert!(!r.estimated);
        let w = &r.choice.warnings[0].message;
        assert!(
            w.contains("--compat release keeps the release's noise table"),
            "{w}"
        );
        assert!(
            w.contains("another camera's noise, not Canon EOS 5D's"),
            "{w}"
        );
        // The paper's phone under release: its own table, no warning.
        let i = img(Some(100), false, "samsung", "SM-G781B");
        assert!(choose(&i, None, true, trusted_estimate())
            .choice
            .warnings
            .is_empty());
    }

    /// `--compat release` uses the release's table even when the input has a usable
    /// NoiseProfile and an ISO (issue 42), and its warning and provenance say so.
    #[test]
    fn release_compat_sets_a_usable_noise_profile_aside_and_says_so() {
        let i = img(Some(100), true, "Canon", "EOS 5D");
        let r = choose(&i, None, true, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
        assert_eq!(r.choice.model.isos, embedded::noise_model().isos);
        assert!(!r.estimated);
        let w = &r.choice.warnings[0].message;
        assert!(
            w.starts_with(
                "noise: --compat release keeps the release's noise table rather than the \
                 input's NoiseProfile (at ISO 100); using the embedded noise table"
            ),
            "{w}"
        );
        assert!(w.contains("not Canon EOS 5D's"), "{w}");
        assert_eq!(r.choice.warnings[0].code, Code::NoiseCompatTable);
        let note = &r.choice.provenance.note;
        assert!(
            note.starts_with(
                "--compat release: the release's table, not the input's NoiseProfile (at ISO 100)"
            ),
            "{note}"
        );
        // Without the preset the same input keeps its own NoiseProfile.
        let r = choose(&i, None, false, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::NoiseProfile);
        // A model file still comes first under the preset.
        let r = choose(&i, Some(file_model(None)), true, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::File);
        // The paper's phone with a NoiseProfile: its own table, no warning, the note says why.
        let i = img(Some(100), true, "samsung", "SM-G781B");
        let r = choose(&i, None, true, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
        assert!(r.choice.warnings.is_empty(), "{:?}", r.choice.warnings);
        assert!(
            r.choice
                .provenance
                .note
                .starts_with("--compat release keeps"),
            "{}",
            r.choice.provenance.note
        );
    }

    #[test]
    fn unknown_iso_gives_the_embedded_table_with_the_reason() {
        for iso in [None, Some(0)] {
            let i = img(iso, false, "Canon", "EOS Kiss X4");
            let r = choose(&i, None, false, trusted_estimate());
            assert!(!r.estimated);
            assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
            assert_eq!(r.choice.warnings.len(), 1);
            let w = &r.choice.warnings[0].message;
            assert!(
                w.starts_with(
                    "noise: the input has no NoiseProfile and its ISO is unknown (Exif ISO 0 or \
                     absent), so its noise cannot be estimated from the image; using the \
                     embedded noise table of the paper's phone (Samsung Galaxy S20 FE): \
                     another camera's noise, not Canon EOS Kiss X4's; calibrate this camera"
                ),
                "{w}"
            );
            assert!(w.contains("--assume-iso N"), "{w}");
        }
    }

    #[test]
    fn unknown_iso_with_a_noise_profile_says_the_profile_needs_the_iso() {
        let i = img(None, true, "Canon", "EOS Kiss X4");
        let r = choose(&i, None, false, trusted_estimate());
        assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
        let w = &r.choice.warnings[0].message;
        assert!(
            w.starts_with(
                "noise: its NoiseProfile cannot be scaled without its ISO and its ISO is unknown"
            ),
            "{w}"
        );
    }

    #[test]
    fn a_trusted_estimate_is_used_and_scaled_like_a_noise_profile() {
        let i = img(Some(100), false, "Canon", "EOS 5D");
        let r = choose(&i, None, false, trusted_estimate());
        assert!(r.estimated);
        assert!(r.choice.warnings.is_empty(), "{:?}", r.choice.warnings);
        assert_eq!(r.choice.provenance.source, NoiseSource::ImageEstimate);
        assert_eq!(r.choice.provenance.camera, Some(CameraId::of(&i.meta)));
        assert_eq!(r.choice.model.camera, Some(CameraId::of(&i.meta)));
        let e = r.choice.model.at(1600).unwrap();
        assert!(e.extrapolated);
        for (p, s) in [1e-4, 1.1e-4, 1.2e-4, 1.3e-4].iter().enumerate() {
            assert!((e.params.positions[p][0] - s * 16.0).abs() < 1e-15);
            assert!((e.params.positions[p][1] - 1e-7 * 256.0).abs() < 1e-18);
        }
    }

    #[test]
    fn an_untrusted_estimate_gives_the_embedded_table_and_says_why() {
        let i = img(Some(100), false, "Canon", "EOS 5D");
        let mut est = trusted_estimate();
        est.positions[2].problem = Some("negative slope (S = -1e-8): x".into());
        let r = choose(&i, None, false, est);
        assert!(r.estimated);
        assert_eq!(r.choice.provenance.source, NoiseSource::EmbeddedS20Fe);
        let w = &r.choice.warnings[0].message;
        assert!(
            w.starts_with(
                "noise: the input has no NoiseProfile and the noise estimated from the image \
                 (ISO 100) cannot be trusted: position 2 (G): negative slope"
            ),
            "{w}"
        );
        assert!(w.contains("another camera's noise"), "{w}");
        // A real degenerate frame: the estimator itself says so.
        let flat = img(Some(100), false, "Canon", "EOS 5D");
        let real = crate::noise::estimate(&flat, &EstimateOptions::default()).unwrap();
        let r = choose(&flat, None, false, real);
        assert!(
            r.choice.warnings[0]
                .message
                .contains("too few smooth samples"),
            "{:?}",
            r.choice.warnings
        );
    }
}
