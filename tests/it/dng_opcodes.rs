//! DNG opcode lists end to end: lists attached by the project's builder and a GainMap written
//! by the Adobe DNG SDK (dngpy, tests/validators/make_gainmap_dng.py) are read and parsed
//! field for field, listed by `info` (text and JSON), carried byte for byte into written and
//! synthesized DNGs, and the SDK reads the night DNG's GainMap back unchanged.
use crate::common;
use crate::dngbuild::Builder;

use day2night::dng::opcodes::{
    encode_list, lists, AreaSpec, GainMap, ListId, Opcode, OpcodeKind, OpcodeList, WarpPlane,
    FLAG_OPTIONAL,
};
use day2night::dng::read_dng;
use serde_json::Value;
use std::path::Path;

fn area(bottom: u32, right: u32) -> AreaSpec {
    AreaSpec {
        top: 0,
        left: 0,
        bottom,
        right,
        plane: 0,
        planes: 1,
        row_pitch: 1,
        col_pitch: 1,
    }
}

/// One list of each kind the ISP applies, on a 16 x 12 image.
fn three_lists() -> [OpcodeList; 3] {
    let l1 = OpcodeList {
        opcodes: vec![
            Opcode::new(
                OpcodeKind::FixBadPixelsList {
                    bayer_phase: 0,
                    points: vec![[3, 4], [7, 9]],
                    rects: vec![[0, 0, 2, 2]],
                },
                FLAG_OPTIONAL,
            ),
            Opcode::new(
                OpcodeKind::MapTable {
                    area: area(12, 16),
                    table: (0..4096u16).collect(),
                },
                0,
            ),
        ],
    };
    let l2 = OpcodeList {
        opcodes: vec![
            Opcode::new(
                OpcodeKind::GainMap(GainMap {
                    area: AreaSpec {
                        row_pitch: 2,
                        col_pitch: 2,
                        ..area(12, 16)
                    },
                    points_v: 3,
                    points_h: 2,
                    spacing_v: 0.5,
                    spacing_h: 1.0,
                    origin_v: 0.0,
                    origin_h: 0.0,
                    map_planes: 1,
                    gains: vec![2.0, 1.5, 1.0, 1.0, 1.5, 2.0],
                }),
                FLAG_OPTIONAL,
            ),
            Opcode::new(
                OpcodeKind::ScalePerRow {
                    area: area(12, 16),
                    scales: vec![1.0; 12],
                },
                FLAG_OPTIONAL,
            ),
        ],
    };
    let l3 = OpcodeList {
        opcodes: vec![Opcode::new(
            OpcodeKind::WarpRectilinear {
                planes: vec![WarpPlane {
                    kr: [1.0, -0.02, 0.001, 0.0],
                    kt: [0.0, 0.0],
                }],
                center: [0.5, 0.5],
            },
            FLAG_OPTIONAL,
        )],
    };
    [l1, l2, l3]
}

fn info_json(path: &Path) -> Value {
    let out = common::bin()
        .args(["info", "--json"])
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    v[0].clone()
}

fn info_text(path: &Path) -> (bool, String) {
    let out = common::bin().arg("info").arg(path).output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

#[test]
fn builder_lists_are_read_listed_and_carried() {
    let t = tempfile::tempdir().unwrap();
    let want = three_lists();
    let src = t.path().join("ops.dng");
    // Lists are big-endian whatever the file's byte order: the same bytes in MM and II
    // files, raw in a SubIFD or in IFD0 (the last one stays for the `info` checks below).
    for (big_endian, raw_in_sub) in [(true, true), (false, false)] {
        let mut b = Builder::new(16, 12, 12);
        b.big_endian = big_endian;
        b.raw_in_sub = raw_in_sub;
        for (i, l) in want.iter().enumerate() {
            b = b.opcode_list(i as u8 + 1, encode_list(l));
        }
        std::fs::write(&src, b.build()).unwrap();

        let img = read_dng(&src).unwrap();
        for (i, l) in want.iter().enumerate() {
            assert_eq!(
                img.meta.opcode_lists[i].as_deref(),
                Some(&encode_list(l)[..])
            );
        }
        assert_eq!(lists(&img.meta).unwrap(), want);

        // The writer carries the bytes unchanged.
        let out = t.path().join("written.dng");
        let bytes = day2night::dng::write::encode_dng(&img, &Default::default()).unwrap();
        std::fs::write(&out, bytes).unwrap();
        let back = read_dng(&out).unwrap();
        assert_eq!(back.meta.opcode_lists, img.meta.opcode_lists);
    }

    let (ok, text) = info_text(&src);
    assert!(ok, "{text}");
    for line in [
        "OpcodeList1 (",
        "1. FixBadPixelsList (id 5, v1.3.0.0, optional): 2 points, 1 rectangles, bayer phase 0",
        "2. MapTable (id 7, v1.3.0.0): planes 0..1, area 0,0-12,16, pitch 1x1, table of 4096 \
         entries (0..4095)",
        "1. GainMap (id 9, v1.3.0.0, optional): planes 0..1, area 0,0-12,16, pitch 2x2, map \
         3x2x1, spacing 0.5x1, origin 0,0, gain 1..2",
        "2. ScalePerRow (id 12, v1.3.0.0, optional): planes 0..1, area 0,0-12,16, pitch 1x1, \
         12 entries (1..1)",
        "1. WarpRectilinear (id 1, v1.3.0.0, optional): coefficients [1 -0.02 0.001 0 0 0] \
         centre 0.5,0.5",
        "synthesis:     ready",
    ] {
        assert!(text.contains(line), "missing {line:?} in\n{text}");
    }

    let j = info_json(&src);
    let ops = &j["raw"]["meta"]["opcodes"];
    assert_eq!(ops.as_array().unwrap().len(), 3);
    assert_eq!(ops[1]["list"], "OpcodeList2");
    let gm = &ops[1]["opcodes"][0];
    assert_eq!(gm["name"], "GainMap");
    assert_eq!(gm["id"], 9);
    assert_eq!(gm["optional"], true);
    assert_eq!(gm["planes"], serde_json::json!([0, 1]));
    assert_eq!(gm["area"], serde_json::json!([0, 0, 12, 16]));
    assert_eq!(gm["pitch"], serde_json::json!([2, 2]));
    assert_eq!(gm["params"]["points_v"], 3);
    assert_eq!(gm["params"]["gain_max"], 2.0);
    assert_eq!(ops[2]["opcodes"][0]["params"]["kind"], "warp");
    assert_eq!(ops[0]["opcodes"][1]["params"]["len"], 4096);
}

#[test]
fn malformed_list_is_reported_and_the_rest_described() {
    let t = tempfile::tempdir().unwrap();
    let [_, mut l2, _] = three_lists();
    if let OpcodeKind::GainMap(g) = &mut l2.opcodes[0].kind {
        g.points_v = 0;
    }
    let src = t.path().join("bad.dng");
    std::fs::write(
        &src,
        Builder::new(16, 12, 12)
            .opcode_list(2, encode_list(&l2))
            .build(),
    )
    .unwrap();
    let (ok, text) = info_text(&src);
    assert!(ok, "{text}");
    assert!(
        text.contains("OpcodeList2: GainMap (opcode 1 of 2): MapPointsV is 0"),
        "{text}"
    );
    assert!(
        text.contains("white level:") && text.contains("orientation:"),
        "{text}"
    );
    assert!(text.contains("synthesis:     not usable"), "{text}");
    let j = info_json(&src);
    let e = j["raw"]["meta"]["opcodes"][0]["error"].as_str().unwrap();
    assert!(e.contains("MapPointsV is 0"), "{e}");
    assert_eq!(j["synth_ready"], false);
}

/// Run tests/validators/make_gainmap_dng.py; `None` (skip) without the validator Python.
fn gainmap_script(py: &Path, args: &[&std::ffi::OsStr]) -> Value {
    let out = common::run_validator(py, "make_gainmap_dng.py", args);
    assert!(
        out.status.success(),
        "make_gainmap_dng.py failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    // The SDK prints timing lines to stdout; the JSON is the last line.
    let stdout = String::from_utf8_lossy(&out.stdout);
    let last = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(last).unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

fn check_gain_map(g: &GainMap, sdk: &Value, width: u32, height: u32) {
    assert_eq!(g.points_v, sdk["rows"].as_u64().unwrap() as u32);
    assert_eq!(g.points_h, sdk["cols"].as_u64().unwrap() as u32);
    assert_eq!(g.map_planes, sdk["planes"].as_u64().unwrap() as u32);
    assert_eq!(g.spacing_v, sdk["spacing_v"].as_f64().unwrap());
    assert_eq!(g.spacing_h, sdk["spacing_h"].as_f64().unwrap());
    assert_eq!(g.origin_v, sdk["origin_v"].as_f64().unwrap());
    assert_eq!(g.origin_h, sdk["origin_h"].as_f64().unwrap());
    let gains: Vec<f32> = sdk["gains"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    assert_eq!(g.gains, gains);
    // The SDK's area: the whole stored image, planes 0..MapPlanes, pitch 1.
    let want = AreaSpec {
        planes: g.map_planes,
        ..area(height, width)
    };
    assert_eq!(g.area, want);
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn adobe_sdk_gain_map_is_parsed_listed_and_kept_by_synth() {
    let py = common::python();
    let t = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let src = t.path().join("shaded.dng");
    let set = gainmap_script(
        &py,
        &[
            "make".as_ref(),
            day.as_os_str(),
            src.as_os_str(),
            "--rows".as_ref(),
            "9".as_ref(),
            "--cols".as_ref(),
            "11".as_ref(),
            "--planes".as_ref(),
            "4".as_ref(),
            "--origin-v".as_ref(),
            "0.01".as_ref(),
            "--origin-h".as_ref(),
            "0.02".as_ref(),
        ],
    );
    // What the script set, as the SDK read it back.
    assert_eq!(set["rows"], 9);
    assert_eq!(set["cols"], 11);
    assert_eq!(set["planes"], 4);
    assert_eq!(set["spacing_v"], 0.125);
    assert_eq!(set["spacing_h"], 0.1);
    assert_eq!(set["origin_v"], 0.01);
    assert_eq!(set["gains"].as_array().unwrap().len(), 9 * 11 * 4);
    assert_eq!(set["gains"][0].as_f64().unwrap() as f32, 2.6f32); // corner, plane 0
    assert_eq!(
        set["gains"][(4 * 11 + 5) * 4 + 3].as_f64().unwrap() as f32,
        1.03f32
    ); // centre, plane 3

    let img = read_dng(&src).unwrap();
    let [l1, l2, l3] = lists(&img.meta).unwrap();
    assert!(l1.opcodes.is_empty() && l3.opcodes.is_empty());
    assert_eq!(l2.opcodes.len(), 1);
    let op = &l2.opcodes[0];
    assert_eq!(
        (op.id, op.name(), op.dng_version),
        (9, "GainMap", [1, 3, 0, 0])
    );
    let OpcodeKind::GainMap(g) = &op.kind else {
        panic!("not a GainMap: {op:?}")
    };
    check_gain_map(g, &set, img.width as u32, img.height as u32);

    let j = info_json(&src);
    let listed = &j["raw"]["meta"]["opcodes"];
    assert_eq!(listed[0]["list"], ListId::List2.tag_name());
    let p = &listed[0]["opcodes"][0]["params"];
    assert_eq!(p["kind"], "gain_map");
    assert_eq!(
        (p["points_v"].as_u64(), p["map_planes"].as_u64()),
        (Some(9), Some(4))
    );
    assert_eq!(p["gain_max"].as_f64().unwrap() as f32, 2.63f32);
    assert_eq!(p["gain_min"].as_f64().unwrap() as f32, 1.0f32);

    // A night DNG written from it keeps the list byte for byte, and the SDK reads it back.
    let out = t.path().join("out");
    let o = common::cli("synth", &src, &out, &["--iso", "3200", "--target", "none"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in ["shaded_clean.dng", "shaded_iso3200.dng"] {
        let night = out.join(name);
        let n = read_dng(&night).unwrap();
        assert_eq!(n.meta.opcode_lists, img.meta.opcode_lists, "{name}");
        let back = gainmap_script(&py, &["read".as_ref(), night.as_os_str()]);
        assert_eq!(back, set, "{name}: the SDK's GainMap");
    }
}
