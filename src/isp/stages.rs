//! The render pipeline as one ordered list of named stages ([`STAGES`]), and the `Plan`
//! every execution of a render ([`super::render::Execution`]: whole frame, bands, a crop,
//! the LinearRaw form) takes its stages from (docs/isp.md, "The pipeline").
//!
//! A `Plan` is made once per render from the image and the [`RenderOptions`]: the
//! neutral, the prepared opcode lists, the normalizer, the demosaicer, the colour stage,
//! DefaultCrop and orientation. An execution asks the plan for each stage it runs (one
//! accessor per stage, which records the asking); the render checks, when the execution
//! returns, that it asked for every stage of [`STAGES`] (`Plan::missing`), and
//! [`super::render::render_with`] reports the stages it ran, so a test sees a stage that one
//! execution runs and another does not. A stage the options turn off (`crop: false`, the
//! opcodes ignored or absent) is asked for and runs as the identity.

use super::color::normalize_neutral;
use super::demosaic::Demosaic;
use super::opcodes::{self, Prepared};
use super::render_parts::RenderOptions;
use super::render_parts::{clip_row, color_matrix, matrix_row, resolve_neutral, Output};
use crate::error::Result;
use crate::normalize::Normalizer;
use crate::raw::RawImage;
use std::sync::atomic::{AtomicU16, Ordering};

/// A stage of the render pipeline, in the order of [`STAGES`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// OpcodeList1 on the stored values.
    Opcodes1,
    /// LinearizationTable, black level, scale to [0, 1] (DNG chapter 5).
    Normalize,
    /// OpcodeList2 on the normalized values.
    Opcodes2,
    /// White balance by the neutral, clipped to [0, 1].
    WhiteBalance,
    /// Demosaic (bilinear, MHC or Menon; the identity for a LinearRaw image).
    Demosaic,
    /// OpcodeList3 on the demosaiced camera RGB.
    Opcodes3,
    /// Camera RGB -> linear sRGB by the colour matrix (or the [0, 1] clip of the network
    /// input's camera RGB), per row.
    Colour,
    /// DefaultCropOrigin/DefaultCropSize.
    DefaultCrop,
    /// The EXIF/TIFF Orientation.
    Orientation,
}

/// The render pipeline, in order: what every execution runs.
pub const STAGES: [Stage; 9] = [
    Stage::Opcodes1,
    Stage::Normalize,
    Stage::Opcodes2,
    Stage::WhiteBalance,
    Stage::Demosaic,
    Stage::Opcodes3,
    Stage::Colour,
    Stage::DefaultCrop,
    Stage::Orientation,
];

impl Stage {
    /// The stage's name (docs/isp.md, "The pipeline").
    pub fn name(self) -> &'static str {
        match self {
            Stage::Opcodes1 => "opcodes1",
            Stage::Normalize => "normalize",
            Stage::Opcodes2 => "opcodes2",
            Stage::WhiteBalance => "white-balance",
            Stage::Demosaic => "demosaic",
            Stage::Opcodes3 => "opcodes3",
            Stage::Colour => "colour",
            Stage::DefaultCrop => "default-crop",
            Stage::Orientation => "orientation",
        }
    }

    fn bit(self) -> u16 {
        let i = STAGES.iter().position(|&s| s == self).unwrap_or(0);
        1 << i
    }
}

/// The colour stage of a render: the colour matrix (linear sRGB output) or the clip of the
/// network input's camera RGB.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Colour {
    /// The white-balanced camera -> linear sRGB matrix, as `f32`.
    Matrix([[f32; 3]; 3]),
    /// Camera RGB, clipped to [0, 1].
    Clip,
}

impl Colour {
    /// The stage on one interleaved row.
    #[inline]
    pub(crate) fn row(&self, row: &mut [f32]) {
        match self {
            Colour::Matrix(m) => matrix_row(row, m),
            Colour::Clip => clip_row(row),
        }
    }
}

/// The stages of one render of `img` with its options (see the module docs).
pub(crate) struct Plan<'a> {
    /// The image rendered.
    pub(crate) img: &'a RawImage,
    opts: &'a RenderOptions,
    neutral: [f64; 3],
    opcodes: Option<Prepared>,
    colour: Colour,
    asked: AtomicU16,
}

impl<'a> Plan<'a> {
    /// The plan of rendering `img` with `opts`: the neutral (normalized), the colour matrix
    /// of a linear render, the opcode lists that apply.
    pub(crate) fn new(img: &'a RawImage, opts: &'a RenderOptions) -> Result<Plan<'a>> {
        let neutral = resolve_neutral(&img.meta, opts.neutral)?;
        let colour = match opts.output {
            Output::Linear => {
                let m = color_matrix(&img.meta, neutral)?;
                Colour::Matrix(m.map(|r| r.map(|v| v as f32)))
            }
            Output::Camera => Colour::Clip,
        };
        let opcodes = opcodes::active_image(img, opts.opcodes)?;
        Ok(Plan {
            img,
            opts,
            neutral,
            opcodes,
            colour,
            asked: AtomicU16::new(0),
        })
    }

    /// Record that the execution runs `stage` (for the stages an execution computes with
    /// code of its own, such as the LinearRaw normalization).
    pub(crate) fn run(&self, stage: Stage) {
        self.asked.fetch_or(stage.bit(), Ordering::Relaxed);
    }

    /// The opcode lists that apply (stages [`Stage::Opcodes1`], [`Stage::Opcodes2`] and
    /// [`Stage::Opcodes3`]); `None`: no list applies and the three stages are the identity.
    pub(crate) fn opcodes(&self) -> Option<&Prepared> {
        for s in [Stage::Opcodes1, Stage::Opcodes2, Stage::Opcodes3] {
            self.run(s);
        }
        self.opcodes.as_ref()
    }

    /// The normalizer of the CFA samples ([`Stage::Normalize`]).
    pub(crate) fn normalizer(&self) -> Result<Normalizer> {
        self.run(Stage::Normalize);
        Normalizer::new(self.img)
    }

    /// The neutral the white balance divides by, normalized to green = 1
    /// ([`Stage::WhiteBalance`]).
    pub(crate) fn neutral(&self) -> Result<[f64; 3]> {
        self.run(Stage::WhiteBalance);
        normalize_neutral(self.neutral)
    }

    /// The demosaicer ([`Stage::Demosaic`]).
    pub(crate) fn demosaic(&self) -> Demosaic {
        self.run(Stage::Demosaic);
        self.opts.demosaic
    }

    /// The demosaicer without running it (to choose an execution).
    pub(crate) fn method(&self) -> Demosaic {
        self.opts.demosaic
    }

    /// The colour stage ([`Stage::Colour`]).
    pub(crate) fn colour(&self) -> Colour {
        self.run(Stage::Colour);
        self.colour
    }

    /// Whether DefaultCrop and orientation apply ([`Stage::DefaultCrop`],
    /// [`Stage::Orientation`]).
    pub(crate) fn geometry(&self) -> (bool, bool) {
        self.run(Stage::DefaultCrop);
        self.run(Stage::Orientation);
        (self.opts.crop, self.opts.orient)
    }

    /// The stages the execution ran, in pipeline order.
    pub(crate) fn ran(&self) -> Vec<Stage> {
        let asked = self.asked.load(Ordering::Relaxed);
        STAGES
            .into_iter()
            .filter(|s| asked & s.bit() != 0)
            .collect()
    }

    /// The stages of [`STAGES`] the execution did not run.
    pub(crate) fn missing(&self) -> Vec<Stage> {
        let ran = self.ran();
        STAGES.into_iter().filter(|s| !ran.contains(s)).collect()
    }

    /// Checked when an execution returns: it ran every stage (a debug assertion naming
    /// the execution and the stages it left out).
    pub(crate) fn finish(&self, execution: &str) {
        debug_assert!(
            self.missing().is_empty(),
            "the {execution} render left out the stages {:?}",
            self.missing()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::{Bayer, RawMeta};

    #[test]
    fn a_plan_names_the_stages_an_execution_left_out() {
        let img = RawImage {
            width: 4,
            height: 4,
            data: vec![100; 16],
            meta: RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0),
        };
        let opts = RenderOptions::default();
        let plan = Plan::new(&img, &opts).unwrap();
        assert_eq!(plan.missing(), STAGES.to_vec());
        plan.neutral().unwrap();
        plan.colour();
        assert_eq!(plan.ran(), vec![Stage::WhiteBalance, Stage::Colour]);
        assert!(plan.missing().contains(&Stage::Demosaic));
        plan.opcodes();
        plan.normalizer().unwrap();
        plan.demosaic();
        plan.geometry();
        assert!(plan.missing().is_empty());
        assert_eq!(plan.ran(), STAGES.to_vec());
        let names: std::collections::HashSet<&str> = STAGES.iter().map(|s| s.name()).collect();
        assert_eq!(names.len(), STAGES.len());
    }
}
