//! Safe output files: written to a temporary file in the destination directory, flushed,
//! synced, then renamed into place, so a crash or error never leaves a half-written output;
//! an existing file is refused unless overwriting was asked for; an input is never replaced.
//!
//! A policy may defer the sync and the rename ([`OutputPolicy::deferring`]): the writer's
//! thread then returns as soon as the data are handed to the kernel, a background thread
//! waits for the disk (`fsync`), and [`DeferredSyncs::finish`] renames the files into place
//! once every sync succeeded. `synth` uses this so that its compute threads do not sit in
//! `fsync` and so that a variant's outputs appear together, or not at all on an error.
//!
//! Across processes, an [`OutputSetLock`] (an advisory lock on a hidden `.<base>.lock` file
//! beside the outputs) makes two runs writing the same output set take turns, so that the
//! files of one set never come from two runs (docs/concurrency.md).
//!
//! Interrupts: every temporary file being written is recorded in a process-wide registry.
//! [`request_stop`] (called on the first SIGINT/SIGTERM) makes deferred writes and
//! [`DeferredSyncs::finish`] refuse to start, so a run stops at its next output and its
//! temporary files are removed as the errors unwind; [`remove_temp_files_and_close`]
//! (called before exiting at once, e.g. on a second signal) removes every registered
//! temporary file and refuses any new one or any rename into place from then on. A set
//! whose deferred renames have begun ([`DeferredSyncs::finish`]) is open until its queue is
//! dropped (after its sidecar): the removal waits for open sets, at most [`SET_GRACE`], so
//! that an exit on an interrupt leaves them whole.

mod atomic;
mod lock;
mod policy;
mod registry;

pub use atomic::{write_atomic, write_bytes_atomic, AtomicFile};
pub use lock::OutputSetLock;
pub use policy::{DeferredSyncs, OutputPolicy};
pub use registry::{
    remove_temp_files_and_close, request_stop, stop_requested, TempRegistry, SET_GRACE,
};

#[cfg(test)]
mod tests;
