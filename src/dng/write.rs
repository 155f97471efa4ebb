//! DNG writer (in progress: owned by the writer work).
use crate::error::{Error, Result};
use crate::output::OutputPolicy;
use crate::raw::RawImage;
use std::path::Path;

/// Raw image compression of written DNGs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Compression {
    /// Uncompressed strips (default: readable by every raw tool).
    #[default]
    None,
    /// Lossless JPEG (compression 7) tiles.
    Ljpeg,
}

/// Where the raw image goes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum RawIfd {
    /// Raw in IFD0 (default).
    #[default]
    Main,
    /// Raw in a SubIFD behind a small RGB thumbnail in IFD0.
    Sub,
}

/// DNG writing options.
#[derive(Debug, Clone, Default)]
pub struct WriteOptions {
    /// Compression of the raw image.
    pub compression: Compression,
    /// IFD holding the raw image.
    pub raw_ifd: RawIfd,
}

/// Encode a DNG into memory.
pub fn encode_dng(img: &RawImage, opts: &WriteOptions) -> Result<Vec<u8>> {
    let _ = (img, opts);
    Err(Error::unsupported("DNG writing is not implemented yet"))
}

/// Encode and write a DNG atomically under `policy`.
pub fn write_dng(
    img: &RawImage,
    path: &Path,
    opts: &WriteOptions,
    policy: &OutputPolicy,
) -> Result<()> {
    let bytes = encode_dng(img, opts)?;
    crate::output::write_bytes_atomic(path, policy, &bytes)
}
