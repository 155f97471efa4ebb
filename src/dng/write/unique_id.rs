//! RawDataUniqueID (docs/dng-writing.md, "RawDataUniqueID"): 16 bytes that identify the raw
//! data, made from a digest of every encoded strip/tile (computed in parallel right after
//! each is encoded, while it is in cache) combined in order with the dimensions and the
//! metadata as written. The DNG specification asks only for an identifier unique to the raw
//! data, not a cryptographic digest, so the default is XXH3-128 ([`UniqueIdHash::Xxh3_128`]);
//! SHA-256 is kept for replaying sidecars written before it and for the committed fixtures.

use super::*;
use sha2::{Digest, Sha256};
use std::str::FromStr;
use twox_hash::XxHash3_128;

/// The hash of RawDataUniqueID.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum UniqueIdHash {
    /// The first 16 bytes of SHA-256 over the SHA-256 of each chunk, the dimensions and the
    /// metadata (every DNG written before XXH3-128; the fixtures).
    Sha256,
    /// XXH3-128 over the XXH3-128 of each chunk, the dimensions and the metadata.
    #[default]
    Xxh3_128,
}

impl UniqueIdHash {
    /// The name a sidecar records (`outputs.raw_data_unique_id`).
    pub fn name(self) -> &'static str {
        match self {
            UniqueIdHash::Sha256 => "sha256",
            UniqueIdHash::Xxh3_128 => "xxh3-128",
        }
    }

    /// The digest of one encoded chunk (16 bytes for XXH3-128, 32 for SHA-256).
    pub(super) fn chunk(self, bytes: &[u8]) -> ChunkDigest {
        match self {
            UniqueIdHash::Sha256 => Sha256::digest(bytes).to_vec(),
            UniqueIdHash::Xxh3_128 => XxHash3_128::oneshot(bytes).to_le_bytes().to_vec(),
        }
    }
}

impl FromStr for UniqueIdHash {
    type Err = Error;
    fn from_str(s: &str) -> Result<UniqueIdHash> {
        match s {
            "sha256" => Ok(UniqueIdHash::Sha256),
            "xxh3-128" => Ok(UniqueIdHash::Xxh3_128),
            other => Err(Error::invalid(format!(
                "RawDataUniqueID hash {other:?} (expected \"xxh3-128\" or \"sha256\")"
            ))),
        }
    }
}

/// The digest of one encoded strip or tile.
pub(super) type ChunkDigest = Vec<u8>;

/// A chunk with its digest (hashed while it is still in cache).
pub(super) fn hashed(bytes: Vec<u8>, hash: UniqueIdHash) -> (Vec<u8>, ChunkDigest) {
    let d = hash.chunk(&bytes);
    (bytes, d)
}

/// RawDataUniqueID: `hash` over a domain tag, the dimensions, the digest of every encoded
/// strip/tile in order (independent of the thread count that made them) and the metadata as
/// written (JSON; no storage description, no regenerated or dropped entries); 16 bytes.
/// Deterministic: the same image written the same way always gets the same ID, a change of
/// pixels or meaning a new one. Hashing the encoded (packed or compressed) data rather than
/// the `u16` samples keeps it cheap.
pub(super) fn raw_data_unique_id(
    m: &RawMeta,
    (width, height): (usize, usize),
    tiled: bool,
    digests: &[ChunkDigest],
    hash: UniqueIdHash,
) -> Vec<u8> {
    let tag: &[u8] = match hash {
        UniqueIdHash::Sha256 => b"day2night RawDataUniqueID v2\0",
        UniqueIdHash::Xxh3_128 => b"day2night RawDataUniqueID v3 xxh3-128\0",
    };
    let mut msg = Vec::with_capacity(tag.len() + 17 + digests.len() * 32 + 4096);
    msg.extend_from_slice(tag);
    msg.extend_from_slice(&(width as u64).to_le_bytes());
    msg.extend_from_slice(&(height as u64).to_le_bytes());
    msg.push(tiled as u8);
    for d in digests {
        msg.extend_from_slice(d);
    }
    // Canonical metadata: what this writer actually writes, so that re-writing a file it
    // wrote reproduces the same ID (a fixed point) while any change of meaning changes it.
    let mut meta = m.clone();
    meta.storage = None;
    meta.dng_version = [1, 4, 0, 0];
    meta.dng_backward_version = None;
    let keep = |e: &Entry| {
        !is_dropped(e.tag)
            && !matches!(
                e.tag,
                t::X_RESOLUTION | t::Y_RESOLUTION | t::RESOLUTION_UNIT
            )
    };
    meta.ifd0_extra.retain(keep);
    meta.raw_extra.retain(keep);
    meta.exif_extra.retain(keep);
    if let Ok(json) = serde_json::to_vec(&meta) {
        msg.extend_from_slice(&json);
    }
    match hash {
        UniqueIdHash::Sha256 => Sha256::digest(&msg)[..UNIQUE_ID_LEN].to_vec(),
        UniqueIdHash::Xxh3_128 => XxHash3_128::oneshot(&msg).to_le_bytes().to_vec(),
    }
}
