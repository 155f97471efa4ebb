//! Interrupts: the stop request ([`request_stop`]) and the registry of the temporary files
//! being written ([`TempRegistry`]), which [`remove_temp_files_and_close`] empties on an
//! exit (see the [module documentation](super)).

use crate::error::{Error, Result};
use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};
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

/// The registry of this process's temporary files (used by [`write_atomic`](super::write_atomic)).
pub(super) static TEMPS: TempRegistry = TempRegistry::new();

/// Remove every temporary file this process is writing and refuse new ones (and renames
/// into place) from now on; returns how many were removed. The lock files of the output
/// sets held are removed too (the locks themselves end with the process). For a process
/// about to exit on an interrupt.
pub fn remove_temp_files_and_close() -> usize {
    let n = TEMPS.close_and_remove_within(SET_GRACE);
    #[cfg(unix)]
    for p in super::lock::held_locks().iter() {
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
    pub(super) fn open_set(&self) -> Result<()> {
        let mut st = self.lock();
        if st.closed {
            return Err(Error::Interrupted);
        }
        st.sets_open += 1;
        Ok(())
    }

    /// The set recorded by [`open_set`](Self::open_set) is done (whole or failed).
    pub(super) fn close_set(&self) {
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
    pub(super) fn close_and_remove_after(&self, mut wait: impl FnMut() -> bool) -> usize {
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
