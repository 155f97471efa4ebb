//! DNG reading and writing on top of the [`crate::tiff`] layer.

pub mod ljpeg;
pub mod ljpeg_encode;
pub mod meta;
pub mod read;
pub mod thumbnail;
pub mod write;

pub use meta::RawMeta;
pub use read::read_dng;
pub use write::{write_dng, WriteOptions};
