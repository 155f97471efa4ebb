//! DNG opcodes (DNG specification 1.6, chapter 6), parsed into types. The DNG layer parses and
//! writes them; the ISP ([`crate::isp::opcodes`]) applies them. The raw bytes of each list stay
//! in [`crate::raw::meta::RawMeta::opcode_lists`] so a night DNG carries them byte for byte.
//!
//! An opcode list is big-endian whatever the file's byte order: a `u32` count, then per
//! opcode its id, the DNG version it needs (4 bytes), flags (bit 0: optional, bit 1: may be
//! skipped for previews), the byte count of its parameters and the parameters.

use serde::Serialize;

pub mod describe;
mod encode;
mod parse;

pub use encode::{encode_list, encode_params};
pub use parse::{area_col_steps, area_row_steps, parse_list};

use crate::error::Result;
use crate::raw::meta::RawMeta;

/// Which of the three lists an opcode came from: where in the pipeline it applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum ListId {
    /// OpcodeList1: on the stored values, before linearization.
    List1,
    /// OpcodeList2: on linear reference values (after linearization, black subtraction and
    /// scaling to [0, 1]), before white balance and demosaicing.
    List2,
    /// OpcodeList3: on the demosaiced camera RGB image, before colour conversion.
    List3,
}

impl ListId {
    /// The three lists in pipeline order.
    pub const ALL: [ListId; 3] = [ListId::List1, ListId::List2, ListId::List3];

    /// The TIFF tag name ("OpcodeList1" ...).
    pub fn tag_name(self) -> &'static str {
        match self {
            ListId::List1 => "OpcodeList1",
            ListId::List2 => "OpcodeList2",
            ListId::List3 => "OpcodeList3",
        }
    }

    /// Index into [`crate::raw::meta::RawMeta::opcode_lists`].
    pub fn index(self) -> usize {
        match self {
            ListId::List1 => 0,
            ListId::List2 => 1,
            ListId::List3 => 2,
        }
    }
}

/// Opcode flag bit 0: a reader that does not know the opcode may skip it.
pub const FLAG_OPTIONAL: u32 = 1;
/// Opcode flag bit 1: may be skipped for preview-quality renders.
pub const FLAG_PREVIEW_SKIP: u32 = 2;

/// One parsed opcode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Opcode {
    /// Opcode id (1 WarpRectilinear ... 14 WarpRectilinear2, others unknown to this reader).
    pub id: u32,
    /// The DNG version the opcode needs, as stored.
    pub dng_version: [u8; 4],
    /// Flags ([`FLAG_OPTIONAL`], [`FLAG_PREVIEW_SKIP`]).
    pub flags: u32,
    /// The parameters.
    pub kind: OpcodeKind,
}

impl Opcode {
    /// An opcode of a known kind (its id from [`OpcodeKind::id`]; 0 for
    /// [`OpcodeKind::Unknown`], whose id the caller sets), DNG version 1.3.0.0 (the version
    /// that introduced opcodes) and `flags`.
    pub fn new(kind: OpcodeKind, flags: u32) -> Opcode {
        Opcode {
            id: kind.id().unwrap_or(0),
            dng_version: [1, 3, 0, 0],
            flags,
            kind,
        }
    }

    /// Bit 0 of the flags: a reader may skip it when it cannot apply it.
    pub fn optional(&self) -> bool {
        self.flags & FLAG_OPTIONAL != 0
    }
}

/// The area an opcode of the "area" family acts on (MapTable, MapPolynomial, GainMap,
/// Delta/Scale per row/column): a rectangle of the image (in image coordinates of the stage:
/// stored-image coordinates for list 1; active-area coordinates for lists 2 and 3, whose
/// stage images the Adobe SDK builds with the active area's origin at (0, 0)), a range of planes, and a row/column pitch (only every `row_pitch`-th row and
/// `col_pitch`-th column from `top`/`left` is touched).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct AreaSpec {
    /// First row of the area.
    pub top: u32,
    /// First column of the area.
    pub left: u32,
    /// One past the last row.
    pub bottom: u32,
    /// One past the last column.
    pub right: u32,
    /// First plane.
    pub plane: u32,
    /// Number of planes.
    pub planes: u32,
    /// Row step.
    pub row_pitch: u32,
    /// Column step.
    pub col_pitch: u32,
}

/// WarpRectilinear coefficients of one plane: radial `kr0..kr3` and tangential `kt0, kt1`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WarpPlane {
    /// Radial coefficients kr0..kr3.
    pub kr: [f64; 4],
    /// Tangential coefficients kt0, kt1.
    pub kt: [f64; 2],
}

/// WarpRectilinear2 coefficients of one plane (DNG 1.6): radial `kr0..kr14` of the
/// polynomial in `r` (not `r^2`), tangential `kt0, kt1`, and the valid radius range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WarpPlane2 {
    /// Radial coefficients kr0..kr14: `ratio = sum kr_i r^i` (or its reciprocal).
    pub kr: [f64; 15],
    /// Tangential coefficients kt0, kt1.
    pub kt: [f64; 2],
    /// Minimum and maximum valid radius (`0 <= min < max <= 1`): `r` is clamped into it.
    pub valid: [f64; 2],
}

/// GainMap (id 9): a grid of gains, bilinearly interpolated, multiplied into the area.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GainMap {
    /// Area, planes and pitch.
    pub area: AreaSpec,
    /// Map rows.
    pub points_v: u32,
    /// Map columns.
    pub points_h: u32,
    /// Row spacing of the map points, relative to the image height (0..1 spans the image).
    pub spacing_v: f64,
    /// Column spacing, relative to the image width.
    pub spacing_h: f64,
    /// Row of the first map point, relative to the image height.
    pub origin_v: f64,
    /// Column of the first map point, relative to the image width.
    pub origin_h: f64,
    /// Planes of the map (1: the same gains for every plane).
    pub map_planes: u32,
    /// `points_v * points_h * map_planes` gains, row-major, planes interleaved last.
    pub gains: Vec<f32>,
}

/// The parameters of each opcode the reader knows.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type")]
pub enum OpcodeKind {
    /// 1: lens distortion (radial + tangential) per plane, about an optical centre given in
    /// relative coordinates of the image.
    WarpRectilinear {
        /// One entry per plane (1 = all planes alike, or one per plane).
        planes: Vec<WarpPlane>,
        /// Optical centre (x, y), relative (0..1).
        center: [f64; 2],
    },
    /// 2: fisheye distortion per plane (`kr0..kr3`).
    WarpFisheye {
        /// Radial coefficients per plane.
        planes: Vec<[f64; 4]>,
        /// Optical centre (x, y), relative.
        center: [f64; 2],
    },
    /// 14 (DNG 1.6): lens distortion with a 15-term radial polynomial in `r`, optionally
    /// its reciprocal, a valid radius range and tangential terms, per plane.
    WarpRectilinear2 {
        /// One entry per plane (1 = all planes alike, or one per plane).
        planes: Vec<WarpPlane2>,
        /// Optical centre (x, y), relative (0..1).
        center: [f64; 2],
        /// The radial ratio is `1 / sum kr_i r^i` instead of the sum.
        reciprocal: bool,
    },
    /// 3: radial vignette correction, gain `1 + k0 r^2 + k1 r^4 + ... + k4 r^10`.
    FixVignetteRadial {
        /// k0..k4.
        k: [f64; 5],
        /// Optical centre (x, y), relative.
        center: [f64; 2],
    },
    /// 4: CFA samples equal to `constant` are bad: replaced from same-colour neighbours.
    FixBadPixelsConstant {
        /// The stored value that marks a bad pixel.
        constant: u32,
        /// Bayer phase (0: top-left red ... per the spec: 0 R, 1 G on R row, 2 G on B row, 3 B).
        bayer_phase: u32,
    },
    /// 5: listed bad pixels and rectangles, replaced from same-colour neighbours.
    FixBadPixelsList {
        /// Bayer phase.
        bayer_phase: u32,
        /// Bad points (row, column).
        points: Vec<[u32; 2]>,
        /// Bad rectangles (top, left, bottom, right).
        rects: Vec<[u32; 4]>,
    },
    /// 6: the image is trimmed to these bounds (top, left, bottom, right).
    TrimBounds {
        /// Top, left, bottom, right.
        bounds: [u32; 4],
    },
    /// 7: a lookup table applied to the area (values past its end take the last entry).
    MapTable {
        /// Area, planes and pitch.
        area: AreaSpec,
        /// The table (at least one entry).
        table: Vec<u16>,
    },
    /// 8: a polynomial of the value applied to the area.
    MapPolynomial {
        /// Area, planes and pitch.
        area: AreaSpec,
        /// Coefficients c0..cN (degree N = len - 1).
        coefficients: Vec<f64>,
    },
    /// 9: gain map (lens shading).
    GainMap(GainMap),
    /// 10: a delta added per row of the area.
    DeltaPerRow {
        /// Area, planes and pitch.
        area: AreaSpec,
        /// One delta per row step.
        deltas: Vec<f32>,
    },
    /// 11: a delta added per column of the area.
    DeltaPerColumn {
        /// Area, planes and pitch.
        area: AreaSpec,
        /// One delta per column step.
        deltas: Vec<f32>,
    },
    /// 12: a scale per row of the area.
    ScalePerRow {
        /// Area, planes and pitch.
        area: AreaSpec,
        /// One scale per row step.
        scales: Vec<f32>,
    },
    /// 13: a scale per column of the area.
    ScalePerColumn {
        /// Area, planes and pitch.
        area: AreaSpec,
        /// One scale per column step.
        scales: Vec<f32>,
    },
    /// An opcode id this reader does not model; its parameters are kept as bytes.
    Unknown {
        /// Parameter bytes, as stored.
        #[serde(skip)]
        params: Vec<u8>,
        /// Their count.
        len: usize,
    },
}

impl OpcodeKind {
    /// The opcode id of this kind (`None` for [`OpcodeKind::Unknown`]).
    pub fn id(&self) -> Option<u32> {
        Some(match self {
            OpcodeKind::WarpRectilinear { .. } => 1,
            OpcodeKind::WarpFisheye { .. } => 2,
            OpcodeKind::FixVignetteRadial { .. } => 3,
            OpcodeKind::FixBadPixelsConstant { .. } => 4,
            OpcodeKind::FixBadPixelsList { .. } => 5,
            OpcodeKind::TrimBounds { .. } => 6,
            OpcodeKind::MapTable { .. } => 7,
            OpcodeKind::MapPolynomial { .. } => 8,
            OpcodeKind::GainMap(_) => 9,
            OpcodeKind::DeltaPerRow { .. } => 10,
            OpcodeKind::DeltaPerColumn { .. } => 11,
            OpcodeKind::ScalePerRow { .. } => 12,
            OpcodeKind::ScalePerColumn { .. } => 13,
            OpcodeKind::WarpRectilinear2 { .. } => 14,
            OpcodeKind::Unknown { .. } => return None,
        })
    }

    /// The area of the area-family opcodes (MapTable, MapPolynomial, GainMap, Delta/Scale per
    /// row/column); `None` for the others.
    pub fn area(&self) -> Option<&AreaSpec> {
        match self {
            OpcodeKind::MapTable { area, .. }
            | OpcodeKind::MapPolynomial { area, .. }
            | OpcodeKind::DeltaPerRow { area, .. }
            | OpcodeKind::DeltaPerColumn { area, .. }
            | OpcodeKind::ScalePerRow { area, .. }
            | OpcodeKind::ScalePerColumn { area, .. } => Some(area),
            OpcodeKind::GainMap(g) => Some(&g.area),
            _ => None,
        }
    }
}

/// The name of an opcode id, as the DNG specification spells it.
pub fn opcode_name(id: u32) -> &'static str {
    match id {
        1 => "WarpRectilinear",
        2 => "WarpFisheye",
        3 => "FixVignetteRadial",
        4 => "FixBadPixelsConstant",
        5 => "FixBadPixelsList",
        6 => "TrimBounds",
        7 => "MapTable",
        8 => "MapPolynomial",
        9 => "GainMap",
        10 => "DeltaPerRow",
        11 => "DeltaPerColumn",
        12 => "ScalePerRow",
        13 => "ScalePerColumn",
        14 => "WarpRectilinear2",
        _ => "unknown",
    }
}

impl Opcode {
    /// The specification's name of this opcode.
    pub fn name(&self) -> &'static str {
        opcode_name(self.id)
    }
}

/// A parsed opcode list.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct OpcodeList {
    /// The opcodes in the order they apply.
    pub opcodes: Vec<Opcode>,
}

/// Each of the three lists of `meta` parsed, in pipeline order: `None` where the tag is
/// absent, else the parse result, its error prefixed with the tag name
/// ("OpcodeList2: GainMap (opcode 1 of 4): MapPointsV is 0, ..."). `info` uses this to
/// describe the good lists of a file whose other list is malformed.
pub fn list_results(meta: &RawMeta) -> [Option<Result<OpcodeList>>; 3] {
    ListId::ALL.map(|id| {
        meta.opcode_lists[id.index()]
            .as_deref()
            .map(|b| parse_list(b).map_err(|e| parse::prefixed(e, id.tag_name())))
    })
}

/// The three lists of `meta` parsed, in pipeline order (an empty list where the tag is
/// absent); the first malformed one is an error naming its tag.
pub fn lists(meta: &RawMeta) -> Result<[OpcodeList; 3]> {
    let [a, b, c] = list_results(meta);
    let get = |r: Option<Result<OpcodeList>>| r.unwrap_or_else(|| Ok(OpcodeList::default()));
    Ok([get(a)?, get(b)?, get(c)?])
}

#[cfg(test)]
mod tests;
