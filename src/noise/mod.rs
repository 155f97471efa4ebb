//! Noise models and noise synthesis: the heteroscedastic Gaussian model per 2x2 CFA position
//! and ISO ([`model`]), and applying it to a clean night raw ([`apply`]); the physics-based
//! model (shot, Tukey-lambda read, row noise; [`physics`], [`physics_apply`], [`tukey`],
//! and the sampler's tables [`poisson_table`], [`tukey_table`]); the single-image estimate
//! of an input's own noise ([`estimate`](mod@estimate)) and where a plan's model came from
//! ([`provenance`]).
//! See docs/noise.md.

pub mod apply;
pub mod estimate;
pub mod estimate_fit;
pub mod model;
pub mod numpy_legacy;
pub mod params;
pub mod physics;
pub mod physics_apply;
pub mod poisson_table;
pub mod provenance;
pub mod release;
pub mod stream;
pub mod tukey;
pub mod tukey_table;

pub use apply::apply_noise;
pub use estimate::{estimate, EstimateOptions, NoiseEstimate};
pub use model::{Evaluated, IsoPoint, NoiseModel, NoiseParams, NOISE_MODEL_FORMAT};
pub use physics::{PhysicsModel, PhysicsParams};
pub use physics_apply::{
    apply_physics_noise, apply_physics_noise_crop, apply_physics_noise_image, with_physics_rows,
};
pub use provenance::{NoiseProvenance, NoiseSource};
pub use stream::NoiseStream;
