//! The render pipeline as one ordered list of named stages ([`STAGES`]), each with the
//! [`Kind`] that says how it runs; one driver (`drive`, drive.rs) runs the list for every
//! execution of a render (docs/isp.md, "The pipeline").
//!
//! The sample stages (white balance, before the demosaic) and the row stages (colour) are
//! functions of one value or one output row, run in the order of [`STAGES`] wherever an
//! execution fills the demosaicer's input ([`Samples::between`], `CfaSites`
//! (pre_demosaic.rs)) or hands an output row on ([`Rows::run`], which also runs a sample
//! stage listed after the demosaic on every sample of the row). The opcode lists, the
//! normalization, the demosaic and the geometry need a neighbourhood or a region: the
//! driver makes their parameters, and each execution (a `Walk`, drive.rs) runs them its way.
//!
//! Adding a stage that works on a sample or a row is one entry in the `stages!` list below
//! and one function: every execution then runs it.

use super::render_parts::{clip_row, matrix_row};
use crate::dng::opcodes::ListId;

/// Where a stage runs (see the module docs).
#[derive(Clone, Copy)]
pub enum Kind {
    /// An opcode list, on the stage image or the rectangle an execution walks.
    Opcodes(ListId),
    /// The normalization of a stored sample, fused with the sample stages after it.
    Normalize,
    /// A function of one sample (its colour index given): before the demosaic in `f64`
    /// (fused with the normalization) or `f32` (after OpcodeList2's `f32` stage image);
    /// after OpcodeList3 in `f32`, on every sample of an output row.
    Sample(SampleFn<f64>, SampleFn<f32>),
    /// The demosaic (the identity for a LinearRaw image).
    Demosaic,
    /// A function of one output row of interleaved RGB, after OpcodeList3.
    Row(fn(&Rows, &mut [f32])),
    /// How the output is cut from the active area.
    Geometry(Geo),
}

/// A geometry stage: what it cuts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Geo {
    /// DefaultCropOrigin/DefaultCropSize (if
    /// [`RenderOptions::crop`](super::render::RenderOptions::crop)).
    DefaultCrop,
    /// The EXIF/TIFF Orientation (if
    /// [`RenderOptions::orient`](super::render::RenderOptions::orient)).
    Orientation,
}

/// A sample stage's function: the value `v` of colour `k` (0 red, 1 green, 2 blue).
pub type SampleFn<T> = fn(&Samples, T, usize) -> T;

/// The list of stages: `Variant => "name", Kind(functions);` in pipeline order (a stage
/// marked `@cfg(...)` exists only under that configuration).
macro_rules! stages {
    (@kind Sample $f:ident) => { Kind::Sample($f::<f64>, $f::<f32>) };
    (@kind Row $f:ident) => { Kind::Row($f) };
    (@kind Opcodes $f:ident) => { Kind::Opcodes(ListId::$f) };
    (@kind Geometry $f:ident) => { Kind::Geometry(Geo::$f) };
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
    Opcodes1 => "opcodes1", Opcodes(List1);
    /// LinearizationTable, black level, scale to [0, 1] (DNG chapter 5).
    Normalize => "normalize", Normalize;
    /// OpcodeList2 on the normalized values.
    Opcodes2 => "opcodes2", Opcodes(List2);
    /// White balance by the neutral, clipped to [0, 1].
    WhiteBalance => "white-balance", Sample(white_balance);
    /// A test's stage: the sample scaled by the test's factor, 1 unless a test sets it
    /// ([`PROBE`]; `isp::stages::tests`: every execution runs it).
    @cfg(test) Probe => "probe", Sample(probe);
    /// Demosaic (bilinear, MHC or Menon; the identity for a LinearRaw image).
    Demosaic => "demosaic", Demosaic;
    /// OpcodeList3 on the demosaiced camera RGB.
    Opcodes3 => "opcodes3", Opcodes(List3);
    /// Camera RGB -> linear sRGB by the colour matrix (or the [0, 1] clip of the network
    /// input's camera RGB), per row.
    Colour => "colour", Row(colour);
    /// A test's sample stage after the demosaic, run on every sample of an output row
    /// ([`Rows::run`]): scaled by the test's second factor.
    @cfg(test) ProbeRgb => "probe-rgb", Sample(probe_rgb);
    /// DefaultCropOrigin/DefaultCropSize.
    DefaultCrop => "default-crop", Geometry(DefaultCrop);
    /// The EXIF/TIFF Orientation.
    Orientation => "orientation", Geometry(Orientation);
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
    /// The test stages' factors ([`PROBE`] when the render began).
    #[cfg(test)]
    probe: [f64; 2],
}

#[cfg(test)]
thread_local! {
    /// The factors of the test stages `Probe` and `ProbeRgb` for the renders this thread
    /// starts (1: the identity, what every other test sees).
    pub(crate) static PROBE: std::cell::Cell<[f64; 2]> = const { std::cell::Cell::new([1.0; 2]) };
}

impl Samples {
    /// The sample stages of a render white-balanced by the normalized neutral `n`.
    pub(crate) fn new(n: [f64; 3]) -> Samples {
        Samples {
            inv: [1.0 / n[0], 1.0, 1.0 / n[2]],
            #[cfg(test)]
            probe: PROBE.with(|p| p.get()),
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

/// [`Stage::Probe`]: scaled by the test's factor (1 but in the test that sets [`PROBE`]).
#[cfg(test)]
#[inline]
fn probe<T: Sample>(s: &Samples, v: T, _: usize) -> T {
    v * T::of(s.probe[0])
}

/// [`Stage::ProbeRgb`]: scaled by the test's second factor.
#[cfg(test)]
#[inline]
fn probe_rgb<T: Sample>(s: &Samples, v: T, _: usize) -> T {
    v * T::of(s.probe[1])
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
    samples: Samples,
}

impl Rows {
    /// The row stages of a render with the colour stage `colour` and the sample stages
    /// `samples`.
    pub(crate) fn new(colour: Colour, samples: Samples) -> Rows {
        Rows { colour, samples }
    }

    /// The stages of [`STAGES`] after the demosaic that are functions of a row or of a
    /// sample, in order, on one interleaved output row (a sample stage on each sample, its
    /// colour the position in the pixel).
    #[inline]
    pub fn run(&self, row: &mut [f32]) {
        let mut after = false;
        for &s in STAGES {
            match s.kind() {
                Kind::Demosaic => after = true,
                Kind::Row(f) => f(self, row),
                Kind::Sample(_, f) if after => {
                    for px in row.chunks_exact_mut(3) {
                        for (k, v) in px.iter_mut().enumerate() {
                            *v = f(&self.samples, *v, k);
                        }
                    }
                }
                _ => {}
            }
        }
    }
}

/// [`Stage::Colour`] on one interleaved row.
///
/// Compiled twice, the second time for AVX2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn colour(r: &Rows, row: &mut [f32]) {
    match &r.colour {
        Colour::Matrix(m) => matrix_row(row, m),
        Colour::Clip => clip_row(row),
    }
}

#[cfg(test)]
#[path = "stages_tests.rs"]
mod tests;
