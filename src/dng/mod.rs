//! DNG reading and writing on top of the [`crate::tiff`] layer: the reader maps a DNG's tags
//! into the raw image model ([`crate::raw::RawImage`], [`crate::raw::RawMeta`]), the writer
//! maps the model back into tags.

pub mod check;
pub mod ljpeg;
pub mod ljpeg_encode;
pub mod opcodes;
pub mod read;
pub mod thumbnail;
pub mod write;

pub use read::read_dng;
pub use write::{write_dng, write_dng_rows, WriteOptions};
