//! Writing a checked scene through the dataset's [`Sink`] (each file hashed for the
//! manifest): the clean raw DNG, the target(s), the noisy inputs copied byte for byte and
//! the per-scene record `real/meta/<id>.json`. Every file is written to its temporary file
//! first, and all of them are renamed into place together, in one step that an interrupt
//! waits for ([`crate::output::DeferredSyncs`]), so a scene is on disk whole or not at all,
//! even when a second signal ends the process at once (docs/concurrency.md).
//!
//! The target is `day2night render CLEAN.dng -o T.png` (and `-o T.exr`): the software ISP's
//! defaults (MHC demosaic, opcodes applied, DefaultCrop, Orientation), white balance by the
//! clean raw's AsShotNeutral, which is the first low-ISO frame's; 8-bit sRGB samples are
//! `(encode(v) * 255 + 0.5) as u8` (docs/real-pairs.md, "Target"). In the release-processed
//! layout the release's own target `clean/NNN.png` is copied instead when present (checked
//! by [`super::scene::prepare`]). With `--isp release` the rendered targets are the
//! release ISP's ([`super::release_targets`]).

use super::discover::{FileRef, ScenePlan};
use super::scene::{FrameCheck, Prepared};
use super::{PairOptions, TargetKind};
use crate::calibrate::merge::MergeReport;
use crate::dataset::{Kind, Sink, UnitInfo};
use crate::dng::write::{write_dng, WriteOptions};
use crate::encode::exr::{standard_attributes, write_exr, ExrOptions};
use crate::encode::png::{write_png, PngOptions};
use crate::error::{Error, Result};
use crate::isp::opcodes::check::check_render;
use crate::isp::render::{render, RenderOptions};
use crate::output::{DeferredSyncs, OutputPolicy};
use serde::Serialize;

/// Format tag of the per-scene record.
pub const META_FORMAT: &str = "day2night-real-pairs/1";

/// The per-scene record `real/meta/<id>.json`.
#[derive(Debug, Serialize)]
pub struct SceneMeta<'a> {
    /// [`META_FORMAT`].
    pub format: &'static str,
    /// Scene id.
    pub scene: &'a str,
    /// Input name relative to SCENES.
    pub input: &'a str,
    /// Layout read.
    pub layout: &'static str,
    /// ISO of the clean burst.
    pub low_iso: u32,
    /// Frames found per ISO.
    pub frames_per_iso: std::collections::BTreeMap<String, u32>,
    /// Every frame used: name, ISO, SHA-256, role, measured motion.
    pub frames: &'a [FrameCheck],
    /// Release-processed: the files the clean raw and target came from.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sources: Vec<&'a FileRef>,
    /// Files of the scene no rule uses.
    pub ignored: &'a [String],
    /// The checks and their values.
    pub checks: Checks<'a>,
    /// The merge (None for the release-processed layout: merged by the release, the frame
    /// count unknown).
    pub merge: Option<&'a MergeReport>,
    /// How the target was made.
    pub target: TargetInfo,
    /// Files written before this record, relative to OUT.
    pub outputs: Vec<String>,
}

/// The checks of a scene.
#[derive(Debug, Serialize)]
pub struct Checks<'a> {
    /// Same size, ActiveArea, CFA, camera, levels and ISO across the clean burst; same size,
    /// CFA and camera for the noisy inputs (all passed when the record exists).
    pub same_capture: &'static str,
    /// Limit of the motion check, raw pixels.
    pub max_motion_px: f64,
    /// Largest motion measured, raw pixels.
    pub motion_max_measured_px: f64,
    /// Warnings.
    pub warnings: &'a [crate::diagnostics::Warning],
}

/// How the target was made.
#[derive(Debug, Serialize)]
pub struct TargetInfo {
    /// `render` (day2night's ISP) or `copied` (the release's `clean/NNN.png`).
    pub png: Option<&'static str>,
    /// EXR written.
    pub exr: bool,
    /// White-balance neutral (camera RGB) of the render.
    pub neutral: [f64; 3],
    /// Demosaic of the render.
    pub demosaic: &'static str,
}

/// Write every output of a checked scene; returns the manifest's unit info. `sink` must
/// defer its renames to `syncs` ([`crate::output::OutputPolicy::deferring`]): nothing is in
/// place until [`commit_scene`].
pub fn write_scene(
    plan: &ScenePlan,
    prep: &Prepared,
    opts: &PairOptions,
    sink: &Sink,
) -> Result<UnitInfo> {
    let clean = &prep.clean;
    let neutral = prep.neutral;
    let mut stages = vec![match prep.merge {
        Some(_) => "merge".to_string(),
        None => "clean_raw_png".to_string(),
    }];
    stages.push("check_motion".into());
    let dng = sink.path(Kind::CleanRaw, ".dng");
    crate::dataset::ensure_parent(&dng)?;
    write_dng(clean, &dng, &WriteOptions::default(), sink.policy())?;
    stages.push("write_clean_raw".into());

    let copied = match (&prep.target_png, opts.target.png()) {
        (Some(bytes), true) => Some(bytes),
        _ => None,
    };
    let render_png = opts.target.png() && copied.is_none();
    if let Some(bytes) = copied {
        sink.write(Kind::Target, ".png", |w| Ok(w.write_all(bytes)?))?;
        stages.push("copy_target_png".into());
    }
    let ropts = RenderOptions {
        neutral: Some(neutral),
        ..RenderOptions::default()
    };
    let which = (render_png, opts.target.exr());
    if opts.release_isp && (render_png || opts.target.exr()) {
        super::release_targets::write(clean, neutral, &dng, which, sink, &mut stages)?;
    } else if render_png || opts.target.exr() {
        check_render(clean, ropts.opcodes, ropts.crop, ropts.orient)?;
        let rgb = render(clean, &ropts)?;
        if render_png {
            let p = sink.path(Kind::Target, ".png");
            crate::dataset::ensure_parent(&p)?;
            write_png(&rgb, &p, &PngOptions::default(), sink.policy())?;
            stages.push("render_png".into());
        }
        if opts.target.exr() {
            let p = sink.path(Kind::Target, ".exr");
            crate::dataset::ensure_parent(&p)?;
            let attrs = standard_attributes(&dng, neutral);
            write_exr(&rgb, &p, &ExrOptions::default(), &attrs, sink.policy())?;
            stages.push("render_exr".into());
        }
    }
    let mut isos = Vec::new();
    for (f, bytes) in &prep.noisy {
        sink.write(Kind::NoisyRaw, &format!("_iso{}.dng", f.iso), |w| {
            Ok(w.write_all(bytes)?)
        })?;
        isos.push(f.iso);
    }
    if !isos.is_empty() {
        stages.push("copy_noisy".into());
    }
    let meta = SceneMeta {
        format: META_FORMAT,
        scene: &plan.id,
        input: &plan.rel,
        layout: plan.layout.name(),
        low_iso: plan.low_iso,
        frames_per_iso: frames_field(plan),
        frames: &prep.frames,
        sources: plan
            .processed
            .iter()
            .flat_map(|p| [Some(&p.clean_raw), p.target.as_ref(), Some(&p.meta_dng)])
            .flatten()
            .collect(),
        ignored: &plan.ignored,
        checks: Checks {
            same_capture: "ok",
            max_motion_px: opts.max_motion_px,
            motion_max_measured_px: prep.max_motion,
            warnings: &prep.warnings,
        },
        merge: prep.merge.as_ref(),
        target: TargetInfo {
            png: match (copied, render_png) {
                (Some(_), _) => Some("copied"),
                (None, true) => Some("render"),
                _ => None,
            },
            exr: opts.target.exr(),
            neutral,
            demosaic: ropts.demosaic.name(),
        },
        outputs: written(sink, opts.target, &isos),
    };
    let text = serde_json::to_vec_pretty(&meta)
        .map_err(|e| Error::invalid(format!("scene record: {e}")))?;
    sink.write(Kind::Meta, ".json", |w| Ok(w.write_all(&text)?))?;
    Ok(UnitInfo {
        iso: isos,
        night_neutral: Some(neutral),
        stages,
    })
}

/// Rename every file [`write_scene`] staged into place, together (`policy`: the sink's
/// policy without the deferral), then hash the files it wrote through the encoders for the
/// manifest. The scene's set stays open for an interrupt until `syncs` is dropped.
pub fn commit_scene(
    sink: &Sink,
    syncs: &DeferredSyncs,
    policy: &OutputPolicy,
    target: TargetKind,
    copied_png: bool,
) -> Result<()> {
    syncs.finish(policy)?;
    sink.adopt(Kind::CleanRaw, ".dng")?;
    if target.png() && !copied_png {
        sink.adopt(Kind::Target, ".png")?;
    }
    if target.exr() {
        sink.adopt(Kind::Target, ".exr")?;
    }
    Ok(())
}

/// The manifest's `frames` field: frames found per ISO, keys as decimal strings.
pub fn frames_field(plan: &ScenePlan) -> std::collections::BTreeMap<String, u32> {
    plan.frames
        .iter()
        .map(|(k, v)| (k.to_string(), *v))
        .collect()
}

fn written(sink: &Sink, target: TargetKind, isos: &[u32]) -> Vec<String> {
    let mut v = vec![sink.rel_path(Kind::CleanRaw, ".dng")];
    if target.png() {
        v.push(sink.rel_path(Kind::Target, ".png"));
    }
    if target.exr() {
        v.push(sink.rel_path(Kind::Target, ".exr"));
    }
    for iso in isos {
        v.push(sink.rel_path(Kind::NoisyRaw, &format!("_iso{iso}.dng")));
    }
    v
}
