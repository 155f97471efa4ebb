//! The render pipeline as one ordered list of named stages ([`STAGES`]) and the driver that
//! runs it: the `Plan` every execution of a render ([`super::render::Execution`]: whole
//! frame, bands, a crop, the LinearRaw form) takes its stages from (docs/isp.md, "The
//! pipeline").
//!
//! Each stage has a [`Kind`] that says where it runs. The sample stages (normalize, white
//! balance) and the row stages (colour) are functions of one value or one output row:
//! the driver runs them, in the order of [`STAGES`], wherever an execution asks for a
//! sample before the demosaic ([`Samples::between`], `CfaSites` (pre_demosaic.rs)) or
//! hands an output row on ([`Rows`]), so an execution never names them. The opcode lists,
//! the demosaic and the geometry are how an execution walks the image (which rows or
//! region, with what context): it asks the plan for them (one accessor each, which records
//! the asking). The render checks, when the execution returns, that every stage of
//! [`STAGES`] ran (`Plan::missing`), and [`super::render::render_with`] reports the stages
//! run. A stage the options turn off (`crop: false`, the opcodes ignored or absent) runs as
//! the identity.
//!
//! Adding a stage that works on a sample or a row is one entry in the `stages!` list below
//! and one function: every execution then runs it.

use super::color::normalize_neutral;
use super::demosaic::Demosaic;
use super::opcodes::{self, Prepared};
use super::render_parts::RenderOptions;
use super::render_parts::{clip_row, color_matrix, matrix_row, resolve_neutral, Output};
use crate::error::Result;
use crate::raw::RawImage;
use std::sync::atomic::{AtomicU32, Ordering};

/// Where a stage runs (see the module docs).
#[derive(Clone, Copy)]
pub enum Kind {
    /// An opcode list, on the stage image or the rectangle an execution walks.
    Opcodes,
    /// The normalization of a stored sample: the first sample stage.
    Normalize,
    /// A function of one sample (its colour index given) before the demosaic, in `f64`
    /// (fused with the normalization) or `f32` (after OpcodeList2's `f32` stage image).
    Sample(SampleFn<f64>, SampleFn<f32>),
    /// The demosaic (the identity for a LinearRaw image).
    Demosaic,
    /// A function of one output row of interleaved RGB, after OpcodeList3.
    Row(fn(&Rows, &mut [f32])),
    /// How the output is cut from the active area (DefaultCrop, orientation).
    Geometry,
}

/// A sample stage's function: the value `v` of colour `k` (0 red, 1 green, 2 blue).
pub type SampleFn<T> = fn(&Samples, T, usize) -> T;

/// The list of stages: `Variant => "name", Kind(functions);` in pipeline order (a stage
/// marked `@cfg(...)` exists only under that configuration).
macro_rules! stages {
    (@kind Sample $f:ident) => { Kind::Sample($f::<f64>, $f::<f32>) };
    (@kind Row $f:ident) => { Kind::Row($f) };
    (@kind $kind:ident) => { Kind::$kind };
    ($($(#[doc = $doc:expr])* $(@cfg($cfg:meta))? $v:ident => $name:literal, $kind:ident $(($f:ident))?;)*) => {
        /// A stage of the render pipeline, in the order of [`STAGES`].
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum Stage {
            $($(#[doc = $doc])* $(#[cfg($cfg)])? $v,)*
        }

        /// The render pipeline, in order: what every execution runs.
        pub const STAGES: &[Stage] = &[$($(#[cfg($cfg)])? Stage::$v,)*];

        impl Stage {
            /// The stage's name (docs/isp.md, "The pipeline").
            pub fn name(self) -> &'static str {
                match self {
                    $($(#[cfg($cfg)])? Stage::$v => $name,)*
                }
            }

            /// Where the stage runs.
            pub fn kind(self) -> Kind {
                match self {
                    $($(#[cfg($cfg)])? Stage::$v => stages!(@kind $kind $($f)?),)*
                }
            }
        }
    };
}

stages! {
    /// OpcodeList1 on the stored values.
    Opcodes1 => "opcodes1", Opcodes;
    /// LinearizationTable, black level, scale to [0, 1] (DNG chapter 5).
    Normalize => "normalize", Normalize;
    /// OpcodeList2 on the normalized values.
    Opcodes2 => "opcodes2", Opcodes;
    /// White balance by the neutral, clipped to [0, 1].
    WhiteBalance => "white-balance", Sample(white_balance);
    /// A test's stage: the sample scaled by 1 (`isp::stages::tests`: every execution runs it).
    @cfg(test) Probe => "probe", Sample(probe);
    /// Demosaic (bilinear, MHC or Menon; the identity for a LinearRaw image).
    Demosaic => "demosaic", Demosaic;
    /// OpcodeList3 on the demosaiced camera RGB.
    Opcodes3 => "opcodes3", Opcodes;
    /// Camera RGB -> linear sRGB by the colour matrix (or the [0, 1] clip of the network
    /// input's camera RGB), per row.
    Colour => "colour", Row(colour);
    /// DefaultCropOrigin/DefaultCropSize.
    DefaultCrop => "default-crop", Geometry;
    /// The EXIF/TIFF Orientation.
    Orientation => "orientation", Geometry;
}

impl Stage {
    fn bit(self) -> u32 {
        let i = STAGES.iter().position(|&s| s == self).unwrap_or(0);
        1 << i
    }
}

/// A sample value of a sample stage: `f64` (fused with the normalization) or `f32`.
pub trait Sample: Copy + std::ops::Mul<Output = Self> {
    /// `v` in this type.
    fn of(v: f64) -> Self;
    /// Clipped to [0, 1].
    fn clip(self) -> Self;
    /// The stage function `f` for this type applied to `v` of colour `k`.
    fn apply(kind: Kind, s: &Samples, v: Self, k: usize) -> Self;
}

impl Sample for f64 {
    #[inline]
    fn of(v: f64) -> f64 {
        v
    }
    #[inline]
    fn clip(self) -> f64 {
        self.clamp(0.0, 1.0)
    }
    #[inline]
    fn apply(kind: Kind, s: &Samples, v: f64, k: usize) -> f64 {
        match kind {
            Kind::Sample(f, _) => f(s, v, k),
            _ => v,
        }
    }
}

impl Sample for f32 {
    #[inline]
    fn of(v: f64) -> f32 {
        v as f32
    }
    #[inline]
    fn clip(self) -> f32 {
        self.clamp(0.0, 1.0)
    }
    #[inline]
    fn apply(kind: Kind, s: &Samples, v: f32, k: usize) -> f32 {
        match kind {
            Kind::Sample(_, f) => f(s, v, k),
            _ => v,
        }
    }
}

/// What the sample stages of one render read: the white balance's inverse neutral.
#[derive(Debug, Clone, Copy)]
pub struct Samples {
    /// `1 / neutral`, the neutral normalized to green = 1.
    inv: [f64; 3],
}

impl Samples {
    /// The sample stages of a render white-balanced by the normalized neutral `n`.
    pub(crate) fn new(n: [f64; 3]) -> Samples {
        Samples {
            inv: [1.0 / n[0], 1.0, 1.0 / n[2]],
        }
    }

    /// The sample stages of [`STAGES`] strictly between `from` and `to`, in order, on the
    /// value `v` of colour `k`: every execution's one way to run them.
    #[inline]
    pub fn between<T: Sample>(&self, from: Stage, to: Stage, v: T, k: usize) -> T {
        let mut v = v;
        let mut on = false;
        for &s in STAGES {
            if s == to {
                break;
            }
            if on {
                v = T::apply(s.kind(), self, v, k);
            }
            on |= s == from;
        }
        v
    }
}

/// [`Stage::WhiteBalance`]: divided by the neutral, clipped to [0, 1].
#[inline]
fn white_balance<T: Sample>(s: &Samples, v: T, k: usize) -> T {
    (v * T::of(s.inv[k])).clip()
}

/// [`Stage::Probe`]: scaled by 1 (a test-only stage that every execution must run).
#[cfg(test)]
#[inline]
fn probe<T: Sample>(_: &Samples, v: T, _: usize) -> T {
    v * T::of(1.0)
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

/// What the row stages of one render read; [`Rows::run`] runs them on an output row.
#[derive(Debug, Clone, Copy)]
pub struct Rows {
    colour: Colour,
}

impl Rows {
    /// The row stages of [`STAGES`], in order, on one interleaved output row.
    #[inline]
    pub fn run(&self, row: &mut [f32]) {
        for &s in STAGES {
            if let Kind::Row(f) = s.kind() {
                f(self, row);
            }
        }
    }
}

/// [`Stage::Colour`] on one interleaved row.
#[inline]
fn colour(r: &Rows, row: &mut [f32]) {
    match &r.colour {
        Colour::Matrix(m) => matrix_row(row, m),
        Colour::Clip => clip_row(row),
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
    asked: AtomicU32,
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
            asked: AtomicU32::new(0),
        })
    }

    fn run(&self, stage: Stage) {
        self.asked.fetch_or(stage.bit(), Ordering::Relaxed);
    }

    /// Record that every stage of `kind` runs.
    fn run_kind(&self, kind: fn(Kind) -> bool) {
        for &s in STAGES {
            if kind(s.kind()) {
                self.run(s);
            }
        }
    }

    /// The opcode lists that apply (the [`Kind::Opcodes`] stages); `None`: no list applies
    /// and the three stages are the identity.
    pub(crate) fn opcodes(&self) -> Option<&Prepared> {
        self.run_kind(|k| matches!(k, Kind::Opcodes));
        self.opcodes.as_ref()
    }

    /// The sample stages ([`Kind::Sample`]) of a render whose normalization an execution
    /// computes itself (a LinearRaw image's, per plane).
    pub(crate) fn samples(&self) -> Result<Samples> {
        self.run_kind(|k| matches!(k, Kind::Normalize | Kind::Sample(..)));
        Ok(Samples::new(normalize_neutral(self.neutral)?))
    }

    /// The neutral, normalized to green = 1 (what OpcodeList3 takes out and puts back).
    pub(crate) fn neutral(&self) -> Result<[f64; 3]> {
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

    /// The row stages ([`Kind::Row`]), run on every output row.
    pub(crate) fn rows(&self) -> Rows {
        self.run_kind(|k| matches!(k, Kind::Row(_)));
        Rows {
            colour: self.colour,
        }
    }

    /// Whether DefaultCrop and orientation apply ([`Kind::Geometry`]).
    pub(crate) fn geometry(&self) -> (bool, bool) {
        self.run_kind(|k| matches!(k, Kind::Geometry));
        (self.opts.crop, self.opts.orient)
    }

    /// The stages the execution ran, in pipeline order.
    pub(crate) fn ran(&self) -> Vec<Stage> {
        let asked = self.asked.load(Ordering::Relaxed);
        STAGES
            .iter()
            .copied()
            .filter(|s| asked & s.bit() != 0)
            .collect()
    }

    /// The stages of [`STAGES`] the execution did not run.
    pub(crate) fn missing(&self) -> Vec<Stage> {
        let ran = self.ran();
        STAGES
            .iter()
            .copied()
            .filter(|s| !ran.contains(s))
            .collect()
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
#[path = "stages_tests.rs"]
mod tests;
