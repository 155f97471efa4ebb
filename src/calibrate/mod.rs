//! Calibration of a new camera from real captures (issue 5; docs/calibration.md):
//! night-illuminant dictionaries from gray cards ([`illuminants`]), night-brightness
//! dictionaries ([`brightness`]), per-ISO noise models from bursts, pairs or NoiseProfile
//! tags ([`noise`]) or estimated from day images ([`noise_image`]), and burst merging for low-noise ground truth ([`merge`]).
//! Every output is JSON in the formats of [`format`](mod@format), consumed by `synth`.

pub mod brightness;
pub mod format;
pub mod illuminants;
pub mod merge;
pub mod noise;
pub mod noise_image;
pub mod physics;
pub mod stats;

use crate::error::{Error, Result};
use crate::raw::RawImage;

/// What two frames must share.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SameCapture {
    /// Also require the same Exif ISO.
    pub iso: bool,
    /// Also require the same levels (black, white, LinearizationTable).
    pub levels: bool,
}

/// Error naming the first mismatch between `first` and `other` in geometry (stored size,
/// ActiveArea), CFA pattern, levels (black, white, LinearizationTable) and, if asked, ISO.
pub fn check_same_capture(first: &RawImage, other: &RawImage, what: SameCapture) -> Result<()> {
    if (first.width, first.height) != (other.width, other.height) {
        return Err(Error::invalid(format!(
            "size {}x{} differs from the first frame's {}x{}",
            other.width, other.height, first.width, first.height
        )));
    }
    if first.active_area() != other.active_area() {
        let (a, b) = (other.active_area(), first.active_area());
        return Err(Error::invalid(format!(
            "ActiveArea {},{},{},{} differs from the first frame's {},{},{},{}",
            a.top, a.left, a.bottom, a.right, b.top, b.left, b.bottom, b.right
        )));
    }
    let (fc, oc) = (&first.meta.cfa, &other.meta.cfa);
    if (fc.rows, fc.cols, &fc.pattern, &fc.plane_color, fc.layout)
        != (oc.rows, oc.cols, &oc.pattern, &oc.plane_color, oc.layout)
    {
        let name = |i: &RawImage| {
            i.bayer()
                .map(|b| b.name())
                .unwrap_or_else(|_| "non-Bayer".into())
        };
        return Err(Error::invalid(format!(
            "CFA pattern {} differs from the first frame's {}",
            name(other),
            name(first)
        )));
    }
    let (fl, ol) = (&first.meta.levels, &other.meta.levels);
    if !what.levels {
        // Only geometry and CFA asked for.
    } else if fl.black != ol.black
        || fl.black_repeat != ol.black_repeat
        || fl.black_delta_h != ol.black_delta_h
        || fl.black_delta_v != ol.black_delta_v
    {
        return Err(Error::invalid(format!(
            "black level {:?} differs from the first frame's {:?}",
            ol.black, fl.black
        )));
    }
    if what.levels && fl.white != ol.white {
        return Err(Error::invalid(format!(
            "white level {} differs from the first frame's {}",
            ol.white, fl.white
        )));
    }
    if what.levels && first.meta.linearization_table != other.meta.linearization_table {
        return Err(Error::invalid(
            "LinearizationTable differs from the first frame's",
        ));
    }
    if what.iso && first.meta.exif.iso != other.meta.exif.iso {
        let s = |i: Option<u32>| i.map(|v| v.to_string()).unwrap_or_else(|| "unknown".into());
        return Err(Error::invalid(format!(
            "ISO {} differs from the first frame's ISO {}",
            s(other.meta.exif.iso),
            s(first.meta.exif.iso)
        )));
    }
    Ok(())
}
