//! Finding the inputs: every `.dng` (any case) under DAY_DIR, recursively, sorted by the
//! path relative to DAY_DIR (with `/` separators, compared byte-wise), so the order and the
//! names never depend on the file system's listing order or on where DAY_DIR is mounted.

use crate::error::{Error, Result, ResultExt};
use std::fs;
use std::path::{Path, PathBuf};

/// One day input found under DAY_DIR.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Input {
    /// Path relative to DAY_DIR, `/`-separated (the input's identity: seeds, split, shard).
    pub rel: String,
    /// Path to open.
    pub path: PathBuf,
}

/// True when `name` ends in `.dng`, in any letter case.
pub fn is_dng_name(name: &str) -> bool {
    name.len() > 4
        && name
            .get(name.len() - 4..)
            .is_some_and(|ext| ext.eq_ignore_ascii_case(".dng"))
}

/// Every DNG under `root`, sorted by relative path. Directories in `exclude` (e.g. an output
/// directory placed inside DAY_DIR) and hidden entries (name starting with `.`) are skipped;
/// symbolic links to directories are not followed (no loops), links to files are.
pub fn discover(root: &Path, exclude: &[PathBuf]) -> Result<Vec<Input>> {
    if !root.is_dir() {
        return Err(Error::invalid("not a directory").in_file(root));
    }
    let exclude: Vec<PathBuf> = exclude
        .iter()
        .filter_map(|p| fs::canonicalize(p).ok())
        .collect();
    let mut out = Vec::new();
    let mut stack: Vec<(PathBuf, String)> = vec![(root.to_path_buf(), String::new())];
    while let Some((dir, prefix)) = stack.pop() {
        if let Ok(c) = fs::canonicalize(&dir) {
            if exclude.contains(&c) {
                continue;
            }
        }
        let entries = fs::read_dir(&dir).map_err(Error::Io).in_file(&dir)?;
        for entry in entries {
            let entry = entry.map_err(Error::Io).in_file(&dir)?;
            let path = entry.path();
            let name = entry.file_name();
            let name = name
                .to_str()
                .ok_or_else(|| Error::unsupported("file name is not valid UTF-8").in_file(&path))?;
            if name.starts_with('.') {
                continue;
            }
            let rel = if prefix.is_empty() {
                name.to_string()
            } else {
                format!("{prefix}/{name}")
            };
            let ft = entry.file_type().map_err(Error::Io).in_file(&path)?;
            if ft.is_dir() {
                stack.push((path, rel));
            } else if is_dng_name(name) && (ft.is_file() || path.is_file()) {
                out.push(Input { rel, path });
            }
        }
    }
    out.sort_by(|a, b| a.rel.as_bytes().cmp(b.rel.as_bytes()));
    Ok(out)
}

/// The sample name of an input: its relative path without the extension, with `/` replaced
/// by `__` (outputs of one split live in flat folders).
pub fn sample_stem(rel: &str) -> String {
    let no_ext = rel.get(..rel.len().saturating_sub(4)).unwrap_or(rel);
    no_ext.replace('/', "__")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_recursively_sorted_any_case() {
        let d = tempfile::tempdir().unwrap();
        let r = d.path();
        fs::create_dir_all(r.join("b/c")).unwrap();
        fs::create_dir_all(r.join("out")).unwrap();
        fs::create_dir_all(r.join(".hidden")).unwrap();
        for p in [
            "z.dng",
            "a.DNG",
            "b/c/x.Dng",
            "b/y.dng",
            "b/notes.txt",
            "out/o.dng",
            ".hidden/h.dng",
            "dng",
        ] {
            fs::write(r.join(p), b"x").unwrap();
        }
        let found = discover(r, &[r.join("out")]).unwrap();
        let rels: Vec<&str> = found.iter().map(|i| i.rel.as_str()).collect();
        assert_eq!(rels, ["a.DNG", "b/c/x.Dng", "b/y.dng", "z.dng"]);
        assert_eq!(sample_stem("b/c/x.Dng"), "b__c__x");
        assert!(discover(&r.join("nope"), &[]).is_err());
    }
}
