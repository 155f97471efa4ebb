//! What `day2night info` says about a file's opcode lists: per list its size and opcodes (or
//! why it is malformed), per opcode its name, id, flags, planes, area, pitch and a summary of
//! its parameters (map size and gain range, coefficients, table length, counts).

use super::{list_results, AreaSpec, ListId, Opcode, OpcodeKind, WarpPlane};
use crate::raw::meta::RawMeta;
use serde::Serialize;

/// One opcode list of a file, as `info` reports it.
#[derive(Debug, Clone, Serialize)]
pub struct OpcodeListInfo {
    /// "OpcodeList1", "OpcodeList2" or "OpcodeList3".
    pub list: &'static str,
    /// Size of the tag's value in bytes.
    pub bytes: usize,
    /// The opcodes, in the order they apply (empty when malformed).
    pub opcodes: Vec<OpcodeInfo>,
    /// Why the list could not be parsed (the list is then carried but not understood).
    pub error: Option<String>,
}

/// One opcode, as `info` reports it.
#[derive(Debug, Clone, Serialize)]
pub struct OpcodeInfo {
    /// The specification's name ("GainMap"; "unknown" for ids this reader does not know).
    pub name: &'static str,
    /// Opcode id.
    pub id: u32,
    /// The DNG version the opcode needs ("1.3.0.0").
    pub dng_version: String,
    /// Flag bit 0: may be skipped by a reader that cannot apply it.
    pub optional: bool,
    /// Flag bit 1: may be skipped for previews.
    pub preview_skip: bool,
    /// Planes acted on, `[first, end)`, for the area family.
    pub planes: Option<[u32; 2]>,
    /// Area `[top, left, bottom, right]`, for the area family.
    pub area: Option<[u32; 4]>,
    /// `[row_pitch, col_pitch]`, for the area family.
    pub pitch: Option<[u32; 2]>,
    /// The parameters in summary.
    pub params: OpcodeParams,
}

/// The parameters of one opcode in summary (gains and tables by size and range).
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum OpcodeParams {
    /// WarpRectilinear / WarpFisheye: coefficients per plane and the optical centre.
    Warp {
        /// Per plane: kr0..kr3 then (rectilinear only) kt0, kt1.
        coefficients: Vec<Vec<f64>>,
        /// Optical centre (x, y), relative.
        center: [f64; 2],
    },
    /// WarpRectilinear2: per plane kr0..kr14 then kt0, kt1, the valid radius range, the
    /// optical centre and whether the radial ratio is the polynomial's reciprocal.
    Warp2 {
        /// Per plane: kr0..kr14, kt0, kt1.
        coefficients: Vec<Vec<f64>>,
        /// Per plane: minimum and maximum valid radius.
        valid: Vec<[f64; 2]>,
        /// Optical centre (x, y), relative.
        center: [f64; 2],
        /// The ratio is `1 / sum kr_i r^i`.
        reciprocal: bool,
    },
    /// FixVignetteRadial.
    Vignette {
        /// k0..k4.
        coefficients: [f64; 5],
        /// Optical centre (x, y), relative.
        center: [f64; 2],
    },
    /// FixBadPixelsConstant.
    BadPixelsConstant {
        /// The marker value.
        constant: u32,
        /// Bayer phase.
        bayer_phase: u32,
    },
    /// FixBadPixelsList.
    BadPixelsList {
        /// Bayer phase.
        bayer_phase: u32,
        /// Bad points.
        points: usize,
        /// Bad rectangles.
        rects: usize,
    },
    /// TrimBounds.
    Trim {
        /// Top, left, bottom, right.
        bounds: [u32; 4],
    },
    /// MapTable.
    Table {
        /// Entries.
        len: usize,
        /// Smallest and largest entry.
        min: u16,
        /// Largest entry.
        max: u16,
    },
    /// MapPolynomial.
    Polynomial {
        /// c0..cN.
        coefficients: Vec<f64>,
    },
    /// GainMap.
    GainMap {
        /// Map rows.
        points_v: u32,
        /// Map columns.
        points_h: u32,
        /// Map planes.
        map_planes: u32,
        /// Spacing (v, h), relative to the image.
        spacing: [f64; 2],
        /// Origin (v, h), relative to the image.
        origin: [f64; 2],
        /// Smallest gain.
        gain_min: f32,
        /// Largest gain.
        gain_max: f32,
    },
    /// Delta/Scale per row/column.
    PerLine {
        /// Entries (one per row or column step).
        count: usize,
        /// Smallest entry.
        min: f32,
        /// Largest entry.
        max: f32,
    },
    /// An opcode this reader does not model.
    Unknown {
        /// Parameter bytes.
        bytes: usize,
    },
}

/// The opcode lists present in `meta`, in pipeline order.
pub fn describe_lists(meta: &RawMeta) -> Vec<OpcodeListInfo> {
    let results = list_results(meta);
    let mut out = Vec::new();
    for (id, r) in ListId::ALL.into_iter().zip(results) {
        let Some(r) = r else { continue };
        let bytes = meta.opcode_lists[id.index()]
            .as_ref()
            .map_or(0, |b| b.len());
        let (opcodes, error) = match r {
            Ok(l) => (l.opcodes.iter().map(describe).collect(), None),
            Err(e) => (vec![], Some(e.to_string())),
        };
        out.push(OpcodeListInfo {
            list: id.tag_name(),
            bytes,
            opcodes,
            error,
        });
    }
    out
}

fn range_f32(v: &[f32]) -> (f32, f32) {
    let mut it = v.iter().copied();
    let first = it.next().unwrap_or(0.0);
    it.fold((first, first), |(a, b), x| (a.min(x), b.max(x)))
}

fn warp_coefficients(p: &WarpPlane) -> Vec<f64> {
    p.kr.iter().chain(p.kt.iter()).copied().collect()
}

/// Summarize one opcode.
pub fn describe(op: &Opcode) -> OpcodeInfo {
    let area: Option<&AreaSpec> = op.kind.area();
    let params = match &op.kind {
        OpcodeKind::WarpRectilinear { planes, center } => OpcodeParams::Warp {
            coefficients: planes.iter().map(warp_coefficients).collect(),
            center: *center,
        },
        OpcodeKind::WarpFisheye { planes, center } => OpcodeParams::Warp {
            coefficients: planes.iter().map(|k| k.to_vec()).collect(),
            center: *center,
        },
        OpcodeKind::WarpRectilinear2 {
            planes,
            center,
            reciprocal,
        } => OpcodeParams::Warp2 {
            coefficients: planes
                .iter()
                .map(|p| p.kr.iter().chain(p.kt.iter()).copied().collect())
                .collect(),
            valid: planes.iter().map(|p| p.valid).collect(),
            center: *center,
            reciprocal: *reciprocal,
        },
        OpcodeKind::FixVignetteRadial { k, center } => OpcodeParams::Vignette {
            coefficients: *k,
            center: *center,
        },
        OpcodeKind::FixBadPixelsConstant {
            constant,
            bayer_phase,
        } => OpcodeParams::BadPixelsConstant {
            constant: *constant,
            bayer_phase: *bayer_phase,
        },
        OpcodeKind::FixBadPixelsList {
            bayer_phase,
            points,
            rects,
        } => OpcodeParams::BadPixelsList {
            bayer_phase: *bayer_phase,
            points: points.len(),
            rects: rects.len(),
        },
        OpcodeKind::TrimBounds { bounds } => OpcodeParams::Trim { bounds: *bounds },
        OpcodeKind::MapTable { table, .. } => OpcodeParams::Table {
            len: table.len(),
            min: table.iter().copied().min().unwrap_or(0),
            max: table.iter().copied().max().unwrap_or(0),
        },
        OpcodeKind::MapPolynomial { coefficients, .. } => OpcodeParams::Polynomial {
            coefficients: coefficients.clone(),
        },
        OpcodeKind::GainMap(g) => {
            let (gain_min, gain_max) = range_f32(&g.gains);
            OpcodeParams::GainMap {
                points_v: g.points_v,
                points_h: g.points_h,
                map_planes: g.map_planes,
                spacing: [g.spacing_v, g.spacing_h],
                origin: [g.origin_v, g.origin_h],
                gain_min,
                gain_max,
            }
        }
        OpcodeKind::DeltaPerRow { deltas: v, .. }
        | OpcodeKind::DeltaPerColumn { deltas: v, .. }
        | OpcodeKind::ScalePerRow { scales: v, .. }
        | OpcodeKind::ScalePerColumn { scales: v, .. } => {
            let (min, max) = range_f32(v);
            OpcodeParams::PerLine {
                count: v.len(),
                min,
                max,
            }
        }
        OpcodeKind::Unknown { params, .. } => OpcodeParams::Unknown {
            bytes: params.len(),
        },
    };
    let v = op.dng_version;
    OpcodeInfo {
        name: op.name(),
        id: op.id,
        dng_version: format!("{}.{}.{}.{}", v[0], v[1], v[2], v[3]),
        optional: op.optional(),
        preview_skip: op.flags & super::FLAG_PREVIEW_SKIP != 0,
        planes: area.map(|a| [a.plane, a.plane.saturating_add(a.planes)]),
        area: area.map(|a| [a.top, a.left, a.bottom, a.right]),
        pitch: area.map(|a| [a.row_pitch, a.col_pitch]),
        params,
    }
}

/// Shortest round-trip-free form of a number for the text report (6 significant digits).
fn g(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-4..1e6).contains(&a) {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{x:.5e}")
    }
}

fn gs(v: &[f64]) -> String {
    v.iter().map(|&x| g(x)).collect::<Vec<_>>().join(" ")
}

impl OpcodeInfo {
    /// One line of text: "GainMap (id 9, optional): planes 0..1, area 0,0-3024,4032, pitch
    /// 1x1, map 17x13x1, spacing 0.0625x0.08333, origin 0,0, gain 1..2.61".
    pub fn text(&self) -> String {
        let mut flags = vec![format!("id {}", self.id), format!("v{}", self.dng_version)];
        if self.optional {
            flags.push("optional".into());
        }
        if self.preview_skip {
            flags.push("preview-skip".into());
        }
        let mut parts = Vec::new();
        if let Some([a, b]) = self.planes {
            parts.push(format!("planes {a}..{b}"));
        }
        if let Some([t, l, b, r]) = self.area {
            parts.push(format!("area {t},{l}-{b},{r}"));
        }
        if let Some([rp, cp]) = self.pitch {
            parts.push(format!("pitch {rp}x{cp}"));
        }
        parts.push(match &self.params {
            OpcodeParams::Warp {
                coefficients,
                center,
            } => {
                let per: Vec<String> = coefficients
                    .iter()
                    .map(|c| format!("[{}]", gs(c)))
                    .collect();
                format!(
                    "coefficients {} centre {},{}",
                    per.join(" "),
                    g(center[0]),
                    g(center[1])
                )
            }
            OpcodeParams::Warp2 {
                coefficients,
                valid,
                center,
                reciprocal,
            } => {
                let per: Vec<String> = coefficients
                    .iter()
                    .zip(valid)
                    .map(|(c, v)| format!("[{}] valid r {}..{}", gs(c), g(v[0]), g(v[1])))
                    .collect();
                format!(
                    "coefficients {} centre {},{}{}",
                    per.join(" "),
                    g(center[0]),
                    g(center[1]),
                    if *reciprocal { " reciprocal" } else { "" }
                )
            }
            OpcodeParams::Vignette {
                coefficients,
                center,
            } => format!(
                "k [{}] centre {},{}",
                gs(coefficients),
                g(center[0]),
                g(center[1])
            ),
            OpcodeParams::BadPixelsConstant {
                constant,
                bayer_phase,
            } => format!("constant {constant}, bayer phase {bayer_phase}"),
            OpcodeParams::BadPixelsList {
                bayer_phase,
                points,
                rects,
            } => format!("{points} points, {rects} rectangles, bayer phase {bayer_phase}"),
            OpcodeParams::Trim { bounds } => format!(
                "bounds {},{}-{},{}",
                bounds[0], bounds[1], bounds[2], bounds[3]
            ),
            OpcodeParams::Table { len, min, max } => {
                format!("table of {len} entries ({min}..{max})")
            }
            OpcodeParams::Polynomial { coefficients } => {
                format!(
                    "degree {} coefficients [{}]",
                    coefficients.len().saturating_sub(1),
                    gs(coefficients)
                )
            }
            OpcodeParams::GainMap {
                points_v,
                points_h,
                map_planes,
                spacing,
                origin,
                gain_min,
                gain_max,
            } => format!(
                "map {points_v}x{points_h}x{map_planes}, spacing {}x{}, origin {},{}, gain {}..{}",
                g(spacing[0]),
                g(spacing[1]),
                g(origin[0]),
                g(origin[1]),
                g(f64::from(*gain_min)),
                g(f64::from(*gain_max))
            ),
            OpcodeParams::PerLine { count, min, max } => format!(
                "{count} entries ({}..{})",
                g(f64::from(*min)),
                g(f64::from(*max))
            ),
            OpcodeParams::Unknown { bytes } => format!("{bytes} parameter bytes (not modelled)"),
        });
        format!("{} ({}): {}", self.name, flags.join(", "), parts.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dng::opcodes::{encode_list, GainMap, OpcodeList, FLAG_OPTIONAL};

    #[test]
    fn gain_map_line_and_malformed_list() {
        let mut m = RawMeta::new_bayer(crate::raw::Bayer::RGGB, 12, 0.0, 4095.0);
        let gm = GainMap {
            area: AreaSpec {
                top: 0,
                left: 0,
                bottom: 3024,
                right: 4032,
                plane: 0,
                planes: 1,
                row_pitch: 1,
                col_pitch: 1,
            },
            points_v: 2,
            points_h: 2,
            spacing_v: 1.0,
            spacing_h: 1.0,
            origin_v: 0.0,
            origin_h: 0.0,
            map_planes: 1,
            gains: vec![2.5, 1.0, 1.0, 1.25],
        };
        m.opcode_lists[1] = Some(encode_list(&OpcodeList {
            opcodes: vec![Opcode::new(OpcodeKind::GainMap(gm), FLAG_OPTIONAL)],
        }));
        m.opcode_lists[2] = Some(vec![0, 0, 0, 1]);
        let d = describe_lists(&m);
        assert_eq!(d.len(), 2);
        assert_eq!(d[0].list, "OpcodeList2");
        assert_eq!(
            d[0].opcodes[0].text(),
            "GainMap (id 9, v1.3.0.0, optional): planes 0..1, area 0,0-3024,4032, pitch 1x1, \
             map 2x2x1, spacing 1x1, origin 0,0, gain 1..2.5"
        );
        assert!(d[1].opcodes.is_empty());
        let e = d[1].error.as_deref().unwrap();
        assert!(
            e.starts_with("malformed input: OpcodeList3: 1 opcodes need"),
            "{e}"
        );
        let j = serde_json::to_value(&d[0]).unwrap();
        assert_eq!(j["opcodes"][0]["params"]["kind"], "gain_map");
        assert_eq!(j["opcodes"][0]["params"]["gain_max"], 2.5);
        assert_eq!(
            j["opcodes"][0]["area"],
            serde_json::json!([0, 0, 3024, 4032])
        );
    }
}
