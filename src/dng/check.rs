//! Metadata checks: every value of a raw image's metadata is used as is, corrected with a
//! warning naming the tag and the value used (pushed to [`RawMeta::warnings`]), or refused
//! with an error naming the tag. The rule (docs/limits.md, "Metadata"): what the Adobe DNG
//! SDK refuses is refused; what it ignores with a warning is ignored with a warning; values it
//! accepts but that cannot be real (a white-balance gain of 10^6, a black level below zero) are
//! refused too, so no output is built on them. The bounds are those of [`crate::bounds`].
//!
//! Called by the DNG reader ([`crate::dng::read::read_dng_bytes`]) on every file it returns,
//! so `info`, `render`, `convert`, `synth`, `dataset` and Python's `read_dng` all apply the
//! same checks; raws built another way (Python's `Raw.from_array`) call [`check_meta`] too.

use crate::bounds::{self, short, short_list};
use crate::diagnostics::Code;
use crate::error::{Error, Result};
use crate::raw::meta::RawMeta;

/// Check and correct `meta` in place (see the module docs); corrections are appended to
/// `meta.warnings`.
pub fn check_meta(meta: &mut RawMeta) -> Result<()> {
    white_level(meta)?;
    linearization_table(meta)?;
    black_level(meta)?;
    neutral(meta)?;
    matrices(meta)?;
    calibration_illuminants(meta);
    noise_profile(meta);
    exif_iso(meta);
    Ok(())
}

/// The warnings of `meta` as one line (`info`'s "ready, with warnings: ...").
pub fn warnings_line(meta: &RawMeta) -> String {
    meta.warnings.messages().join("; ")
}

fn white_level(meta: &RawMeta) -> Result<()> {
    let bits = meta.bits_per_sample.clamp(1, 16);
    let max = if meta.linearization_table.is_some() {
        65535.0
    } else {
        ((1u32 << bits) - 1) as f64
    };
    let white = meta.levels.white;
    if white > max {
        let why = if meta.linearization_table.is_some() {
            "the largest linearized value".to_string()
        } else {
            format!("the largest {bits}-bit value (BitsPerSample {bits})")
        };
        return Err(Error::malformed(format!(
            "WhiteLevel {} exceeds {why}, {}: no sample can reach it (the DNG SDK refuses \
             such files)",
            short(white),
            short(max)
        )));
    }
    Ok(())
}

fn linearization_table(meta: &RawMeta) -> Result<()> {
    if let Some(t) = &meta.linearization_table {
        if t.len() < 2 {
            return Err(Error::malformed(format!(
                "LinearizationTable has {} entry: at least 2 are needed to map stored values \
                 (the DNG SDK refuses a one-entry table)",
                t.len()
            )));
        }
    }
    Ok(())
}

/// The lowest effective black level (BlackLevel + BlackLevelDeltaH + BlackLevelDeltaV) over
/// the plane, and which tag drives it below its repeat pattern's own minimum.
fn black_level(meta: &RawMeta) -> Result<()> {
    let l = &meta.levels;
    let (rr, rc) = l.black_repeat;
    if rr == 0 || rc == 0 || l.black.len() != rr * rc {
        return Ok(()); // Levels::validate names this.
    }
    // Per repeat site (i, j): black[i][j] + min over columns c = j mod rc of DeltaH[c]
    // + min over rows r = i mod rr of DeltaV[r]: the exact minimum over the plane.
    let min_delta = |d: &[f64], phase: usize, period: usize| -> f64 {
        d.iter()
            .skip(phase)
            .step_by(period)
            .fold(f64::INFINITY, |a, &v| a.min(v))
    };
    for i in 0..rr {
        for j in 0..rc {
            let b = l.black[i * rc + j];
            if b < 0.0 {
                return Err(Error::malformed(format!(
                    "BlackLevel {} is below 0",
                    short(b)
                )));
            }
            let dh = if l.black_delta_h.is_empty() {
                0.0
            } else {
                min_delta(&l.black_delta_h, j, rc).min(0.0)
            };
            let dv = if l.black_delta_v.is_empty() {
                0.0
            } else {
                min_delta(&l.black_delta_v, i, rr).min(0.0)
            };
            let eff = b + dh + dv;
            if eff < 0.0 {
                let tag = if dh < 0.0 && (dv >= 0.0 || dh <= dv) {
                    "BlackLevelDeltaH"
                } else {
                    "BlackLevelDeltaV"
                };
                return Err(Error::malformed(format!(
                    "{tag} drives the black level below 0: BlackLevel {} + BlackLevelDeltaH {} \
                     + BlackLevelDeltaV {} = {} at its lowest",
                    short(b),
                    short(dh),
                    short(dv),
                    short(eff)
                )));
            }
        }
    }
    Ok(())
}

fn neutral(meta: &RawMeta) -> Result<()> {
    if let Some(n) = meta.as_shot_neutral {
        let max = bounds::MAX_NEUTRAL_RATIO;
        for (i, name) in [(0, "red/green"), (2, "blue/green")] {
            let r = n[i];
            if !(r.is_finite() && (1.0 / max..=max).contains(&r)) {
                return Err(Error::malformed(format!(
                    "AsShotNeutral [{}]: {name} {} is outside [{}, {}] (a white-balance gain \
                     beyond any real light)",
                    short_list(&n),
                    short(r),
                    short(1.0 / max),
                    short(max)
                )));
            }
        }
    }
    Ok(())
}

fn matrices(meta: &RawMeta) -> Result<()> {
    let c = &meta.color;
    for (name, m, sdk) in [
        ("ColorMatrix1", &c.color_matrix1, true),
        ("ColorMatrix2", &c.color_matrix2, true),
        ("CameraCalibration1", &c.camera_calibration1, false),
        ("CameraCalibration2", &c.camera_calibration2, false),
    ] {
        if let Some(m) = m {
            bounds::matrix3(name, m, sdk)?;
        }
    }
    Ok(())
}

/// A CalibrationIlluminant outside the EXIF LightSource table ([`bounds::EXIF_LIGHT_SOURCES`])
/// is kept with a warning: it has no colour temperature, so two matrix sets are not
/// interpolated (the DNG SDK does the same) and ColorMatrix1 is used alone.
fn calibration_illuminants(meta: &mut RawMeta) {
    let c = &meta.color;
    for (name, code) in [
        ("CalibrationIlluminant1", c.calibration_illuminant1),
        ("CalibrationIlluminant2", c.calibration_illuminant2),
    ] {
        if let Some(v) = code.filter(|v| !bounds::EXIF_LIGHT_SOURCES.contains(v)) {
            meta.warnings.warn(
                Code::CalibrationIlluminantUnknown,
                format!(
                    "{name} {v} is not an EXIF LightSource code (0-4, 9-24 or 255): its colour \
                 temperature is unknown, so the colour matrices are not interpolated \
                 (ColorMatrix1 is used)"
                ),
            );
        }
    }
}

/// NoiseProfile pairs must have S > 0, O >= 0 (the DNG SDK ignores the tag otherwise, with
/// "Invalid NoiseProfile") and both at most [`bounds::MAX_NOISE_PROFILE`]: otherwise the tag
/// is dropped with a warning, so the built-in noise table (or `--noise-model`) is used and no
/// output carries the bad profile.
fn noise_profile(meta: &mut RawMeta) {
    let Some(p) = &meta.noise_profile else {
        return;
    };
    let max = bounds::MAX_NOISE_PROFILE;
    let bad = p.iter().enumerate().find(|(_, &(s, o))| {
        !(s.is_finite() && o.is_finite() && s > 0.0 && o >= 0.0 && s <= max && o <= max)
    });
    if let Some((i, &(s, o))) = bad {
        let what = format!(
            "NoiseProfile pair {i} (S {}, O {}) is not a noise model (need 0 < S <= {}, \
             0 <= O <= {})",
            short(s),
            short(o),
            short(max),
            short(max)
        );
        meta.warnings.warn(
            Code::NoiseProfileInvalid,
            format!("{what}: ignored; noise from the built-in table unless --noise-model"),
        );
        meta.noise_profile_problem = Some(format!("invalid {what}"));
        meta.noise_profile = None;
    }
}

fn exif_iso(meta: &mut RawMeta) {
    if let Some(iso) = meta.exif.iso {
        if bounds::iso("ISOSpeedRatings", iso).is_err() {
            meta.exif.iso = None;
            meta.warnings.warn(
                Code::IsoOutOfRange,
                format!(
                    "ISOSpeedRatings {iso} is outside {}..={}: ignored (ISO unknown; clean \
                 outputs use ISO {})",
                    bounds::ISO_RANGE.0,
                    bounds::ISO_RANGE.1,
                    meta.iso_or_default()
                ),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::Bayer;

    fn meta() -> RawMeta {
        RawMeta::new_bayer(Bayer::RGGB, 14, 512.0, 16383.0)
    }

    #[test]
    fn plausible_metadata_passes_untouched() {
        let mut m = meta();
        m.noise_profile = Some(vec![(2e-4, 1e-6)]);
        m.exif.iso = Some(1600);
        let before = m.clone();
        check_meta(&mut m).unwrap();
        assert_eq!(m, before);
        assert!(m.warnings.is_empty());
    }

    #[test]
    fn refusals_name_the_tag() {
        type Edit = Box<dyn Fn(&mut RawMeta)>;
        let cases: Vec<(&str, Edit)> = vec![
            ("WhiteLevel 16384", Box::new(|m| m.levels.white = 16384.0)),
            (
                "LinearizationTable has 1",
                Box::new(|m| m.linearization_table = Some(vec![5])),
            ),
            ("BlackLevel -1", Box::new(|m| m.levels.black = vec![-1.0])),
            (
                "BlackLevelDeltaH drives",
                Box::new(|m| m.levels.black_delta_h = vec![0.0, -600.0, 3.0]),
            ),
            (
                "BlackLevelDeltaV drives",
                Box::new(|m| m.levels.black_delta_v = vec![-513.0]),
            ),
            (
                "AsShotNeutral",
                Box::new(|m| m.as_shot_neutral = Some([1e-6, 1.0, 1.0])),
            ),
            (
                "AsShotNeutral",
                Box::new(|m| m.as_shot_neutral = Some([1.0, 1.0, 1001.0])),
            ),
            (
                "ColorMatrix2",
                Box::new(|m| {
                    m.color.color_matrix2 = Some(vec![
                        2f64.powi(31),
                        0.,
                        0.,
                        0.,
                        1.,
                        0.,
                        0.,
                        0.,
                        2f64.powi(-31),
                    ])
                }),
            ),
        ];
        for (want, f) in cases {
            let mut m = meta();
            f(&mut m);
            let e = check_meta(&mut m).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    #[test]
    fn neutral_at_the_bound_is_used() {
        let mut m = meta();
        m.as_shot_neutral = Some([1e-3, 1.0, 1e3]);
        check_meta(&mut m).unwrap();
        assert!(m.warnings.is_empty());
    }

    #[test]
    fn a_calibration_illuminant_outside_the_exif_table_is_warned_about() {
        let mut m = meta();
        m.color.calibration_illuminant1 = Some(21);
        check_meta(&mut m).unwrap();
        assert!(m.warnings.is_empty(), "{:?}", m.warnings);
        m.color.calibration_illuminant2 = Some(99);
        check_meta(&mut m).unwrap();
        assert_eq!(m.warnings.len(), 1);
        assert!(
            m.warnings[0]
                .message
                .starts_with("CalibrationIlluminant2 99 is not an EXIF LightSource code"),
            "{:?}",
            m.warnings
        );
    }

    #[test]
    fn bad_noise_profiles_are_dropped_with_a_warning() {
        for p in [
            (0.0, 0.0),
            (-1e-4, 1e-6),
            (1e30, 1e30),
            (1e-4, -1e-9),
            (f64::NAN, 0.0),
        ] {
            let mut m = meta();
            m.noise_profile = Some(vec![(2e-4, 1e-6), p]);
            check_meta(&mut m).unwrap();
            assert_eq!(m.noise_profile, None, "{p:?}");
            let why = m.noise_profile_problem.as_deref().unwrap_or_default();
            assert!(why.starts_with("invalid NoiseProfile pair 1 (S "), "{why}");
            assert_eq!(m.warnings.len(), 1);
            assert!(
                m.warnings[0].message.starts_with("NoiseProfile pair 1"),
                "{:?}",
                m.warnings
            );
        }
        // O = 0 (no read noise) is a valid model.
        let mut m = meta();
        m.noise_profile = Some(vec![(1e-4, 0.0)]);
        check_meta(&mut m).unwrap();
        assert!(m.noise_profile.is_some() && m.warnings.is_empty());
    }

    #[test]
    fn absurd_iso_is_ignored_with_a_warning() {
        let mut m = meta();
        m.exif.iso = Some(5_000_000);
        check_meta(&mut m).unwrap();
        assert_eq!(m.exif.iso, None);
        assert!(
            m.warnings[0].message.contains("ISOSpeedRatings 5000000"),
            "{:?}",
            m.warnings
        );
    }
}
