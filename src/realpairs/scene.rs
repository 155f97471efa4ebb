//! One scene, read and checked before anything is written: the clean burst merged by
//! [`Merger`] (which refuses frames of another size, ActiveArea, CFA, black/white level or
//! ISO), every frame of the same camera (Make/Model) as the first, the noisy inputs of the
//! same size and CFA (other levels: a warning), and no motion above the limit between the
//! burst's frames and its first frame, or between the merged raw and each noisy input
//! ([`super::motion`]; a frame whose motion cannot be measured is a warning, never a
//! guessed shift). The white balance of the target must exist, and in the processed tree
//! the release's target `clean/NNN.png` must be an 8-bit RGB PNG of the scene's size. The
//! first failure is an error naming the file.

use super::discover::{FileRef, ProcessedFiles, ScenePlan};
use super::motion::{magnitude, px_text, shift, GreenPlane, Motion};
use super::processed;
use crate::calibrate::merge::{MergeReport, Merger};
use crate::calibrate::{check_same_capture, SameCapture};
use crate::diagnostics::{Code, Diagnostics};
use crate::dng::read::read_dng_bytes;
use crate::error::{Error, Result, ResultExt};
use crate::isp::render::resolve_neutral;
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
    /// clean frame, against the merged raw otherwise; null when it cannot be measured.
    pub motion_px: Option<[f64; 2]>,
    /// Its length (null when not measured).
    pub motion: Option<f64>,
    /// Why the motion could not be measured (absent when it was).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion_unmeasured: Option<String>,
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
    pub warnings: Diagnostics,
    /// Largest motion measured, raw pixels.
    pub max_motion: f64,
    /// White balance of the target (camera RGB, green 1).
    pub neutral: [f64; 3],
    /// Release-processed: the bytes of `clean/NNN.png`, checked, when it exists.
    pub target_png: Option<Vec<u8>>,
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

/// Error when `c` moved more than `limit`; a warning when its motion was not measurable.
fn check_motion(c: &FrameCheck, limit: f64, against: &str, w: &mut Diagnostics) -> Result<()> {
    let Some(m) = c.motion else {
        w.warn(
            Code::RealMotionUnmeasured,
            format!(
                "{}: motion against {against} not measured: {} (the motion check could not verify this frame)",
                c.name,
                c.motion_unmeasured.as_deref().unwrap_or("unmeasurable")
            ),
        );
        return Ok(());
    };
    if m > limit || !m.is_finite() {
        let [dx, dy] = c.motion_px.unwrap_or([f64::NAN; 2]);
        return Err(Error::invalid(format!(
            "{} moved {} px (dx {}, dy {}) against {against}: more than --max-motion {} px (a target merged or paired with it would be blurred or misaligned)",
            c.name, px_text(m), px_text(dx), px_text(dy), px_text(limit)
        )));
    }
    Ok(())
}

fn measured(f: &FileRef, role: &'static str, m: Motion) -> FrameCheck {
    let (motion_px, motion, motion_unmeasured) = match m {
        Motion::Shift(dx, dy) => (Some([dx, dy]), Some(magnitude((dx, dy))), None),
        Motion::Unmeasurable(why) => (None, None, Some(why)),
    };
    FrameCheck {
        name: f.name.clone(),
        iso: f.iso,
        sha256: f.sha256.clone(),
        role,
        motion_px,
        motion,
        motion_unmeasured,
    }
}

/// Read, check and merge the clean burst: (merged raw, merge report, the first frame's
/// metadata, per-frame checks).
fn merge_burst(
    plan: &ScenePlan,
    limit: f64,
    w: &mut Diagnostics,
) -> Result<(RawImage, MergeReport, RawImage, Vec<FrameCheck>)> {
    let mut it = plan.clean.iter();
    let Some(f0) = it.next() else {
        return Err(Error::invalid("no low-ISO burst"));
    };
    let (_, img0) = read_frame(f0)?;
    let first = meta_only(&img0);
    let g0 = GreenPlane::of(&img0).in_file(&f0.path)?;
    let mut checks = vec![measured(f0, "clean", Motion::Shift(0.0, 0.0))];
    let mut merger = Merger::new(img0).in_file(&f0.path)?;
    for f in it {
        let (_, img) = read_frame(f)?;
        same_camera(&first, &img).in_file(&f.path)?;
        merger.add(&img).in_file(&f.path)?;
        let g = GreenPlane::of(&img).in_file(&f.path)?;
        let c = measured(f, "clean", shift(&g0, &g).in_file(&f.path)?);
        check_motion(
            &c,
            limit,
            &format!("the burst's first frame {}", f0.name),
            w,
        )?;
        checks.push(c);
    }
    let (merged, report) = merger.finish()?;
    Ok((merged, report, first, checks))
}

/// The processed tree's clean raw (its PNG in the iso_50 frame's metadata), checked against
/// that frame for motion, and its target PNG checked: (clean raw, the frame's metadata, the
/// frame's check, the target's bytes).
fn processed_clean(
    p: &ProcessedFiles,
    limit: f64,
    w: &mut Diagnostics,
) -> Result<(RawImage, RawImage, FrameCheck, Option<Vec<u8>>)> {
    let (_, frame) = read_frame(&p.meta_dng)?;
    let png = processed::read_png16(&p.clean_raw.path).in_file(&p.clean_raw.path)?;
    let png_size = (png.0, png.1);
    let clean = processed::clean_raw(png, &frame).in_file(&p.clean_raw.path)?;
    let target = match &p.target {
        Some(t) => Some(processed::read_target_png(&t.path, &frame, png_size).in_file(&t.path)?),
        None => None,
    };
    let gm = GreenPlane::of(&clean).in_file(&p.clean_raw.path)?;
    let gf = GreenPlane::of(&frame).in_file(&p.meta_dng.path)?;
    let c = measured(
        &p.meta_dng,
        "clean_meta",
        shift(&gm, &gf).in_file(&p.meta_dng.path)?,
    );
    check_motion(&c, limit, &format!("the clean raw {}", p.clean_raw.name), w)?;
    Ok((clean, meta_only(&frame), c, target))
}

/// The target's white balance: the clean raw's AsShotNeutral (or AsShotWhiteXY), which is
/// `source`'s; an error naming `source` when it has none or an unusable one.
fn target_neutral(clean: &RawImage, source: &FileRef) -> Result<[f64; 3]> {
    let m = &clean.meta;
    if m.as_shot_neutral.is_none() && m.as_shot_white_xy.is_none() {
        return Err(Error::invalid(
            "has neither AsShotNeutral nor AsShotWhiteXY: the target is rendered with this frame's white balance, so real-pairs needs one (write AsShotNeutral into the DNG, e.g. with exiftool)",
        )
        .in_file(&source.path));
    }
    resolve_neutral(m, None)
        .map_err(|e| Error::invalid(format!("unusable white balance for the target: {e}")))
        .in_file(&source.path)
}

/// Read, check and measure the scene (see the module documentation).
pub fn prepare(plan: &ScenePlan, limit: f64) -> Result<Prepared> {
    let mut warnings = Diagnostics::new();
    let (clean, merge, first, mut frames, target_png, wb_source) = match &plan.processed {
        None => {
            let (m, r, first, checks) = merge_burst(plan, limit, &mut warnings)?;
            let Some(f0) = plan.clean.first() else {
                return Err(Error::invalid("no low-ISO burst"));
            };
            (m, Some(r), first, checks, None, f0)
        }
        Some(p) => {
            let (clean, first, c, target) = processed_clean(p, limit, &mut warnings)?;
            (clean, None, first, vec![c], target, &p.meta_dng)
        }
    };
    let neutral = target_neutral(&clean, wb_source)?;
    let gm = GreenPlane::of(&clean)?;
    let mut noisy = Vec::with_capacity(plan.noisy.len());
    for f in &plan.noisy {
        let (bytes, img) = read_frame(f)?;
        check_noisy(f, &first, &img, &mut warnings)?;
        let g = GreenPlane::of(&img).in_file(&f.path)?;
        let c = measured(f, "noisy", shift(&gm, &g).in_file(&f.path)?);
        check_motion(&c, limit, "the merged clean raw", &mut warnings)?;
        frames.push(c);
        noisy.push((f.clone(), bytes));
    }
    if plan.noisy.is_empty() {
        warnings.warn(
            Code::RealNoNoisyFrame,
            "no high-ISO frame: the scene serves the clean task only",
        );
    }
    let max_motion = frames.iter().filter_map(|c| c.motion).fold(0.0, f64::max);
    Ok(Prepared {
        clean,
        merge,
        noisy,
        frames,
        warnings,
        max_motion,
        neutral,
        target_png,
    })
}

/// A noisy input against the clean burst's first frame: same camera and capture (size,
/// ActiveArea, CFA: errors), levels and ISO (warnings).
fn check_noisy(f: &FileRef, first: &RawImage, img: &RawImage, w: &mut Diagnostics) -> Result<()> {
    same_camera(first, img).in_file(&f.path)?;
    check_same_capture(
        first,
        &meta_only(img),
        SameCapture {
            iso: false,
            levels: false,
        },
    )
    .in_file(&f.path)?;
    let (fl, nl) = (&first.meta.levels, &img.meta.levels);
    if fl.black != nl.black || fl.white != nl.white {
        w.warn(Code::RealLevelsDiffer, format!(
            "{}: black/white levels {:?}/{} differ from the clean burst's {:?}/{} (the noisy input keeps its own)",
            f.name, nl.black, nl.white, fl.black, fl.white
        ));
    }
    if let Some(iso) = img.meta.exif.iso.filter(|&i| i != f.iso) {
        w.warn(
            Code::RealIsoMismatch,
            format!(
                "{}: the DNG says ISO {iso}, its name or folder ISO {}",
                f.name, f.iso
            ),
        );
    }
    Ok(())
}
