//! A decoded day DNG ([`DayInput`]) with what the outputs record about it: the SHA-256 of
//! its bytes (the sidecar's `input.sha256`) and its file (named in the EXR attributes).

use super::sidecar::sha256_hex;
use crate::error::{Error, Result, ResultExt};
use crate::noise::NoiseEstimate;
use crate::raw::RawImage;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The file size from which [`DayInput::read`] drops a file's bytes before it decodes the
/// samples (64 MiB: a 12 MP file is read once, a 109 MP one twice, its blocks from the
/// page cache).
pub const STREAM_FROM: u64 = 64 << 20;

/// A decoded day DNG with what the outputs record about it.
#[derive(Debug, Clone)]
pub struct DayInput {
    /// The decoded raw.
    pub raw: RawImage,
    /// SHA-256 (lower-case hex) of the file's bytes (sidecar `input.sha256`).
    pub sha256: String,
    /// The file; its name goes into the EXR renders' attributes.
    pub source: PathBuf,
    /// The image's noise estimate, made on first use ([`DayInput::noise_estimate`]).
    estimate: OnceLock<std::result::Result<NoiseEstimate, String>>,
}

impl DayInput {
    /// Decode the bytes of `source` (hashing and decoding run in parallel).
    pub fn from_bytes(source: &Path, bytes: &[u8]) -> Result<DayInput> {
        let (sha256, raw) = rayon::join(
            || sha256_hex(bytes),
            || crate::dng::read::read_dng_bytes(bytes),
        );
        let raw = raw.in_file(source)?;
        if raw.meta.linear_raw.is_some() {
            // A day input is a CFA mosaic: refused here, before anything is planned.
            return Err(Error::unsupported(crate::raw::meta::LINEAR_RAW_NOT_CFA).in_file(source));
        }
        Ok(DayInput::new(raw, sha256, source.to_path_buf()))
    }

    /// A decoded raw with the SHA-256 of its file and the file's path.
    pub fn new(raw: RawImage, sha256: String, source: PathBuf) -> DayInput {
        DayInput {
            raw,
            sha256,
            source,
            estimate: OnceLock::new(),
        }
    }

    /// The single-image noise estimate of the raw (default options), computed once: every
    /// variant planned from this input reuses it.
    pub fn noise_estimate(&self) -> Result<NoiseEstimate> {
        self.estimate
            .get_or_init(|| {
                crate::noise::estimate(&self.raw, &Default::default()).map_err(|e| e.to_string())
            })
            .clone()
            .map_err(Error::invalid)
    }

    /// Read and decode the DNG at `path`. A file of [`STREAM_FROM`] bytes or more is
    /// decoded block by block after its bytes are hashed and dropped
    /// ([`crate::dng::read::read_dng_with`]): the same raw, a lower peak of memory.
    pub fn read(path: &Path) -> Result<DayInput> {
        DayInput::read_streaming_from(path, STREAM_FROM)
    }

    /// [`DayInput::read`] with the size from which the file's blocks are read one at a
    /// time (tests use 0 to take that path on small files).
    pub fn read_streaming_from(path: &Path, stream_from: u64) -> Result<DayInput> {
        let (raw, sha256) = crate::dng::read::read_dng_with(path, stream_from, sha256_hex)?;
        if raw.meta.linear_raw.is_some() {
            return Err(Error::unsupported(crate::raw::meta::LINEAR_RAW_NOT_CFA).in_file(path));
        }
        Ok(DayInput::new(raw, sha256, path.to_path_buf()))
    }

    /// A raw that is in memory only (e.g. [`RawImage::from_parts`]), named `file_name` (the
    /// name the EXR targets record). Its `sha256` (the sidecar's `input.sha256`) is the
    /// SHA-256 of its contents: "day2night in-memory raw v1", width and height (u64 LE),
    /// the samples (u16 LE) and the metadata as JSON.
    pub fn in_memory(raw: RawImage, file_name: &str) -> DayInput {
        use sha2::{Digest, Sha256};
        let mut h = Sha256::new();
        h.update(b"day2night in-memory raw v1\0");
        h.update((raw.width as u64).to_le_bytes());
        h.update((raw.height as u64).to_le_bytes());
        for chunk in raw.data.chunks(1 << 16) {
            let bytes: Vec<u8> = chunk.iter().flat_map(|v| v.to_le_bytes()).collect();
            h.update(&bytes);
        }
        if let Ok(json) = serde_json::to_vec(&raw.meta) {
            h.update(&json);
        }
        DayInput::new(
            raw,
            h.finalize().iter().map(|b| format!("{b:02x}")).collect(),
            PathBuf::from(file_name),
        )
    }
}
