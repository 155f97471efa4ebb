//! DNG reader (in progress: owned by the reader work).
use crate::error::{Error, Result};
use crate::raw::RawImage;
use std::path::Path;

/// Read the raw CFA image and metadata of a DNG file.
pub fn read_dng(path: &Path) -> Result<RawImage> {
    let _ = path;
    Err(Error::unsupported("DNG reading is not implemented yet"))
}
