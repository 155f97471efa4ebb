//! DNG opcodes applied by the ISP (DNG specification 1.6, chapter 6), in the Adobe DNG SDK's
//! stage order: OpcodeList1 on the stored values, OpcodeList2 on the linear reference values
//! (after linearization, black subtraction and scaling to [0, 1]) before white balance and
//! demosaicing, OpcodeList3 on the demosaiced camera RGB before the colour matrix. The lists
//! are parsed by [`crate::dng::opcodes`]; this module decides what each list can apply
//! ([`prepare`]), and holds one file per opcode family: [`area`] (MapTable, MapPolynomial,
//! Delta/Scale per row/column), [`gain_map`], [`vignette`], [`bad_pixels`], [`warp`]
//! (WarpRectilinear, WarpFisheye) and [`trim`]. [`pipeline`] runs the stages for the
//! renders of [`crate::isp::render()`] and [`crate::isp::render_crop()`].
//!
//! Coordinates, as in the SDK: OpcodeList1 in stored-image coordinates (the whole stored
//! image); OpcodeList2 and OpcodeList3 in active-area coordinates (the SDK's stage-2 image
//! is the linearized active area, origin (0, 0); stage 3 has its size). Values: stage 1 in
//! stored units (range 0..=65535), stages 2 and 3 in [0, 1]; every opcode pins its results
//! into that range like the SDK's 16-bit stage images. See docs/isp.md, "DNG opcodes".

pub mod area;
pub mod bad_pixels;
pub(crate) mod banded;
pub mod budget;
pub mod check;
pub mod gain_map;
pub mod pipeline;
pub mod trim;
pub mod vignette;
pub mod warp;
pub(crate) mod warp_bounds;
pub mod warp_window;

use crate::dng::opcodes::{ListId, Opcode, OpcodeKind, OpcodeList};
use crate::error::{Error, Result};
use crate::raw::meta::RawMeta;
use crate::raw::RawImage;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Whether renders apply the file's opcode lists.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OpcodeMode {
    /// Apply them (the default; what the Adobe DNG SDK does).
    #[default]
    Apply,
    /// Ignore them (today's renders; what the authors' data preparation and LibRaw do).
    Ignore,
}

impl OpcodeMode {
    /// Both modes.
    pub const ALL: [OpcodeMode; 2] = [OpcodeMode::Apply, OpcodeMode::Ignore];
    /// True for [`OpcodeMode::Apply`] (serde's `skip_serializing_if`).
    pub fn is_apply(&self) -> bool {
        *self == OpcodeMode::Apply
    }
}

crate::choices! {
    OpcodeMode, ignore_case: true,
    unknown: |s| Error::invalid(format!(
        "opcodes {s:?} (use {})",
        crate::choice::listed::<OpcodeMode>(", ", " or ")
    )),
    Apply => "apply": "Apply them",
    Ignore => "ignore": "Ignore them (the authors' data preparation)",
}

/// One opcode as reported: its list, name and id, and why it was skipped (skipped ones).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct OpcodeEntry {
    /// "OpcodeList1", "OpcodeList2" or "OpcodeList3".
    pub list: String,
    /// The specification's name ("GainMap", ... or "unknown").
    pub name: String,
    /// The opcode id.
    pub id: u32,
    /// Why it was not applied (skipped entries only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// What a render does with a file's opcodes: the mode, the opcodes applied and those skipped
/// (optional ones this reader cannot apply). The synth plan records it (sidecar `plan.opcodes`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct OpcodeReport {
    /// The mode.
    pub mode: OpcodeMode,
    /// Applied, in pipeline order.
    #[serde(default)]
    pub applied: Vec<OpcodeEntry>,
    /// Skipped (optional, not applicable here), in pipeline order.
    #[serde(default)]
    pub skipped: Vec<OpcodeEntry>,
    /// Dropped before the render because they change nothing (an identity warp, gains of
    /// 1, ...; `reason` says which), in pipeline order; absent when none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dropped: Vec<OpcodeEntry>,
}

impl OpcodeReport {
    /// One warning line per skipped opcode ("OpcodeList3: WarpRectilinear2 (id 14), optional,
    /// skipped: not implemented").
    pub fn warnings(&self) -> crate::diagnostics::Diagnostics {
        self.skipped
            .iter()
            .map(|e| {
                crate::diagnostics::Warning::new(
                    crate::diagnostics::Code::OpcodeSkipped,
                    format!(
                        "{}: {} (id {}), optional, skipped: {}",
                        e.list,
                        e.name,
                        e.id,
                        e.reason.as_deref().unwrap_or("not applicable")
                    ),
                )
            })
            .collect()
    }
}

/// The opcodes a render applies, per list, and the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// Applicable opcodes of OpcodeList1, 2 and 3, in order (no-ops dropped).
    pub lists: [Vec<Opcode>; 3],
    /// What is applied, skipped and dropped.
    pub report: OpcodeReport,
    /// For each opcode of `lists`, its position (1-based) in its list and the list's length.
    pub positions: [Vec<(usize, usize)>; 3],
}

impl Prepared {
    /// True when nothing is applied (the plain render path runs).
    pub fn is_noop(&self) -> bool {
        self.lists.iter().all(|l| l.is_empty())
    }
    /// The applicable opcodes of `list`.
    pub fn list(&self, list: ListId) -> &[Opcode] {
        &self.lists[list.index()]
    }
    /// The cost of each opcode (docs/limits.md, "Opcode work") on an image of `stored`
    /// (width, height) with an active area of `active`.
    pub fn costs(
        &self,
        stored: (usize, usize),
        active: (usize, usize),
    ) -> Vec<crate::limits::OpcodeCost> {
        let mut out = vec![];
        for id in ListId::ALL {
            let dims = if id == ListId::List1 { stored } else { active };
            let ops = self.list(id);
            for (i, op) in ops.iter().enumerate() {
                let repeat = matches!(op.kind, OpcodeKind::FixBadPixelsConstant { .. })
                    && i > 0
                    && ops[i - 1].kind == op.kind;
                let (pos, n) = self.positions[id.index()]
                    .get(i)
                    .copied()
                    .unwrap_or((i + 1, ops.len()));
                out.push(crate::limits::OpcodeCost {
                    list: id.tag_name(),
                    what: format!("{} (opcode {pos} of {n})", op.name()),
                    cost: budget::cost(&op.kind, dims, repeat),
                });
            }
        }
        out
    }

    /// Error unless the work of these opcodes on `img` is within the budget in force
    /// ([`crate::limits::opcode_budget`]).
    pub fn check_budget(&self, img: &RawImage) -> Result<()> {
        let a = img.active_area();
        let costs = self.costs((img.width, img.height), (a.width(), a.height()));
        crate::limits::check_opcode_work(&costs, crate::limits::opcode_budget()?)
    }

    /// True when some applied opcode needs more than the samples it writes (bad pixels read
    /// neighbours, warps read anywhere, TrimBounds moves the image): a crop's render then
    /// needs the whole frame.
    pub fn needs_whole_frame(&self) -> bool {
        self.lists
            .iter()
            .flatten()
            .any(|op| !is_pointwise(&op.kind))
    }
}

/// True for the opcodes whose output sample depends only on the same sample and its
/// position.
pub fn is_pointwise(kind: &OpcodeKind) -> bool {
    matches!(
        kind,
        OpcodeKind::MapTable { .. }
            | OpcodeKind::MapPolynomial { .. }
            | OpcodeKind::GainMap(_)
            | OpcodeKind::DeltaPerRow { .. }
            | OpcodeKind::DeltaPerColumn { .. }
            | OpcodeKind::ScalePerRow { .. }
            | OpcodeKind::ScalePerColumn { .. }
            | OpcodeKind::FixVignetteRadial { .. }
    )
}

/// Why `kind` cannot be applied in `list` (None: it can).
pub fn unsupported_reason(list: ListId, kind: &OpcodeKind) -> Option<&'static str> {
    match kind {
        OpcodeKind::Unknown { .. } => Some("not implemented by day2night"),
        k if is_pointwise(k) => None,
        OpcodeKind::FixBadPixelsConstant { .. } | OpcodeKind::FixBadPixelsList { .. } => {
            (list == ListId::List3).then_some("bad pixels are fixed on the CFA mosaic (lists 1-2)")
        }
        OpcodeKind::WarpRectilinear { .. }
        | OpcodeKind::WarpFisheye { .. }
        | OpcodeKind::WarpRectilinear2 { .. } => (list != ListId::List3)
            .then_some("a warp of the CFA mosaic is not supported (OpcodeList3 only)"),
        OpcodeKind::TrimBounds { .. } => {
            (list != ListId::List3).then_some("TrimBounds is applied in OpcodeList3 only")
        }
        _ => Some("not implemented by day2night"),
    }
}

/// Why `kind` cannot be applied in `list` of a LinearRaw image (already demosaiced, three
/// planes; [`crate::isp::render_linear_raw`]): as [`unsupported_reason`], except that the
/// bad-pixel fixes, which repair a CFA mosaic, have nothing to work on.
pub fn unsupported_reason_linear_raw(list: ListId, kind: &OpcodeKind) -> Option<&'static str> {
    match kind {
        OpcodeKind::FixBadPixelsConstant { .. } | OpcodeKind::FixBadPixelsList { .. } => {
            Some("bad pixels are fixed on a CFA mosaic; a LinearRaw image has none")
        }
        k => unsupported_reason(list, k),
    }
}

fn entry(list: ListId, op: &Opcode, reason: Option<&str>) -> OpcodeEntry {
    OpcodeEntry {
        list: list.tag_name().into(),
        name: op.name().into(),
        id: op.id,
        reason: reason.map(str::to_string),
    }
}

/// Decide what a render of a file with these lists does: `None` when the file has no
/// opcode (or no list tag at all), else the applicable opcodes and the report. With
/// [`OpcodeMode::Ignore`] nothing is applied (the report lists nothing). An opcode that
/// cannot be applied is skipped when its optional flag is set, else an
/// [`Error::Unsupported`] naming the list, the opcode and its id.
pub fn prepare_lists(lists: &[OpcodeList; 3], mode: OpcodeMode) -> Result<Option<Prepared>> {
    prepare_lists_for(lists, mode, false)
}

/// [`prepare_lists`] for a CFA image (`linear_raw` false, [`unsupported_reason`]) or a
/// LinearRaw one ([`unsupported_reason_linear_raw`]).
pub fn prepare_lists_for(
    lists: &[OpcodeList; 3],
    mode: OpcodeMode,
    linear_raw: bool,
) -> Result<Option<Prepared>> {
    let reason = if linear_raw {
        unsupported_reason_linear_raw
    } else {
        unsupported_reason
    };
    if lists.iter().all(|l| l.opcodes.is_empty()) {
        return Ok(None);
    }
    let mut out: [Vec<Opcode>; 3] = Default::default();
    let mut positions: [Vec<(usize, usize)>; 3] = Default::default();
    let mut report = OpcodeReport {
        mode,
        applied: vec![],
        skipped: vec![],
        dropped: vec![],
    };
    if mode == OpcodeMode::Ignore {
        return Ok(Some(Prepared {
            lists: out,
            report,
            positions,
        }));
    }
    for id in ListId::ALL {
        let all = &lists[id.index()].opcodes;
        for (i, op) in all.iter().enumerate() {
            match reason(id, &op.kind) {
                None => {
                    let kept = &mut out[id.index()];
                    let noop = budget::noop_reason(&op.kind).or_else(|| {
                        budget::repeats_idempotently(kept.last(), op)
                            .then_some("repeats the opcode before it")
                    });
                    if let Some(why) = noop {
                        report.dropped.push(entry(id, op, Some(why)));
                        continue;
                    }
                    report.applied.push(entry(id, op, None));
                    kept.push(op.clone());
                    positions[id.index()].push((i + 1, all.len()));
                }
                Some(why) if op.optional() => report.skipped.push(entry(id, op, Some(why))),
                Some(why) => {
                    return Err(Error::unsupported(format!(
                        "{}: {} (id {}) is not optional and cannot be applied: {why} \
                         (render with --opcodes ignore to leave the lists out)",
                        id.tag_name(),
                        op.name(),
                        op.id
                    )))
                }
            }
        }
    }
    Ok(Some(Prepared {
        lists: out,
        report,
        positions,
    }))
}

/// [`prepare_lists_for`] on the lists of `meta` (parsed by [`crate::dng::opcodes::lists`]),
/// with the LinearRaw rules when `meta` is a LinearRaw image. Cheap when the file has no
/// list tag (no parsing).
pub fn prepare(meta: &RawMeta, mode: OpcodeMode) -> Result<Option<Prepared>> {
    if meta.opcode_lists.iter().all(|l| l.is_none()) {
        return Ok(None);
    }
    if mode == OpcodeMode::Ignore {
        // Not even parsed: ignoring a list must not fail on it.
        return Ok(Some(Prepared {
            lists: Default::default(),
            report: OpcodeReport {
                mode,
                applied: vec![],
                skipped: vec![],
                dropped: vec![],
            },
            positions: Default::default(),
        }));
    }
    prepare_lists_for(
        &crate::dng::opcodes::lists(meta)?,
        mode,
        meta.linear_raw.is_some(),
    )
}

/// The applicable opcodes of `meta` for a render in `mode`, `None` when the render takes
/// the plain path (no opcode, [`OpcodeMode::Ignore`], or nothing applicable).
pub fn active(meta: &RawMeta, mode: OpcodeMode) -> Result<Option<Prepared>> {
    Ok(prepare(meta, mode)?.filter(|p| !p.is_noop()))
}

/// [`prepare`] with the work of the applied opcodes checked against the budget on `img`'s
/// size ([`Prepared::check_budget`]): what planning calls, before any pixel work.
pub fn prepare_image(img: &RawImage, mode: OpcodeMode) -> Result<Option<Prepared>> {
    let p = prepare(&img.meta, mode)?;
    if let Some(p) = &p {
        p.check_budget(img)?;
    }
    Ok(p)
}

/// [`active`] with the budget checked ([`prepare_image`]).
pub fn active_image(img: &RawImage, mode: OpcodeMode) -> Result<Option<Prepared>> {
    Ok(prepare_image(img, mode)?.filter(|p| !p.is_noop()))
}

/// A rectangle `[t, b) x [l, r)` in the coordinates of a stage image: the extent of a stage
/// image (its `extent`) or a part of it. (Not a range of values: that is `crate::bounds`;
/// the DNG opcode TrimBounds keeps the spec's name and cuts a stage image to one of these.)
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StageRect {
    /// Top.
    pub t: i64,
    /// Left.
    pub l: i64,
    /// Bottom (exclusive).
    pub b: i64,
    /// Right (exclusive).
    pub r: i64,
}

impl StageRect {
    /// `[0, h) x [0, w)`.
    pub fn of_size(w: usize, h: usize) -> StageRect {
        StageRect {
            t: 0,
            l: 0,
            b: h as i64,
            r: w as i64,
        }
    }
    /// Height.
    pub fn h(&self) -> i64 {
        self.b - self.t
    }
    /// Width.
    pub fn w(&self) -> i64 {
        self.r - self.l
    }
    /// What this (trimmed) extent keeps of the DefaultCrop (`crop`) or of the whole
    /// `aw x ah` active area, in active-area coordinates: the render's output rectangle
    /// before orientation, planned by [`check`] and cut by the render alike. An error when
    /// nothing is kept.
    pub(crate) fn kept(
        &self,
        meta: &RawMeta,
        (aw, ah): (usize, usize),
        crop: bool,
    ) -> Result<StageRect> {
        let (x0, y0, cw, ch) = if crop {
            crate::isp::geometry::default_crop(meta, aw, ah)
        } else {
            (0, 0, aw, ah)
        };
        let k = StageRect {
            t: (y0 as i64).max(self.t),
            l: (x0 as i64).max(self.l),
            b: ((y0 + ch) as i64).min(self.b),
            r: ((x0 + cw) as i64).min(self.r),
        };
        if k.b <= k.t || k.r <= k.l {
            return Err(Error::malformed(
                "OpcodeList3: TrimBounds leaves nothing of the DefaultCrop area",
            ));
        }
        Ok(k)
    }
}

/// A rectangle of a stage image held in memory: `height` rows of `width` pixels of
/// `planes` interleaved samples from (`top`, `left`) (stage coordinates), inside the stage
/// image `extent` (relative positions of gain maps, optical centres and radii refer to
/// `extent`). Samples lie in `[0, range]` (65535 for stage 1, 1 for stages 2 and 3).
#[derive(Debug)]
pub struct Region<'a> {
    /// Samples.
    pub data: &'a mut [f32],
    /// Stage row of the first row.
    pub top: usize,
    /// Stage column of the first column.
    pub left: usize,
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Samples per pixel (1 for the CFA stages, 3 for stage 3).
    pub planes: usize,
    /// The whole stage image.
    pub extent: StageRect,
    /// Largest sample value.
    pub range: f32,
}

/// Pin `v` into `[0, range]` (NaN to 0), as the SDK's 16-bit stage images do.
#[inline]
pub fn pin(v: f32, range: f32) -> f32 {
    if v > 0.0 {
        v.min(range)
    } else {
        0.0
    }
}

/// A per-row operation: `(stage row, samples of the row)`.
type RowFn<'a> = dyn Fn(usize, &mut [f32]) + Sync + 'a;

/// Apply one pointwise opcode to every row of `reg` (in parallel over rows when `par`).
fn apply_pointwise(kind: &OpcodeKind, reg: &mut Region, par: bool) {
    let (left, width, planes, top) = (reg.left, reg.width, reg.planes, reg.top);
    let (extent, range) = (reg.extent, reg.range);
    let row_fn: Box<RowFn<'_>> = match kind {
        OpcodeKind::GainMap(g) => {
            let gm = gain_map::Prepared::new(g, extent);
            Box::new(move |r, row| gm.row(r, left, planes, range, row))
        }
        OpcodeKind::FixVignetteRadial { k, center } => {
            let v = vignette::Vignette::new(*k, *center, extent);
            Box::new(move |r, row| v.row(r, left, planes, range, row))
        }
        other => match area::AreaOp::new(other, range) {
            Some(op) => Box::new(move |r, row| op.row(r, left, planes, row)),
            None => return,
        },
    };
    if width == 0 || planes == 0 {
        return;
    }
    if par {
        reg.data
            .par_chunks_mut(width * planes)
            .enumerate()
            .for_each(|(i, row)| row_fn(top + i, row));
    } else {
        reg.data
            .chunks_mut(width * planes)
            .enumerate()
            .for_each(|(i, row)| row_fn(top + i, row));
    }
}

/// Apply `ops` in order to `reg` (pointwise opcodes and the bad-pixel fixes; warps and
/// TrimBounds are applied by [`pipeline`] on whole stage-3 images), in parallel over rows.
/// A run of identical FixBadPixelsConstant opcodes is one merged pass
/// ([`bad_pixels::fix_constant_repeated`]: the same samples as one pass per opcode).
pub fn apply_region(ops: &[Opcode], reg: &mut Region) {
    apply_region_with(ops, reg, true)
}

/// [`apply_region`] on the calling thread only (for the bands of a banded render, which
/// run in parallel themselves and must not wait for other rayon work).
pub fn apply_region_seq(ops: &[Opcode], reg: &mut Region) {
    apply_region_with(ops, reg, false)
}

fn apply_region_with(ops: &[Opcode], reg: &mut Region, par: bool) {
    let mut i = 0;
    while i < ops.len() {
        let op = &ops[i];
        i += 1;
        match &op.kind {
            OpcodeKind::FixBadPixelsConstant {
                constant,
                bayer_phase,
            } => {
                let mut n = 1;
                while i < ops.len() && ops[i].kind == op.kind {
                    n += 1;
                    i += 1;
                }
                bad_pixels::fix_constant_repeated(reg, *constant, *bayer_phase, n)
            }
            OpcodeKind::FixBadPixelsList {
                bayer_phase,
                points,
                rects,
            } => bad_pixels::fix_list(reg, *bayer_phase, points, rects),
            k if is_pointwise(k) => apply_pointwise(k, reg, par),
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dng::opcodes::{AreaSpec, FLAG_OPTIONAL};

    fn op(kind: OpcodeKind, id: u32, flags: u32) -> Opcode {
        Opcode {
            id,
            dng_version: [1, 3, 0, 0],
            flags,
            kind,
        }
    }

    fn area() -> AreaSpec {
        AreaSpec {
            top: 0,
            left: 0,
            bottom: 4,
            right: 4,
            plane: 0,
            planes: 1,
            row_pitch: 1,
            col_pitch: 1,
        }
    }

    #[test]
    fn unsupported_optional_is_skipped_and_mandatory_is_an_error() {
        let unknown = |flags| {
            op(
                OpcodeKind::Unknown {
                    params: vec![],
                    len: 0,
                },
                99,
                flags,
            )
        };
        let scale = op(
            OpcodeKind::ScalePerRow {
                area: area(),
                scales: vec![2.0; 4],
            },
            12,
            0,
        );
        let mut lists: [OpcodeList; 3] = Default::default();
        lists[1].opcodes = vec![scale.clone(), unknown(FLAG_OPTIONAL)];
        let p = prepare_lists(&lists, OpcodeMode::Apply).unwrap().unwrap();
        assert_eq!(p.list(ListId::List2), std::slice::from_ref(&scale));
        assert_eq!(p.report.applied.len(), 1);
        assert_eq!(p.report.skipped[0].id, 99);
        assert!(p.report.warnings()[0]
            .message
            .contains("OpcodeList2: unknown (id 99)"));
        lists[2].opcodes = vec![unknown(0)];
        let e = prepare_lists(&lists, OpcodeMode::Apply)
            .unwrap_err()
            .to_string();
        assert!(e.contains("OpcodeList3: unknown (id 99)"), "{e}");
        // ignore: nothing applied, nothing fails
        let p = prepare_lists(&lists, OpcodeMode::Ignore).unwrap().unwrap();
        assert!(p.is_noop());
        // a warp in list 2 is mandatory here: error naming it
        lists[2].opcodes.clear();
        lists[1].opcodes = vec![op(
            OpcodeKind::WarpFisheye {
                planes: vec![[1.0, 0.0, 0.0, 0.0]],
                center: [0.5, 0.5],
            },
            2,
            0,
        )];
        let e = prepare_lists(&lists, OpcodeMode::Apply)
            .unwrap_err()
            .to_string();
        assert!(e.contains("OpcodeList2: WarpFisheye (id 2)"), "{e}");
        assert!(prepare_lists(&Default::default(), OpcodeMode::Apply)
            .unwrap()
            .is_none());
    }

    #[test]
    fn modes_parse() {
        assert_eq!("apply".parse::<OpcodeMode>().unwrap(), OpcodeMode::Apply);
        assert_eq!("IGNORE".parse::<OpcodeMode>().unwrap(), OpcodeMode::Ignore);
        assert!("x".parse::<OpcodeMode>().is_err());
        assert_eq!(OpcodeMode::default(), OpcodeMode::Apply);
    }

    #[test]
    fn pin_is_nan_free() {
        assert_eq!(pin(f32::NAN, 1.0), 0.0);
        assert_eq!(pin(-1.0, 1.0), 0.0);
        assert_eq!(pin(2.0, 1.0), 1.0);
        assert_eq!(pin(f32::INFINITY, 65535.0), 65535.0);
    }
}
