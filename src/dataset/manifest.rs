//! `manifest.jsonl`: one JSON record per (input, variant), appended as each unit completes
//! (each line written in one piece and flushed), then rewritten at the end of the run sorted
//! byte-wise and with one record per unit, so a finished manifest is deterministic and the
//! `LC_ALL=C sort -m` of all shard manifests equals the unsharded one. Reading tolerates a
//! torn last line left by a killed run.

use super::{split::Split, Kind};
use crate::error::{Error, Result, ResultExt};
use crate::output::{write_bytes_atomic, OutputPolicy};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Outcome of a unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Every output written.
    Ok,
    /// The unit failed (see `error`); retried by the next run.
    Failed,
}

/// One output file of a unit.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutputFile {
    /// What it is (folder).
    pub kind: Kind,
    /// Path relative to OUT_DIR, `/`-separated.
    pub path: String,
    /// Size in bytes.
    pub bytes: u64,
    /// SHA-256 of the content, hex.
    pub sha256: String,
}

/// One manifest line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Input path relative to DAY_DIR.
    pub input: String,
    /// Variant, 1-based.
    pub variant: u32,
    /// Split of the input.
    pub split: Split,
    /// `ok` or `failed`.
    pub status: Status,
    /// SHA-256 of the input file, hex.
    pub input_sha256: String,
    /// Run seed; the unit's random stream is keyed by (seed, input, variant).
    pub seed: u64,
    /// SHA-256 of the processing options' fingerprint, hex.
    pub options_sha256: String,
    /// Output files (empty when failed).
    pub outputs: Vec<OutputFile>,
    /// ISO of each noisy output.
    pub iso: Vec<u32>,
    /// Night white-balance neutral (camera RGB), if sampled.
    pub night_neutral: Option<[f64; 3]>,
    /// Stages that ran.
    pub stages: Vec<String>,
    /// Why the unit failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// `"real"` for a record of `real-pairs` (absent in synthetic datasets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// Real pairs: the scene id (the output file stem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// Real pairs: frames read per ISO (`{"50": 30, "1600": 1, ...}`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<std::collections::BTreeMap<String, u32>>,
}

impl Record {
    /// The unit key: (input, variant).
    pub fn key(&self) -> (String, u32) {
        (self.input.clone(), self.variant)
    }
    /// One JSON line with its newline.
    pub fn to_line(&self) -> Result<String> {
        let mut s = serde_json::to_string(self)
            .map_err(|e| Error::invalid(format!("manifest record: {e}")))?;
        s.push('\n');
        Ok(s)
    }
}

/// Manifest file name for a shard (`manifest.jsonl` when unsharded).
pub fn file_name(shard: super::Shard) -> String {
    if shard.is_all() {
        "manifest.jsonl".to_string()
    } else {
        format!("manifest.shard-{}-of-{}.jsonl", shard.index, shard.count)
    }
}

/// What reading a manifest found.
#[derive(Debug, Default)]
pub struct Loaded {
    /// Records, in file order.
    pub records: Vec<Record>,
    /// Lines that did not parse (a torn last line after a kill, normally).
    pub bad_lines: usize,
    /// True when the file does not end with a newline (torn tail).
    pub torn_tail: bool,
}

/// Read one manifest; a missing file is an empty manifest. Unparseable lines are counted,
/// not fatal.
pub fn read(path: &Path) -> Result<Loaded> {
    let text = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Loaded::default()),
        Err(e) => return Err(Error::Io(e).in_file(path)),
    };
    let mut out = Loaded {
        torn_tail: !text.is_empty() && text.last() != Some(&b'\n'),
        ..Loaded::default()
    };
    for line in text.split(|&b| b == b'\n') {
        if line.iter().all(|b| b.is_ascii_whitespace()) {
            continue;
        }
        match serde_json::from_slice::<Record>(line) {
            Ok(r) => out.records.push(r),
            Err(_) => out.bad_lines += 1,
        }
    }
    Ok(out)
}

/// Every `manifest*.jsonl` in `out_dir` (this run's and other shards'), sorted by name.
pub fn all_manifests(out_dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v = Vec::new();
    let rd = match std::fs::read_dir(out_dir) {
        Ok(rd) => rd,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(v),
        Err(e) => return Err(Error::Io(e).in_file(out_dir)),
    };
    for e in rd {
        let e = e.map_err(Error::Io).in_file(out_dir)?;
        let name = e.file_name();
        let name = name.to_string_lossy();
        if name.starts_with("manifest") && name.ends_with(".jsonl") {
            v.push(e.path());
        }
    }
    v.sort();
    Ok(v)
}

/// The latest record per unit over several manifests (later files and later lines win).
pub fn latest(records: impl IntoIterator<Item = Record>) -> BTreeMap<(String, u32), Record> {
    let mut m = BTreeMap::new();
    for r in records {
        m.insert(r.key(), r);
    }
    m
}

/// Rewrite `path` atomically with these records, one per line, lines sorted byte-wise.
pub fn write_compacted(path: &Path, records: impl IntoIterator<Item = Record>) -> Result<()> {
    let mut lines = records
        .into_iter()
        .map(|r| r.to_line())
        .collect::<Result<Vec<_>>>()?;
    lines.sort();
    let policy = OutputPolicy {
        overwrite: true,
        inputs: vec![],
        ..OutputPolicy::default()
    };
    write_bytes_atomic(path, &policy, lines.concat().as_bytes())
}

/// Appends records as units complete: each record is one `write` of a whole line on a file
/// opened in append mode, flushed and synced, under a lock.
pub struct Appender {
    file: Mutex<File>,
    path: PathBuf,
}

impl Appender {
    /// Open (create) `path` for appending. If its last line is torn (killed run), the file
    /// is first rewritten without it so new lines never glue onto a fragment.
    pub fn open(path: &Path) -> Result<Appender> {
        let loaded = read(path)?;
        if loaded.torn_tail || loaded.bad_lines > 0 {
            write_compacted(path, loaded.records)?;
        }
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(Error::Io)
            .in_file(path)?;
        Ok(Appender {
            file: Mutex::new(file),
            path: path.to_path_buf(),
        })
    }

    /// Append one record.
    pub fn append(&self, r: &Record) -> Result<()> {
        let line = r.to_line()?;
        let mut f = self.file.lock().unwrap_or_else(|e| e.into_inner());
        f.write_all(line.as_bytes())
            .and_then(|_| f.flush())
            .and_then(|_| f.sync_data())
            .map_err(Error::Io)
            .in_file(&self.path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(input: &str, v: u32) -> Record {
        Record {
            input: input.into(),
            variant: v,
            split: Split::Train,
            status: Status::Ok,
            input_sha256: "ab".into(),
            seed: u64::MAX,
            options_sha256: "cd".into(),
            outputs: vec![OutputFile {
                kind: Kind::CleanRaw,
                path: format!("train/clean_raw/{input}.dng"),
                bytes: 3,
                sha256: "ef".into(),
            }],
            iso: vec![1600, 3200],
            night_neutral: Some([0.5, 1.0, 0.7]),
            stages: vec!["relight".into()],
            error: None,
            kind: None,
            scene: None,
            frames: None,
        }
    }

    #[test]
    fn append_read_torn_and_compact() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("manifest.jsonl");
        assert!(read(&p).unwrap().records.is_empty());
        let a = Appender::open(&p).unwrap();
        a.append(&rec("b", 1)).unwrap();
        a.append(&rec("a", 1)).unwrap();
        drop(a);
        // Simulate a kill in the middle of a line.
        let mut f = OpenOptions::new().append(true).open(&p).unwrap();
        f.write_all(b"{\"input\":\"c\",\"vari").unwrap();
        drop(f);
        let l = read(&p).unwrap();
        assert_eq!(l.records.len(), 2);
        assert_eq!(l.bad_lines, 1);
        assert!(l.torn_tail);
        assert_eq!(l.records[0], rec("b", 1));
        // Reopening repairs the tail; new lines are whole.
        let a = Appender::open(&p).unwrap();
        a.append(&rec("c", 2)).unwrap();
        drop(a);
        let l = read(&p).unwrap();
        assert_eq!((l.records.len(), l.bad_lines, l.torn_tail), (3, 0, false));
        write_compacted(&p, latest(l.records).into_values()).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let mut sorted = lines.clone();
        sorted.sort();
        assert_eq!(lines, sorted);
        assert!(lines[0].starts_with("{\"input\":\"a\""));
        assert_eq!(
            file_name(super::super::Shard { index: 2, count: 4 }),
            "manifest.shard-2-of-4.jsonl"
        );
    }
}
