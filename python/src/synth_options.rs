//! The keyword options of the synthesis functions (`synthesize`, `night_pair`,
//! `write_unit`, `write_units`), parsed through the library's option table
//! (`day2night::synth::options::OPTIONS`, the one declaration of each option that the
//! command line's flags are also made from), and the jobs built from them, cached per
//! process. Each value is type checked here (a `TypeError` naming the keyword); the table
//! checks an integer against its range (a `ValueError` naming the keyword, the value and
//! the range) and its setter parses the rest (a `ValueError` naming the keyword, the value and
//! what it accepts). An unknown keyword lists the keywords the function takes.

use crate::args;
use crate::errors::{text, value_err};
pub(crate) use crate::option_default::python_default;
use day2night::synth::config::JobConfig;
use day2night::synth::job::SynthJob;
use day2night::synth::options::{
    self, Draft, Kind, OptionDef, OptionError, Python, Spelling, Value, OPTIONS,
};
use day2night::Error;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// Which functions' keywords: the in-memory ones or those that write files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scope {
    /// `synthesize`, `night_pair` (`NightPairs`): no output settings; `mode`, `isos` and
    /// `target` are parameters of their own.
    InMemory,
    /// `write_unit`, `write_units`: every option `dataset` has.
    Files,
}

/// Whether `scope`'s functions take `d` as a keyword option.
fn accepts(d: &OptionDef, scope: Scope) -> bool {
    match d.python {
        Python::Keyword => true,
        Python::Files | Python::Parameter => scope == Scope::Files,
        Python::Absent(_) => false,
    }
}

/// The keyword options `scope`'s functions take, with their Python defaults, in the table's
/// order: `day2night._native.KEYWORDS[scope]`, the keyword-only parameters of their
/// signatures (python/pysrc/day2night/signatures.py).
fn keywords(py: pyo3::Python<'_>, scope: Scope) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for d in OPTIONS.iter().filter(|d| accepts(d, scope)) {
        list.append((d.python_name(), python_default(py, d)?))?;
    }
    Ok(list)
}

/// `day2night._native.KEYWORDS`: `in_memory` (`synthesize`, `night_pair`, `fresh_pair`,
/// `NightPairs`) and `files` (`write_unit`, `write_units`).
pub(crate) fn keywords_dict(py: pyo3::Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("in_memory", keywords(py, Scope::InMemory)?)?;
    d.set_item("files", keywords(py, Scope::Files)?)?;
    Ok(d)
}

/// `day2night._native.SYNTH_CONSTANTS`: the synthesis fields that are not options, as
/// (sidecar field, value, why) (`day2night::synth::options::CONSTANTS`).
pub(crate) fn constants_list(py: pyo3::Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for c in options::CONSTANTS {
        list.append((c.field, c.value, c.why))?;
    }
    Ok(list)
}

/// The kind's name in `SYNTH_OPTIONS` (`kind`).
fn kind_name(k: &Kind) -> &'static str {
    match k {
        Kind::Switch => "switch",
        Kind::Int { .. } => "int",
        Kind::Float { .. } => "float",
        Kind::Text => "text",
        Kind::Isos => "isos",
        Kind::Numbers(_) | Kind::Pair { .. } => "numbers",
        Kind::Path => "path",
        Kind::Choice(_) => "choice",
    }
}

/// The keyword options `scope`'s functions take, in the table's order.
pub(crate) fn known(scope: Scope) -> Vec<String> {
    OPTIONS
        .iter()
        .filter(|d| accepts(d, scope))
        .map(|d| d.python_name())
        .collect()
}

/// `day2night._native.SYNTH_OPTIONS`: every option of the table by its keyword: its flag,
/// where Python takes it (`keyword`: every synthesis function; `files`: `write_unit` and
/// `write_units`; `parameter`: a parameter of the in-memory functions (their signatures
/// spell it), a keyword of the writers; `absent`: not in Python, `note` says why), its
/// `default` as the command line types it and `python_default` as Python's value, `kind`,
/// `choices` (names), `range` ((lo, hi) of an integer), `alias`, `help` and `value_name`.
pub(crate) fn table_dict(py: pyo3::Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for o in OPTIONS {
        let e = PyDict::new(py);
        e.set_item("flag", format!("--{}", o.name))?;
        let (scope, note) = match o.python {
            Python::Keyword => ("keyword", None),
            Python::Files => ("files", None),
            Python::Parameter => ("parameter", None),
            Python::Absent(why) => ("absent", Some(why)),
        };
        e.set_item("python", scope)?;
        e.set_item("note", note)?;
        e.set_item("default", o.default_text())?;
        e.set_item("python_default", python_default(py, o)?)?;
        e.set_item("kind", kind_name(&o.kind))?;
        let choices = match o.kind {
            Kind::Choice(c) => Some(c.iter().map(|c| c.shown()).collect::<Vec<_>>()),
            _ => None,
        };
        e.set_item("choices", choices)?;
        let range = match o.kind {
            Kind::Int { lo, hi, .. } => Some((lo, hi)),
            _ => None,
        };
        e.set_item("range", range)?;
        e.set_item("alias", o.python_alias)?;
        e.set_item("help", o.help)?;
        e.set_item("value_name", o.value_name)?;
        d.set_item(o.python_name(), e)?;
    }
    Ok(d)
}

/// An option's error as Python's `ValueError`.
fn option_err(e: OptionError) -> PyErr {
    match &e.option {
        Some(_) => value_err(e.to_string()),
        None => value_err(text(&e.error)),
    }
}

/// The Python value `v` of the option `d` (called `key`) as the table's [`Value`].
fn value(d: &OptionDef, key: &str, v: &Bound<'_, PyAny>) -> PyResult<Value> {
    // None is the unset state of an option unset by default (the default its signature
    // shows), and of the texts and paths whose setters take it.
    let none_ok = (d.default_text().is_none() && !matches!(d.kind, Kind::Switch))
        || !matches!(d.kind, Kind::Switch | Kind::Float { .. });
    if none_ok && v.is_none() {
        return Ok(Value::Unset);
    }
    Ok(match d.kind {
        Kind::Switch => Value::Switch(v.extract::<bool>().map_err(|_| {
            PyTypeError::new_err(format!("{key} must be a bool (got {})", type_name(v)))
        })?),
        // the type here; the range is the table's check (Draft::set, or Draft::finish)
        Kind::Int { lo, hi, .. } => Value::Int(args::integer(v, key, lo, hi)?),
        Kind::Float { .. } => Value::Float(args::float(v, key)?),
        Kind::Text | Kind::Choice(_) => Value::Text(args::string(v, key)?),
        Kind::Path => Value::Path(v.extract::<PathBuf>().map_err(|_| {
            PyTypeError::new_err(format!("{key} must be a path (got {})", type_name(v)))
        })?),
        Kind::Isos => {
            // As --iso: "1600,3200" or "none"; or one ISO, or a sequence of them.
            if let Ok(s) = v.extract::<String>() {
                Value::Text(s)
            } else if v.hasattr("__index__")? {
                Value::Isos(vec![args::ISO.get_as(v, key)?])
            } else {
                Value::Isos(args::isos(v, key)?)
            }
        }
        Kind::Numbers(_) | Kind::Pair { .. } => {
            let n = match d.kind {
                Kind::Numbers(n) => n,
                _ => 2,
            };
            if let Ok(s) = v.extract::<String>() {
                Value::Text(s)
            } else {
                Value::Numbers(v.extract::<Vec<f64>>().map_err(|_| {
                    PyTypeError::new_err(format!(
                        "{key} must be {n} numbers (got {})",
                        type_name(v)
                    ))
                })?)
            }
        }
    })
}

fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// Apply the keyword options `opts` that `scope`'s functions take; another key is a
/// `ValueError` listing the ones they take (and `note`, if any).
pub(crate) fn apply(
    draft: &mut Draft,
    opts: Option<&Bound<'_, PyDict>>,
    scope: Scope,
    note: &str,
) -> PyResult<()> {
    let Some(opts) = opts else { return Ok(()) };
    for (k, v) in opts.iter() {
        let key: String = k.extract()?;
        match options::find(&key) {
            Some(d) if accepts(d, scope) && !key.contains('-') => {
                let value = value(d, &key, &v)?;
                draft.set(d, value, Spelling::Python).map_err(option_err)?;
            }
            _ => {
                return Err(value_err(format!(
                    "unknown option {key:?} (known: {}{note})",
                    known(scope).join(", ")
                )))
            }
        }
    }
    Ok(())
}

/// The configuration of a draft: the options that depend on each other checked together.
pub(crate) fn finish(draft: Draft) -> PyResult<JobConfig> {
    draft.finish(Spelling::Python).map_err(option_err)
}

/// The job options a ``synthesize`` or ``night_pair`` call spells: `mode`, `isos` (each
/// already in range) and the keyword options; the target is rendered when `want_target`.
pub(crate) fn job_config(
    mode: &str,
    isos: Vec<u32>,
    want_target: bool,
    opts: Option<&Bound<'_, PyDict>>,
) -> PyResult<JobConfig> {
    let mut draft = Draft::new(1);
    for (key, v) in [
        ("mode", Value::Text(mode.into())),
        ("iso", Value::Isos(isos)),
    ] {
        let d = options::find(key).ok_or_else(|| value_err(format!("no option {key:?}")))?;
        draft.set(d, v, Spelling::Python).map_err(option_err)?;
    }
    apply(&mut draft, opts, Scope::InMemory, "")?;
    let mut cfg = finish(draft)?;
    cfg.target = if want_target {
        day2night::synth::job::Target::Exr
    } else {
        day2night::synth::job::Target::None
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
