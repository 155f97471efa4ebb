//! What `day2night info` says about a file's opcode lists: per list its size and opcodes (or
//! why it is malformed), per opcode its name, id, flags, planes, area, pitch and a summary of
//! its parameters (map size and gain range, coefficients, table length, counts).

use super::{list_results, AreaSpec, ListId, Opcode, OpcodeKind, WarpPlane};
use crate::raw::meta::RawMeta;
use serde::ser::SerializeStruct;
use serde::{Serialize, Serializer};

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

/// The parameters of one opcode in summary (gains and tables by size and range): a view of
/// its [`OpcodeKind`], not a copy of its fields. `info --json` writes it as
/// `{"kind": ..., ...}` (see its `Serialize`), [`OpcodeInfo::text`] as one line; a kind
/// added to [`OpcodeKind`] is summarized by one arm in each.
#[derive(Debug, Clone, PartialEq)]
pub struct OpcodeParams(pub OpcodeKind);

impl OpcodeParams {
    /// The warps' coefficients per plane: kr then kt (WarpFisheye: kr0..kr3).
    fn warp_coefficients(&self) -> Vec<Vec<f64>> {
        match &self.0 {
            OpcodeKind::WarpRectilinear { planes, .. } => {
                planes.iter().map(warp_coefficients).collect()
            }
            OpcodeKind::WarpFisheye { planes, .. } => planes.iter().map(|k| k.to_vec()).collect(),
            OpcodeKind::WarpRectilinear2 { planes, .. } => planes
                .iter()
                .map(|p| p.kr.iter().chain(p.kt.iter()).copied().collect())
                .collect(),
            _ => Vec::new(),
        }
    }
}

impl Serialize for OpcodeParams {
    /// The form serde gives an internally tagged enum: `{"kind": "gain_map", "points_v": 2,
    /// ...}`, each kind's summary fields in order.
    fn serialize<S: Serializer>(&self, ser: S) -> std::result::Result<S::Ok, S::Error> {
        macro_rules! summary {
            ($kind:literal $(, $name:literal => $value:expr)+ $(,)?) => {{
                let mut st = ser.serialize_struct("OpcodeParams", 1 + [$($name),+].len())?;
                st.serialize_field("kind", $kind)?;
                $(st.serialize_field($name, &$value)?;)+
                st.end()
            }};
        }
        match &self.0 {
            OpcodeKind::WarpRectilinear { center, .. } | OpcodeKind::WarpFisheye { center, .. } => {
                summary!("warp", "coefficients" => self.warp_coefficients(), "center" => center)
            }
            OpcodeKind::WarpRectilinear2 {
                planes,
                center,
                reciprocal,
            } => summary!(
                "warp2",
                "coefficients" => self.warp_coefficients(),
                "valid" => planes.iter().map(|p| p.valid).collect::<Vec<_>>(),
                "center" => center,
                "reciprocal" => reciprocal,
            ),
            OpcodeKind::FixVignetteRadial { k, center } => {
                summary!("vignette", "coefficients" => k, "center" => center)
            }
            OpcodeKind::FixBadPixelsConstant {
                constant,
                bayer_phase,
            } => summary!(
                "bad_pixels_constant",
                "constant" => constant,
                "bayer_phase" => bayer_phase,
            ),
            OpcodeKind::FixBadPixelsList {
                bayer_phase,
                points,
                rects,
            } => summary!(
                "bad_pixels_list",
                "bayer_phase" => bayer_phase,
                "points" => points.len(),
                "rects" => rects.len(),
            ),
            OpcodeKind::TrimBounds { bounds } => summary!("trim", "bounds" => bounds),
            OpcodeKind::MapTable { table, .. } => {
                let (min, max) = range_u16(table);
                summary!("table", "len" => table.len(), "min" => min, "max" => max)
            }
            OpcodeKind::MapPolynomial { coefficients, .. } => {
                summary!("polynomial", "coefficients" => coefficients)
            }
            OpcodeKind::GainMap(g) => {
                let (gain_min, gain_max) = range_f32(&g.gains);
                summary!(
                    "gain_map",
                    "points_v" => g.points_v,
                    "points_h" => g.points_h,
                    "map_planes" => g.map_planes,
                    "spacing" => [g.spacing_v, g.spacing_h],
                    "origin" => [g.origin_v, g.origin_h],
                    "gain_min" => gain_min,
                    "gain_max" => gain_max,
                )
            }
            OpcodeKind::DeltaPerRow { deltas: v, .. }
            | OpcodeKind::DeltaPerColumn { deltas: v, .. }
            | OpcodeKind::ScalePerRow { scales: v, .. }
            | OpcodeKind::ScalePerColumn { scales: v, .. } => {
                let (min, max) = range_f32(v);
                summary!("per_line", "count" => v.len(), "min" => min, "max" => max)
            }
            OpcodeKind::Unknown { params, .. } => summary!("unknown", "bytes" => params.len()),
        }
    }
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

fn range_u16(v: &[u16]) -> (u16, u16) {
    let min = v.iter().copied().min().unwrap_or(0);
    (min, v.iter().copied().max().unwrap_or(0))
}

fn warp_coefficients(p: &WarpPlane) -> Vec<f64> {
    p.kr.iter().chain(p.kt.iter()).copied().collect()
}

/// Summarize one opcode.
pub fn describe(op: &Opcode) -> OpcodeInfo {
    let area: Option<&AreaSpec> = op.kind.area();
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
        params: OpcodeParams(op.kind.clone()),
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
        parts.push(self.params.text());
        format!("{} ({}): {}", self.name, flags.join(", "), parts.join(", "))
    }
}

impl OpcodeParams {
    /// The summary as text: "map 17x13x1, spacing 0.0625x0.08333, origin 0,0, gain 1..2.61".
    pub fn text(&self) -> String {
        let centre = |c: &[f64; 2]| format!("centre {},{}", g(c[0]), g(c[1]));
        match &self.0 {
            OpcodeKind::WarpRectilinear { center, .. } | OpcodeKind::WarpFisheye { center, .. } => {
                let per: Vec<String> = self
                    .warp_coefficients()
                    .iter()
                    .map(|c| format!("[{}]", gs(c)))
                    .collect();
                format!("coefficients {} {}", per.join(" "), centre(center))
            }
            OpcodeKind::WarpRectilinear2 {
                planes,
                center,
                reciprocal,
            } => {
                let per: Vec<String> = self
                    .warp_coefficients()
                    .iter()
                    .zip(planes)
                    .map(|(c, p)| {
                        format!("[{}] valid r {}..{}", gs(c), g(p.valid[0]), g(p.valid[1]))
                    })
                    .collect();
                format!(
                    "coefficients {} {}{}",
                    per.join(" "),
                    centre(center),
                    if *reciprocal { " reciprocal" } else { "" }
                )
            }
            OpcodeKind::FixVignetteRadial { k, center } => {
                format!("k [{}] {}", gs(k), centre(center))
            }
            OpcodeKind::FixBadPixelsConstant {
                constant,
                bayer_phase,
            } => format!("constant {constant}, bayer phase {bayer_phase}"),
            OpcodeKind::FixBadPixelsList {
                bayer_phase,
                points,
                rects,
            } => format!(
                "{} points, {} rectangles, bayer phase {bayer_phase}",
                points.len(),
                rects.len()
            ),
            OpcodeKind::TrimBounds { bounds } => format!(
                "bounds {},{}-{},{}",
                bounds[0], bounds[1], bounds[2], bounds[3]
            ),
            OpcodeKind::MapTable { table, .. } => {
                let (min, max) = range_u16(table);
                format!("table of {} entries ({min}..{max})", table.len())
            }
            OpcodeKind::MapPolynomial { coefficients, .. } => format!(
                "degree {} coefficients [{}]",
                coefficients.len().saturating_sub(1),
                gs(coefficients)
            ),
            OpcodeKind::GainMap(gm) => {
                let (gain_min, gain_max) = range_f32(&gm.gains);
                format!(
                    "map {}x{}x{}, spacing {}x{}, origin {},{}, gain {}..{}",
                    gm.points_v,
                    gm.points_h,
                    gm.map_planes,
                    g(gm.spacing_v),
                    g(gm.spacing_h),
                    g(gm.origin_v),
                    g(gm.origin_h),
                    g(f64::from(gain_min)),
                    g(f64::from(gain_max))
                )
            }
            OpcodeKind::DeltaPerRow { deltas: v, .. }
            | OpcodeKind::DeltaPerColumn { deltas: v, .. }
            | OpcodeKind::ScalePerRow { scales: v, .. }
            | OpcodeKind::ScalePerColumn { scales: v, .. } => {
                let (min, max) = range_f32(v);
                format!(
                    "{} entries ({}..{})",
                    v.len(),
                    g(f64::from(min)),
                    g(f64::from(max))
                )
            }
            OpcodeKind::Unknown { params, .. } => {
                format!("{} parameter bytes (not modelled)", params.len())
            }
        }
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
            serde_json::to_string(&d[0].opcodes[0].params).unwrap(),
            r#"{"kind":"gain_map","points_v":2,"points_h":2,"map_planes":1,"spacing":[1.0,1.0],"origin":[0.0,0.0],"gain_min":1.0,"gain_max":2.5}"#
        );
        assert_eq!(
            j["opcodes"][0]["area"],
            serde_json::json!([0, 0, 3024, 4032])
        );
    }

    /// Every kind's summary in `info --json`'s form (serde's internally tagged enum, as the
    /// summary type it replaced wrote it) and as text.
    #[test]
    fn every_kind_summarized_as_info_writes_it() {
        use crate::dng::opcodes::{WarpPlane, WarpPlane2};
        let area = AreaSpec {
            top: 0,
            left: 0,
            bottom: 4,
            right: 6,
            plane: 0,
            planes: 1,
            row_pitch: 1,
            col_pitch: 1,
        };
        let mut kr = [0.0; 15];
        kr[0] = 1.0;
        let cases = [
            (
                OpcodeKind::WarpRectilinear {
                    planes: vec![WarpPlane {
                        kr: [1.0, 0.5, 0.0, 0.0],
                        kt: [0.0, 0.25],
                    }],
                    center: [0.5, 0.5],
                },
                r#"{"kind":"warp","coefficients":[[1.0,0.5,0.0,0.0,0.0,0.25]],"center":[0.5,0.5]}"#,
                "coefficients [1 0.5 0 0 0 0.25] centre 0.5,0.5",
            ),
            (
                OpcodeKind::WarpFisheye {
                    planes: vec![[1.0, 0.0, 0.0, 0.125]],
                    center: [0.5, 0.25],
                },
                r#"{"kind":"warp","coefficients":[[1.0,0.0,0.0,0.125]],"center":[0.5,0.25]}"#,
                "coefficients [1 0 0 0.125] centre 0.5,0.25",
            ),
            (
                OpcodeKind::WarpRectilinear2 {
                    planes: vec![WarpPlane2 {
                        kr,
                        kt: [0.0, 0.5],
                        valid: [0.0, 0.75],
                    }],
                    center: [0.5, 0.5],
                    reciprocal: true,
                },
                r#"{"kind":"warp2","coefficients":[[1.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.5]],"valid":[[0.0,0.75]],"center":[0.5,0.5],"reciprocal":true}"#,
                "coefficients [1 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0.5] valid r 0..0.75 centre 0.5,0.5 reciprocal",
            ),
            (
                OpcodeKind::FixVignetteRadial {
                    k: [0.5, 0.0, 0.0, 0.0, 0.0],
                    center: [0.5, 0.5],
                },
                r#"{"kind":"vignette","coefficients":[0.5,0.0,0.0,0.0,0.0],"center":[0.5,0.5]}"#,
                "k [0.5 0 0 0 0] centre 0.5,0.5",
            ),
            (
                OpcodeKind::FixBadPixelsConstant {
                    constant: 0,
                    bayer_phase: 1,
                },
                r#"{"kind":"bad_pixels_constant","constant":0,"bayer_phase":1}"#,
                "constant 0, bayer phase 1",
            ),
            (
                OpcodeKind::FixBadPixelsList {
                    bayer_phase: 2,
                    points: vec![[1, 2]],
                    rects: vec![],
                },
                r#"{"kind":"bad_pixels_list","bayer_phase":2,"points":1,"rects":0}"#,
                "1 points, 0 rectangles, bayer phase 2",
            ),
            (
                OpcodeKind::TrimBounds {
                    bounds: [1, 2, 3, 4],
                },
                r#"{"kind":"trim","bounds":[1,2,3,4]}"#,
                "bounds 1,2-3,4",
            ),
            (
                OpcodeKind::MapTable {
                    area,
                    table: vec![3, 1, 2],
                },
                r#"{"kind":"table","len":3,"min":1,"max":3}"#,
                "table of 3 entries (1..3)",
            ),
            (
                OpcodeKind::MapPolynomial {
                    area,
                    coefficients: vec![0.0, 1.0],
                },
                r#"{"kind":"polynomial","coefficients":[0.0,1.0]}"#,
                "degree 1 coefficients [0 1]",
            ),
            (
                OpcodeKind::DeltaPerRow {
                    area,
                    deltas: vec![-0.5, 0.25],
                },
                r#"{"kind":"per_line","count":2,"min":-0.5,"max":0.25}"#,
                "2 entries (-0.5..0.25)",
            ),
            (
                OpcodeKind::ScalePerColumn {
                    area,
                    scales: vec![],
                },
                r#"{"kind":"per_line","count":0,"min":0.0,"max":0.0}"#,
                "0 entries (0..0)",
            ),
            (
                OpcodeKind::Unknown {
                    params: vec![1, 2, 3],
                    len: 3,
                },
                r#"{"kind":"unknown","bytes":3}"#,
                "3 parameter bytes (not modelled)",
            ),
        ];
        for (kind, json, text) in cases {
            let info = describe(&Opcode::new(kind, 0));
            assert_eq!(serde_json::to_string(&info.params).unwrap(), json);
            assert_eq!(info.params.text(), text);
        }
    }
}
