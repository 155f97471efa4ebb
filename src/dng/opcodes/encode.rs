//! Write an [`OpcodeList`] as the bytes of an OpcodeList tag (big-endian, DNG 1.6 chapter 6):
//! the exact inverse of [`super::parse_list`] for every list it accepts. Used by test builders
//! and by the ISP's tests; the DNG writer itself carries the bytes it read, unchanged.

use super::{AreaSpec, GainMap, OpcodeKind, OpcodeList};

/// The bytes of `list`. Counts are written from the lengths of the vectors (the `len` of an
/// [`OpcodeKind::Unknown`] is not consulted: its `params` are written as they are).
pub fn encode_list(list: &OpcodeList) -> Vec<u8> {
    let mut out = Vec::new();
    put_u32(&mut out, list.opcodes.len() as u32);
    for op in &list.opcodes {
        let params = encode_params(&op.kind);
        put_u32(&mut out, op.id);
        out.extend_from_slice(&op.dng_version);
        put_u32(&mut out, op.flags);
        put_u32(&mut out, params.len() as u32);
        out.extend_from_slice(&params);
    }
    out
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_be_bytes());
}

fn put_f64(out: &mut Vec<u8>, v: f64) {
    out.extend_from_slice(&v.to_be_bytes());
}

fn put_f32(out: &mut Vec<u8>, v: f32) {
    out.extend_from_slice(&v.to_be_bytes());
}

fn put_area(out: &mut Vec<u8>, a: &AreaSpec) {
    for v in [
        a.top,
        a.left,
        a.bottom,
        a.right,
        a.plane,
        a.planes,
        a.row_pitch,
        a.col_pitch,
    ] {
        put_u32(out, v);
    }
}

fn put_gain_map(out: &mut Vec<u8>, g: &GainMap) {
    put_area(out, &g.area);
    put_u32(out, g.points_v);
    put_u32(out, g.points_h);
    for v in [g.spacing_v, g.spacing_h, g.origin_v, g.origin_h] {
        put_f64(out, v);
    }
    put_u32(out, g.map_planes);
    for &v in &g.gains {
        put_f32(out, v);
    }
}

fn put_area_f32s(out: &mut Vec<u8>, area: &AreaSpec, values: &[f32]) {
    put_area(out, area);
    put_u32(out, values.len() as u32);
    for &v in values {
        put_f32(out, v);
    }
}

/// The parameter bytes of one opcode (without the header).
pub fn encode_params(kind: &OpcodeKind) -> Vec<u8> {
    let mut out = Vec::new();
    match kind {
        OpcodeKind::WarpRectilinear { planes, center } => {
            put_u32(&mut out, planes.len() as u32);
            for p in planes {
                for &v in p.kr.iter().chain(p.kt.iter()) {
                    put_f64(&mut out, v);
                }
            }
            put_f64(&mut out, center[0]);
            put_f64(&mut out, center[1]);
        }
        OpcodeKind::WarpRectilinear2 {
            planes,
            center,
            reciprocal,
        } => {
            put_u32(&mut out, planes.len() as u32);
            for p in planes {
                for &v in p.kr.iter().chain(p.kt.iter()).chain(p.valid.iter()) {
                    put_f64(&mut out, v);
                }
            }
            put_f64(&mut out, center[0]);
            put_f64(&mut out, center[1]);
            put_u32(&mut out, u32::from(*reciprocal));
        }
        OpcodeKind::WarpFisheye { planes, center } => {
            put_u32(&mut out, planes.len() as u32);
            for p in planes {
                for &v in p {
                    put_f64(&mut out, v);
                }
            }
            put_f64(&mut out, center[0]);
            put_f64(&mut out, center[1]);
        }
        OpcodeKind::FixVignetteRadial { k, center } => {
            for &v in k.iter().chain(center.iter()) {
                put_f64(&mut out, v);
            }
        }
        OpcodeKind::FixBadPixelsConstant {
            constant,
            bayer_phase,
        } => {
            put_u32(&mut out, *constant);
            put_u32(&mut out, *bayer_phase);
        }
        OpcodeKind::FixBadPixelsList {
            bayer_phase,
            points,
            rects,
        } => {
            put_u32(&mut out, *bayer_phase);
            put_u32(&mut out, points.len() as u32);
            put_u32(&mut out, rects.len() as u32);
            for v in points.iter().flatten().chain(rects.iter().flatten()) {
                put_u32(&mut out, *v);
            }
        }
        OpcodeKind::TrimBounds { bounds } => {
            for &v in bounds {
                put_u32(&mut out, v);
            }
        }
        OpcodeKind::MapTable { area, table } => {
            put_area(&mut out, area);
            put_u32(&mut out, table.len() as u32);
            for &v in table {
                out.extend_from_slice(&v.to_be_bytes());
            }
        }
        OpcodeKind::MapPolynomial { area, coefficients } => {
            put_area(&mut out, area);
            put_u32(&mut out, coefficients.len().saturating_sub(1) as u32);
            for &v in coefficients {
                put_f64(&mut out, v);
            }
        }
        OpcodeKind::GainMap(g) => put_gain_map(&mut out, g),
        OpcodeKind::DeltaPerRow { area, deltas } | OpcodeKind::DeltaPerColumn { area, deltas } => {
            put_area_f32s(&mut out, area, deltas)
        }
        OpcodeKind::ScalePerRow { area, scales } | OpcodeKind::ScalePerColumn { area, scales } => {
            put_area_f32s(&mut out, area, scales)
        }
        OpcodeKind::Unknown { params, .. } => out.extend_from_slice(params),
    }
    out
}
