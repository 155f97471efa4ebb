//! Checks of a file's opcode lists made before anything is rendered (docs/isp.md, "DNG
//! opcodes", "Checks before rendering"):
//!
//! * [`check_render`]: what a render does with the lists ([`super::prepare`]'s decision and
//!   report) plus the warnings it owes the user: optional opcodes it skips, opcodes whose
//!   parameters make every sample they touch one value (`flat_opcodes`: a GainMap whose
//!   gains are all <= 0, a MapPolynomial <= 0 over the whole value range, a MapTable of one
//!   value, a scale <= 0, a delta past the range, a vignette gain <= 0), and an OpcodeList3
//!   TrimBounds that changes the size of the rendered image;
//! * [`report_without_render`]: the same report for a job that renders nothing (`synth
//!   --target none`): a list that cannot be parsed, or a mandatory opcode that cannot be
//!   applied, is a warning there, not an error;
//! * [`unrenderable_lists`]: the lists that would make a render fail (what `convert`
//!   refuses or drops).
//!
//! The checks read parameters only (no pixel), so they cost nothing next to a render.

use super::area::plane_range;
use super::{
    prepare, prepare_lists_for, OpcodeEntry, OpcodeMode, OpcodeReport, Prepared, StageRect,
};
use crate::diagnostics::{Code, Diagnostics, Warning};
use crate::dng::opcodes::{
    list_results, lists, AreaSpec, ListId, Opcode, OpcodeKind, OpcodeList, FLAG_OPTIONAL,
};
use crate::error::{Error, Result};
use crate::raw::{RawImage, RawMeta};

/// What a render of a file does with its opcode lists, and what it must say about them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Checked {
    /// The opcodes applied and the report ([`super::prepare`]); `None` for a file without
    /// opcode lists.
    pub prepared: Option<Prepared>,
    /// Warnings, in pipeline order: skipped optional opcodes
    /// ([`OpcodeReport::warnings`]), then opcodes that make their samples one value, then
    /// a TrimBounds that changes the rendered size. No subject (the caller knows the file).
    pub warnings: Diagnostics,
    /// The rendered size (width, height) when an OpcodeList3 TrimBounds changes it (`None`
    /// otherwise).
    pub trimmed_size: Option<(usize, usize)>,
}

/// The checks of a render of `img` in `mode` with DefaultCrop (`crop`) and orientation
/// (`orient`) as the render applies them. Errors as the render would: a mandatory opcode
/// it cannot apply, a malformed list, a TrimBounds outside the image or leaving nothing of
/// the crop.
pub fn check_render(img: &RawImage, mode: OpcodeMode, crop: bool, orient: bool) -> Result<Checked> {
    let meta = &img.meta;
    if mode == OpcodeMode::Ignore || meta.opcode_lists.iter().all(Option::is_none) {
        return Ok(Checked {
            prepared: prepare(meta, mode)?,
            ..Checked::default()
        });
    }
    let parsed = lists(meta)?;
    let linear_raw = meta.linear_raw.is_some();
    let prepared = prepare_lists_for(&parsed, mode, linear_raw)?;
    if let Some(p) = &prepared {
        p.check_budget(img)?;
    }
    let mut warnings = prepared
        .as_ref()
        .map(|p| p.report.warnings())
        .unwrap_or_default();
    let geometry = StageGeometry::of(img);
    warnings.extend(flat_opcodes(&parsed, &geometry, linear_raw));
    let (trimmed_size, trim_warning) =
        trimmed_size(&parsed, &geometry, linear_raw, meta, crop, orient)?;
    warnings.extend(trim_warning);
    Ok(Checked {
        prepared,
        warnings,
        trimmed_size,
    })
}

/// The report of a job that renders nothing (no target, no network input): applicable
/// opcodes are listed as applied (what a render of the night raws would apply) and no-ops
/// as dropped, optional ones that cannot be applied as skipped, as [`super::prepare`] does;
/// a list that cannot be parsed and a mandatory opcode that cannot be applied are skipped
/// too, with a warning each, instead of failing the job. No work budget applies (nothing is
/// rendered). `None` for a file without opcode lists.
pub fn report_without_render(
    meta: &RawMeta,
    mode: OpcodeMode,
) -> (Option<OpcodeReport>, Diagnostics) {
    if mode == OpcodeMode::Ignore || meta.opcode_lists.iter().all(Option::is_none) {
        // prepare() neither parses nor fails in these cases.
        return (
            prepare(meta, mode).ok().flatten().map(|p| p.report),
            Diagnostics::new(),
        );
    }
    let linear_raw = meta.linear_raw.is_some();
    let reason = if linear_raw {
        super::unsupported_reason_linear_raw
    } else {
        super::unsupported_reason
    };
    // Lists as parsed, mandatory opcodes a render cannot apply made optional (so that
    // prepare skips them, as it skips the optional ones), and which were.
    let mut parsed: [OpcodeList; 3] = Default::default();
    let mut malformed: [Option<Error>; 3] = Default::default();
    let mut forced: [Vec<bool>; 3] = Default::default();
    for (id, result) in ListId::ALL.into_iter().zip(list_results(meta)) {
        match result {
            None => {}
            Some(Err(e)) => malformed[id.index()] = Some(e),
            Some(Ok(mut l)) => {
                for op in &mut l.opcodes {
                    if reason(id, &op.kind).is_some() {
                        forced[id.index()].push(!op.optional());
                        op.flags |= FLAG_OPTIONAL;
                    }
                }
                parsed[id.index()] = l;
            }
        }
    }
    let prepared = prepare_lists_for(&parsed, mode, linear_raw).ok().flatten();
    let mut report = prepared.map(|p| p.report).unwrap_or(OpcodeReport {
        mode,
        applied: vec![],
        skipped: vec![],
        dropped: vec![],
    });
    let mut skipped = std::mem::take(&mut report.skipped).into_iter();
    let mut warnings = Diagnostics::new();
    for id in ListId::ALL {
        if let Some(e) = &malformed[id.index()] {
            let (why, what) = match e.root() {
                Error::Limits(m) => (m.clone(), "exceeds a limit"),
                Error::Malformed(m) => (m.clone(), "is malformed"),
                other => (other.to_string(), "cannot be read"),
            };
            warnings.warn(
                Code::OpcodeListMalformed,
                format!(
                    "{why}: the list {what}; no render was requested, so it is not used (the \
                 night raws carry it as stored; a render of them fails the same way unless \
                 it ignores the opcode lists)"
                ),
            );
            report.skipped.push(OpcodeEntry {
                list: id.tag_name().into(),
                name: MALFORMED_LIST.into(),
                id: 0,
                reason: Some(why),
            });
            continue;
        }
        for &was_mandatory in &forced[id.index()] {
            let Some(mut e) = skipped.next() else { break };
            if was_mandatory {
                let why = e.reason.take().unwrap_or_default();
                warnings.warn(
                    Code::OpcodeNotApplied,
                    format!(
                        "{}: {} (id {}) is not optional and cannot be applied: {why}; no render \
                     was requested, so nothing fails (a render of this file or of its night \
                     raws would, unless it ignores the opcode lists)",
                        e.list, e.name, e.id
                    ),
                );
                e.reason = Some(format!("{why}; not optional (no render was requested)"));
            } else {
                // The same words as a render's warning.
                warnings.extend(
                    OpcodeReport {
                        mode,
                        applied: vec![],
                        skipped: vec![e.clone()],
                        dropped: vec![],
                    }
                    .warnings(),
                );
            }
            report.skipped.push(e);
        }
    }
    (Some(report), warnings)
}

/// [`OpcodeEntry::name`] of a list that cannot be parsed ([`report_without_render`]).
pub const MALFORMED_LIST: &str = "(malformed list)";

/// The lists of `img` that would make a render (CFA or LinearRaw, DefaultCrop applied)
/// fail, each with the reason: a list that cannot be parsed, a mandatory opcode that
/// cannot be applied, a TrimBounds outside the image or leaving nothing of the crop. Each
/// list is judged on its own, in pipeline order.
pub fn unrenderable_lists(img: &RawImage) -> Vec<(ListId, Error)> {
    let mut out = vec![];
    for (id, result) in ListId::ALL.into_iter().zip(list_results(&img.meta)) {
        let list = match result {
            None => continue,
            Some(Err(e)) => {
                out.push((id, e));
                continue;
            }
            Some(Ok(l)) => l,
        };
        let mut lists_: [OpcodeList; 3] = Default::default();
        lists_[id.index()] = list;
        let linear_raw = img.meta.linear_raw.is_some();
        let verdict = prepare_lists_for(&lists_, OpcodeMode::Apply, linear_raw).and_then(|_| {
            let g = StageGeometry::of(img);
            trimmed_size(&lists_, &g, linear_raw, &img.meta, true, true).map(|_| ())
        });
        if let Err(e) = verdict {
            out.push((id, e));
        }
    }
    out
}

/// Sizes of the stage images of a render.
#[derive(Debug, Clone, Copy)]
struct StageGeometry {
    /// The stored image (OpcodeList1's stage).
    stored: StageRect,
    /// The active area, in stored coordinates.
    active_in_stored: StageRect,
    /// Active width and height (OpcodeList2 and 3 work in active-area coordinates).
    active: (usize, usize),
}

impl StageGeometry {
    fn of(img: &RawImage) -> StageGeometry {
        let a = img.active_area();
        let (t, l) = (a.top as i64, a.left as i64);
        StageGeometry {
            stored: StageRect::of_size(img.width, img.height),
            active_in_stored: StageRect {
                t,
                l,
                b: t + a.height() as i64,
                r: l + a.width() as i64,
            },
            active: (a.width(), a.height()),
        }
    }
}

/// One stage image as a static check sees it.
#[derive(Debug, Clone, Copy)]
struct Stage {
    /// The stage image (relative positions of gain maps and vignette centres refer to it).
    extent: StageRect,
    /// The part of it that reaches the render (OpcodeList1: the active area).
    relevant: StageRect,
    /// Samples per pixel.
    planes: usize,
    /// Largest sample value (65535 for stage 1, 1 for stages 2 and 3).
    range: f32,
}

/// The samples an area opcode touches inside `rel`: rows, columns (first, end, pitch) and
/// planes.
#[derive(Debug, Clone)]
struct Touched {
    rows: (i64, i64, i64),
    cols: (i64, i64, i64),
    planes: Vec<usize>,
}

/// First index >= `lo` of the walk `start, start + pitch, ...`, and the walk's end within
/// `[lo, hi)` (None when the walk misses it).
fn walk(start: i64, end: i64, pitch: i64, lo: i64, hi: i64) -> Option<(i64, i64, i64)> {
    let first = if start >= lo {
        start
    } else {
        start + (lo - start + pitch - 1) / pitch * pitch
    };
    let end = end.min(hi);
    (first < end).then_some((first, end, pitch))
}

fn touched(kind: &OpcodeKind, s: &Stage) -> Option<Touched> {
    let rel = s.relevant;
    let Some(a) = kind.area() else {
        // The vignette: every sample of the stage.
        return Some(Touched {
            rows: (rel.t, rel.b, 1),
            cols: (rel.l, rel.r, 1),
            planes: (0..s.planes).collect(),
        })
        .filter(|_| rel.h() > 0 && rel.w() > 0);
    };
    let planes: Vec<usize> = plane_range(a, s.planes).collect();
    if planes.is_empty() {
        return None;
    }
    if a.top >= a.bottom || a.left >= a.right {
        // An empty area means the whole image (the SDK's rule).
        return (rel.h() > 0 && rel.w() > 0).then_some(Touched {
            rows: (rel.t, rel.b, 1),
            cols: (rel.l, rel.r, 1),
            planes,
        });
    }
    let rows = walk(
        a.top.into(),
        a.bottom.into(),
        a.row_pitch.max(1).into(),
        rel.t,
        rel.b,
    )?;
    let cols = walk(
        a.left.into(),
        a.right.into(),
        a.col_pitch.max(1).into(),
        rel.l,
        rel.r,
    )?;
    Some(Touched { rows, cols, planes })
}

/// Step indices (0-based) of the walk `(first, end, pitch)` of `a` along rows (`rows`) or
/// columns, as [`super::area`] indexes per-row and per-column values: from the area's
/// start, or the stage row/column itself for an empty area (the whole-image rule).
fn steps(a: &AreaSpec, rows: bool, (first, end, pitch): (i64, i64, i64)) -> std::ops::Range<usize> {
    let empty = a.top >= a.bottom || a.left >= a.right;
    let start = match (empty, rows) {
        (true, _) => 0,
        (false, true) => i64::from(a.top),
        (false, false) => i64::from(a.left),
    };
    let k0 = usize::try_from((first - start) / pitch).unwrap_or(0);
    let n = usize::try_from((end - first + pitch - 1) / pitch).unwrap_or(0);
    k0..k0.saturating_add(n)
}

/// How `kind` makes every sample it touches one value: (why, the value), for some planes
/// of `t` (the planes kept in `t`).
fn flat_kind(kind: &OpcodeKind, s: &Stage, t: &mut Touched) -> Option<(String, f32)> {
    let range = s.range;
    let unit = range / 65535.0;
    match kind {
        OpcodeKind::GainMap(g) => {
            let mp = (g.map_planes as usize).max(1);
            let max_of = |p: usize| {
                let m = p.min(mp - 1);
                g.gains
                    .iter()
                    .skip(m)
                    .step_by(mp)
                    .fold(f32::NEG_INFINITY, |a, &v| a.max(v))
            };
            t.planes.retain(|&p| max_of(p) <= 0.0);
            let top = t
                .planes
                .iter()
                .map(|&p| max_of(p))
                .fold(f32::NEG_INFINITY, f32::max);
            (!t.planes.is_empty()).then(|| {
                (
                    format!("every gain is <= 0 (the largest is {})", short(top)),
                    0.0,
                )
            })
        }
        OpcodeKind::MapTable { table, .. } => {
            let reach = table.len().min(65536);
            let v0 = *table.first()?;
            table[..reach].iter().all(|&v| v == v0).then(|| {
                (
                    format!("every entry the samples can reach is {v0}"),
                    v0 as f32 * unit,
                )
            })
        }
        OpcodeKind::MapPolynomial { coefficients, .. } => {
            let eval = |x: f64| {
                coefficients
                    .iter()
                    .rev()
                    .fold(0.0f64, |acc, &k| acc * x + k)
            };
            // Stage 1 holds integers; stages 2-3 any value in [0, 1], sampled at the 65536
            // 16-bit values.
            let out = |k: u32| {
                let x = f64::from(k) * f64::from(unit);
                let y = super::pin(eval(x) as f32, range);
                if range > 1.0 {
                    y.round()
                } else {
                    y
                }
            };
            let v0 = out(0);
            (0..=65535u32).all(|k| out(k) == v0).then(|| {
                let what = if v0 <= 0.0 {
                    "<= 0".to_string()
                } else if v0 >= range {
                    format!(">= {}", short(range))
                } else {
                    short(v0)
                };
                (
                    format!(
                        "the polynomial is {what} for every value in [0, {}]",
                        short(range)
                    ),
                    v0,
                )
            })
        }
        OpcodeKind::DeltaPerRow { area, deltas } | OpcodeKind::DeltaPerColumn { area, deltas } => {
            let used = if matches!(kind, OpcodeKind::DeltaPerRow { .. }) {
                steps(area, true, t.rows)
            } else {
                steps(area, false, t.cols)
            };
            let vals: Vec<f32> = deltas.get(used)?.iter().map(|d| d * unit).collect();
            if vals.is_empty() {
                None
            } else if vals.iter().all(|&d| d <= -range) {
                Some(("every delta is <= -65535 (16-bit units)".into(), 0.0))
            } else if vals.iter().all(|&d| d >= range) {
                Some(("every delta is >= 65535 (16-bit units)".into(), range))
            } else {
                None
            }
        }
        OpcodeKind::ScalePerRow { area, scales } | OpcodeKind::ScalePerColumn { area, scales } => {
            let used = if matches!(kind, OpcodeKind::ScalePerRow { .. }) {
                steps(area, true, t.rows)
            } else {
                steps(area, false, t.cols)
            };
            let vals = scales.get(used)?;
            let top = vals.iter().fold(f32::NEG_INFINITY, |a, &v| a.max(v));
            (!vals.is_empty() && top <= 0.0).then(|| {
                (
                    format!("every scale is <= 0 (the largest is {})", short(top)),
                    0.0,
                )
            })
        }
        OpcodeKind::FixVignetteRadial { k, center } => {
            vignette_never_positive(*k, *center, s.extent, s.relevant).then(|| {
                (
                    "the gain 1 + k0 r^2 + ... + k4 r^10 is <= 0 at every pixel".into(),
                    0.0,
                )
            })
        }
        _ => None,
    }
}

/// True when the vignette gain is <= 0 over the whole of `rel` (sampled along r^2 between
/// its smallest and largest value there, 4097 points and both ends).
fn vignette_never_positive(k: [f64; 5], center: [f64; 2], b: StageRect, rel: StageRect) -> bool {
    let lerp = |a: i64, z: i64, f: f64| a as f64 + (z - a) as f64 * f;
    let (cv, ch) = (lerp(b.t, b.b, center[1]), lerp(b.l, b.r, center[0]));
    let dv = (cv - b.t as f64).abs().max((cv - b.b as f64).abs());
    let dh = (ch - b.l as f64).abs().max((ch - b.r as f64).abs());
    let r = dv.hypot(dh);
    if !(r > 0.0 && r.is_finite()) || rel.h() <= 0 || rel.w() <= 0 {
        return false;
    }
    // Pixel centres of rel nearest to and farthest from the centre.
    let near = |c: f64, lo: i64, hi: i64| (c - 0.5).clamp(lo as f64, (hi - 1) as f64) + 0.5 - c;
    let far = |c: f64, lo: i64, hi: i64| {
        let (a, z) = (lo as f64 + 0.5 - c, (hi - 1) as f64 + 0.5 - c);
        if a.abs() > z.abs() {
            a
        } else {
            z
        }
    };
    let t0 = (near(cv, rel.t, rel.b).powi(2) + near(ch, rel.l, rel.r).powi(2)) / (r * r);
    let t1 = (far(cv, rel.t, rel.b).powi(2) + far(ch, rel.l, rel.r).powi(2)) / (r * r);
    let (t0, t1) = (t0.min(1.0), t1.min(1.0));
    let gain = |t: f64| 1.0 + k.iter().rev().fold(0.0f64, |acc, &kk| t * (kk + acc));
    (0..=4096).all(|i| gain(t0 + (t1 - t0) * f64::from(i) / 4096.0) <= 0.0)
        && gain(t0) <= 0.0
        && gain(t1) <= 0.0
}

/// A number in short form (`0.5`, `-2`, `1e-05`).
fn short(v: f32) -> String {
    format!("{}", v)
}

fn value_text(v: f32, range: f32) -> String {
    if v <= 0.0 {
        "0 (black)".into()
    } else if v >= range {
        format!("{} (the top of the range: white)", short(range))
    } else {
        short(v)
    }
}

fn region_text(t: &Touched, s: &Stage) -> String {
    let rel = s.relevant;
    let whole_rows = t.rows == (rel.t, rel.b, 1);
    let whole_cols = t.cols == (rel.l, rel.r, 1);
    let all_planes = t.planes.len() == s.planes;
    let walk = |(f, e, p): (i64, i64, i64), one: &str, many: &str| match p {
        1 => format!("{many} {f}..{e}"),
        2 => format!("every 2nd {one} of {f}..{e}"),
        3 => format!("every 3rd {one} of {f}..{e}"),
        p => format!("every {p}th {one} of {f}..{e}"),
    };
    let mut text = if whole_rows && whole_cols {
        "the whole image".to_string()
    } else {
        format!(
            "{}, {} of the image",
            walk(t.rows, "row", "rows"),
            walk(t.cols, "column", "columns")
        )
    };
    if s.planes > 1 && !all_planes {
        let list: Vec<String> = t.planes.iter().map(|p| p.to_string()).collect();
        let word = if t.planes.len() == 1 {
            "plane"
        } else {
            "planes"
        };
        text = format!("{word} {} of {text}", list.join(", "));
    }
    text
}

/// Warnings for the applicable opcodes of `parsed` whose parameters make every sample they
/// touch one value (0 for the "non-positive" cases: the stage images are pinned at 0),
/// named by list and position: "OpcodeList2: GainMap (opcode 1 of 1): every gain is <= 0
/// (the largest is -2): the whole image becomes 0 (black) ...".
fn flat_opcodes(parsed: &[OpcodeList; 3], g: &StageGeometry, linear_raw: bool) -> Vec<Warning> {
    let reason = if linear_raw {
        super::unsupported_reason_linear_raw
    } else {
        super::unsupported_reason
    };
    let cfa_planes = if linear_raw { 3 } else { 1 };
    let active = StageRect::of_size(g.active.0, g.active.1);
    let mut out = vec![];
    for id in ListId::ALL {
        let mut stage = match id {
            ListId::List1 => Stage {
                extent: g.stored,
                relevant: g.active_in_stored,
                planes: cfa_planes,
                range: 65535.0,
            },
            ListId::List2 => Stage {
                extent: active,
                relevant: active,
                planes: cfa_planes,
                range: 1.0,
            },
            ListId::List3 => Stage {
                extent: active,
                relevant: active,
                planes: 3,
                range: 1.0,
            },
        };
        let ops = &parsed[id.index()].opcodes;
        for (i, op) in ops.iter().enumerate() {
            if reason(id, &op.kind).is_some() {
                continue;
            }
            if let OpcodeKind::TrimBounds { bounds } = op.kind {
                if let Some(b) = trimmed(stage.extent, bounds) {
                    stage.extent = b;
                    stage.relevant = b;
                }
                continue;
            }
            if let Some(w) = flat_one(id, i, ops.len(), op, &stage) {
                out.push(w);
            }
        }
    }
    out
}

fn flat_one(id: ListId, i: usize, n: usize, op: &Opcode, s: &Stage) -> Option<Warning> {
    let mut t = touched(&op.kind, s)?;
    let (why, v) = flat_kind(&op.kind, s, &mut t)?;
    let message = format!(
        "{}: {} (opcode {} of {n}): {why}: {} becomes {} (render with --opcodes ignore to \
         leave the lists out)",
        id.tag_name(),
        op.name(),
        i + 1,
        region_text(&t, s),
        value_text(v, s.range)
    );
    Some(Warning::new(Code::OpcodeFlattens, message))
}

/// `rect` (top, left, bottom, right) when it is a non-empty rectangle inside `b`.
fn trimmed(b: StageRect, rect: [u32; 4]) -> Option<StageRect> {
    let nb = StageRect {
        t: rect[0].into(),
        l: rect[1].into(),
        b: rect[2].into(),
        r: rect[3].into(),
    };
    (nb.h() > 0 && nb.w() > 0 && nb.t >= b.t && nb.l >= b.l && nb.b <= b.b && nb.r <= b.r)
        .then_some(nb)
}

/// The rendered size (width, height) after a TrimBounds that changes it, and its warning.
type Trimmed = (Option<(usize, usize)>, Option<Warning>);

/// The rendered size after OpcodeList3's TrimBounds, when they change it, and the warning
/// that says so; errors as the render does for a TrimBounds outside the image or one that
/// leaves nothing of the crop.
fn trimmed_size(
    parsed: &[OpcodeList; 3],
    g: &StageGeometry,
    linear_raw: bool,
    meta: &RawMeta,
    crop: bool,
    orient: bool,
) -> Result<Trimmed> {
    let reason = if linear_raw {
        super::unsupported_reason_linear_raw
    } else {
        super::unsupported_reason
    };
    let (aw, ah) = g.active;
    let mut b = StageRect::of_size(aw, ah);
    let ops = &parsed[ListId::List3.index()].opcodes;
    let mut last = None;
    for (i, op) in ops.iter().enumerate() {
        if let OpcodeKind::TrimBounds { bounds } = op.kind {
            if reason(ListId::List3, &op.kind).is_some() {
                continue;
            }
            b = trimmed(b, bounds).ok_or_else(|| {
                Error::malformed(format!(
                    "OpcodeList3: TrimBounds {bounds:?} is empty or not inside the image ({}, {}, {}, {})",
                    b.t, b.l, b.b, b.r
                ))
            })?;
            last = Some(i);
        }
    }
    let Some(i) = last else {
        return Ok((None, None));
    };
    if aw == 0 || ah == 0 {
        return Ok((None, None));
    }
    let (whole, kept) = (
        StageRect::of_size(aw, ah).kept(meta, (aw, ah), crop)?,
        b.kept(meta, (aw, ah), crop)?,
    );
    let turned = orient && (5..=8).contains(&meta.orientation);
    let size = |k: StageRect| {
        let (w, h) = (k.w() as usize, k.h() as usize);
        if turned {
            (h, w)
        } else {
            (w, h)
        }
    };
    let (before, after) = (size(whole), size(kept));
    if before == after {
        return Ok((None, None));
    }
    let what = if crop { "default crop" } else { "active area" };
    let warning = format!(
        "OpcodeList3: TrimBounds (opcode {} of {}) keeps rows {}..{}, columns {}..{} of the \
         active area: rendered images are {}x{} pixels where the raw's {what} is {}x{} (raw \
         outputs keep the raw's size)",
        i + 1,
        ops.len(),
        b.t,
        b.b,
        b.l,
        b.r,
        after.0,
        after.1,
        before.0,
        before.1
    );
    Ok((Some(after), Some(Warning::new(Code::OpcodeTrim, warning))))
}

#[cfg(test)]
#[path = "check_tests.rs"]
mod tests;
