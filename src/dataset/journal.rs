//! The dataset journal: one record file per unit computed since the last manifest, in
//! `OUT_DIR/.day2night-units/`, written by [`super::units::write_unit`] (units run by an
//! external scheduler) and folded into a manifest by `dataset` ([`super::run()`]) or
//! [`super::units::write_manifest`], which then clear it.

use super::discover::sample_stem;
use super::manifest::Record;
use std::path::{Path, PathBuf};

/// Folder (inside OUT_DIR) of the records of units computed since the last manifest.
pub const JOURNAL_DIR: &str = ".day2night-units";

/// Path of a unit's record in the journal.
pub fn journal_path(out_dir: &Path, rel: &str, variant: u32) -> PathBuf {
    out_dir
        .join(JOURNAL_DIR)
        .join(format!("{}.v{variant}.json", sample_stem(rel)))
}

/// The record in a journal file, if it is readable.
pub(super) fn read_journal(path: &Path) -> Option<Record> {
    let text = std::fs::read(path).ok()?;
    serde_json::from_slice(&text).ok()
}

/// Every record in OUT_DIR's journal (units written since the last manifest), unordered;
/// unreadable files are ignored (the unit is then recomputed).
pub fn journal_records(out_dir: &Path) -> Vec<Record> {
    let Ok(rd) = std::fs::read_dir(out_dir.join(JOURNAL_DIR)) else {
        return Vec::new();
    };
    rd.flatten()
        .filter(|e| e.file_name().to_str().is_some_and(|n| !n.starts_with('.')))
        .filter_map(|e| read_journal(&e.path()))
        .collect()
}

/// Remove the journal files of these units (now in a manifest), and the journal folder
/// when that empties it.
pub fn clear_journal(out_dir: &Path, keys: &[(String, u32)]) {
    let dir = out_dir.join(JOURNAL_DIR);
    if !dir.is_dir() {
        return;
    }
    for (rel, variant) in keys {
        let _ = std::fs::remove_file(journal_path(out_dir, rel, *variant));
    }
    // Removed only when empty (units of another run may still be listed there).
    let _ = std::fs::remove_dir(dir);
}
