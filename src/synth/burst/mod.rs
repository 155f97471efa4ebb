//! Night bursts (`synth --burst N`): N noisy frames of one synthesized night scene per ISO,
//! still (`--motion none`) or hand-shaken (`--motion shake`), for burst denoisers and
//! night-mode pipelines (docs/synthesis.md, "Bursts").
//!
//! - [`checks`]: every check of a burst's options and transforms, for every entry point;
//! - [`motion`]: the options, the planned per-frame rigid transforms (their own random
//!   stream, recorded in the sidecar's plan) and the frames' noise seeds;
//! - [`interp`]: the warp's interpolants;
//! - [`warp`]: frame k's clean raw from the clean night raw (demosaic that keeps measured
//!   samples, warp, mosaic back), tile by tile;
//! - [`frames`]: frame k's noisy raw, row by row on demand (whole frames) or as a crop.
//!
//! Every frame goes through the one synthesis path ([`super::night::synthesize_into`]):
//! frame 00 is the single-frame output (its clean raw is the clean DNG, its noisy raw the
//! single-frame noisy raw), frames 01.. are handed to the same sink after it.

pub mod checks;
pub mod frames;
pub mod interp;
pub mod motion;
pub mod warp;

pub use interp::Interp;
pub use motion::{BurstOptions, BurstPlan, FrameTransform, Motion, Shake, ValidRect};

#[cfg(test)]
mod tests;
