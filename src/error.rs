//! The library's error type: malformed input, unsupported feature, I/O, limits, invalid
//! parameter. Every variant carries enough context to print `file: reason`.

use std::path::PathBuf;

/// Result alias used throughout the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in day2night.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The input breaks the TIFF/DNG (or EXR, PNG, JSON) format rules.
    #[error("malformed input: {0}")]
    Malformed(String),
    /// The input is well formed but uses a feature day2night does not handle; the message
    /// names the feature, e.g. "compression 9 (VC-5) is not supported".
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A hostile or absurd size: entry counts, dimensions, allocations over the limits.
    #[error("limit exceeded: {0}")]
    Limits(String),
    /// A caller- or user-supplied parameter is out of range or inconsistent.
    #[error("invalid parameter: {0}")]
    InvalidParam(String),
    /// An output exists and overwriting was not requested, or an output would replace an input.
    #[error("{}: refusing to overwrite: {reason}", path.display())]
    WouldOverwrite {
        /// The output that would be replaced.
        path: PathBuf,
        /// Why it is refused.
        reason: String,
    },
    /// Another process is writing the same outputs (it holds their advisory lock, see
    /// [`crate::output::OutputSetLock`]); the message names the output set.
    #[error("{0}")]
    Busy(String),
    /// The run was asked to stop (SIGINT/SIGTERM, see [`crate::output::request_stop`])
    /// before this work could finish; its temporary files were removed.
    #[error("interrupted")]
    Interrupted,
    /// An operating-system I/O error.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    /// An error tied to a file: wraps any other variant with the path it concerns.
    #[error("{}: {source}", path.display())]
    File {
        /// The file concerned.
        path: PathBuf,
        /// What went wrong with it.
        #[source]
        source: Box<Error>,
    },
}

impl Error {
    /// Malformed-input error from anything printable.
    pub fn malformed(msg: impl Into<String>) -> Self {
        Error::Malformed(msg.into())
    }
    /// Unsupported-feature error from anything printable.
    pub fn unsupported(msg: impl Into<String>) -> Self {
        Error::Unsupported(msg.into())
    }
    /// Limits error from anything printable.
    pub fn limits(msg: impl Into<String>) -> Self {
        Error::Limits(msg.into())
    }
    /// Invalid-parameter error from anything printable.
    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::InvalidParam(msg.into())
    }
    /// Attach a file path (no-op if the error already names one).
    pub fn in_file(self, path: impl Into<PathBuf>) -> Self {
        match self {
            e @ Error::File { .. } => e,
            e => Error::File {
                path: path.into(),
                source: Box::new(e),
            },
        }
    }
    /// The innermost error, below any `File` wrappers.
    pub fn root(&self) -> &Error {
        match self {
            Error::File { source, .. } => source.root(),
            e => e,
        }
    }
    /// True for errors caused by the input or the user (exit code 1), false for none.
    pub fn is_input_error(&self) -> bool {
        !matches!(self.root(), Error::Io(_))
    }
}

/// Extension to attach a path to any `Result<_, Error>`.
pub trait ResultExt<T> {
    /// Wrap the error with the file it concerns.
    fn in_file(self, path: impl Into<PathBuf>) -> Result<T>;
}

impl<T> ResultExt<T> for Result<T> {
    fn in_file(self, path: impl Into<PathBuf>) -> Result<T> {
        self.map_err(|e| e.in_file(path))
    }
}
