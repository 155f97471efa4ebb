//! [`OutputSetLock`]: the advisory lock that makes two processes writing the same output
//! set take turns (docs/concurrency.md).

use crate::error::{Error, Result, ResultExt};
use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// The lock files of the [`OutputSetLock`]s this process holds (removed by an exit on an
/// interrupt, which does not run their destructors).
static HELD_LOCKS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

pub(super) fn held_locks() -> MutexGuard<'static, Vec<PathBuf>> {
    HELD_LOCKS.lock().unwrap_or_else(PoisonError::into_inner)
}

/// An advisory lock on one output set: the files a run writes under one base name (e.g.
/// `day_clean.dng`, `day_iso1600.dng`, `day_target.exr`, `day.json` for the base `day`).
/// Held from before the existing outputs are checked until the last one is renamed into
/// place, it makes concurrent day2night processes writing the same set take turns, so a set
/// never mixes the files of two runs. The lock is `flock`-style on a hidden file
/// `.<base>.lock` in the output folder, removed again on release (Unix); another process
/// ignoring the lock is not stopped by it.
#[derive(Debug)]
pub struct OutputSetLock {
    path: PathBuf,
    _file: File,
}

impl OutputSetLock {
    /// The lock file of the set `base` in `dir`.
    pub fn lock_path(dir: &Path, base: &str) -> PathBuf {
        dir.join(format!(".{base}.lock"))
    }

    /// Lock the output set `base` in `dir` (which must exist). When another process holds
    /// it: wait for it if `wait`, else fail at once with [`Error::Busy`].
    pub fn acquire(dir: &Path, base: &str, wait: bool) -> Result<OutputSetLock> {
        let path = Self::lock_path(dir, base);
        loop {
            let file = fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(Error::Io)
                .in_file(&path)?;
            // Called through the trait: std's File::lock (same names) needs Rust 1.89.
            let locked = if wait {
                fs4::FileExt::lock(&file)
            } else {
                match fs4::FileExt::try_lock(&file) {
                    Ok(()) => Ok(()),
                    Err(fs4::TryLockError::WouldBlock) => {
                        return Err(Error::Busy(format!(
                            "output set {base}_* is being written by another day2night process (pass --wait to wait for it)"
                        ))
                        .in_file(dir))
                    }
                    Err(fs4::TryLockError::Error(e)) => Err(e),
                }
            };
            match locked {
                Ok(()) => {}
                // A file system without locks: go on unlocked rather than refuse to work.
                Err(e) if e.kind() == std::io::ErrorKind::Unsupported => {}
                Err(e) => return Err(Error::Io(e).in_file(&path)),
            }
            // A releasing holder removes the file: if the path no longer names the file
            // locked, lock the new one instead.
            if same_file(&file, &path) {
                held_locks().push(path.clone());
                return Ok(OutputSetLock { path, _file: file });
            }
        }
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for OutputSetLock {
    fn drop(&mut self) {
        // Removed while still locked (a waiter then sees a stale file and retries), then
        // unlocked as the file closes.
        let mut held = held_locks();
        if let Some(i) = held.iter().position(|p| *p == self.path) {
            held.swap_remove(i);
        }
        #[cfg(unix)]
        let _ = fs::remove_file(&self.path);
    }
}

#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &File, _path: &Path) -> bool {
    true
}
