//! One scene, read and checked before anything is written: the clean burst merged by
//! [`Merger`] (which refuses frames of another size, ActiveArea, CFA, black/white level or
//! ISO), every frame of the same camera (Make/Model) as the first, the noisy inputs of the
//! same size and CFA (other levels: a warning), and no motion above the limit between the
//! burst's frames and its first frame, or between the merged raw and each noisy input
//! ([`super::motion`]). The first failure is an error naming the file.

use super::discover::{FileRef, ScenePlan};
use super::motion::{magnitude, shift, GreenPlane};
use super::processed;
use crate::calibrate::merge::{MergeReport, Merger};
use crate::calibrate::{check_same_capture, SameCapture};
use crate::dng::read::read_dng_bytes;
use crate::error::{Error, Result, ResultExt};
use crate::raw::RawImage;
use serde::Serialize;

/// What was measured for one frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameCheck {
    /// Path relative to SCENES.
    pub name: String,
    /// ISO.
    pub iso: u32,
    /// SHA-256 of the file.
    pub sha256: String,
    /// Role: `clean` (merged), `noisy` (copied as the ISO's input) or `clean_meta` (the
    /// processed tree's iso_50 frame).
    pub role: &'static str,
    /// Measured translation `[dx, dy]` in raw pixels: against the burst's first frame for a
    /// clean frame, against the merged raw otherwise.
    pub motion_px: [f64; 2],
    /// Its length.
    pub motion: f64,
}

/// A checked scene, ready to write.
#[derive(Debug)]
pub struct Prepared {
    /// The clean raw (merged, or the processed tree's PNG in the iso_50 frame's metadata).
    pub clean: RawImage,
    /// The merge's statistics (None for the processed tree).
    pub merge: Option<MergeReport>,
    /// The noisy inputs with their bytes, by ascending ISO.
    pub noisy: Vec<(FileRef, Vec<u8>)>,
    /// Every frame's checks, clean frames first.
    pub frames: Vec<FrameCheck>,
    /// Warnings (not fatal), for stderr and the sidecar; no subject (the scene's caller
    /// names it).
    pub warnings: crate::diagnostics::Diagnostics,
    /// Largest motion measured, raw pixels.
    pub max_motion: f64,
}

fn read_frame(f: &FileRef) -> Result<(Vec<u8>, RawImage)> {
    let bytes = std::fs::read(&f.path).map_err(Error::Io).in_file(&f.path)?;
    let img = read_dng_bytes(&bytes).in_file(&f.path)?;
    Ok((bytes, img))
}

fn meta_only(img: &RawImage) -> RawImage {
    RawImage {
        width: img.width,
        height: img.height,
        data: vec![],
        meta: img.meta.clone(),
    }
}

fn camera(img: &RawImage) -> String {
    format!(
        "{} {}",
        img.meta.make.as_deref().unwrap_or("(no Make)"),
        img.meta.model.as_deref().unwrap_or("(no Model)")
    )
}

/// Error unless `other` comes from the camera of `first` (Make and Model).
fn same_camera(first: &RawImage, other: &RawImage) -> Result<()> {
    if (&first.meta.make, &first.meta.model) != (&other.meta.make, &other.meta.model) {
        return Err(Error::invalid(format!(
            "camera {} differs from the first frame's {}",
            camera(other),
            camera(first)
        )));
    }
    Ok(())
}

fn check_motion(c: &FrameCheck, limit: f64, against: &str) -> Result<()> {
    if c.motion > limit || !c.motion.is_finite() {
        return Err(Error::invalid(format!(
            "{} moved {:.2} px (dx {:.2}, dy {:.2}) against {against}: more than --max-motion {limit} px (a target merged or paired with it would be blurred or misaligned)",
            c.name, c.motion, c.motion_px[0], c.motion_px[1]
        )));
    }
    Ok(())
}

fn measured(f: &FileRef, role: &'static str, d: (f64, f64)) -> FrameCheck {
    FrameCheck {
        name: f.name.clone(),
        iso: f.iso,
        sha256: f.sha256.clone(),
        role,
        motion_px: [d.0, d.1],
        motion: magnitude(d),
    }
}

/// Read, check and merge the clean burst: (merged raw, merge report, the first frame's
/// metadata, per-frame checks).
fn merge_burst(
    plan: &ScenePlan,
    limit: f64,
) -> Result<(RawImage, MergeReport, RawImage, Vec<FrameCheck>)> {
    let mut it = plan.clean.iter();
    let Some(f0) = it.next() else {
        return Err(Error::invalid("no low-ISO burst"));
    };
    let (_, img0) = read_frame(f0)?;
    let first = meta_only(&img0);
    let g0 = GreenPlane::of(&img0).in_file(&f0.path)?;
    let mut checks = vec![measured(f0, "clean", (0.0, 0.0))];
    let mut merger = Merger::new(img0).in_file(&f0.path)?;
    for f in it {
        let (_, img) = read_frame(f)?;
        same_camera(&first, &img).in_file(&f.path)?;
        merger.add(&img).in_file(&f.path)?;
        let g = GreenPlane::of(&img).in_file(&f.path)?;
        let c = measured(f, "clean", shift(&g0, &g).in_file(&f.path)?);
        check_motion(&c, limit, &format!("the burst's first frame {}", f0.name))?;
        checks.push(c);
    }
    let (merged, report) = merger.finish()?;
    Ok((merged, report, first, checks))
}

/// Read, check and measure the scene (see the module documentation).
pub fn prepare(plan: &ScenePlan, limit: f64) -> Result<Prepared> {
    let mut warnings = crate::diagnostics::Diagnostics::new();
    let (clean, merge, first, mut frames) = match &plan.processed {
        None => {
            let (m, r, first, checks) = merge_burst(plan, limit)?;
            (m, Some(r), first, checks)
        }
        Some(p) => {
            let (_, frame) = read_frame(&p.meta_dng)?;
            let png = processed::read_png16(&p.clean_raw.path).in_file(&p.clean_raw.path)?;
            let clean = processed::clean_raw(png, &frame).in_file(&p.clean_raw.path)?;
            let gm = GreenPlane::of(&clean).in_file(&p.clean_raw.path)?;
            let gf = GreenPlane::of(&frame).in_file(&p.meta_dng.path)?;
            let c = measured(
                &p.meta_dng,
                "clean_meta",
                shift(&gm, &gf).in_file(&p.meta_dng.path)?,
            );
            check_motion(&c, limit, &format!("the clean raw {}", p.clean_raw.name))?;
            (clean, None, meta_only(&frame), vec![c])
        }
    };
    let gm = GreenPlane::of(&clean)?;
    let mut noisy = Vec::with_capacity(plan.noisy.len());
    for f in &plan.noisy {
        let (bytes, img) = read_frame(f)?;
        same_camera(&first, &img).in_file(&f.path)?;
        check_same_capture(
            &first,
            &meta_only(&img),
            SameCapture {
                iso: false,
                levels: false,
            },
        )
        .in_file(&f.path)?;
        let (fl, nl) = (&first.meta.levels, &img.meta.levels);
        if fl.black != nl.black || fl.white != nl.white {
            warnings.warn(crate::diagnostics::Code::RealLevelsDiffer, format!(
                "{}: black/white levels {:?}/{} differ from the clean burst's {:?}/{} (the noisy input keeps its own)",
                f.name, nl.black, nl.white, fl.black, fl.white
            ));
        }
        if let Some(iso) = img.meta.exif.iso.filter(|&i| i != f.iso) {
            warnings.warn(
                crate::diagnostics::Code::RealIsoMismatch,
                format!(
                    "{}: the DNG says ISO {iso}, its name or folder ISO {}",
                    f.name, f.iso
                ),
            );
        }
        let g = GreenPlane::of(&img).in_file(&f.path)?;
        let c = measured(f, "noisy", shift(&gm, &g).in_file(&f.path)?);
        check_motion(&c, limit, "the merged clean raw")?;
        frames.push(c);
        noisy.push((f.clone(), bytes));
    }
    if plan.noisy.is_empty() {
        warnings.warn(
            crate::diagnostics::Code::RealNoNoisyFrame,
            "no high-ISO frame: the scene serves the clean task only",
        );
    }
    let max_motion = frames.iter().map(|c| c.motion).fold(0.0, f64::max);
    Ok(Prepared {
        clean,
        merge,
        noisy,
        frames,
        warnings,
        max_motion,
    })
}
