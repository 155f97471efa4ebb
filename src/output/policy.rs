//! [`OutputPolicy`]: whether an output may replace an existing file (never an input), and
//! whether its sync and rename are deferred.

use super::DeferredSyncs;
use crate::error::{Error, Result};
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
