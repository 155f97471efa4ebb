//! `real-pairs --isp release`: a scene's targets rendered by the authors' release ISP
//! ([`crate::isp::release`], as `day2night render --isp release`) instead of day2night's,
//! white-balanced by the clean raw's neutral: the 8-bit PNG is the release's bytes (its own
//! crop and orientation), the EXR its linear sRGB before gamma.

use crate::dataset::{Kind, Sink};
use crate::encode::exr::{standard_attributes, write_exr, ExrOptions};
use crate::error::Result;
use crate::isp::release::render_linear;
use crate::isp::tone::DisplayTone;
use crate::raw::RawImage;
use std::path::Path;

/// Write the release-ISP targets of `clean` (`png`, `exr`: which ones) through `sink`; the
/// names of the stages done are pushed on `stages`.
pub fn write(
    clean: &RawImage,
    neutral: [f64; 3],
    dng: &Path,
    (png, exr): (bool, bool),
    sink: &Sink,
    stages: &mut Vec<String>,
) -> Result<()> {
    let lin = render_linear(clean, Some(neutral), true)?;
    if png {
        let p = sink.path(Kind::Target, ".png");
        crate::dataset::ensure_parent(&p)?;
        let bytes = lin.to_u8();
        crate::encode::png_rows::write_png_rgb8(
            &bytes,
            lin.width,
            lin.height,
            DisplayTone::Release,
            &p,
            sink.policy(),
        )?;
        stages.push("render_png_release_isp".into());
    }
    if exr {
        let p = sink.path(Kind::Target, ".exr");
        crate::dataset::ensure_parent(&p)?;
        let mut attrs = standard_attributes(dng, neutral);
        attrs.push(("day2night:isp".into(), "release".into()));
        write_exr(
            &lin.to_rgb_image(),
            &p,
            &ExrOptions::default(),
            &attrs,
            sink.policy(),
        )?;
        stages.push("render_exr_release_isp".into());
    }
    Ok(())
}
