//! Parse an opcode list (the value of OpcodeList1/2/3) into [`OpcodeList`]: big-endian always,
//! every count checked against the bytes and against the bounds of [`crate::limits`] before
//! anything is allocated, every parameter checked against DNG 1.6 chapter 6. Errors are
//! [`Error::Malformed`] (or [`Error::Limits`] for a bound) naming the opcode, its position in
//! the list and the field; [`super::lists`] adds the list's tag name in front.

use super::{AreaSpec, GainMap, Opcode, OpcodeKind, OpcodeList, WarpPlane, WarpPlane2};
use crate::error::{Error, Result};
use crate::limits::{
    MAX_BAD_PIXEL_ENTRIES, MAX_GAIN_MAP_POINTS, MAX_MAP_TABLE_LEN, MAX_OPCODES_PER_LIST,
    MAX_PER_LINE_ENTRIES, MAX_POLYNOMIAL_DEGREE, MAX_WARP_PLANES,
};

/// Bytes of one opcode's header: id, DNG version, flags, parameter byte count.
pub(crate) const HEADER_BYTES: usize = 16;
/// Bytes of an area specification (top, left, bottom, right, plane, planes, pitches).
pub(crate) const AREA_BYTES: usize = 32;
/// Bytes of a GainMap's fixed part: area, points (2), spacing (2), origin (2), map planes.
pub(crate) const GAIN_MAP_FIXED_BYTES: usize = AREA_BYTES + 8 + 32 + 4;

/// Parse one opcode list (the bytes of an OpcodeList tag).
pub fn parse_list(bytes: &[u8]) -> Result<OpcodeList> {
    if bytes.len() < 4 {
        return Err(Error::malformed(format!(
            "{} bytes: too short for the opcode count (4 bytes)",
            bytes.len()
        )));
    }
    let count = be_u32(bytes, 0);
    if count > MAX_OPCODES_PER_LIST {
        return Err(Error::limits(format!(
            "{count} opcodes: more than the limit of {MAX_OPCODES_PER_LIST} per list"
        )));
    }
    let rest = (bytes.len() - 4) as u64;
    if u64::from(count) * HEADER_BYTES as u64 > rest {
        return Err(Error::malformed(format!(
            "{count} opcodes need at least {} bytes of headers, the list has {rest} after the count",
            u64::from(count) * HEADER_BYTES as u64
        )));
    }
    let mut opcodes = Vec::with_capacity(count as usize);
    let mut pos = 4usize;
    for i in 0..count {
        let ordinal = i + 1;
        let left = bytes.len() - pos;
        if left < HEADER_BYTES {
            return Err(Error::malformed(format!(
                "opcode {ordinal} of {count}: header needs {HEADER_BYTES} bytes, {left} left"
            )));
        }
        let id = be_u32(bytes, pos);
        let dng_version = [
            bytes[pos + 4],
            bytes[pos + 5],
            bytes[pos + 6],
            bytes[pos + 7],
        ];
        let flags = be_u32(bytes, pos + 8);
        let n = be_u32(bytes, pos + 12) as usize;
        pos += HEADER_BYTES;
        let what = format!("{} (opcode {ordinal} of {count})", super::opcode_name(id));
        let left = bytes.len() - pos;
        if n > left {
            return Err(Error::malformed(format!(
                "{what}: parameter byte count {n} runs past the end of the list ({left} bytes left)"
            )));
        }
        let params = &bytes[pos..pos + n];
        pos += n;
        let kind = parse_kind(id, params).map_err(|e| prefixed(e, &what))?;
        opcodes.push(Opcode {
            id,
            dng_version,
            flags,
            kind,
        });
    }
    if pos != bytes.len() {
        return Err(Error::malformed(format!(
            "{} bytes after the last of {count} opcodes",
            bytes.len() - pos
        )));
    }
    Ok(OpcodeList { opcodes })
}

/// `e` with `prefix: ` in front of its message (Malformed and Limits; others unchanged).
pub(crate) fn prefixed(e: Error, prefix: &str) -> Error {
    match e {
        Error::Malformed(m) => Error::Malformed(format!("{prefix}: {m}")),
        Error::Limits(m) => Error::Limits(format!("{prefix}: {m}")),
        e => e,
    }
}

fn be_u32(b: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    w.copy_from_slice(&b[at..at + 4]);
    u32::from_be_bytes(w)
}

/// A cursor over one opcode's parameters. Sizes are checked before reading, so running out
/// is a bug; it is still an error, never a panic.
struct Params<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Params<'a> {
    fn take<const N: usize>(&mut self, field: &str) -> Result<[u8; N]> {
        let end = self.pos.checked_add(N).filter(|&e| e <= self.b.len());
        let Some(end) = end else {
            return Err(Error::malformed(format!(
                "parameters end before {field} ({} bytes)",
                self.b.len()
            )));
        };
        let mut w = [0u8; N];
        w.copy_from_slice(&self.b[self.pos..end]);
        self.pos = end;
        Ok(w)
    }
    fn u32(&mut self, field: &str) -> Result<u32> {
        Ok(u32::from_be_bytes(self.take::<4>(field)?))
    }
    fn u16(&mut self, field: &str) -> Result<u16> {
        Ok(u16::from_be_bytes(self.take::<2>(field)?))
    }
    fn f64(&mut self, field: &str) -> Result<f64> {
        let v = f64::from_be_bytes(self.take::<8>(field)?);
        if !v.is_finite() {
            return Err(Error::malformed(format!("{field} is {v}, not finite")));
        }
        Ok(v)
    }
    fn f32(&mut self, field: &str) -> Result<f32> {
        let v = f32::from_be_bytes(self.take::<4>(field)?);
        if !v.is_finite() {
            return Err(Error::malformed(format!("{field} is {v}, not finite")));
        }
        Ok(v)
    }
    fn area(&mut self) -> Result<AreaSpec> {
        let a = AreaSpec {
            top: self.u32("Top")?,
            left: self.u32("Left")?,
            bottom: self.u32("Bottom")?,
            right: self.u32("Right")?,
            plane: self.u32("Plane")?,
            planes: self.u32("Planes")?,
            row_pitch: self.u32("RowPitch")?,
            col_pitch: self.u32("ColPitch")?,
        };
        check_area(&a)?;
        Ok(a)
    }
}

/// The checks of DNG 1.6's area specification (and of the Adobe SDK's reader).
fn check_area(a: &AreaSpec) -> Result<()> {
    if a.top > a.bottom {
        return Err(Error::malformed(format!(
            "area Top {} is below Bottom {}",
            a.top, a.bottom
        )));
    }
    if a.left > a.right {
        return Err(Error::malformed(format!(
            "area Left {} is right of Right {}",
            a.left, a.right
        )));
    }
    if a.planes < 1 {
        return Err(Error::malformed("area Planes is 0, must be at least 1"));
    }
    if a.plane.checked_add(a.planes).is_none() {
        return Err(Error::malformed(format!(
            "area Plane {} + Planes {} overflows",
            a.plane, a.planes
        )));
    }
    if a.row_pitch < 1 || a.col_pitch < 1 {
        return Err(Error::malformed(format!(
            "area RowPitch {} / ColPitch {}: both must be at least 1",
            a.row_pitch, a.col_pitch
        )));
    }
    let empty = a.top == a.bottom || a.left == a.right;
    if empty && (a.row_pitch != 1 || a.col_pitch != 1) {
        return Err(Error::malformed(format!(
            "empty area with RowPitch {} / ColPitch {} (must be 1)",
            a.row_pitch, a.col_pitch
        )));
    }
    Ok(())
}

/// Rows of `a` an opcode touches: `ceil((bottom - top) / row_pitch)`.
pub fn area_row_steps(a: &AreaSpec) -> u64 {
    u64::from(a.bottom.saturating_sub(a.top)).div_ceil(u64::from(a.row_pitch.max(1)))
}

/// Columns of `a` an opcode touches: `ceil((right - left) / col_pitch)`.
pub fn area_col_steps(a: &AreaSpec) -> u64 {
    u64::from(a.right.saturating_sub(a.left)).div_ceil(u64::from(a.col_pitch.max(1)))
}

/// `params.len()` must be exactly `need` (computed from counts already read).
fn check_len(params: &[u8], need: u64) -> Result<()> {
    if params.len() as u64 != need {
        return Err(Error::malformed(format!(
            "parameter byte count is {}, its fields need {need}",
            params.len()
        )));
    }
    Ok(())
}

/// `params.len()` must be at least `need` to read the fixed part.
fn check_min(params: &[u8], need: usize) -> Result<()> {
    if params.len() < need {
        return Err(Error::malformed(format!(
            "parameter byte count is {}, its fixed fields alone need {need}",
            params.len()
        )));
    }
    Ok(())
}

fn center(p: &mut Params) -> Result<[f64; 2]> {
    let cx = p.f64("cx")?;
    let cy = p.f64("cy")?;
    for (name, v) in [("cx", cx), ("cy", cy)] {
        if !(0.0..=1.0).contains(&v) {
            return Err(Error::malformed(format!(
                "optical centre {name} is {v}, must be in 0..1 (relative to the image)"
            )));
        }
    }
    Ok([cx, cy])
}

fn warp_planes(params: &[u8], per_plane: u64) -> Result<u32> {
    check_min(params, 4)?;
    let n = be_u32(params, 0);
    if !(1..=MAX_WARP_PLANES).contains(&n) {
        return Err(Error::malformed(format!(
            "N (planes) is {n}, must be 1..={MAX_WARP_PLANES}"
        )));
    }
    check_len(params, 4 + per_plane * u64::from(n) + 16)?;
    Ok(n)
}

/// The plane count of a WarpRectilinear2 (19 doubles per plane, then the centre and a u32).
fn warp_planes2(params: &[u8]) -> Result<u32> {
    check_min(params, 4)?;
    let n = be_u32(params, 0);
    if !(1..=MAX_WARP_PLANES).contains(&n) {
        return Err(Error::malformed(format!(
            "N (planes) is {n}, must be 1..={MAX_WARP_PLANES}"
        )));
    }
    check_len(params, 4 + 19 * 8 * u64::from(n) + 16 + 4)?;
    Ok(n)
}

fn parse_kind(id: u32, params: &[u8]) -> Result<OpcodeKind> {
    let mut p = Params { b: params, pos: 0 };
    let kind = match id {
        1 => parse_warp_rectilinear(params, &mut p)?,
        14 => parse_warp_rectilinear2(params, &mut p)?,
        2 => parse_warp_fisheye(params, &mut p)?,
        3 => {
            check_len(params, 56)?;
            let mut k = [0.0; 5];
            for (j, v) in k.iter_mut().enumerate() {
                *v = p.f64(&format!("k{j}"))?;
            }
            OpcodeKind::FixVignetteRadial {
                k,
                center: center(&mut p)?,
            }
        }
        4 => {
            check_len(params, 8)?;
            let constant = p.u32("Constant")?;
            let bayer_phase = bayer_phase(p.u32("BayerPhase")?)?;
            OpcodeKind::FixBadPixelsConstant {
                constant,
                bayer_phase,
            }
        }
        5 => parse_bad_pixel_list(params, &mut p)?,
        6 => {
            check_len(params, 16)?;
            let b = [
                p.u32("Top")?,
                p.u32("Left")?,
                p.u32("Bottom")?,
                p.u32("Right")?,
            ];
            if b[0] >= b[2] || b[1] >= b[3] {
                return Err(Error::malformed(format!(
                    "bounds (top {}, left {}, bottom {}, right {}) are empty",
                    b[0], b[1], b[2], b[3]
                )));
            }
            OpcodeKind::TrimBounds { bounds: b }
        }
        7 => parse_map_table(params, &mut p)?,
        8 => parse_map_polynomial(params, &mut p)?,
        9 => OpcodeKind::GainMap(parse_gain_map(params, &mut p)?),
        10..=13 => parse_per_line(id, params, &mut p)?,
        _ => {
            return Ok(OpcodeKind::Unknown {
                params: params.to_vec(),
                len: params.len(),
            })
        }
    };
    if p.pos != params.len() {
        // Unreachable with the length checks above; kept so a slip is an error, not a
        // silently ignored tail.
        return Err(Error::malformed(format!(
            "{} parameter bytes left unread",
            params.len() - p.pos
        )));
    }
    Ok(kind)
}

/// WarpRectilinear (opcode 1).
fn parse_warp_rectilinear(params: &[u8], p: &mut Params) -> Result<OpcodeKind> {
    let n = warp_planes(params, 48)?;
    p.pos = 4;
    let mut planes = Vec::with_capacity(n as usize);
    for i in 0..n {
        let mut kr = [0.0; 4];
        for (j, k) in kr.iter_mut().enumerate() {
            *k = p.f64(&format!("plane {i} kr{j}"))?;
        }
        let kt = [
            p.f64(&format!("plane {i} kt0"))?,
            p.f64(&format!("plane {i} kt1"))?,
        ];
        planes.push(WarpPlane { kr, kt });
    }
    Ok(OpcodeKind::WarpRectilinear {
        planes,
        center: center(p)?,
    })
}

/// WarpRectilinear2 (opcode 14).
fn parse_warp_rectilinear2(params: &[u8], p: &mut Params) -> Result<OpcodeKind> {
    // N, per plane kr0..kr14, kt0, kt1, min and max valid radius, then cx, cy and
    // the reciprocal flag (a u32 after the centre).
    let n = warp_planes2(params)?;
    p.pos = 4;
    let mut planes = Vec::with_capacity(n as usize);
    for i in 0..n {
        let mut kr = [0.0; 15];
        for (j, k) in kr.iter_mut().enumerate() {
            *k = p.f64(&format!("plane {i} kr{j}"))?;
        }
        let kt = [
            p.f64(&format!("plane {i} kt0"))?,
            p.f64(&format!("plane {i} kt1"))?,
        ];
        let valid = [
            p.f64(&format!("plane {i} minimum valid radius"))?,
            p.f64(&format!("plane {i} maximum valid radius"))?,
        ];
        if !(0.0 <= valid[0] && valid[0] < valid[1] && valid[1] <= 1.0) {
            return Err(Error::malformed(format!(
                "plane {i}: valid radius range {}..{} must satisfy 0 <= min < max <= 1",
                valid[0], valid[1]
            )));
        }
        planes.push(WarpPlane2 { kr, kt, valid });
    }
    let center = center(p)?;
    let reciprocal = p.u32("reciprocal flag")? != 0;
    Ok(OpcodeKind::WarpRectilinear2 {
        planes,
        center,
        reciprocal,
    })
}

/// WarpFisheye (opcode 2).
fn parse_warp_fisheye(params: &[u8], p: &mut Params) -> Result<OpcodeKind> {
    let n = warp_planes(params, 32)?;
    p.pos = 4;
    let mut planes = Vec::with_capacity(n as usize);
    for i in 0..n {
        let mut kr = [0.0; 4];
        for (j, k) in kr.iter_mut().enumerate() {
            *k = p.f64(&format!("plane {i} kr{j}"))?;
        }
        planes.push(kr);
    }
    Ok(OpcodeKind::WarpFisheye {
        planes,
        center: center(p)?,
    })
}

/// MapTable (opcode 7).
fn parse_map_table(params: &[u8], p: &mut Params) -> Result<OpcodeKind> {
    check_min(params, AREA_BYTES + 4)?;
    let area = p.area()?;
    let n = p.u32("TableSize")?;
    if n < 1 {
        return Err(Error::malformed("TableSize is 0, must be at least 1"));
    }
    if n > MAX_MAP_TABLE_LEN {
        return Err(Error::limits(format!(
            "TableSize {n} exceeds the limit of {MAX_MAP_TABLE_LEN}"
        )));
    }
    check_len(params, (AREA_BYTES + 4) as u64 + 2 * u64::from(n))?;
    let mut table = Vec::with_capacity(n as usize);
    for _ in 0..n {
        table.push(p.u16("Table")?);
    }
    Ok(OpcodeKind::MapTable { area, table })
}

/// MapPolynomial (opcode 8).
fn parse_map_polynomial(params: &[u8], p: &mut Params) -> Result<OpcodeKind> {
    check_min(params, AREA_BYTES + 4)?;
    let area = p.area()?;
    let degree = p.u32("Degree")?;
    if degree > MAX_POLYNOMIAL_DEGREE {
        return Err(Error::malformed(format!(
            "Degree {degree} exceeds the specification's {MAX_POLYNOMIAL_DEGREE}"
        )));
    }
    check_len(
        params,
        (AREA_BYTES + 4) as u64 + 8 * (u64::from(degree) + 1),
    )?;
    let mut coefficients = Vec::with_capacity(degree as usize + 1);
    for i in 0..=degree {
        coefficients.push(p.f64(&format!("Coefficient {i}"))?);
    }
    Ok(OpcodeKind::MapPolynomial { area, coefficients })
}

/// DeltaPerRow, DeltaPerColumn, ScalePerRow and ScalePerColumn (opcodes 10 to 13).
fn parse_per_line(id: u32, params: &[u8], p: &mut Params) -> Result<OpcodeKind> {
    check_min(params, AREA_BYTES + 4)?;
    let area = p.area()?;
    let n = p.u32("Count")?;
    let (steps, per) = if id == 10 || id == 12 {
        (area_row_steps(&area), "row")
    } else {
        (area_col_steps(&area), "column")
    };
    if u64::from(n) != steps {
        return Err(Error::malformed(format!(
            "Count is {n}, the area has {steps} {per} steps"
        )));
    }
    if u64::from(n) > MAX_PER_LINE_ENTRIES {
        return Err(Error::limits(format!(
            "Count {n} exceeds the limit of {MAX_PER_LINE_ENTRIES}"
        )));
    }
    check_len(params, (AREA_BYTES + 4) as u64 + 4 * u64::from(n))?;
    let field = if id <= 11 { "Delta" } else { "Scale" };
    let mut v = Vec::with_capacity(n as usize);
    for i in 0..n {
        v.push(p.f32(&format!("{field} {i}"))?);
    }
    Ok(match id {
        10 => OpcodeKind::DeltaPerRow { area, deltas: v },
        11 => OpcodeKind::DeltaPerColumn { area, deltas: v },
        12 => OpcodeKind::ScalePerRow { area, scales: v },
        _ => OpcodeKind::ScalePerColumn { area, scales: v },
    })
}

fn bayer_phase(v: u32) -> Result<u32> {
    if v > 3 {
        return Err(Error::malformed(format!(
            "BayerPhase is {v}, must be 0..=3"
        )));
    }
    Ok(v)
}

fn parse_bad_pixel_list(params: &[u8], p: &mut Params) -> Result<OpcodeKind> {
    check_min(params, 12)?;
    let bayer_phase = bayer_phase(p.u32("BayerPhase")?)?;
    let n_points = p.u32("BadPointCount")?;
    let n_rects = p.u32("BadRectCount")?;
    let total = u64::from(n_points) + u64::from(n_rects);
    if total > MAX_BAD_PIXEL_ENTRIES {
        return Err(Error::limits(format!(
            "BadPointCount {n_points} + BadRectCount {n_rects} exceeds the limit of \
             {MAX_BAD_PIXEL_ENTRIES}"
        )));
    }
    check_len(
        params,
        12 + 8 * u64::from(n_points) + 16 * u64::from(n_rects),
    )?;
    let mut points = Vec::with_capacity(n_points as usize);
    for i in 0..n_points {
        points.push([
            p.u32(&format!("BadPoint {i} row"))?,
            p.u32(&format!("BadPoint {i} column"))?,
        ]);
    }
    let mut rects = Vec::with_capacity(n_rects as usize);
    for i in 0..n_rects {
        let r = [
            p.u32(&format!("BadRect {i} top"))?,
            p.u32(&format!("BadRect {i} left"))?,
            p.u32(&format!("BadRect {i} bottom"))?,
            p.u32(&format!("BadRect {i} right"))?,
        ];
        if r[0] > r[2] || r[1] > r[3] {
            return Err(Error::malformed(format!(
                "BadRect {i} (top {}, left {}, bottom {}, right {}) is inverted",
                r[0], r[1], r[2], r[3]
            )));
        }
        rects.push(r);
    }
    Ok(OpcodeKind::FixBadPixelsList {
        bayer_phase,
        points,
        rects,
    })
}

fn parse_gain_map(params: &[u8], p: &mut Params) -> Result<GainMap> {
    check_min(params, GAIN_MAP_FIXED_BYTES)?;
    let area = p.area()?;
    let points_v = p.u32("MapPointsV")?;
    let points_h = p.u32("MapPointsH")?;
    let spacing_v = p.f64("MapSpacingV")?;
    let spacing_h = p.f64("MapSpacingH")?;
    let origin_v = p.f64("MapOriginV")?;
    let origin_h = p.f64("MapOriginH")?;
    let map_planes = p.u32("MapPlanes")?;
    for (name, v) in [
        ("MapPointsV", points_v),
        ("MapPointsH", points_h),
        ("MapPlanes", map_planes),
    ] {
        if v < 1 {
            return Err(Error::malformed(format!("{name} is 0, must be at least 1")));
        }
    }
    // One map point along an axis: its spacing and origin are unused (the SDK sets them to
    // 1 and 0); more: the spacing must be positive.
    for (name, points, spacing) in [
        ("MapSpacingV", points_v, spacing_v),
        ("MapSpacingH", points_h, spacing_h),
    ] {
        if points > 1 && spacing <= 0.0 {
            return Err(Error::malformed(format!(
                "{name} is {spacing}, must be positive with {points} map points"
            )));
        }
    }
    let n = u64::from(points_v) * u64::from(points_h) * u64::from(map_planes);
    if n > MAX_GAIN_MAP_POINTS {
        return Err(Error::limits(format!(
            "MapPointsV {points_v} x MapPointsH {points_h} x MapPlanes {map_planes} = {n} gains \
             exceeds the limit of {MAX_GAIN_MAP_POINTS}"
        )));
    }
    check_len(params, GAIN_MAP_FIXED_BYTES as u64 + 4 * n)?;
    let mut gains = Vec::with_capacity(n as usize);
    for i in 0..n {
        gains.push(p.f32_gain(i, points_h, map_planes)?);
    }
    Ok(GainMap {
        area,
        points_v,
        points_h,
        spacing_v,
        spacing_h,
        origin_v,
        origin_h,
        map_planes,
        gains,
    })
}

impl Params<'_> {
    /// One MapGain entry; an error names its row, column and plane.
    fn f32_gain(&mut self, i: u64, points_h: u32, map_planes: u32) -> Result<f32> {
        let w = self.take::<4>("MapGain")?;
        let v = f32::from_be_bytes(w);
        if !v.is_finite() {
            let planes = u64::from(map_planes);
            let cols = u64::from(points_h);
            return Err(Error::malformed(format!(
                "MapGain at row {}, column {}, plane {} is {v}, not finite",
                i / planes / cols,
                (i / planes) % cols,
                i % planes
            )));
        }
        Ok(v)
    }
}
