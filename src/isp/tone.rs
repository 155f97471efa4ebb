//! Display encodings of linear RGB: the sRGB OETF (IEC 61966-2-1, [`crate::color::srgb`]), a
//! pure 2.2 gamma, and the tone of the authors' released pipeline (gamma 2.2, then the
//! smoothstep tone curve `3x^2 - 2x^3`, in that stage order as in the simple camera pipeline
//! the release uses).

use crate::color::srgb;
use crate::error::Error;

/// How linear values become display values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DisplayTone {
    /// The sRGB OETF of IEC 61966-2-1 ([`srgb::oetf`]).
    #[default]
    Srgb,
    /// x^(1/2.2).
    Gamma22,
    /// The released code's targets: x^(1/2.2), then smoothstep 3y^2 - 2y^3.
    Release,
}

crate::choices! {
    DisplayTone, ignore_case: true,
    unknown: |s| Error::invalid(format!(
        "unknown tone {s:?} ({})",
        crate::choice::listed::<DisplayTone>(", ", ", ")
    )),
    Srgb => "srgb": "The sRGB OETF",
    Gamma22 => "gamma22" | "gamma2.2" | "gamma": "x^(1/2.2)",
    Release => "release": "The release's targets: gamma 2.2, then smoothstep",
}

/// The smoothstep tone curve of the release, on [0, 1].
#[inline]
pub fn smoothstep(x: f32) -> f32 {
    x * x * (3.0 - 2.0 * x)
}

impl DisplayTone {
    /// Display value in [0, 1] of a linear value (clamped to [0, 1] first; NaN -> 0).
    #[inline]
    pub fn encode(self, x: f32) -> f32 {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        match self {
            DisplayTone::Srgb => srgb::oetf(x),
            DisplayTone::Gamma22 => x.powf(1.0 / 2.2),
            DisplayTone::Release => smoothstep(x.powf(1.0 / 2.2)),
        }
        .clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tones_are_monotone_and_bounded() {
        for t in [
            DisplayTone::Srgb,
            DisplayTone::Gamma22,
            DisplayTone::Release,
        ] {
            let mut last = -1.0;
            for i in 0..=1000 {
                let v = t.encode(i as f32 / 1000.0);
                assert!((0.0..=1.0).contains(&v) && v >= last, "{t:?}");
                last = v;
            }
            assert_eq!(t.encode(f32::NAN), 0.0);
            assert_eq!(t.encode(5.0), t.encode(1.0));
        }
        assert!(
            (DisplayTone::Release.encode(0.5) - smoothstep(0.5f32.powf(1.0 / 2.2))).abs() < 1e-7
        );
        assert_eq!(DisplayTone::Srgb.encode(0.18), srgb::oetf(0.18));
    }
}
