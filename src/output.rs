//! Safe output files: written to a temporary file in the destination directory, flushed,
//! then renamed into place, so a crash or error never leaves a half-written output; an
//! existing file is refused unless overwriting was asked for; an input is never replaced.

use crate::error::{Error, Result, ResultExt};
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// How an output may treat an existing file at its path.
#[derive(Debug, Clone, Default)]
pub struct OutputPolicy {
    /// Replace an existing output (never an input).
    pub overwrite: bool,
    /// Inputs of this run: an output resolving to one of them is always refused.
    pub inputs: Vec<PathBuf>,
}

impl OutputPolicy {
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
        };
        assert!(write_bytes_atomic(&p, &pol2, b"two").is_err());
        let pol3 = OutputPolicy {
            overwrite: true,
            inputs: vec![],
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
}
