//! The [`NightSink`] that writes files: each product of a variant encoded as its DNG, EXR or
//! PNG and written through an [`OutputSink`]'s paths and policy; the banded target goes into
//! its open files band by band (`encode::target_files`). Used by
//! [`SynthJob`](super::job::SynthJob) for `synth`, `dataset` and Python's `write_outputs`.

use super::night::{NightSink, TargetOut};
use super::outputs::{OutputKind, OutputSink, Target};
use super::Plan;
use crate::dng::write::{write_dng, write_dng_rows, Compression, UniqueIdHash, WriteOptions};
use crate::encode::exr::{encodes_rows, standard_attributes, write_exr, ExrOptions};
use crate::encode::png::{write_png, PngOptions};
use crate::encode::target_files::TargetFiles;
use crate::error::{Error, Result};
use crate::isp::RgbImage;
use crate::output::OutputPolicy;
use crate::raw::rows::RowSource;
use crate::raw::{RawImage, RawMeta};
use std::path::Path;
use std::sync::OnceLock;

/// The [`NightSink`] of the file outputs: encodes each product of a variant as its file
/// (DNG, EXR, PNG) and writes it through the [`OutputSink`]'s paths and policy (deferred
/// renames). It computes nothing but encodings.
pub struct FileSink<'a> {
    target: Target,
    exr: &'a ExrOptions,
    sink: &'a dyn OutputSink,
    policy: &'a OutputPolicy,
    wopts: WriteOptions,
    attrs: Vec<(String, String)>,
    /// Frames per ISO (1 without a burst).
    frames: u32,
    /// The banded target's files, open while it is rendered.
    target_files: OnceLock<TargetFiles<'a>>,
}

impl<'a> FileSink<'a> {
    /// The sink of one variant's files: the `target` files (EXR encoded with `exr`), DNGs
    /// compressed with `compression`, placed and named by `sink` and written under `policy`;
    /// the EXR renders record `source` and `plan`'s seed and variant.
    pub(crate) fn new(
        target: Target,
        exr: &'a ExrOptions,
        (compression, unique_id): (Compression, UniqueIdHash),
        (sink, policy): (&'a dyn OutputSink, &'a OutputPolicy),
        source: &Path,
        plan: &Plan,
    ) -> FileSink<'a> {
        FileSink {
            target,
            exr,
            sink,
            policy,
            wopts: WriteOptions {
                compression,
                unique_id,
                ..WriteOptions::default()
            },
            attrs: exr_attributes(source, plan),
            frames: plan.burst.as_ref().map_or(1, |b| b.frames),
            target_files: OnceLock::new(),
        }
    }

    /// The target files opened by [`NightSink::target_start`].
    fn started(&self) -> Result<&TargetFiles<'a>> {
        self.target_files
            .get()
            .ok_or_else(|| Error::invalid("a target band came before the target's size"))
    }

    /// Write a whole target image (the EXR and/or PNG the job asks for).
    pub(crate) fn target_image(&self, rgb: &RgbImage) -> Result<()> {
        let (want_exr, want_png) = (self.target.exr(), self.target.png());
        let (e, p) = rayon::join(
            || {
                if !want_exr {
                    return Ok(());
                }
                let path = self.sink.path(OutputKind::TargetExr)?;
                write_exr(rgb, &path, self.exr, &self.attrs, self.policy)
            },
            || {
                if !want_png {
                    return Ok(());
                }
                let path = self.sink.path(OutputKind::TargetPng)?;
                write_png(rgb, &path, &PngOptions::default(), self.policy)
            },
        );
        e.and(p)
    }
}

impl NightSink for FileSink<'_> {
    type Band = ();

    fn clean(&self, clean: &RawImage) -> Result<()> {
        let path = self.sink.path(OutputKind::CleanDng)?;
        write_dng(clean, &path, &self.wopts, self.policy)
    }

    fn noisy(&self, iso: u32, frame: u32, noisy: &RawImage) -> Result<()> {
        let path = self.sink.path(OutputKind::noisy(iso, frame, self.frames))?;
        write_dng(noisy, &path, &self.wopts, self.policy)
    }

    /// Packed and written strip by strip: no noisy plane (same bytes as `noisy`).
    fn noisy_rows(&self, iso: u32, frame: u32, meta: &RawMeta, rows: &dyn RowSource) -> Result<()> {
        let path = self.sink.path(OutputKind::noisy(iso, frame, self.frames))?;
        write_dng_rows(meta, rows, &path, &self.wopts, self.policy)
    }

    /// Band by band when every requested target can be encoded from bands (the default
    /// ZIP/none EXRs, 8-bit PNG): same bytes, no whole f32 image, each band is encoded
    /// while it is in cache and written at once (`encode::target_files`), so the encoded
    /// target is never held whole either.
    fn banded(&self) -> bool {
        !self.target.exr() || encodes_rows(self.exr)
    }

    fn target_start(&self, w: usize, h: usize) -> Result<()> {
        let exr = match self.target.exr() {
            true => Some(self.sink.path(OutputKind::TargetExr)?),
            false => None,
        };
        let png = match self.target.png() {
            true => Some(self.sink.path(OutputKind::TargetPng)?),
            false => None,
        };
        let files = TargetFiles::create(
            (w, h),
            exr.as_deref(),
            (self.exr, &self.attrs),
            png.as_deref()
                .map(|p| (p, crate::encode::png::PngOptions::default().tone)),
            self.policy,
        )?;
        self.target_files
            .set(files)
            .map_err(|_| Error::invalid("the target was started twice"))
    }

    fn target_band(&self, y0: usize, w: usize, rows: &[f32]) -> Result<()> {
        self.started()?.band(y0, w, rows)
    }

    fn target(&self, target: TargetOut<()>) -> Result<()> {
        match target {
            TargetOut::Image(rgb) => self.target_image(&rgb),
            TargetOut::Bands(_) => self.started()?.finish(),
        }
    }

    fn input(&self, rgb: &RgbImage) -> Result<()> {
        let path = self.sink.path(OutputKind::InputExr)?;
        write_exr(rgb, &path, self.exr, &self.attrs, self.policy)
    }
}

/// The EXR header attribute of a render: one custom attribute only, because the `exr` crate
/// keeps custom attributes in a HashMap (several would be written in a per-process random
/// order, hence non-deterministic bytes).
fn exr_attributes(source: &Path, plan: &Plan) -> Vec<(String, String)> {
    let summary = standard_attributes(source, plan.night_neutral)
        .into_iter()
        .map(|(k, v)| format!("{}={}", k.trim_start_matches("day2night:"), v))
        .chain([
            format!("seed={}", plan.seed),
            format!("variant={}", plan.variant),
        ])
        .collect::<Vec<_>>()
        .join("; ");
    vec![("day2night:synth".to_string(), summary)]
}
