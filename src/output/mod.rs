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
mod deferred;
mod lock;
mod policy;

pub use atomic::{write_atomic, write_bytes_atomic, AtomicFile};
pub use deferred::DeferredSyncs;
pub use lock::OutputSetLock;
pub use policy::OutputPolicy;

use crate::error::{Error, Result, ResultExt};
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long [`remove_temp_files_and_close`] waits for the output sets being renamed into
/// place to be completed (their sidecars written) before it removes what is left.
pub const SET_GRACE: Duration = Duration::from_millis(300);

/// The signal number that asked this process to stop; 0 while none did.
static STOP: AtomicI32 = AtomicI32::new(0);

/// Ask this process to stop starting new work (e.g. on SIGINT = 2 or SIGTERM = 15; any
/// positive number). Returns true for the first request; later ones keep the first signal.
pub fn request_stop(signal: i32) -> bool {
    STOP.compare_exchange(0, signal.max(1), Ordering::SeqCst, Ordering::SeqCst)
        .is_ok()
}

/// The signal of the first [`request_stop`], if any.
pub fn stop_requested() -> Option<i32> {
    match STOP.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// The temporary files a process is writing, so that an interrupt can remove them. Creating
/// a temporary file, renaming it into place and removing it all happen under its lock, so
/// after [`TempRegistry::close_and_remove`] no temporary file is created or renamed.
#[derive(Debug, Default)]
pub struct TempRegistry {
    state: Mutex<TempState>,
}

#[derive(Debug, Default)]
struct TempState {
    closed: bool,
    live: Vec<PathBuf>,
    /// Output sets whose renames have begun and whose queue is not dropped yet.
    sets_open: usize,
}

/// The registry of this process's temporary files (used by [`write_atomic`]).
static TEMPS: TempRegistry = TempRegistry::new();

/// Remove every temporary file this process is writing and refuse new ones (and renames
/// into place) from now on; returns how many were removed. The lock files of the output
/// sets held are removed too (the locks themselves end with the process). For a process
/// about to exit on an interrupt.
pub fn remove_temp_files_and_close() -> usize {
    let n = TEMPS.close_and_remove_within(SET_GRACE);
    #[cfg(unix)]
    for p in lock::held_locks().iter() {
        let _ = fs::remove_file(p);
    }
    n
}

impl TempRegistry {
    /// An empty, open registry.
    pub const fn new() -> TempRegistry {
        TempRegistry {
            state: Mutex::new(TempState {
                closed: false,
                live: Vec::new(),
                sets_open: 0,
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, TempState> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Create (truncate) the temporary file `tmp` and record it; [`Error::Interrupted`]
    /// once the registry is closed.
    pub fn create(&self, tmp: &Path) -> Result<File> {
        let mut st = self.lock();
        if st.closed {
            return Err(Error::Interrupted);
        }
        let f = File::create(tmp)?;
        st.live.push(tmp.to_path_buf());
        Ok(f)
    }

    /// Remove `tmp` (if it still exists) and forget it.
    pub fn discard(&self, tmp: &Path) {
        let mut st = self.lock();
        let _ = fs::remove_file(tmp);
        st.live.retain(|p| p != tmp);
    }

    /// Rename each `(tmp, path)` into place in order, under one hold of the lock (an
    /// interrupt waits for the whole group), after `check(path)` passes. On the first
    /// failure (or if the registry is closed) that file and the rest are removed and the
    /// error is returned, naming its file; the files renamed before stay.
    pub fn commit_all(
        &self,
        files: Vec<(PathBuf, PathBuf)>,
        check: impl Fn(&Path) -> Result<()>,
    ) -> Result<()> {
        let mut st = self.lock();
        let mut err = None;
        for (tmp, path) in files {
            if err.is_none() {
                let r = if st.closed {
                    Err(Error::Interrupted)
                } else {
                    check(&path).and_then(|_| fs::rename(&tmp, &path).map_err(Error::from))
                };
                if let Err(e) = r {
                    err = Some(e.in_file(&path));
                }
            }
            if err.is_some() {
                let _ = fs::remove_file(&tmp);
            }
            st.live.retain(|p| *p != tmp);
        }
        match err {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The temporary files recorded now.
    pub fn live(&self) -> Vec<PathBuf> {
        self.lock().live.clone()
    }

    /// Record an output set whose renames begin; [`Error::Interrupted`] once closed.
    fn open_set(&self) -> Result<()> {
        let mut st = self.lock();
        if st.closed {
            return Err(Error::Interrupted);
        }
        st.sets_open += 1;
        Ok(())
    }

    /// The set recorded by [`open_set`](Self::open_set) is done (whole or failed).
    fn close_set(&self) {
        let mut st = self.lock();
        st.sets_open = st.sets_open.saturating_sub(1);
    }

    /// [`close_and_remove_within`](Self::close_and_remove_within) without waiting.
    pub fn close_and_remove(&self) -> usize {
        self.close_and_remove_within(Duration::ZERO)
    }

    /// Remove every recorded temporary file and close the registry (see
    /// [`remove_temp_files_and_close`]), once no output set is being renamed into place or
    /// after `grace`; returns how many were removed.
    pub fn close_and_remove_within(&self, grace: Duration) -> usize {
        let t0 = Instant::now();
        self.close_and_remove_after(|| {
            if t0.elapsed() >= grace {
                return false;
            }
            std::thread::sleep(Duration::from_millis(2));
            true
        })
    }

    /// [`close_and_remove_within`](Self::close_and_remove_within) with its wait for the open
    /// sets as `wait`: called without the registry's lock while a set is open, it returns
    /// false to stop waiting (the tests' seam: they wait on an event, not on a clock).
    fn close_and_remove_after(&self, mut wait: impl FnMut() -> bool) -> usize {
        let mut st = self.lock();
        while st.sets_open > 0 {
            drop(st);
            let again = wait();
            st = self.lock();
            if !again {
                break;
            }
        }
        st.closed = true;
        let mut n = 0;
        for p in std::mem::take(&mut st.live) {
            if fs::remove_file(&p).is_ok() {
                n += 1;
            }
        }
        n
    }
}

#[cfg(test)]
mod tests;
