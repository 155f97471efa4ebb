//! The real processing callback: day-to-night synthesis of one (input, variant) through the
//! library (`synth::plan` -> `synth::run_clean` -> `synth::run_noise`, `dng::write`,
//! `isp::render_linear`), written into the dataset layout, plus the synth sidecar.
//!
//! The random stream of a unit is keyed by (run seed, relative input path, variant - 1), as
//! `synth` keys it by (seed, file name, variant): it depends on the file, never on its
//! position, shard or the thread count. For a file directly in DAY_DIR the relative path is
//! the file name, so its plan (sidecar `plan`) equals what `day2night synth` samples.

use super::{Kind, Processor, Sink, Unit, UnitInfo};
use crate::dng::write::{encode_dng, Compression, WriteOptions};
use crate::error::Result;
use crate::exr::{encode_exr, standard_attributes, ExrOptions};
use crate::isp::{render_input, render_linear, RenderOptions};
use crate::raw::RawImage;
use crate::synth::sidecar::{CalibrationInfo, InputInfo, OutputInfo, Sidecar, SIDECAR_FORMAT};
use crate::synth::{self, Calibration, SynthOptions};
use std::path::Path;

/// Which rendered targets to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Target {
    /// Linear EXR (default).
    #[default]
    Exr,
    /// sRGB PNG.
    Png,
    /// Both.
    Both,
    /// None.
    None,
}

impl Target {
    /// Command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Target::Exr => "exr",
            Target::Png => "png",
            Target::Both => "both",
            Target::None => "none",
        }
    }
    fn exr(self) -> bool {
        matches!(self, Target::Exr | Target::Both)
    }
    fn png(self) -> bool {
        matches!(self, Target::Png | Target::Both)
    }
}

/// Everything the synthesis of a dataset needs.
#[derive(Debug, Clone)]
pub struct SynthProcessor {
    /// Synthesis options.
    pub options: SynthOptions,
    /// Calibration (illuminants, brightness, noise model).
    pub calibration: Calibration,
    /// Rendered targets.
    pub target: Target,
    /// DNG compression of the raw outputs.
    pub compression: Compression,
    /// Also write the network input render (`input/<id>.exr`).
    pub input_exr: bool,
}

/// A decoded input and its SHA-256.
pub struct LoadedInput {
    raw: RawImage,
    sha256: String,
}

impl SynthProcessor {
    fn compression_name(&self) -> &'static str {
        match self.compression {
            Compression::None => "none",
            Compression::Ljpeg => "ljpeg",
        }
    }
}

impl Processor for SynthProcessor {
    type Loaded = LoadedInput;

    fn fingerprint(&self) -> String {
        // Everything that changes output bytes: options, calibration, output settings and
        // the tool version (a new version may change the bytes).
        let cal = serde_json::json!({
            "illuminants": self.calibration.illuminants,
            "brightness": self.calibration.brightness,
            "noise": self.calibration.noise.as_ref().map(|n| n.to_json()),
        });
        format!(
            "day2night {} dataset-outputs/1\noptions {}\ncalibration {}\ntarget {}\ninput_exr {}\ncompression {}",
            crate::VERSION,
            serde_json::to_string(&self.options).unwrap_or_default(),
            cal,
            self.target.name(),
            self.input_exr,
            self.compression_name()
        )
    }

    fn load(&self, _path: &Path, bytes: &[u8]) -> Result<LoadedInput> {
        Ok(LoadedInput {
            raw: crate::dng::read::read_dng_bytes(bytes)?,
            sha256: super::sha256_hex(bytes),
        })
    }

    fn process(&self, input: &LoadedInput, unit: &Unit, sink: &Sink) -> Result<UnitInfo> {
        // Mirrors `day2night synth` (src/cli/synth.rs, process_variant) output for output,
        // with the dataset's names and folders.
        let day = &input.raw;
        let plan = synth::plan(
            day,
            &unit.rel,
            unit.seed,
            unit.variant.saturating_sub(1),
            &self.options,
            &self.calibration,
        )?;
        let (mut clean, report) = synth::relight::run_clean(day, &plan)?;
        clean.meta = synth::night_meta(&day.meta, &plan, plan.clean_iso, &plan.clean_noise);
        let wopts = WriteOptions {
            compression: self.compression,
            ..WriteOptions::default()
        };
        let mut stages = plan.stages.clone();
        let mut files = Vec::new();
        let bytes = encode_dng(&clean, &wopts)?;
        sink.write(Kind::CleanRaw, ".dng", |w| Ok(w.write_all(&bytes)?))?;
        drop(bytes);
        files.push(sink.rel_path(Kind::CleanRaw, ".dng"));
        stages.push("write_clean_dng".into());
        let mut isos = Vec::new();
        let mut first_noisy = None;
        for i in 0..plan.noise.len() {
            let (iso, noisy) = synth::run_noise(&clean, &plan, i)?;
            let bytes = encode_dng(&noisy, &wopts)?;
            let suffix = format!("_iso{iso}.dng");
            sink.write(Kind::NoisyRaw, &suffix, |w| Ok(w.write_all(&bytes)?))?;
            files.push(sink.rel_path(Kind::NoisyRaw, &suffix));
            isos.push(iso);
            if first_noisy.is_none() && self.input_exr {
                first_noisy = Some(noisy);
            }
        }
        if !isos.is_empty() {
            stages.push("write_noisy_dng".into());
        }
        let neutral = plan.night_neutral;
        // One custom attribute only: the `exr` crate keeps custom attributes in a HashMap, so
        // with several their order in the header (hence the bytes) changes per process.
        let summary = standard_attributes(Path::new(&unit.rel), neutral)
            .into_iter()
            .map(|(k, v)| format!("{}={}", k.trim_start_matches("day2night:"), v))
            .chain([
                format!("seed={}", plan.seed),
                format!("variant={}", plan.variant),
            ])
            .collect::<Vec<_>>()
            .join("; ");
        let attrs = vec![("day2night:synth".to_string(), summary)];
        let exr_bytes = |rgb: &crate::isp::RgbImage| -> Result<Vec<u8>> {
            let mut cur = std::io::Cursor::new(Vec::new());
            encode_exr(rgb, &mut cur, &ExrOptions::default(), &attrs)?;
            Ok(cur.into_inner())
        };
        if self.target.exr() || self.target.png() {
            let ropts = RenderOptions {
                neutral: Some(neutral),
                ..RenderOptions::default()
            };
            let rgb = render_linear(&clean, &ropts)?;
            if self.target.exr() {
                let bytes = exr_bytes(&rgb)?;
                sink.write(Kind::Target, ".exr", |w| Ok(w.write_all(&bytes)?))?;
                files.push(sink.rel_path(Kind::Target, ".exr"));
                stages.push("target_exr".into());
            }
            if self.target.png() {
                let path = sink.path(Kind::Target, ".png");
                crate::png::write_png(
                    &rgb,
                    &path,
                    &crate::png::PngOptions::default(),
                    sink.policy(),
                )?;
                sink.adopt(Kind::Target, ".png")?;
                files.push(sink.rel_path(Kind::Target, ".png"));
                stages.push("target_png".into());
            }
        }
        if self.input_exr {
            let src = first_noisy.as_ref().unwrap_or(&clean);
            let rgb = render_input(src, Some(neutral), Default::default())?;
            let bytes = exr_bytes(&rgb)?;
            sink.write(Kind::Input, ".exr", |w| Ok(w.write_all(&bytes)?))?;
            files.push(sink.rel_path(Kind::Input, ".exr"));
            stages.push("input_exr".into());
        }
        drop(first_noisy);
        files.push(sink.rel_path(Kind::Meta, ".json"));
        let sidecar = Sidecar {
            format: SIDECAR_FORMAT.into(),
            tool: "day2night".into(),
            version: crate::VERSION.into(),
            input: InputInfo {
                name: unit.rel.clone(),
                sha256: input.sha256.clone(),
            },
            options: self.options.clone(),
            calibration: CalibrationInfo {
                illuminants: self.calibration.illuminants.clone(),
                brightness: self.calibration.brightness.clone(),
                noise_model: plan.noise_model_source.clone(),
            },
            plan: plan.clone(),
            run: report,
            stages: stages.clone(),
            outputs: OutputInfo {
                variants: unit.variants,
                compression: self.compression_name().into(),
                target: self.target.name().into(),
                input_exr: self.input_exr,
                files,
                exr_compression: "zip".into(),
            },
        };
        let json = sidecar.to_json()?;
        sink.write(Kind::Meta, ".json", |w| Ok(w.write_all(json.as_bytes())?))?;
        Ok(UnitInfo {
            iso: isos,
            night_neutral: Some(plan.night_neutral),
            stages,
        })
    }
}
