//! The I/O floor of a `synth` run (issue 7): read the input DNG and write output files of
//! the same number and sizes as a reference `synth` output directory, through the same
//! atomic output path as `synth` (temporary file; fsync on a background thread and the
//! renames once all are synced, the sidecar `.json` last and synced at once), with no
//! computation.
//!
//! ```text
//! cargo run --release --example io_floor -- DAY.dng REFERENCE_OUT_DIR OUT_DIR
//! ```
//!
//! Only the sizes of the reference files are looked up (metadata, not contents); the bytes
//! written are the input's bytes repeated to each size.

use day2night::output::{write_bytes_atomic, DeferredSyncs, OutputPolicy};
use std::path::PathBuf;
use std::sync::Arc;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let usage = "usage: io_floor DAY.dng REFERENCE_OUT_DIR OUT_DIR";
    let input = args.next().ok_or(usage)?;
    let reference = args.next().ok_or(usage)?;
    let out = args.next().ok_or(usage)?;
    let mut files: Vec<(std::ffi::OsString, u64)> = std::fs::read_dir(&reference)?
        .map(|e| -> std::io::Result<_> {
            let e = e?;
            Ok((e.file_name(), e.metadata()?.len()))
        })
        .collect::<Result<_, _>>()?;
    files.sort();
    let bytes = std::fs::read(&input)?;
    if bytes.is_empty() {
        return Err("empty input".into());
    }
    std::fs::create_dir_all(&out)?;
    let policy = OutputPolicy {
        overwrite: true,
        inputs: vec![input.clone()],
        ..OutputPolicy::default()
    };
    let syncs = Arc::new(DeferredSyncs::default());
    let deferred = policy.deferring(&syncs);
    // The sidecar last, as synth writes it.
    files.sort_by_key(|(name, _)| name.to_string_lossy().ends_with(".json"));
    let mut buf = Vec::new();
    for (name, size) in files {
        let sidecar = name.to_string_lossy().ends_with(".json");
        let size = size as usize;
        buf.clear();
        while buf.len() < size {
            let take = (size - buf.len()).min(bytes.len());
            buf.extend_from_slice(&bytes[..take]);
        }
        if sidecar {
            syncs.finish(&policy)?;
            write_bytes_atomic(&out.join(name), &policy, &buf)?;
        } else {
            write_bytes_atomic(&out.join(name), &deferred, &buf)?;
        }
    }
    syncs.finish(&policy)?;
    Ok(())
}
