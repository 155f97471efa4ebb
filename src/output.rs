//! Safe output files: written to a temporary file in the destination directory, flushed,
//! synced, then renamed into place, so a crash or error never leaves a half-written output;
//! an existing file is refused unless overwriting was asked for; an input is never replaced.
//!
//! A policy may defer the sync and the rename ([`OutputPolicy::deferring`]): the writer's
//! thread then returns as soon as the data are handed to the kernel, a background thread
//! waits for the disk (`fsync`), and [`DeferredSyncs::finish`] renames the files into place
//! once every sync succeeded. `synth` uses this so that its compute threads do not sit in
//! `fsync` and so that a variant's outputs appear together, or not at all on an error.

use crate::error::{Error, Result, ResultExt};
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

/// How an output may treat an existing file at its path.
#[derive(Debug, Clone, Default)]
pub struct OutputPolicy {
    /// Replace an existing output (never an input).
    pub overwrite: bool,
    /// Inputs of this run: an output resolving to one of them is always refused.
    pub inputs: Vec<PathBuf>,
    /// When set, [`write_atomic`] leaves the sync and the rename to this queue (see the
    /// module documentation); `None` (the default) syncs and renames at once.
    pub defer: Option<Arc<DeferredSyncs>>,
}

/// A file written and flushed whose sync runs on a background thread; renamed into place by
/// [`DeferredSyncs::finish`].
#[derive(Debug)]
struct PendingSync {
    tmp: PathBuf,
    path: PathBuf,
    sync: JoinHandle<std::io::Result<()>>,
}

/// The outputs of a deferring policy waiting for their sync and rename. Dropping it with
/// files still pending (e.g. after an error elsewhere) waits for their syncs and removes
/// the temporary files: nothing is renamed into place.
#[derive(Debug, Default)]
pub struct DeferredSyncs {
    pending: Mutex<Vec<PendingSync>>,
}

impl DeferredSyncs {
    fn push(&self, p: PendingSync) {
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
        let mut synced = synced.into_iter();
        if first_err.is_none() {
            for (tmp, path) in synced.by_ref() {
                let r = policy
                    .check(&path)
                    .and_then(|_| fs::rename(&tmp, &path).map_err(Error::from));
                if let Err(e) = r {
                    let _ = fs::remove_file(&tmp);
                    first_err = Some(e.in_file(&path));
                    break;
                }
            }
        }
        for (tmp, _) in synced {
            let _ = fs::remove_file(&tmp);
        }
        match first_err {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

impl Drop for DeferredSyncs {
    fn drop(&mut self) {
        for p in self.take() {
            let _ = p.sync.join();
            let _ = fs::remove_file(&p.tmp);
        }
    }
}

impl OutputPolicy {
    /// This policy with its syncs and renames deferred to `queue` (see the module
    /// documentation).
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

/// Write `path` atomically: `fill` writes into a buffered temporary file beside `path`,
/// which is synced and renamed over `path` only if `fill` succeeds. On any error the
/// temporary file is removed and `path` is untouched.
pub fn write_atomic<F>(path: &Path, policy: &OutputPolicy, fill: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<()>,
{
    policy.check(path)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| Error::invalid(format!("{}: not a file path", path.display())))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| -> Result<()> {
        let file = File::create(&tmp)?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        w.flush()?;
        let file = w.into_inner().map_err(|e| Error::Io(e.into_error()))?;
        if let Some(queue) = &policy.defer {
            let sync = std::thread::Builder::new()
                .name("day2night-sync".into())
                .spawn(move || file.sync_all())?;
            queue.push(PendingSync {
                tmp: tmp.clone(),
                path: path.to_path_buf(),
                sync,
            });
            return Ok(());
        }
        file.sync_all()?;
        drop(file);
        // Re-check just before the rename: a racing writer may have created the output.
        policy.check(path)?;
        fs::rename(&tmp, path)?;
        Ok(())
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.in_file(path)
}

/// Write a byte buffer atomically (see [`write_atomic`]).
pub fn write_bytes_atomic(path: &Path, policy: &OutputPolicy, bytes: &[u8]) -> Result<()> {
    write_atomic(path, policy, |w| Ok(w.write_all(bytes)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_existing_and_inputs_and_cleans_up() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.bin");
        let pol = OutputPolicy::default();
        write_bytes_atomic(&p, &pol, b"one").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"one");
        let err = write_bytes_atomic(&p, &pol, b"two").unwrap_err();
        assert!(err.to_string().contains("--overwrite"), "{err}");
        let pol2 = OutputPolicy {
            overwrite: true,
            inputs: vec![p.clone()],
            ..OutputPolicy::default()
        };
        assert!(write_bytes_atomic(&p, &pol2, b"two").is_err());
        let pol3 = OutputPolicy {
            overwrite: true,
            inputs: vec![],
            ..OutputPolicy::default()
        };
        write_bytes_atomic(&p, &pol3, b"two").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"two");
        // A failing fill leaves nothing behind.
        let q = dir.path().join("b.bin");
        let r = write_atomic(&q, &pol, |w| {
            w.write_all(b"partial")?;
            Err(Error::invalid("boom"))
        });
        assert!(r.is_err());
        assert!(!q.exists());
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    fn tmp_files(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect();
        v.sort();
        v
    }

    #[test]
    fn deferred_outputs_appear_on_finish_only() {
        let dir = tempfile::tempdir().unwrap();
        let queue = Arc::new(DeferredSyncs::default());
        let base = OutputPolicy::default();
        let pol = base.deferring(&queue);
        let (a, b) = (dir.path().join("a.bin"), dir.path().join("b.bin"));
        write_bytes_atomic(&a, &pol, b"one").unwrap();
        write_bytes_atomic(&b, &pol, b"two").unwrap();
        assert!(!a.exists() && !b.exists());
        assert_eq!(tmp_files(dir.path()).len(), 2);
        queue.finish(&base).unwrap();
        assert_eq!(fs::read(&a).unwrap(), b"one");
        assert_eq!(fs::read(&b).unwrap(), b"two");
        assert!(tmp_files(dir.path()).is_empty());
        // the queue is empty again: finishing twice is harmless
        queue.finish(&base).unwrap();
        // a failing fill under deferral leaves nothing and queues nothing
        let c = dir.path().join("c.bin");
        let r = write_atomic(&c, &pol, |w| {
            w.write_all(b"partial")?;
            Err(Error::invalid("boom"))
        });
        assert!(r.is_err() && !c.exists());
        assert!(tmp_files(dir.path()).is_empty());
        queue.finish(&base).unwrap();
    }

    #[test]
    fn dropped_queue_removes_its_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.bin");
        {
            let queue = Arc::new(DeferredSyncs::default());
            let pol = OutputPolicy::default().deferring(&queue);
            write_bytes_atomic(&p, &pol, b"one").unwrap();
            assert_eq!(tmp_files(dir.path()).len(), 1);
        }
        assert!(!p.exists());
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn finish_rechecks_the_policy_and_cleans_up() {
        let dir = tempfile::tempdir().unwrap();
        let queue = Arc::new(DeferredSyncs::default());
        let base = OutputPolicy::default();
        let pol = base.deferring(&queue);
        let (a, b, c) = (
            dir.path().join("a.bin"),
            dir.path().join("b.bin"),
            dir.path().join("c.bin"),
        );
        for p in [&a, &b, &c] {
            write_bytes_atomic(p, &pol, b"new").unwrap();
        }
        // another writer creates b meanwhile: a is renamed, b refused, c removed
        fs::write(&b, b"theirs").unwrap();
        let err = queue.finish(&base).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("b.bin") && msg.contains("--overwrite"),
            "{msg}"
        );
        assert_eq!(fs::read(&a).unwrap(), b"new");
        assert_eq!(fs::read(&b).unwrap(), b"theirs");
        assert!(!c.exists());
        assert!(tmp_files(dir.path()).is_empty());
    }
}
