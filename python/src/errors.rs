//! The one place that turns errors into Python exceptions: a library error becomes
//! `OSError` (I/O) or `ValueError` (everything else) with the message the command line
//! prints after `day2night: `; a bad Python argument is a `ValueError` naming it.

use day2night::Error;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::PyErr;

/// Whether `e` is, under its file context, an I/O error.
fn is_io(e: &Error) -> bool {
    let mut cur = e;
    while let Error::File { source, .. } = cur {
        cur = source;
    }
    matches!(cur, Error::Io(_))
}

/// A library error as a Python exception: `OSError` for I/O, `ValueError` otherwise, with
/// the message the command line prints (after its `day2night: ` prefix).
pub(crate) fn py_err(e: Error) -> PyErr {
    py_err_noting(e, "")
}

/// [`py_err`] with `note` appended to the message (after a space), e.g. the dict key a
/// metadata error came from.
pub(crate) fn py_err_noting(e: Error, note: &str) -> PyErr {
    let msg = if note.is_empty() {
        e.to_string()
    } else {
        format!("{e} {note}")
    };
    if is_io(&e) {
        PyOSError::new_err(msg)
    } else {
        PyValueError::new_err(msg)
    }
}

/// An error's message without its kind (`invalid parameter: `, ...) or file context: the
/// words a Python argument's error speaks.
pub(crate) fn text(e: &Error) -> String {
    match e.root() {
        Error::InvalidParam(m) | Error::Malformed(m) | Error::Unsupported(m) | Error::Limits(m) => {
            m.clone()
        }
        e => e.to_string(),
    }
}

/// A `ValueError` with `msg`.
pub(crate) fn value_err(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}
