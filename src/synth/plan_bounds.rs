//! Bounds on a [`Plan`] read from a file (`synth --replay` sidecars): every count, ISO,
//! sigma, window, gain and level must be finite and within a physical range, so that a
//! hostile or damaged sidecar (200,000 lights, sigma 1e30) is refused at once with the field
//! named, before any pixel work. Plans sampled by [`super::plan::Planner`] always pass (the
//! report's lists: [`super::plan_report::PlanReport::validate_bounds`]).

use super::burst::BurstPlan;
use super::dim::DimPlan;
use super::masks::LightKind;
use super::plan::Plan;
use super::MAX_LIGHTS;
use crate::error::{Error, Result};

/// Most lights in a plan: the ambient light plus [`MAX_LIGHTS`] local lights and
/// [`MAX_LIGHTS`] bulbs.
pub const MAX_PLAN_LIGHTS: usize = 1 + 2 * MAX_LIGHTS as usize;
pub use super::plan_report::MAX_PLAN_OPCODES;
// The value bounds live in the one table, crate::bounds (re-exported here by their old names).
pub use crate::bounds::{
    ISO_RANGE, MAX_EXTENT_FACTOR, MAX_GAIN, MAX_LIST, MAX_NOISE_ENTRIES, MAX_NOISE_PARAM, MAX_RATIO,
};

fn field(name: impl std::fmt::Display, why: impl std::fmt::Display) -> Error {
    Error::invalid(format!("plan field {name}: {why}"))
}

fn in_range(name: &str, v: f64, lo: f64, hi: f64) -> Result<()> {
    crate::bounds::in_range(&format!("plan field {name}"), v, lo, hi)
}

fn ratio(name: &str, v: &[f64]) -> Result<()> {
    crate::bounds::ratios(&format!("plan field {name}"), v, MAX_RATIO)
}

fn noise_params(name: &str, p: &crate::noise::NoiseParams) -> Result<()> {
    for (i, pos) in p.positions.iter().enumerate() {
        for (j, &v) in pos.iter().enumerate() {
            let n = format!("{name}.positions[{i}][{j}]");
            in_range(&n, v, -MAX_NOISE_PARAM, MAX_NOISE_PARAM)?;
        }
    }
    Ok(())
}

fn iso(name: &str, v: u32) -> Result<()> {
    crate::bounds::iso(&format!("plan field {name}"), v)
}

impl Plan {
    /// Error naming the first field of this plan that is out of its physical range
    /// (counts, ISOs, sigmas, windows, gains, neutrals, noise parameters). Cheap: no pixels.
    pub fn validate_bounds(&self) -> Result<()> {
        let max_side = crate::dng::read::MAX_DIMENSION as usize;
        for (name, v) in [
            ("active_width", self.active_width),
            ("active_height", self.active_height),
        ] {
            if v == 0 || v > max_side {
                return Err(field(name, format!("{v} is outside 1..={max_side}")));
            }
        }
        if self.lights.len() > MAX_PLAN_LIGHTS {
            return Err(field(
                "lights",
                format!("{} lights (at most {MAX_PLAN_LIGHTS})", self.lights.len()),
            ));
        }
        if self.noise.len() > MAX_NOISE_ENTRIES {
            return Err(field(
                "noise",
                format!("{} entries (at most {MAX_NOISE_ENTRIES})", self.noise.len()),
            ));
        }
        ratio("day_neutral", &self.day_neutral)?;
        ratio("night_neutral", &self.night_neutral)?;
        match &self.dim {
            DimPlan::None => {}
            DimPlan::Uniform { s, range } => {
                in_range("dim.s", *s, 0.0, MAX_RATIO)?;
                in_range("dim.range[0]", range[0], 0.0, MAX_RATIO)?;
                in_range("dim.range[1]", range[1], 0.0, MAX_RATIO)?;
            }
            DimPlan::TargetMean { target_mean, .. } => {
                in_range("dim.target_mean", *target_mean, 0.0, MAX_RATIO)?;
            }
        }
        let extent = MAX_EXTENT_FACTOR * self.active_width.max(self.active_height) as f64;
        if let Some(b) = &self.burst {
            burst(b, (self.active_width, self.active_height), extent)?;
        }
        for (i, l) in self.lights.iter().enumerate() {
            let n = |f: &str| format!("lights[{i}].{f}");
            ratio(&n("illuminant"), &l.illuminant)?;
            in_range(&n("gain"), l.gain, 0.0, MAX_GAIN)?;
            in_range(&n("weight"), l.weight, 0.0, MAX_GAIN)?;
            in_range(&n("floor"), l.floor, 0.0, 1.0)?;
            for (k, &c) in l.center.iter().enumerate() {
                in_range(&n(&format!("center[{k}]")), c, -extent, extent)?;
            }
            if let Some(w) = l.window {
                for (k, &v) in w.iter().enumerate() {
                    let name = n(&format!("window[{k}]"));
                    in_range(&name, v, 0.0, extent)?;
                    if v <= 0.0 {
                        return Err(field(name, "must be > 0"));
                    }
                }
            }
            if l.kind != LightKind::Ambient {
                for (k, &s) in l.sigma.iter().enumerate() {
                    let name = n(&format!("sigma[{k}]"));
                    in_range(&name, s, 0.0, extent)?;
                    if s <= 0.0 {
                        return Err(field(name, "must be > 0"));
                    }
                }
            } else {
                for (k, &s) in l.sigma.iter().enumerate() {
                    in_range(&n(&format!("sigma[{k}]")), s, 0.0, extent)?;
                }
            }
        }
        iso("clean_iso", self.clean_iso)?;
        noise_params("clean_noise", &self.clean_noise)?;
        for (i, e) in self.noise.iter().enumerate() {
            iso(&format!("noise[{i}].iso"), e.iso)?;
            noise_params(&format!("noise[{i}].params"), &e.params)?;
        }
        Ok(())
    }
}

/// The burst part: frame count, parameters, the centre, and every frame's transform as
/// [`check_transform`](super::burst::checks::check_transform) checks it (the one check of a
/// replayed transform: rigid, consistent with its pose, its valid rectangle allowed).
fn burst(b: &BurstPlan, (w, h): (usize, usize), extent: f64) -> Result<()> {
    use super::burst::checks::{check_transform, TRANSLATION_TOLERANCE};
    use super::burst::motion::BurstOptions;
    use super::options::{check_fields_of, MAX_FRAMES};
    if !(2..=MAX_FRAMES).contains(&b.frames) || b.transforms.len() != b.frames as usize {
        return Err(field(
            "burst",
            format!(
                "{} frames with {} transforms (2 to {MAX_FRAMES}, one each)",
                b.frames,
                b.transforms.len()
            ),
        ));
    }
    // the ranges of the burst's options, the option table's, named as the plan's fields
    let options = super::SynthOptions {
        burst: BurstOptions {
            frames: b.frames,
            motion: b.motion,
            shake: b.shake,
            interp: b.interp,
        },
        ..super::SynthOptions::default()
    };
    check_fields_of(
        &options,
        |d| d.sidecar.is_some_and(|f| f.starts_with("burst.")),
        |d| format!("plan field {}", d.sidecar.unwrap_or(d.name)),
    )?;
    let want = [(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0];
    for (k, &c) in b.centre.iter().enumerate() {
        in_range(&format!("burst.centre[{k}]"), c, -extent, extent)?;
        if (c - want[k]).abs() > TRANSLATION_TOLERANCE * extent.max(1.0) {
            return Err(field(
                format!("burst.centre[{k}]"),
                format!(
                    "{} is not the centre of the {w}x{h} active area ({})",
                    crate::bounds::short(c),
                    crate::bounds::short(want[k])
                ),
            ));
        }
    }
    for (i, t) in b.transforms.iter().enumerate() {
        check_transform(i, t, (b.centre, b.interp), (w, h), extent)?;
    }
    Ok(())
}
