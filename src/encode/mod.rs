//! Image files of the targets and renders: the encoders (the ISP renders, these encode)
//! and the readers `eval` uses.
//!
//! - [`exr`]: OpenEXR, day2night's own scan-line ZIP/ZIPS/none writer (band by band, with
//!   the [`crate::deflate`] encoder at level 1) and the `exr` crate for the other codecs;
//!   the chunk-table checks and band reader for EXR inputs.
//! - [`png_rows`]: the own 8-bit PNG writer from row groups (filtered and deflated where
//!   they are rendered).
//! - [`png`]: display encodings (sRGB OETF, gamma 2.2, the release's tone), 16-bit PNG and
//!   TIFF through the `image` crate.
//! - [`read`]: reading PNG, TIFF and EXR images for evaluation.

pub mod exr;
pub mod png;
pub mod png_rows;
pub mod read;
pub mod target_files;
