//! The EXR writer's options: [`ExrCompression`] (with its command-line names) and
//! [`ExrOptions`].

use crate::error::{Error, Result};
use exr::prelude::*;

/// EXR compression choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ExrCompression {
    /// No compression.
    None,
    /// Run-length encoding.
    Rle,
    /// zlib, one scan line per block.
    Zips,
    /// zlib, 16 scan lines per block (default).
    #[default]
    Zip,
    /// Wavelet + Huffman (good on noisy images).
    Piz,
    /// Lossy for f32 (24-bit floats), lossless for half.
    Pxr24,
    /// Lossy 4x4 blocks for half (f32 stored uncompressed).
    B44,
    /// B44 with flat-area optimisation.
    B44a,
}

impl ExrCompression {
    /// All choices.
    pub const ALL: [ExrCompression; 8] = [
        ExrCompression::None,
        ExrCompression::Rle,
        ExrCompression::Zips,
        ExrCompression::Zip,
        ExrCompression::Piz,
        ExrCompression::Pxr24,
        ExrCompression::B44,
        ExrCompression::B44a,
    ];
    pub(super) fn to_exr(self) -> Compression {
        match self {
            ExrCompression::None => Compression::Uncompressed,
            ExrCompression::Rle => Compression::RLE,
            ExrCompression::Zips => Compression::ZIP1,
            ExrCompression::Zip => Compression::ZIP16,
            ExrCompression::Piz => Compression::PIZ,
            ExrCompression::Pxr24 => Compression::PXR24,
            ExrCompression::B44 => Compression::B44,
            ExrCompression::B44a => Compression::B44A,
        }
    }
}

crate::choices! {
    ExrCompression, ignore_case: true,
    unknown: |s| Error::invalid(format!(
        "unknown EXR compression {s:?} ({})",
        crate::choice::listed::<ExrCompression>(", ", ", ")
    )),
    Zip => "zip" | "zip16": "Lossless, zlib in 16-row blocks: the fastest",
    Piz => "piz": "Lossless wavelet: slower; larger on synth targets, smaller on noisy images",
    Zips => "zips" | "zip1": "Lossless, zlib row by row",
    Rle => "rle": "Lossless run-length",
    None => "none" | "uncompressed": "Uncompressed",
    Pxr24 => "pxr24": "Lossy for half",
    B44 => "b44": "Lossy for half: 4x4 blocks",
    B44a => "b44a": "Lossy for half: b44, flat blocks smaller",
}

/// Options of [`write_exr`](super::write_exr).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExrOptions {
    /// 16-bit half samples (default); false = 32-bit float.
    pub half: bool,
    /// Compression (default ZIP).
    pub compression: ExrCompression,
    /// zlib effort of ZIP/ZIPS blocks, 1 (fastest, default) ..= 9 (smallest); ignored by the
    /// other compressions. 1 is day2night's own run-length + Huffman encoder
    /// ([`crate::deflate`]), 2..=9 are miniz_oxide's levels (the `exr` crate, used before,
    /// hard-codes 4). See docs/benchmarks.md, "EXR writer", for time and size per level.
    pub zip_level: u8,
}

impl Default for ExrOptions {
    fn default() -> Self {
        ExrOptions {
            half: true,
            compression: ExrCompression::Zip,
            zip_level: ExrOptions::DEFAULT_ZIP_LEVEL,
        }
    }
}

impl ExrOptions {
    /// Default [`ExrOptions::zip_level`].
    pub const DEFAULT_ZIP_LEVEL: u8 = 1;

    /// Reject a zip level outside 1..=9 ([`crate::bounds::EXR_ZIP_LEVEL_RANGE`]).
    pub fn validate(&self) -> Result<()> {
        let (lo, hi) = crate::bounds::EXR_ZIP_LEVEL_RANGE;
        if !(lo..=hi).contains(&self.zip_level) {
            return Err(Error::invalid(format!(
                "EXR zip level {} is outside {lo}..={hi}",
                self.zip_level
            )));
        }
        Ok(())
    }
}
