//! Software ISP: the renders of raw images that serve as training targets, network inputs
//! and previews (docs/synthesis.md, "Targets"; docs/isp.md).
//!
//! The pipeline is one ordered list of named stages ([`stages::STAGES`]): the opcode lists,
//! normalize (the shared [`crate::normalize`] path), white balance by the neutral,
//! demosaic ([`demosaic`]), camera -> XYZ (D50) -> linear sRGB/Rec.709 (D65) per DNG
//! chapter 6 ([`color`], on the maths of [`crate::color`]), DefaultCrop and orientation.
//! [`render()`] runs it: an options record ([`RenderOptions`]) and an execution choice
//! ([`Execution`]: whole frame, bands, a crop). Display encodings (the sRGB OETF of
//! [`crate::color::srgb`], the release's gamma + smoothstep tone) are in [`tone`].
//! [`release`] is the authors' release ISP itself, stage for stage (`render --isp release`).

pub(crate) mod bands;
pub mod color;
pub mod demosaic;
pub(crate) mod drive;
pub mod flat;
pub mod geometry;
pub mod opcodes;
pub(crate) mod place;
pub(crate) mod pre_demosaic;
pub mod release;
pub mod release_input;
pub mod render;
pub mod render_bands;
pub mod render_crop;
pub mod render_linear_raw;
pub mod render_parts;
pub mod rgb;
pub mod stages;
pub mod tone;

pub use demosaic::Demosaic;
pub use render::{
    render, render_bands, render_crop, render_with, CropSamples, Execution, Output, RenderOptions,
    Rendered,
};
pub use rgb::RgbImage;
