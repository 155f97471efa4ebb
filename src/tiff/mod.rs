//! Hand-written TIFF layer: byte order, IFD entries and values, IFD reading and writing.
//! (The `tiff` crate's decoder rejects CFA images and its encoder cannot lay out tiles,
//! lossless JPEG or DNG's SubIFD trees; see docs/dng-support.md.)

pub mod read;
pub mod tags;
pub mod value;
pub mod write;

/// TIFF byte order (also the byte order a raw image was stored in, `raw::meta::Storage`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ByteOrder {
    /// "II".
    Little,
    /// "MM".
    Big,
}
