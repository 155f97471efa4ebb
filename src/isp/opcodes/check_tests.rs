use super::*;
use crate::dng::opcodes::{encode_list, AreaSpec, GainMap, FLAG_OPTIONAL};
use crate::raw::meta::LinearRaw;
use crate::raw::Rect;
use crate::raw::{Bayer, Levels};

fn area(top: u32, left: u32, bottom: u32, right: u32) -> AreaSpec {
    AreaSpec {
        top,
        left,
        bottom,
        right,
        plane: 0,
        planes: 1,
        row_pitch: 1,
        col_pitch: 1,
    }
}

fn gain_map(a: AreaSpec, map_planes: u32, gains: Vec<f32>) -> OpcodeKind {
    OpcodeKind::GainMap(GainMap {
        area: a,
        points_v: 1,
        points_h: (gains.len() as u32 / map_planes).max(1),
        spacing_v: 1.0,
        spacing_h: 1.0,
        origin_v: 0.0,
        origin_h: 0.0,
        map_planes,
        gains,
    })
}

/// A 16-bit RGGB frame of `w x h` with the lists given (list 1, 2, 3).
fn frame(w: usize, h: usize, lists: [Vec<OpcodeKind>; 3]) -> RawImage {
    let mut meta = RawMeta::new_bayer(Bayer::RGGB, 16, 0.0, 65535.0);
    meta.as_shot_neutral = Some([0.5, 1.0, 0.6]);
    for (i, l) in lists.into_iter().enumerate() {
        let opcodes: Vec<Opcode> = l.into_iter().map(|k| Opcode::new(k, 0)).collect();
        meta.opcode_lists[i] = (!opcodes.is_empty()).then(|| encode_list(&OpcodeList { opcodes }));
    }
    RawImage {
        width: w,
        height: h,
        data: vec![1000; w * h],
        meta,
    }
}

fn warnings(img: &RawImage) -> Vec<String> {
    check_render(img, OpcodeMode::Apply, true, true)
        .unwrap()
        .warnings
        .iter()
        .map(|w| w.message.clone())
        .collect()
}

#[test]
fn the_issues_two_silent_blacks_warn() {
    // A GainMap with gain -2 everywhere.
    let img = frame(
        64,
        48,
        [
            vec![],
            vec![gain_map(area(0, 0, 48, 64), 1, vec![-2.0])],
            vec![],
        ],
    );
    let w = warnings(&img);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("OpcodeList2: GainMap (opcode 1 of 1): every gain is <= 0 (the largest is -2): the whole image becomes 0 (black)"),
        "{}",
        w[0]
    );
    // A MapPolynomial of -0.5 over an area whose left equals its right: the whole image.
    let poly = OpcodeKind::MapPolynomial {
        area: area(0, 5, 48, 5),
        coefficients: vec![-0.5],
    };
    let img = frame(64, 48, [vec![], vec![poly], vec![]]);
    let w = warnings(&img);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("OpcodeList2: MapPolynomial (opcode 1 of 1): the polynomial is <= 0 for every value in [0, 1]: the whole image becomes 0 (black)"),
        "{}",
        w[0]
    );
    // --opcodes ignore: nothing to say.
    let c = check_render(&img, OpcodeMode::Ignore, true, true).unwrap();
    assert!(c.warnings.is_empty() && c.prepared.unwrap().is_noop());
}

#[test]
fn each_flattening_kind_warns_and_its_harmless_twin_does_not() {
    let a = area(0, 0, 8, 8);
    let cases: Vec<(OpcodeKind, Option<&str>)> = vec![
        (
            OpcodeKind::MapTable {
                area: a,
                table: vec![700; 300],
            },
            Some("every entry the samples can reach is 700: the whole image becomes 0.0106"),
        ),
        (
            OpcodeKind::MapTable {
                area: a,
                table: vec![0, 65535],
            },
            None,
        ),
        (
            OpcodeKind::MapPolynomial {
                area: a,
                coefficients: vec![2.0, 1.0],
            },
            Some("the polynomial is >= 1 for every value in [0, 1]: the whole image becomes 1 (the top of the range: white)"),
        ),
        (
            OpcodeKind::MapPolynomial {
                area: a,
                coefficients: vec![-0.5, 1.0],
            },
            None,
        ),
        (
            OpcodeKind::MapPolynomial {
                area: a,
                coefficients: vec![0.25, 0.0, 0.0],
            },
            Some("the polynomial is 0.25 for every value"),
        ),
        (
            OpcodeKind::ScalePerRow {
                area: a,
                scales: vec![0.0; 8],
            },
            Some("every scale is <= 0 (the largest is 0): the whole image becomes 0 (black)"),
        ),
        (
            OpcodeKind::ScalePerColumn {
                area: a,
                scales: vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5],
            },
            None,
        ),
        (
            OpcodeKind::DeltaPerColumn {
                area: a,
                deltas: vec![-65535.0; 8],
            },
            Some("every delta is <= -65535 (16-bit units): the whole image becomes 0 (black)"),
        ),
        (
            OpcodeKind::DeltaPerRow {
                area: a,
                deltas: vec![70000.0; 8],
            },
            Some("every delta is >= 65535"),
        ),
        (
            OpcodeKind::DeltaPerRow {
                area: a,
                deltas: vec![-65000.0; 8],
            },
            None,
        ),
        (
            // An empty area (left = right): the whole image, values indexed by row.
            OpcodeKind::DeltaPerRow {
                area: area(0, 3, 8, 3),
                deltas: vec![-70000.0; 8],
            },
            Some("every delta is <= -65535 (16-bit units): the whole image becomes 0 (black)"),
        ),
        (
            OpcodeKind::ScalePerRow {
                area: area(4, 3, 8, 3),
                scales: vec![0.0; 4],
            },
            None,
        ),
        (gain_map(a, 1, vec![0.0, -1.0, 0.0]), Some("every gain is <= 0 (the largest is 0)")),
        (gain_map(a, 1, vec![0.0, 1e-6]), None),
    ];
    for (k, (kind, want)) in cases.into_iter().enumerate() {
        let img = frame(8, 8, [vec![], vec![kind], vec![]]);
        let w = warnings(&img);
        match want {
            Some(text) => {
                assert_eq!(w.len(), 1, "case {k}: {w:?}");
                assert!(w[0].contains(text), "case {k}: {}", w[0]);
                assert!(w[0].starts_with("OpcodeList2: "), "case {k}: {}", w[0]);
            }
            None => assert!(w.is_empty(), "case {k}: {w:?}"),
        }
    }
}

#[test]
fn regions_planes_and_positions_are_named() {
    // Every 2nd row and column from (1, 0): one CFA colour of list 1, opcode 2 of 2.
    let pitched = AreaSpec {
        row_pitch: 2,
        col_pitch: 2,
        ..area(1, 0, 16, 16)
    };
    let img = frame(
        16,
        16,
        [
            vec![
                OpcodeKind::ScalePerRow {
                    area: area(0, 0, 16, 16),
                    scales: vec![1.0; 16],
                },
                gain_map(pitched, 1, vec![-1.0]),
            ],
            vec![],
            vec![],
        ],
    );
    let w = warnings(&img);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("OpcodeList1: GainMap (opcode 2 of 2)")
            && w[0].contains("every 2nd row of 1..16, every 2nd column of 0..16 of the image"),
        "{}",
        w[0]
    );
    // List 1 works on the stored image: only what falls in the active area counts.
    let mut outside = frame(
        16,
        16,
        [
            vec![gain_map(area(0, 0, 2, 16), 1, vec![-1.0])],
            vec![],
            vec![],
        ],
    );
    outside.meta.active_area = Some(Rect {
        top: 2,
        left: 0,
        bottom: 16,
        right: 16,
    });
    assert!(warnings(&outside).is_empty());
    // Stage 3 has three planes: a map whose plane 1 is <= 0 names plane 1.
    let a3 = AreaSpec {
        planes: 3,
        ..area(0, 0, 8, 8)
    };
    let img = frame(
        8,
        8,
        [vec![], vec![], vec![gain_map(a3, 3, vec![1.0, -0.5, 2.0])]],
    );
    let w = warnings(&img);
    assert!(
        w[0].contains("plane 1 of the whole image becomes 0"),
        "{w:?}"
    );
    // After a TrimBounds, list 3 works on the trimmed rectangle.
    let img = frame(
        8,
        8,
        [
            vec![],
            vec![],
            vec![
                OpcodeKind::TrimBounds {
                    bounds: [2, 2, 6, 6],
                },
                OpcodeKind::ScalePerRow {
                    area: area(2, 0, 6, 8),
                    scales: vec![0.0; 4],
                },
            ],
        ],
    );
    let w = warnings(&img);
    assert!(
        w.iter()
            .any(|w| w.contains("ScalePerRow (opcode 2 of 2)") && w.contains("the whole image")),
        "{w:?}"
    );
}

#[test]
fn a_vignette_that_is_never_positive_warns() {
    let v = |k0: f64| OpcodeKind::FixVignetteRadial {
        k: [k0, 0.0, 0.0, 0.0, 0.0],
        center: [0.0, 0.0],
    };
    // 2x2, centre at the corner: r^2 from 1/16 to 9/16; 1 + k0 r^2 <= 0 needs k0 <= -16.
    assert!(
        warnings(&frame(2, 2, [vec![], vec![v(-20.0)], vec![]]))[0].contains("FixVignetteRadial")
    );
    assert!(warnings(&frame(2, 2, [vec![], vec![v(-10.0)], vec![]])).is_empty());
    // On a real frame the centre pixel keeps a gain near 1.
    let middle = OpcodeKind::FixVignetteRadial {
        k: [-2.0, 0.0, 0.0, 0.0, 0.0],
        center: [0.5, 0.5],
    };
    assert!(warnings(&frame(64, 48, [vec![], vec![middle], vec![]])).is_empty());
}

#[test]
fn a_trim_that_changes_the_size_is_said_and_measured() {
    let trim = |b: [u32; 4]| OpcodeKind::TrimBounds { bounds: b };
    let img = frame(64, 48, [vec![], vec![], vec![trim([8, 16, 24, 48])]]);
    let c = check_render(&img, OpcodeMode::Apply, true, true).unwrap();
    assert_eq!(c.trimmed_size, Some((32, 16)));
    assert_eq!(c.warnings.len(), 1);
    assert_eq!(c.warnings[0].code, crate::diagnostics::Code::OpcodeTrim);
    assert!(
        c.warnings[0]
            .message
            .contains("OpcodeList3: TrimBounds (opcode 1 of 1) keeps rows 8..24, columns 16..48")
            && c.warnings[0]
                .message
                .contains("rendered images are 32x16 pixels where the raw's default crop is 64x48"),
        "{}",
        c.warnings[0]
    );
    // Orientation 6 turns both sizes.
    let mut turned = img.clone();
    turned.meta.orientation = 6;
    let c = check_render(&turned, OpcodeMode::Apply, true, true).unwrap();
    assert_eq!(c.trimmed_size, Some((16, 32)));
    assert!(c.warnings[0]
        .message
        .contains("16x32 pixels where the raw's default crop is 48x64"));
    // A trim around the DefaultCrop does not change the size: nothing to say.
    let mut cropped = frame(64, 48, [vec![], vec![], vec![trim([4, 4, 44, 60])]]);
    cropped.meta.default_crop_origin = Some([8.0, 8.0]);
    cropped.meta.default_crop_size = Some([48.0, 32.0]);
    let c = check_render(&cropped, OpcodeMode::Apply, true, true).unwrap();
    assert_eq!((c.trimmed_size, c.warnings.len()), (None, 0));
    // ... but it does without the crop.
    let c = check_render(&cropped, OpcodeMode::Apply, false, true).unwrap();
    assert_eq!(c.trimmed_size, Some((56, 40)));
    // Outside the image, or nothing left of the crop: the render's errors, before it runs.
    let e = check_render(
        &frame(64, 48, [vec![], vec![], vec![trim([0, 0, 49, 64])]]),
        OpcodeMode::Apply,
        true,
        true,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("TrimBounds") && e.contains("not inside the image"),
        "{e}"
    );
    let mut apart = frame(64, 48, [vec![], vec![], vec![trim([0, 0, 8, 8])]]);
    apart.meta.default_crop_origin = Some([16.0, 16.0]);
    apart.meta.default_crop_size = Some([16.0, 16.0]);
    let e = check_render(&apart, OpcodeMode::Apply, true, true)
        .unwrap_err()
        .to_string();
    assert!(e.contains("leaves nothing of the DefaultCrop"), "{e}");
}

fn unknown(id: u32, flags: u32) -> Opcode {
    Opcode {
        id,
        dng_version: [1, 3, 0, 0],
        flags,
        kind: OpcodeKind::Unknown {
            params: vec![],
            len: 0,
        },
    }
}

/// A mandatory opcode OpcodeList3 cannot apply (bad pixels are fixed on the mosaic).
fn bad_pixels_in_list3() -> Opcode {
    Opcode::new(
        OpcodeKind::FixBadPixelsConstant {
            constant: 0,
            bayer_phase: 0,
        },
        0,
    )
}

#[test]
fn without_a_render_nothing_fails_and_the_report_says_why() {
    let mut img = frame(
        8,
        8,
        [
            vec![],
            vec![gain_map(area(0, 0, 8, 8), 1, vec![1.5])],
            vec![],
        ],
    );
    img.meta.opcode_lists[0] = Some(vec![0, 0, 0, 1, 0, 0]); // malformed: truncated
    img.meta.opcode_lists[2] = Some(encode_list(&OpcodeList {
        opcodes: vec![bad_pixels_in_list3(), unknown(99, FLAG_OPTIONAL)],
    }));
    // A render refuses it.
    assert!(check_render(&img, OpcodeMode::Apply, true, true).is_err());
    let (report, warnings) = report_without_render(&img.meta, OpcodeMode::Apply);
    let report = report.unwrap();
    assert_eq!(report.applied.len(), 1);
    assert_eq!(report.applied[0].name, "GainMap");
    let skipped: Vec<(&str, &str, u32)> = report
        .skipped
        .iter()
        .map(|e| (e.list.as_str(), e.name.as_str(), e.id))
        .collect();
    assert_eq!(
        skipped,
        [
            ("OpcodeList1", MALFORMED_LIST, 0),
            ("OpcodeList3", "FixBadPixelsConstant", 4),
            ("OpcodeList3", "unknown", 99)
        ]
    );
    assert!(report.skipped[1]
        .reason
        .as_deref()
        .unwrap()
        .ends_with("not optional (no render was requested)"));
    assert_eq!(warnings.len(), 3, "{warnings:?}");
    use crate::diagnostics::Code;
    let codes: Vec<Code> = warnings.iter().map(|w| w.code).collect();
    assert_eq!(
        codes,
        [
            Code::OpcodeListMalformed,
            Code::OpcodeNotApplied,
            Code::OpcodeSkipped
        ]
    );
    let warnings = warnings.messages();
    assert!(
        warnings[0].starts_with("OpcodeList1: ")
            && warnings[0].contains("the list is malformed; no render was requested"),
        "{}",
        warnings[0]
    );
    assert!(
        warnings[1].starts_with("OpcodeList3: FixBadPixelsConstant (id 4) is not optional"),
        "{}",
        warnings[1]
    );
    // The optional skip says what a render says.
    assert_eq!(
        warnings[2],
        "OpcodeList3: unknown (id 99), optional, skipped: not implemented by day2night"
    );
    // A file a render accepts gets the render's report and warnings, word for word.
    let fine = frame(
        8,
        8,
        [
            vec![],
            vec![gain_map(area(0, 0, 8, 8), 1, vec![1.5])],
            vec![],
        ],
    );
    let mut fine = fine;
    fine.meta.opcode_lists[2] = Some(encode_list(&OpcodeList {
        opcodes: vec![unknown(99, FLAG_OPTIONAL)],
    }));
    let with = check_render(&fine, OpcodeMode::Apply, true, true).unwrap();
    let (without, w) = report_without_render(&fine.meta, OpcodeMode::Apply);
    assert_eq!(without.as_ref(), with.prepared.as_ref().map(|p| &p.report));
    assert_eq!(w, with.warnings);
    // No list, or ignore: as prepare says.
    assert_eq!(
        report_without_render(&frame(4, 4, Default::default()).meta, OpcodeMode::Apply),
        (None, Default::default())
    );
    let (r, w) = report_without_render(&img.meta, OpcodeMode::Ignore);
    assert!(r.unwrap().applied.is_empty() && w.is_empty());
}

#[test]
fn unrenderable_lists_are_named_one_by_one() {
    let mut img = frame(
        8,
        8,
        [
            vec![gain_map(area(0, 0, 8, 8), 1, vec![1.5])],
            vec![],
            vec![],
        ],
    );
    img.meta.opcode_lists[1] = Some(vec![0, 0, 0, 2]);
    img.meta.opcode_lists[2] = Some(encode_list(&OpcodeList {
        opcodes: vec![bad_pixels_in_list3()],
    }));
    let bad: Vec<(ListId, String)> = unrenderable_lists(&img)
        .into_iter()
        .map(|(l, e)| (l, e.to_string()))
        .collect();
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert_eq!(bad[0].0, ListId::List2);
    assert!(bad[0].1.contains("OpcodeList2"), "{}", bad[0].1);
    assert_eq!(bad[1].0, ListId::List3);
    assert!(
        bad[1]
            .1
            .contains("FixBadPixelsConstant (id 4) is not optional"),
        "{}",
        bad[1].1
    );
    let trim = frame(
        8,
        8,
        [
            vec![],
            vec![],
            vec![OpcodeKind::TrimBounds {
                bounds: [0, 0, 9, 8],
            }],
        ],
    );
    assert_eq!(unrenderable_lists(&trim).len(), 1);
    assert!(unrenderable_lists(&frame(8, 8, Default::default())).is_empty());
}

#[test]
fn linear_raw_stages_have_three_planes() {
    let mut img = frame(8, 8, [vec![], vec![], vec![]]);
    img.meta.cfa.rows = 0;
    img.meta.cfa.cols = 0;
    img.meta.cfa.pattern.clear();
    img.meta.levels = Levels {
        black_repeat: (1, 1),
        black: vec![0.0],
        black_delta_h: vec![],
        black_delta_v: vec![],
        white: 65535.0,
    };
    img.meta.linear_raw = Some(LinearRaw {
        samples_per_pixel: 3,
        black: vec![0.0; 3],
        white: vec![65535.0; 3],
    });
    img.data = vec![1000; 8 * 8 * 3];
    let a = AreaSpec {
        plane: 2,
        ..area(0, 0, 8, 8)
    };
    let poly = OpcodeKind::MapPolynomial {
        area: a,
        coefficients: vec![0.0, 0.0],
    };
    img.meta.opcode_lists[1] = Some(encode_list(&OpcodeList {
        opcodes: vec![Opcode::new(poly, 0)],
    }));
    let w = warnings(&img);
    assert!(
        w[0].contains("OpcodeList2: MapPolynomial (opcode 1 of 1)")
            && w[0].contains("plane 2 of the whole image becomes 0"),
        "{w:?}"
    );
}
