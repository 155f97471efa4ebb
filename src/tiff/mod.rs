//! Hand-written TIFF layer: byte order, IFD entries and values, IFD reading and writing.
//! (The `tiff` crate's decoder rejects CFA images and its encoder cannot lay out tiles,
//! lossless JPEG or DNG's SubIFD trees; see docs/dng-support.md.)

pub mod read;
pub mod tags;
pub mod value;
pub mod write;
