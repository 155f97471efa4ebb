//! Whole-dataset generation: find every day DNG under a folder, split it into train/val,
//! keep one shard, and run a per-(input, variant) processing callback in parallel with
//! bounded memory, writing every output atomically into a PyTorch-friendly layout and one
//! `manifest.jsonl` record per (input, variant). Reruns resume: work whose outputs exist and
//! match the manifest is skipped.
//!
//! The core is independent of the synthesis: it drives any [`Processor`]. The CLI binds it
//! to the real synthesis (`crate::cli::dataset`); tests bind it to fast fakes.
//!
//! Layout of OUT_DIR (per split `train/` and `val/`):
//! ```text
//! manifest.jsonl                 (manifest.shard-I-of-N.jsonl for --shard I/N)
//! train/clean_raw/<id>.dng       clean night raw
//! train/noisy_raw/<id>_iso<ISO>.dng
//! train/target/<id>.exr|.png     rendered target(s)
//! train/input/<id>.exr           network input (when asked)
//! train/meta/<id>.json           sidecar: every sampled value
//! ```
//! `<id>` is the input's relative path without extension, `/` replaced by `__`, plus `_vK`
//! when more than one variant is made.

pub mod discover;
pub mod journal;
pub mod manifest;
pub mod pool;
pub mod progress;
pub mod resume;
pub mod run;
pub mod shard;
pub mod split;
pub mod synthesis;
pub mod units;

use crate::error::{Error, Result, ResultExt};
use crate::output::{write_atomic, OutputPolicy};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

pub use discover::{discover, Input};
pub use manifest::{OutputFile, Record, Status};
pub use progress::{InputDone, Progress, ProgressSink};
pub use run::{run, RunOptions, Summary};
pub use shard::Shard;
pub use split::{Split, SplitRule};

/// Lower-case hex of a byte slice.
pub fn hex(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        s.push_str(&format!("{b:02x}"));
    }
    s
}

/// SHA-256 of bytes, as hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// A stable 64-bit hash of a list of strings (SHA-256 of the NUL-joined parts, first 8
/// bytes little-endian): identical on every machine and Rust version.
pub fn stable_u64(parts: &[&str]) -> u64 {
    let mut h = Sha256::new();
    h.update(b"day2night-dataset");
    for p in parts {
        h.update([0u8]);
        h.update(p.as_bytes());
    }
    let d = h.finalize();
    let mut b = [0u8; 8];
    b.copy_from_slice(&d[..8]);
    u64::from_le_bytes(b)
}

/// Kind of output file, i.e. the folder it goes to inside a split.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Clean night raw DNG.
    CleanRaw,
    /// Noisy night raw DNG (one per ISO).
    NoisyRaw,
    /// Rendered target (EXR or PNG).
    Target,
    /// Network input render (EXR).
    Input,
    /// Sidecar JSON.
    Meta,
}

/// Every output kind.
pub const ALL_KINDS: [Kind; 5] = [
    Kind::CleanRaw,
    Kind::NoisyRaw,
    Kind::Target,
    Kind::Input,
    Kind::Meta,
];

impl Kind {
    /// Folder name inside a split.
    pub fn dir(self) -> &'static str {
        match self {
            Kind::CleanRaw => "clean_raw",
            Kind::NoisyRaw => "noisy_raw",
            Kind::Target => "target",
            Kind::Input => "input",
            Kind::Meta => "meta",
        }
    }
}

/// One unit of work: one variant of one input.
#[derive(Debug, Clone)]
pub struct Unit {
    /// The input's relative path (identity).
    pub rel: String,
    /// Path to the input file.
    pub path: PathBuf,
    /// Split the input belongs to.
    pub split: Split,
    /// Variant number, 1-based.
    pub variant: u32,
    /// Number of variants per input in this run.
    pub variants: u32,
    /// The run seed. A processor must key its random stream by (seed, `rel`, `variant`),
    /// never by position, so results do not depend on the shard or the thread count.
    pub seed: u64,
    /// Output id: `<stem>` or `<stem>_vK`.
    pub id: String,
}

/// What a processor reports about a finished unit (goes into the manifest).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct UnitInfo {
    /// ISO of each noisy output.
    pub iso: Vec<u32>,
    /// Night white-balance neutral (camera RGB, green = 1), if one was sampled.
    pub night_neutral: Option<[f64; 3]>,
    /// Stages that ran, in order.
    pub stages: Vec<String>,
}

/// Where a processor writes the outputs of one unit. Every file goes through
/// [`crate::output`] (temporary file + rename): a killed run never leaves a half-written
/// output. The sink records the files written, with size and SHA-256, for the manifest.
pub struct Sink {
    out_dir: PathBuf,
    split: Split,
    id: String,
    policy: OutputPolicy,
    written: Mutex<Vec<OutputFile>>,
}

impl Sink {
    /// A sink for the unit `id` of `split` in `out_dir`; `policy` guards the writes.
    pub fn new(out_dir: &Path, split: Split, id: &str, policy: OutputPolicy) -> Sink {
        Sink {
            out_dir: out_dir.to_path_buf(),
            split,
            id: id.to_string(),
            policy,
            written: Mutex::new(Vec::new()),
        }
    }

    /// The unit's sample id (file names are `<id><suffix>`).
    pub fn id(&self) -> &str {
        &self.id
    }

    /// Path relative to OUT_DIR of the output `<split>/<kind>/<id><suffix>` (suffix such
    /// as `.dng`, `_iso1600.dng`, `.exr`).
    pub fn rel_path(&self, kind: Kind, suffix: &str) -> String {
        format!("{}/{}/{}{}", self.split.name(), kind.dir(), self.id, suffix)
    }

    /// Absolute path of an output (see [`Sink::rel_path`]).
    pub fn path(&self, kind: Kind, suffix: &str) -> PathBuf {
        self.out_dir.join(self.rel_path(kind, suffix))
    }

    /// Write one output atomically through `fill`, hashing it on the way.
    pub fn write<F>(&self, kind: Kind, suffix: &str, fill: F) -> Result<()>
    where
        F: FnOnce(&mut dyn Write) -> Result<()>,
    {
        let rel = self.rel_path(kind, suffix);
        let path = self.out_dir.join(&rel);
        ensure_parent(&path)?;
        let mut hasher = Sha256::new();
        let mut bytes = 0u64;
        write_atomic(&path, &self.policy, |w| {
            let mut hw = HashingWriter {
                inner: w,
                hasher: &mut hasher,
                bytes: &mut bytes,
            };
            fill(&mut hw)
        })?;
        self.push(kind, rel, bytes, hex(&hasher.finalize()));
        Ok(())
    }

    /// Record an output that the processor wrote itself at [`Sink::path`] (it must have used
    /// [`crate::output`] with [`Sink::policy`]); it is read back (in 1 MiB pieces) to hash it.
    pub fn adopt(&self, kind: Kind, suffix: &str) -> Result<()> {
        let rel = self.rel_path(kind, suffix);
        let path = self.out_dir.join(&rel);
        let (bytes, sha256) = hash_file(&path).in_file(&path)?;
        self.push(kind, rel, bytes, sha256);
        Ok(())
    }

    /// The policy outputs must be written with.
    pub fn policy(&self) -> &OutputPolicy {
        &self.policy
    }

    fn push(&self, kind: Kind, path: String, bytes: u64, sha256: String) {
        let mut w = self.written.lock().unwrap_or_else(|e| e.into_inner());
        w.retain(|o| o.path != path);
        w.push(OutputFile {
            kind,
            path,
            bytes,
            sha256,
        });
    }

    /// The files written so far, sorted by path.
    pub fn into_outputs(self) -> Vec<OutputFile> {
        let mut v = self.written.into_inner().unwrap_or_else(|e| e.into_inner());
        v.sort_by(|a, b| a.path.cmp(&b.path));
        v
    }
}

/// Size and SHA-256 (hex) of a file, read in pieces.
pub fn hash_file(path: &Path) -> Result<(u64, String)> {
    use std::io::Read;
    let mut f = std::fs::File::open(path).map_err(Error::Io)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = match f.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(Error::Io(e)),
        };
        hasher.update(buf.get(..n).unwrap_or(&buf));
        bytes += n as u64;
    }
    Ok((bytes, hex(&hasher.finalize())))
}

/// Create the parent folder of `path`.
pub fn ensure_parent(path: &Path) -> Result<()> {
    if let Some(p) = path.parent() {
        std::fs::create_dir_all(p).map_err(Error::Io).in_file(p)?;
    }
    Ok(())
}

struct HashingWriter<'a, W: Write> {
    inner: &'a mut W,
    hasher: &'a mut Sha256,
    bytes: &'a mut u64,
}

impl<W: Write> Write for HashingWriter<'_, W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        let done = buf.get(..n).unwrap_or(buf);
        self.hasher.update(done);
        *self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The processing callback the dataset drives: the real synthesis in the CLI, fakes in
/// tests. It must be deterministic: same input bytes, unit seed and options = same bytes.
pub trait Processor: Sync {
    /// Decoded input, shared by the variants of one input.
    type Loaded: Send;
    /// Canonical text of every option that changes outputs (hashed into the manifest; a
    /// change recomputes everything). Thread counts and the like must not be in it.
    fn fingerprint(&self) -> String;
    /// Decode one input from its bytes (already read and hashed by the caller).
    fn load(&self, path: &Path, bytes: &[u8]) -> Result<Self::Loaded>;
    /// Make every output of one unit through `sink`.
    fn process(&self, input: &Self::Loaded, unit: &Unit, sink: &Sink) -> Result<UnitInfo>;
    /// [`process`](Self::process) for the last unit computed from an input, which may use
    /// up the decoded input (the synthesis relights the day plane in place instead of
    /// copying it). The same outputs; by default it is `process`.
    fn process_last(&self, input: Self::Loaded, unit: &Unit, sink: &Sink) -> Result<UnitInfo> {
        self.process(&input, unit, sink)
    }
    /// Warnings about a decoded input (metadata corrections), said once per input through
    /// the run's [`Progress`]. None by default.
    fn warnings(&self, input: &Self::Loaded) -> crate::diagnostics::Diagnostics {
        let _ = input;
        Default::default()
    }
}
