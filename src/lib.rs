//! # day2night
//!
//! Turn daytime camera raw photos (DNG) into realistic nighttime raw photos for training
//! night-mode neural ISPs, after Punnappurath et al., "Day-to-Night Image Synthesis for
//! Training Nighttime Neural ISPs" (CVPR 2022).
//!
//! Flow: [`dng::read`] -> [`raw::RawImage`] -> [`synth`] (a seeded `Plan`, then a pure run)
//! -> [`noise`] -> [`dng::write`], plus the software ISP in [`isp`] for EXR/PNG targets,
//! [`metrics`] for evaluation and [`calibrate`] for new cameras.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bounds;
pub mod calibrate;
pub mod choice;
pub mod color;
pub mod dataset;
pub mod deflate;
pub mod diagnostics;
pub mod dng;
pub mod encode;
pub mod error;
pub mod isp;
pub mod limits;
pub mod metrics;
pub mod noise;
pub mod normalize;
pub mod output;
/// The plots' common frame (needs the `cli` feature: drawn with plotters).
#[cfg(feature = "cli")]
pub(crate) mod plot;
pub mod raw;
pub mod realpairs;
/// The HTML report of a dataset (needs the `cli` feature: its plots are drawn with plotters).
#[cfg(feature = "cli")]
pub mod report;
pub mod synth;
pub mod tiff;

pub use diagnostics::{Code, Diagnostics, Warning};
pub use error::{Error, Result};
pub use raw::{Bayer, Levels, RawImage, Rect};

/// Tool version written into Software tags, EXR attributes and sidecars.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// "day2night `<version>`": the Software tag value.
pub fn software_name() -> String {
    format!("day2night {}", VERSION)
}
