//! The options of `synthesize` and `night_pair` (the command line's flags as keyword
//! arguments) converted to a `JobConfig`, and the jobs built from them, cached per process.

use crate::args::{BULBS, LIGHTS};
use crate::errors::{py_err, value_err};
use day2night::synth::config::JobConfig;
use day2night::synth::job::{SynthJob, Target};
use day2night::synth::{Covariance, MaskEval, Mode, RelightFormula};
use day2night::Error;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// The job options a ``synthesize`` call spells, as the command line's flags.
pub(crate) fn job_config(
    mode: &str,
    isos: Vec<u32>,
    want_target: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<JobConfig> {
    let mut cfg = JobConfig::default();
    let o = &mut cfg.options;
    o.mode = mode.parse::<Mode>().map_err(py_err)?;
    o.isos = Vec::new();
    for iso in isos {
        // Each in ISO_RANGE: checked when the argument was extracted (args::Isos).
        if !o.isos.contains(&iso) {
            o.isos.push(iso);
        }
    }
    let mut release = false;
    let mut opcodes = None;
    let mut burst = day2night::synth::burst::checks::BurstRequest::default();
    if let Some(opts) = options {
        for (k, v) in opts.iter() {
            let key: String = k.extract()?;
            let path = |v: &Bound<'_, PyAny>| -> PyResult<Option<PathBuf>> {
                if v.is_none() {
                    Ok(None)
                } else {
                    Ok(Some(v.extract::<PathBuf>()?))
                }
            };
            match key.as_str() {
                "relight_formula" | "formula" => {
                    o.formula = v
                        .extract::<String>()?
                        .parse::<RelightFormula>()
                        .map_err(py_err)?
                }
                "bulbs" => o.bulbs = BULBS.opt(&v)?,
                "lights" => o.local_lights = LIGHTS.opt(&v)?,
                "truncate" => o.truncate = v.extract()?,
                "covariance" => {
                    o.covariance = v
                        .extract::<String>()?
                        .parse::<Covariance>()
                        .map_err(py_err)?
                }
                "day_neutral" => {
                    o.day_neutral = if v.is_none() {
                        None
                    } else {
                        let n: Vec<f64> = v.extract()?;
                        match n.as_slice() {
                            [r, g, b] => Some([*r, *g, *b]),
                            _ => return Err(value_err("day_neutral must be (r, g, b)")),
                        }
                    }
                }
                "mask_eval" => {
                    o.mask_eval = v.extract::<String>()?.parse::<MaskEval>().map_err(py_err)?
                }
                "compat" => {
                    release = match v.extract::<Option<String>>()?.as_deref() {
                        None => false,
                        Some("release") => true,
                        Some(c) => {
                            return Err(value_err(format!("compat {c:?}: use \"release\" or None")))
                        }
                    }
                }
                "opcodes" => {
                    opcodes = Some(
                        v.extract::<String>()?
                            .parse::<day2night::isp::opcodes::OpcodeMode>()
                            .map_err(py_err)?,
                    )
                }
                "illuminants" => cfg.illuminants = path(&v)?,
                "brightness" => cfg.brightness = path(&v)?,
                "noise_model" => cfg.noise_model = path(&v)?,
                k if crate::burst::OPTIONS.contains(&k) => {
                    crate::burst::set_option(&mut burst, k, &v)?
                }
                other => {
                    return Err(value_err(format!(
                    "unknown option {other:?} (known: relight_formula, bulbs, lights, truncate, \
covariance, day_neutral, mask_eval, opcodes, illuminants, brightness, noise_model, burst, \
motion, shake_step, shake_roll, warp_interp)"
                )))
                }
            }
        }
    }
    cfg.options.burst = crate::burst::resolve(&burst)?;
    if release {
        // Applied last, like --compat release: it checks the other options.
        cfg.options = cfg.options.clone().release_compat().map_err(py_err)?;
    }
    if let Some(m) = opcodes {
        cfg.options.opcodes = m;
    }
    cfg.target = if want_target {
        Target::Exr
    } else {
        Target::None
    };
    Ok(cfg)
}

/// Jobs already built (calibration files loaded), by their configuration: a data loader
/// calls `synthesize` with the same options for every item.
pub(crate) fn job_for(cfg: &JobConfig) -> Result<Arc<SynthJob>, Error> {
    static JOBS: OnceLock<Mutex<HashMap<String, Arc<SynthJob>>>> = OnceLock::new();
    let key = format!("{cfg:?}");
    let jobs = JOBS.get_or_init(Default::default);
    if let Some(j) = jobs.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Ok(j.clone());
    }
    let job = Arc::new(cfg.build()?);
    let mut map = jobs.lock().unwrap_or_else(|e| e.into_inner());
    if map.len() > 64 {
        map.clear();
    }
    map.insert(key, job.clone());
    Ok(job)
}
