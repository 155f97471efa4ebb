//! An option's default as Python sees it, made from the option table's default text (kept
//! apart from `synth_options.rs` so that `args.rs`, which binds parameters whose defaults
//! come from the table, does not depend on the keyword parser that depends on it).

use crate::errors::value_err;
use day2night::synth::options::{Kind, OptionDef};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyTuple};

/// The option's default as a Python value, made from the table's default text by its kind:
/// an int, a float, a tuple of numbers or ISOs, a str, False for a switch; None when the
/// option is unset by default (or `iso="none"`).
pub(crate) fn python_default<'py>(
    py: pyo3::Python<'py>,
    d: &OptionDef,
) -> PyResult<Bound<'py, PyAny>> {
    let bad = |t: &str| value_err(format!("option {}: default {t:?} is not its kind", d.name));
    let Some(t) = d.default_text() else {
        return Ok(match d.kind {
            Kind::Switch => PyBool::new(py, false).to_owned().into_any(),
            _ => py.None().into_bound(py),
        });
    };
    Ok(match d.kind {
        Kind::Switch => PyBool::new(py, t == "true").to_owned().into_any(),
        Kind::Int { .. } => t
            .parse::<u64>()
            .map_err(|_| bad(t))?
            .into_pyobject(py)?
            .into_any(),
        Kind::Float { .. } => t
            .parse::<f64>()
            .map_err(|_| bad(t))?
            .into_pyobject(py)?
            .into_any(),
        Kind::Isos if t == "none" => py.None().into_bound(py),
        Kind::Isos => {
            let v = t
                .split(',')
                .map(|i| i.trim().parse::<u32>())
                .collect::<Result<Vec<_>, _>>()
                .map_err(|_| bad(t))?;
            PyTuple::new(py, v)?.into_any()
        }
        Kind::Numbers(_) | Kind::Pair { .. } => {
            let v = t
                .split(',')
                .map(|i| i.trim().parse::<f64>())
                .collect::<Result<Vec<_>, _>>()
                .map_err(|_| bad(t))?;
            PyTuple::new(py, v)?.into_any()
        }
        Kind::Text | Kind::Path | Kind::Choice(_) => t.into_pyobject(py)?.into_any(),
    })
}
