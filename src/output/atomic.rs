//! One output file written atomically: [`write_atomic`], [`write_bytes_atomic`] and
//! [`AtomicFile`] (a temporary file beside the output, synced and renamed into place).

use super::policy::{OutputPolicy, PendingSync};
use super::registry::{stop_requested, TEMPS};
use crate::error::{Error, Result, ResultExt};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Write `path` atomically: `fill` writes into a buffered temporary file beside `path`,
/// which is synced and renamed over `path` only if `fill` succeeds. On any error the
/// temporary file is removed and `path` is untouched. (The same as [`AtomicFile::create`],
/// `fill` on [`AtomicFile::writer`], [`AtomicFile::finish`].)
pub fn write_atomic<F>(path: &Path, policy: &OutputPolicy, fill: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<()>,
{
    let mut file = AtomicFile::create(path, policy)?;
    fill(file.writer()?).in_file(path)?;
    file.finish()
}

/// An output being written across several calls (e.g. band by band while an image is
/// rendered): the temporary file of [`write_atomic`], opened by [`AtomicFile::create`],
/// written through [`AtomicFile::writer`] (buffered, seekable) and synced and renamed into
/// place (or handed to the policy's deferred queue) by [`AtomicFile::finish`], under the
/// same policy checks and interrupt rules. Dropped without `finish` (an error, a panic, an
/// abandoned render), it removes its temporary file: `path` is never touched.
#[derive(Debug)]
pub struct AtomicFile<'p> {
    path: PathBuf,
    tmp: PathBuf,
    policy: &'p OutputPolicy,
    /// None once finished (or when the buffer could not be flushed into the file).
    w: Option<BufWriter<File>>,
}

impl<'p> AtomicFile<'p> {
    /// Check `policy` for `path` and create the temporary file beside it (registered for
    /// interrupts). Refused once a stop was requested under a deferring policy.
    pub fn create(path: &Path, policy: &'p OutputPolicy) -> Result<AtomicFile<'p>> {
        policy.check(path)?;
        if policy.defer.is_some() && stop_requested().is_some() {
            // Interrupted: start no new output (the deferred set will not be committed).
            return Err(Error::Interrupted.in_file(path));
        }
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
        let file = TEMPS.create(&tmp).in_file(path)?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            policy,
            w: Some(BufWriter::with_capacity(1 << 20, file)),
        })
    }

    /// The output's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The buffered temporary file (seekable: `BufWriter` flushes before a seek). It is
    /// there until `finish` or drop, which both consume the `AtomicFile`.
    pub fn writer(&mut self) -> Result<&mut BufWriter<File>> {
        self.w
            .as_mut()
            .ok_or_else(|| Error::invalid("output already finished"))
    }

    /// Flush, then sync and rename into place (re-checking the policy just before the
    /// rename), or hand the sync and rename to the policy's deferred queue. On an error the
    /// temporary file is removed; errors name `path`.
    pub fn finish(mut self) -> Result<()> {
        let r = self.commit();
        if r.is_err() {
            TEMPS.discard(&self.tmp);
        }
        r.in_file(&self.path)
    }

    fn commit(&mut self) -> Result<()> {
        let Some(mut w) = self.w.take() else {
            return Err(Error::invalid("output already finished"));
        };
        w.flush()?;
        let file = w.into_inner().map_err(|e| Error::Io(e.into_error()))?;
        if let Some(queue) = &self.policy.defer {
            let sync = std::thread::Builder::new()
                .name("day2night-sync".into())
                .spawn(move || file.sync_all())?;
            queue.push(PendingSync {
                tmp: self.tmp.clone(),
                path: self.path.clone(),
                sync,
            });
            return Ok(());
        }
        file.sync_all()?;
        drop(file);
        // Re-check just before the rename: a racing writer may have created the output.
        TEMPS.commit_all(vec![(self.tmp.clone(), self.path.clone())], |p| {
            self.policy.check(p)
        })
    }
}

impl Drop for AtomicFile<'_> {
    fn drop(&mut self) {
        // Not finished: close the file, then remove it.
        if let Some(w) = self.w.take() {
            // Dropping a BufWriter flushes its buffer first: skip that, the file goes.
            let (file, _) = w.into_parts();
            drop(file);
            TEMPS.discard(&self.tmp);
        }
    }
}

/// Write a byte buffer atomically (see [`write_atomic`]).
pub fn write_bytes_atomic(path: &Path, policy: &OutputPolicy, bytes: &[u8]) -> Result<()> {
    write_atomic(path, policy, |w| Ok(w.write_all(bytes)?))
}
