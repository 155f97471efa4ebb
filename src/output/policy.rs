//! [`OutputPolicy`]: whether an output may replace an existing file (never an input), and
//! whether its sync and rename are deferred to a [`DeferredSyncs`] queue: a deferring
//! policy's files are synced on background threads and renamed into place together by
//! [`DeferredSyncs::finish`], or removed when the queue is dropped first. (One file: the
//! policy names its queue, the queue re-checks the policy.)

use super::registry::{stop_requested, TEMPS};
use crate::error::{Error, Result};
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

/// How an output may treat an existing file at its path.
#[derive(Debug, Clone, Default)]
pub struct OutputPolicy {
    /// Replace an existing output (never an input).
    pub overwrite: bool,
    /// Inputs of this run: an output resolving to one of them is always refused.
    pub inputs: Vec<PathBuf>,
    /// When set, [`write_atomic`](super::write_atomic) leaves the sync and the rename to
    /// this queue (see the [module documentation](super)); `None` (the default) syncs and
    /// renames at once.
    pub defer: Option<Arc<DeferredSyncs>>,
}

impl OutputPolicy {
    /// This policy with its syncs and renames deferred to `queue` (see the
    /// [module documentation](super)).
    pub fn deferring(&self, queue: &Arc<DeferredSyncs>) -> OutputPolicy {
        OutputPolicy {
            defer: Some(Arc::clone(queue)),
            ..self.clone()
        }
    }

    /// Error if `path` may not be written under this policy.
    pub fn check(&self, path: &Path) -> Result<()> {
        let canon_out = canonical_or_self(path);
        for input in &self.inputs {
            if canonical_or_self(input) == canon_out {
                return Err(Error::WouldOverwrite {
                    path: path.to_path_buf(),
                    reason: "it is an input of this run".into(),
                });
            }
        }
        if !self.overwrite && path.exists() {
            return Err(Error::WouldOverwrite {
                path: path.to_path_buf(),
                reason: "it exists (pass --overwrite to replace it)".into(),
            });
        }
        Ok(())
    }
}

fn canonical_or_self(p: &Path) -> PathBuf {
    fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

/// A file written and flushed whose sync runs on a background thread; renamed into place by
/// [`DeferredSyncs::finish`].
#[derive(Debug)]
pub(super) struct PendingSync {
    pub(super) tmp: PathBuf,
    pub(super) path: PathBuf,
    pub(super) sync: JoinHandle<std::io::Result<()>>,
}

/// The outputs of a deferring policy waiting for their sync and rename. Dropping it with
/// files still pending (e.g. after an error elsewhere) waits for their syncs and removes
/// the temporary files: nothing is renamed into place.
#[derive(Debug, Default)]
pub struct DeferredSyncs {
    pending: Mutex<Vec<PendingSync>>,
    /// The renames of [`finish`](Self::finish) began: the set stays open in the registry
    /// until this queue is dropped.
    set_open: std::sync::atomic::AtomicBool,
}

impl DeferredSyncs {
    pub(super) fn push(&self, p: PendingSync) {
        self.pending
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(p);
    }
    fn take(&self) -> Vec<PendingSync> {
        std::mem::take(&mut *self.pending.lock().unwrap_or_else(PoisonError::into_inner))
    }
    /// Wait for every pending sync; if all succeeded, rename the files into place (in the
    /// order they were written, re-checking `policy` just before each rename). On an error
    /// the files not yet renamed are removed and the first error is returned, naming its
    /// file.
    pub fn finish(&self, policy: &OutputPolicy) -> Result<()> {
        let pending = self.take();
        let mut first_err: Option<Error> = None;
        let mut synced = Vec::with_capacity(pending.len());
        for p in pending {
            let r = match p.sync.join() {
                Ok(r) => r.map_err(Error::from),
                Err(_) => Err(Error::Io(std::io::Error::other("the sync thread panicked"))),
            };
            if let Err(e) = r {
                first_err.get_or_insert(e.in_file(&p.path));
            }
            synced.push((p.tmp, p.path));
        }
        if first_err.is_none() && stop_requested().is_some() {
            first_err = synced.first().map(|(_, p)| Error::Interrupted.in_file(p));
        }
        if first_err.is_none() && !self.set_open.load(Ordering::SeqCst) {
            match TEMPS.open_set() {
                Ok(()) => self.set_open.store(true, Ordering::SeqCst),
                Err(e) => first_err = synced.first().map(|(_, p)| e.in_file(p)),
            }
        }
        if let Some(e) = first_err {
            for (tmp, _) in &synced {
                TEMPS.discard(tmp);
            }
            return Err(e);
        }
        TEMPS.commit_all(synced, |path| policy.check(path))
    }
}

impl Drop for DeferredSyncs {
    fn drop(&mut self) {
        for p in self.take() {
            let _ = p.sync.join();
            TEMPS.discard(&p.tmp);
        }
        if self.set_open.load(Ordering::SeqCst) {
            TEMPS.close_set();
        }
    }
}
