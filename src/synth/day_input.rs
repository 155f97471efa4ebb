//! A decoded day DNG ([`DayInput`]) with what the outputs record about it: the SHA-256 of
//! its bytes (the sidecar's `input.sha256`) and its file (named in the EXR attributes).

use super::sidecar::sha256_hex;
use crate::error::{Error, Result, ResultExt};
use crate::noise::NoiseEstimate;
use crate::raw::RawImage;
use crate::synth::dim::{DimPlan, FrameMean, MeanKey};
use crate::synth::plan::Plan;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

/// A poisoned lock only means another thread panicked; the memo is still valid.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

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
    /// The whole-frame means `mean(y_w)` worked out so far, per clean-pass key
    /// ([`DayInput::frame_mean`]; shared by clones, which hold the same raw).
    frame_means: Arc<Mutex<Vec<(MeanKey, f64)>>>,
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
            frame_means: Arc::default(),
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

    /// The whole-frame mean white-balanced intensity of the raw under `plan`'s clean pass
    /// ([`crate::synth::relight::frame_mean_y_w`]), computed once per key: every variant
    /// and crop planned from this input reuses it (a fresh training crop would otherwise
    /// read the whole frame for it).
    pub fn frame_mean(&self, plan: &Plan) -> Result<f64> {
        let key = plan.mean_key();
        let known = |v: &Vec<(MeanKey, f64)>| v.iter().find(|(k, _)| *k == key).map(|e| e.1);
        if let Some(m) = known(&lock(&self.frame_means)) {
            return Ok(m);
        }
        // computed outside the lock: two threads may both compute it, with the same result
        let m = crate::synth::relight::frame_mean_y_w(&self.raw, plan)?;
        let mut v = lock(&self.frame_means);
        if known(&v).is_none() {
            v.push((key, m));
        }
        Ok(m)
    }

    /// `plan` with its [`Plan::frame_mean`] memo filled in when its dimming needs the
    /// whole-frame mean (a brightness dictionary's target mean).
    pub fn with_frame_mean(&self, mut plan: Plan) -> Result<Plan> {
        if matches!(plan.dim, DimPlan::TargetMean { .. }) {
            plan.frame_mean = FrameMean::new(plan.mean_key(), self.frame_mean(&plan)?);
        }
        Ok(plan)
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
