//! The settings of a synthesis job by name, as the command line and the Python package
//! spell them, and the one place that turns them into a [`SynthJob`]: option values are
//! parsed and checked, calibration files loaded (illuminant dictionary or fit, brightness
//! dictionary, noise model), output settings validated. `synth`, `dataset` and
//! `day2night.synthesize` build their jobs here, so the same flags mean the same job.

use super::dictionaries;
use super::job::{SynthJob, Target};
use super::{Calibration, Covariance, IlluminantChoice, Mode, RelightFormula, SynthOptions};
use crate::dng::write::Compression;
use crate::encode::exr::ExrOptions;
use crate::error::{Error, Result};
use crate::noise::NoiseModel;
use std::path::PathBuf;

/// Everything that makes a [`SynthJob`], with calibration as file paths.
#[derive(Debug, Clone, PartialEq)]
pub struct JobConfig {
    /// Synthesis options (mode, formula, bulbs, lights, ISOs, mask evaluation...).
    pub options: SynthOptions,
    /// Night illuminant dictionary (`--illuminants`): `paper`, `cie` or a file (camera
    /// neutrals, a fitted Gaussian, xy lamps); None = the default
    /// ([`IlluminantChoice::Auto`], or the paper's under the release preset).
    pub illuminants: Option<PathBuf>,
    /// Brightness dictionary (`--brightness`).
    pub brightness: Option<PathBuf>,
    /// Noise model file (`--noise-model`).
    pub noise_model: Option<PathBuf>,
    /// Variants per input.
    pub variants: u32,
    /// Rendered targets.
    pub target: Target,
    /// Also render the network input EXR.
    pub input_exr: bool,
    /// DNG compression.
    pub compression: Compression,
    /// EXR options.
    pub exr: ExrOptions,
}

impl Default for JobConfig {
    fn default() -> Self {
        JobConfig::of(SynthOptions::default())
    }
}

impl JobConfig {
    /// A configuration of `options` with everything else at its default.
    pub fn of(options: SynthOptions) -> JobConfig {
        JobConfig {
            options,
            illuminants: None,
            brightness: None,
            noise_model: None,
            variants: 1,
            target: Target::default(),
            input_exr: false,
            compression: Compression::None,
            exr: ExrOptions::default(),
        }
    }

    /// Check the options, load the calibration files and make the job.
    pub fn build(&self) -> Result<SynthJob> {
        self.options.validate()?;
        if self.variants == 0 {
            return Err(Error::invalid("variants must be at least 1"));
        }
        self.exr.validate()?;
        let illuminants = match &self.illuminants {
            Some(p) => IlluminantChoice::from_arg(p, self.options.covariance)?,
            None => IlluminantChoice::default_for(self.options.compat.paper_illuminants),
        };
        let brightness = self
            .brightness
            .as_deref()
            .map(dictionaries::load_brightness)
            .transpose()?;
        let noise = self
            .noise_model
            .as_deref()
            .map(NoiseModel::from_file)
            .transpose()?;
        Ok(SynthJob {
            options: self.options.clone(),
            calibration: Calibration {
                illuminants,
                brightness,
                noise,
            },
            variants: self.variants,
            target: self.target,
            input_exr: self.input_exr,
            compression: self.compression,
            exr: self.exr,
            unique_id: Default::default(),
        })
    }
}

/// A list of ISOs: `1600,3200` (duplicates dropped, order kept) or `none` (no noisy raw).
pub fn parse_isos(s: &str) -> Result<Vec<u32>> {
    if s.trim().eq_ignore_ascii_case("none") {
        return Ok(vec![]);
    }
    let mut v = Vec::new();
    for part in s.split(',') {
        let iso: u32 = part.trim().parse().map_err(|_| {
            Error::invalid(format!(
                "{:?} is not an ISO (use e.g. 1600,3200 or none)",
                part
            ))
        })?;
        crate::bounds::iso("", iso)?;
        if !v.contains(&iso) {
            v.push(iso);
        }
    }
    Ok(v)
}

/// A neutral `r,g,b`.
pub fn parse_neutral(s: &str) -> Result<[f64; 3]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::invalid(format!("{:?} is not r,g,b", s)))?;
    match v.as_slice() {
        [r, g, b] => Ok([*r, *g, *b]),
        _ => Err(Error::invalid(format!("{:?} is not r,g,b", s))),
    }
}

/// The presets of `--compat` (docs/synthesis.md, "Release compatibility").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    /// The authors' released code where it is deterministic.
    Release,
}

crate::choices! {
    Preset, ignore_case: false,
    unknown: |s| Error::invalid(format!(
        "preset {s:?} (use {})",
        crate::choice::listed::<Preset>(", ", " or ")
    )),
    Release => "release": "The authors' released code where it is deterministic",
}

crate::choices! {
    Mode, ignore_case: false,
    unknown: |s| Error::invalid(format!(
        "mode {s:?} (use {})",
        crate::choice::listed::<Mode>(", ", " or ")
    )),
    Local => "local": "Several local lights (the paper's method)",
    Global => "global": "One night illuminant",
    Dimmed => "dimmed": "Dimmed day image (baseline)",
    Day => "day": "The day image itself (baseline)",
}

crate::choices! {
    RelightFormula, ignore_case: false,
    unknown: |s| Error::invalid(format!(
        "relight formula {s:?} (use {})",
        crate::choice::listed::<RelightFormula>(", ", " or ")
    )),
    Release => "release": "The authors' released code",
    Paper => "paper": "The paper's equation",
}

crate::choices! {
    Covariance, ignore_case: false,
    unknown: |s| Error::invalid(format!(
        "covariance {s:?} (use {})",
        crate::choice::listed::<Covariance>(", ", " or ")
    )),
    Unbiased => "unbiased": "1/(M-1) (released code)",
    MaximumLikelihood => "ml": "1/M (the paper's equation 2)",
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::MaskEval;

    #[test]
    fn parses() {
        assert_eq!(parse_isos("1600, 3200,1600").unwrap(), [1600, 3200]);
        assert!(parse_isos("none").unwrap().is_empty());
        assert!(parse_isos("0").is_err());
        assert!(parse_isos("x").is_err());
        assert_eq!(parse_neutral("0.5,1,0.7").unwrap(), [0.5, 1.0, 0.7]);
        assert!(parse_neutral("1,2").is_err());
        assert_eq!(
            "truncated:3".parse::<MaskEval>().unwrap(),
            MaskEval::Truncated { k: 3.0 }
        );
        assert!("truncated:-1".parse::<MaskEval>().is_err());
        for m in ["local", "global", "dimmed", "day"] {
            m.parse::<Mode>().unwrap();
        }
        assert!("night".parse::<Mode>().is_err());
        assert_eq!(
            "ml".parse::<Covariance>().unwrap(),
            Covariance::MaximumLikelihood
        );
        assert!("paper".parse::<RelightFormula>().is_ok());
    }

    #[test]
    fn build_checks_and_loads() {
        let job = JobConfig::default().build().unwrap();
        assert_eq!(job, SynthJob::new(SynthOptions::default()).unwrap());
        let bad = JobConfig {
            variants: 0,
            ..JobConfig::default()
        };
        assert!(bad.build().is_err());
        let missing = JobConfig {
            noise_model: Some("/nonexistent/model.json".into()),
            ..JobConfig::default()
        };
        assert!(missing
            .build()
            .unwrap_err()
            .to_string()
            .contains("model.json"));
    }
}
