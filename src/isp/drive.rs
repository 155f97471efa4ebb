//! The driver of every render: [`drive`] runs the stage list [`STAGES`] in order, each
//! stage by its [`Kind`], and hands what it made (a [`Pipe`]) to the execution, a [`Walk`]
//! that supplies only how it walks the image (docs/isp.md, "The pipeline").
//!
//! Per kind, the driver makes the stage ready to run:
//!
//! * an opcode list ([`Kind::Opcodes`]): the file's lists, prepared once as the options say
//!   (none: the identity);
//! * the normalization ([`Kind::Normalize`]): the neutral and the sample stages
//!   ([`Samples`]) the pre-demosaic step (`CfaSites`, pre_demosaic.rs) fuses with it;
//! * a sample stage ([`Kind::Sample`]): nothing to make, it runs in list order inside the
//!   pre-demosaic step ([`Samples::between`]) or, after the demosaic, on every output row
//!   ([`Rows::run`]);
//! * the demosaic ([`Kind::Demosaic`]): the demosaicer;
//! * a row stage ([`Kind::Row`]): the colour stage's matrix or clip ([`Rows`]);
//! * a geometry stage ([`Kind::Geometry`]): whether it applies.
//!
//! A walk is one execution: the whole frame, bands (with or without opcodes), a crop from
//! its samples or from the frame, a LinearRaw image. It decides which rows or region it
//! computes and with what context (bands and where they go, a crop's margin, a warp's
//! window), and takes every stage from the pipe, whose parts only the driver makes; every
//! public render starts with [`drive`]. The stages that need a neighbourhood or a region
//! (opcodes, normalization, demosaic, geometry) keep the DNG SDK's order in every walk;
//! [`check_order`] refuses a list whose stages stand where no walk could run them in
//! order.

use super::color::normalize_neutral;
use super::demosaic::Demosaic;
use super::opcodes::{self, Prepared};
use super::render_parts::{color_matrix, resolve_neutral, Output, RenderOptions};
use super::stages::{Colour, Geo, Kind, Rows, Samples, Stage, STAGES};
use crate::dng::opcodes::ListId;
use crate::error::{Error, Result};
use crate::raw::RawImage;

/// One execution of a render: how it walks the image, given the stages [`drive`] made.
pub(crate) trait Walk {
    /// What the walk makes (an image, bands; `None` when it cannot run this render).
    type Out;
    /// The execution's name, in the log of the driven renders that the unit tests read.
    #[cfg_attr(not(test), allow(dead_code))]
    const NAME: &'static str;
    /// The render of `pipe`'s stages, walked this execution's way.
    fn walk(self, pipe: &Pipe) -> Result<Self::Out>;
}

/// The stages of one render, made ready by [`drive`] from [`STAGES`] (see the module docs).
pub(crate) struct Pipe<'a> {
    /// The image rendered.
    pub(crate) img: &'a RawImage,
    opcodes: Option<Prepared>,
    neutral: [f64; 3],
    samples: Samples,
    method: Demosaic,
    rows: Rows,
    crop: bool,
    orient: bool,
}

impl Pipe<'_> {
    /// The opcode lists that apply ([`Kind::Opcodes`]); `None`: the three stages are the
    /// identity.
    pub(crate) fn opcodes(&self) -> Option<&Prepared> {
        self.opcodes.as_ref()
    }

    /// The neutral, normalized to green = 1 (what OpcodeList3 takes out and puts back).
    pub(crate) fn neutral(&self) -> [f64; 3] {
        self.neutral
    }

    /// The sample stages ([`Kind::Sample`]), for a walk that normalizes the samples itself
    /// (a LinearRaw image, per plane).
    pub(crate) fn samples(&self) -> Samples {
        self.samples
    }

    /// The demosaicer ([`Kind::Demosaic`]).
    pub(crate) fn method(&self) -> Demosaic {
        self.method
    }

    /// The stages run on every output row ([`Rows::run`]).
    pub(crate) fn rows(&self) -> Rows {
        self.rows
    }

    /// Whether DefaultCrop and orientation apply ([`Kind::Geometry`]).
    pub(crate) fn geometry(&self) -> (bool, bool) {
        (self.crop, self.orient)
    }
}

/// What [`drive`] returns: the walk's result and the stages run, in order.
pub(crate) struct Driven<T> {
    /// The walk's result.
    pub(crate) out: T,
    /// The stages of [`STAGES`] the driver ran.
    pub(crate) stages: Vec<Stage>,
}

impl<T> Driven<T> {
    /// The result mapped by `f`, the stages kept.
    pub(crate) fn map<U>(self, f: impl FnOnce(T) -> U) -> Driven<U> {
        Driven {
            out: f(self.out),
            stages: self.stages,
        }
    }
}

/// The render of `img` with `opts`: every stage of [`STAGES`], in order, made ready by its
/// kind (see the module docs), then walked as `walk` does.
pub(crate) fn drive<W: Walk>(
    img: &RawImage,
    opts: &RenderOptions,
    walk: W,
) -> Result<Driven<W::Out>> {
    check_order(STAGES)?;
    let neutral = resolve_neutral(&img.meta, opts.neutral)?;
    // Every part starts as the identity; the stages of the list make theirs.
    let identity = Samples::new([1.0; 3]);
    let mut pipe = Pipe {
        img,
        opcodes: None,
        neutral: [1.0; 3],
        samples: identity,
        method: opts.demosaic,
        rows: Rows::new(Colour::Clip, identity),
        crop: false,
        orient: false,
    };
    let mut prepared = false;
    let mut colour = Colour::Clip;
    let mut stages = Vec::with_capacity(STAGES.len());
    for &s in STAGES {
        match s.kind() {
            Kind::Opcodes(_) if !prepared => {
                pipe.opcodes = opcodes::active_image(img, opts.opcodes)?;
                prepared = true;
            }
            Kind::Opcodes(_) | Kind::Sample(..) => {}
            Kind::Normalize => {
                pipe.neutral = normalize_neutral(neutral)?;
                pipe.samples = Samples::new(pipe.neutral);
            }
            Kind::Demosaic => pipe.method = opts.demosaic,
            Kind::Row(_) => {
                if let Output::Linear = opts.output {
                    let m = color_matrix(&img.meta, neutral)?;
                    colour = Colour::Matrix(m.map(|r| r.map(|v| v as f32)));
                }
            }
            Kind::Geometry(Geo::DefaultCrop) => pipe.crop = opts.crop,
            Kind::Geometry(Geo::Orientation) => pipe.orient = opts.orient,
        }
        stages.push(s);
    }
    pipe.rows = Rows::new(colour, pipe.samples);
    #[cfg(test)]
    DRIVEN.with(|d| d.borrow_mut().push((W::NAME, stages.clone())));
    let out = walk.walk(&pipe)?;
    Ok(Driven { out, stages })
}

#[cfg(test)]
thread_local! {
    /// The renders this thread drove: the walk's name and the stages run.
    pub(crate) static DRIVEN: std::cell::RefCell<Vec<(&'static str, Vec<Stage>)>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// The stages of [`STAGES`] that need a neighbourhood or a region, in the order every walk
/// runs them (the DNG SDK's).
const WALKED: [Kind; 7] = [
    Kind::Opcodes(ListId::List1),
    Kind::Normalize,
    Kind::Opcodes(ListId::List2),
    Kind::Demosaic,
    Kind::Opcodes(ListId::List3),
    Kind::Geometry(Geo::DefaultCrop),
    Kind::Geometry(Geo::Orientation),
];

/// Checks that the walks run the stage list `list` ([`STAGES`]) in its order: the stages of
/// [`WALKED`] in that order, a sample stage after the normalization and not between the
/// demosaic and OpcodeList3, a row stage after OpcodeList3.
pub(crate) fn check_order(list: &[Stage]) -> Result<()> {
    let mut at = 0;
    for &s in list {
        let k = s.kind();
        let ok = match k {
            Kind::Sample(..) => (2..=3).contains(&at) || at >= WALKED.len() - 2,
            Kind::Row(_) => at >= WALKED.len() - 2,
            _ => {
                let next = WALKED.get(at).is_some_and(|w| same(*w, k));
                at += 1;
                next
            }
        };
        if !ok {
            return Err(Error::invalid(format!(
                "the stage {} stands where no execution can run it in list order",
                s.name()
            )));
        }
    }
    if at != WALKED.len() {
        return Err(Error::invalid(
            "the stage list lacks a stage every execution walks",
        ));
    }
    Ok(())
}

/// The same kind, the functions of sample and row stages aside.
fn same(a: Kind, b: Kind) -> bool {
    match (a, b) {
        (Kind::Opcodes(x), Kind::Opcodes(y)) => x == y,
        (Kind::Geometry(x), Kind::Geometry(y)) => x == y,
        (Kind::Normalize, Kind::Normalize) | (Kind::Demosaic, Kind::Demosaic) => true,
        _ => false,
    }
}
