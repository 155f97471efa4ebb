//! Noise models and noise synthesis: the heteroscedastic Gaussian model per 2x2 CFA position
//! and ISO ([`model`]), and applying it to a clean night raw ([`apply`]). See docs/noise.md.

pub mod apply;
pub mod model;

pub use apply::apply_noise;
pub use model::{Evaluated, IsoPoint, NoiseModel, NoiseParams, NOISE_MODEL_FORMAT};
