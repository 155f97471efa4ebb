//! The library's warnings as Python warnings: each [`Warning`] is raised as the
//! `day2night.Day2NightWarning` subclass of its code (python/pysrc/day2night/diagnostics.py),
//! `<subject>: <message>`, as the command line prints `warning[CODE]: <subject>: <message>`.
use day2night::raw::meta::RawMeta;
use day2night::Warning;
use pyo3::prelude::*;

/// Raise each metadata correction of the reader (`day2night::dng::check`) as its
/// `day2night.Day2NightWarning` subclass: `<file>: <message>`, as the command line says
/// `warning[CODE]: <file>: <message>`.
pub(crate) fn warn_meta(py: Python<'_>, path: &std::path::Path, meta: &RawMeta) -> PyResult<()> {
    warn_lines(py, &path.display().to_string(), &meta.warnings)
}

/// Raise each of `warnings` (about the raw `name` when they name nothing else) as a Python
/// warning of its code's class (`day2night.Day2NightWarning` subclasses, python/pysrc/
/// day2night/diagnostics.py), attributed to the caller of the extension's function.
pub(crate) fn warn_lines(py: Python<'_>, name: &str, warnings: &[Warning]) -> PyResult<()> {
    warn_at(py, name, warnings, 1)
}

/// [`warn_lines`] with the caller `stacklevel` frames up (1: the caller of the extension's
/// function).
pub(crate) fn warn_at(
    py: Python<'_>,
    name: &str,
    warnings: &[Warning],
    stacklevel: i32,
) -> PyResult<()> {
    if warnings.is_empty() {
        return Ok(());
    }
    let emit = py.import("day2night.diagnostics")?.getattr("_emit")?;
    for w in warnings {
        // One frame more: `_emit` itself.
        emit.call1((
            w.code.as_str(),
            w.subject_or(name),
            &w.message,
            stacklevel + 1,
        ))?;
    }
    Ok(())
}

/// Raise the warnings of a plan beyond the reader's own (those `read_dng` already raised):
/// the noise model's source (another camera's table, an untrusted estimate, a model file of
/// another camera), another camera's illuminants, ISO extrapolation, opcodes; then
/// `extra` (the run's); each as its code's `Day2NightWarning` subclass, `<file>: <message>`,
/// as `day2night synth` prints `warning[CODE]: <file>: <message>`.
pub(crate) fn warn_plan(
    py: Python<'_>,
    file: &str,
    meta: &RawMeta,
    report: &day2night::synth::PlanReport,
    extra: &[Warning],
) -> PyResult<()> {
    // The plan's list starts with the reader's corrections (dng::check), given the input's
    // name as their subject.
    let same = |(p, m): (&Warning, &Warning)| p.code == m.code && p.message == m.message;
    let own = if report.warnings.len() >= meta.warnings.len()
        && report.warnings.iter().zip(meta.warnings.iter()).all(same)
    {
        meta.warnings.len()
    } else {
        0
    };
    let mut new = report.warnings[own..].to_vec();
    new.extend(extra.iter().cloned());
    warn_lines(py, file, &new)
}
