//! What a dataset run tells while it works, as calls on a [`Progress`] the caller supplies:
//! the library prints nothing itself. The CLI turns the calls into a bar or plain lines on
//! stderr (`src/cli/progress.rs`); Python and the tests pass [`ProgressSink::silent`].

use std::fmt;
use std::path::Path;
use std::sync::Arc;

/// One input of a run finished (all of its variants made, skipped or failed).
#[derive(Debug, Clone, Copy)]
pub struct InputDone<'a> {
    /// How many inputs have finished so far, this one included (1-based).
    pub index: usize,
    /// Inputs in the run.
    pub total: usize,
    /// The input's split ("train", "val").
    pub split: &'a str,
    /// The input's path relative to the day folder.
    pub input: &'a str,
    /// Variants made.
    pub done: usize,
    /// Variants skipped (already up to date).
    pub skipped: usize,
    /// Variants that failed.
    pub failed: usize,
    /// Seconds spent on the input.
    pub secs: f64,
}

/// Receiver of a run's progress. Every method has an empty default; calls come from the
/// worker threads.
pub trait Progress: Send + Sync {
    /// The run starts work on `total` inputs.
    fn start(&self, total: usize) {
        let _ = total;
    }
    /// A warning about one input (a metadata correction, without a subject: the input is
    /// `path`), said once per input.
    fn warning(&self, path: &Path, warning: &crate::diagnostics::Warning) {
        let _ = (path, warning);
    }
    /// One input finished.
    fn input_done(&self, event: &InputDone<'_>) {
        let _ = event;
    }
    /// The run's work is over (finished or stopped).
    fn finish(&self) {}
}

/// A [`Progress`] that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {}

/// A shared [`Progress`], the form [`super::RunOptions`] carries (cloneable, printable).
#[derive(Clone)]
pub struct ProgressSink(Arc<dyn Progress>);

impl ProgressSink {
    /// Wrap a receiver.
    pub fn new(progress: impl Progress + 'static) -> ProgressSink {
        ProgressSink(Arc::new(progress))
    }

    /// A sink that ignores everything (the default).
    pub fn silent() -> ProgressSink {
        ProgressSink::new(Silent)
    }
}

impl Default for ProgressSink {
    fn default() -> Self {
        ProgressSink::silent()
    }
}

impl fmt::Debug for ProgressSink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ProgressSink(..)")
    }
}

impl std::ops::Deref for ProgressSink {
    type Target = dyn Progress;
    fn deref(&self) -> &Self::Target {
        &*self.0
    }
}
