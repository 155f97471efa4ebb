//! Tests of the opcode parser and encoder: hand-written byte layouts against the
//! specification, every rejection naming its field, and round trips of arbitrary lists.

use super::*;
use crate::error::Error;
use crate::limits::{MAX_GAIN_MAP_POINTS, MAX_OPCODES_PER_LIST};
use proptest::prelude::*;

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

fn gain_map() -> GainMap {
    GainMap {
        area: AreaSpec {
            row_pitch: 2,
            col_pitch: 2,
            ..area(0, 1, 3000, 4001)
        },
        points_v: 2,
        points_h: 3,
        spacing_v: 1.0,
        spacing_h: 0.5,
        origin_v: 0.0,
        origin_h: 0.0,
        map_planes: 1,
        gains: vec![2.0, 1.5, 2.0, 1.25, 1.0, 1.25],
    }
}

fn one(kind: OpcodeKind) -> OpcodeList {
    OpcodeList {
        opcodes: vec![Opcode::new(kind, FLAG_OPTIONAL)],
    }
}

fn err(bytes: &[u8]) -> String {
    parse_list(bytes).unwrap_err().to_string()
}

#[test]
fn gain_map_bytes_follow_the_specification() {
    let l = one(OpcodeKind::GainMap(gain_map()));
    let b = encode_list(&l);
    // count, id 9, version 1.3.0.0, flags 1, 76 + 6*4 bytes of parameters.
    assert_eq!(&b[..4], &[0, 0, 0, 1]);
    assert_eq!(&b[4..8], &[0, 0, 0, 9]);
    assert_eq!(&b[8..12], &[1, 3, 0, 0]);
    assert_eq!(&b[12..16], &[0, 0, 0, 1]);
    assert_eq!(&b[16..20], &100u32.to_be_bytes());
    assert_eq!(b.len(), 20 + 100);
    // area: top 0, left 1, bottom 3000, right 4001, plane 0, planes 1, pitches 2.
    assert_eq!(&b[20..24], &0u32.to_be_bytes());
    assert_eq!(&b[24..28], &1u32.to_be_bytes());
    assert_eq!(&b[48..52], &2u32.to_be_bytes());
    // points 2 x 3, spacing_h 0.5, first gain 2.0f32.
    assert_eq!(&b[52..56], &2u32.to_be_bytes());
    assert_eq!(&b[56..60], &3u32.to_be_bytes());
    assert_eq!(&b[68..76], &0.5f64.to_be_bytes());
    assert_eq!(&b[92..96], &1u32.to_be_bytes());
    assert_eq!(&b[96..100], &2.0f32.to_be_bytes());
    let p = parse_list(&b).unwrap();
    assert_eq!(p, l);
    assert!(p.opcodes[0].optional());
    assert_eq!(p.opcodes[0].name(), "GainMap");
}

#[test]
fn empty_list_and_unknown_opcode() {
    assert_eq!(parse_list(&[0, 0, 0, 0]).unwrap(), OpcodeList::default());
    let mut op = Opcode::new(
        OpcodeKind::Unknown {
            params: vec![1, 2, 3],
            len: 3,
        },
        FLAG_OPTIONAL,
    );
    op.id = 15;
    let l = OpcodeList { opcodes: vec![op] };
    let p = parse_list(&encode_list(&l)).unwrap();
    assert_eq!(p, l);
    assert_eq!(p.opcodes[0].name(), "unknown");
}

#[test]
fn warp_rectilinear2_round_trips_in_the_sdk_layout() {
    let mut kr = [0.0; 15];
    kr[0] = 1.0;
    kr[14] = -0.5;
    let plane = super::WarpPlane2 {
        kr,
        kt: [0.001, -0.002],
        valid: [0.0, 0.75],
    };
    let op = Opcode::new(
        OpcodeKind::WarpRectilinear2 {
            planes: vec![plane; 3],
            center: [0.25, 0.5],
            reciprocal: true,
        },
        0,
    );
    assert_eq!(op.id, 14);
    let l = OpcodeList { opcodes: vec![op] };
    let b = encode_list(&l);
    // count, header, then N, 19 doubles per plane, the centre and the reciprocal flag
    let n = u32::from_be_bytes(b[16..20].try_into().unwrap()) as usize;
    assert_eq!(n, 4 + 19 * 8 * 3 + 16 + 4);
    assert_eq!(&b[b.len() - 4..], &1u32.to_be_bytes());
    assert_eq!(parse_list(&b).unwrap(), l);
    // a valid range with min >= max, or max > 1, is malformed (the SDK refuses it too)
    for valid in [[0.5, 0.5], [0.0, 1.5], [-0.1, 0.5]] {
        let bad = OpcodeList {
            opcodes: vec![Opcode::new(
                OpcodeKind::WarpRectilinear2 {
                    planes: vec![super::WarpPlane2 { valid, ..plane }],
                    center: [0.5, 0.5],
                    reciprocal: false,
                },
                0,
            )],
        };
        let e = parse_list(&encode_list(&bad)).unwrap_err().to_string();
        assert!(e.contains("plane 0: valid radius range"), "{e}");
    }
    // one byte short
    let mut short = b.clone();
    short.pop();
    short[19] -= 1;
    assert!(parse_list(&short).is_err());
}

#[test]
fn truncations_and_counts_are_malformed() {
    assert!(err(&[]).contains("too short for the opcode count"));
    assert!(err(&[0, 0, 1]).contains("too short"));
    // A hostile count is refused before anything is allocated.
    let e = parse_list(&[0xff, 0xff, 0xff, 0xff]).unwrap_err();
    assert!(matches!(e, Error::Limits(_)), "{e}");
    let mut b = (MAX_OPCODES_PER_LIST).to_be_bytes().to_vec();
    b.extend_from_slice(&[0; 16]);
    assert!(err(&b).contains("need at least"), "{}", err(&b));
    // Parameter count past the end.
    let mut b = encode_list(&one(OpcodeKind::GainMap(gain_map())));
    b[19] = 200;
    assert!(err(&b).contains("runs past the end"), "{}", err(&b));
    // Trailing bytes.
    let mut b = encode_list(&one(OpcodeKind::TrimBounds {
        bounds: [0, 0, 2, 2],
    }));
    b.push(0);
    assert!(err(&b).contains("1 bytes after the last"), "{}", err(&b));
    // Every prefix of a valid list is malformed, never a panic.
    let b = encode_list(&one(OpcodeKind::GainMap(gain_map())));
    for n in 0..b.len() {
        assert!(parse_list(&b[..n]).is_err(), "{n}");
    }
}

/// Patch the parameter byte count of the first opcode and append/remove bytes.
fn with_param_len(mut b: Vec<u8>, n: u32) -> Vec<u8> {
    b[16..20].copy_from_slice(&n.to_be_bytes());
    b.resize(20 + n as usize, 0);
    b
}

#[test]
fn declared_byte_count_must_equal_the_kind() {
    let b = encode_list(&one(OpcodeKind::FixBadPixelsConstant {
        constant: 0,
        bayer_phase: 1,
    }));
    let e = err(&with_param_len(b, 12));
    assert!(
        e.contains("FixBadPixelsConstant (opcode 1 of 1)")
            && e.contains("is 12, its fields need 8"),
        "{e}"
    );
    let b = encode_list(&one(OpcodeKind::GainMap(gain_map())));
    let e = err(&with_param_len(b.clone(), 104));
    assert!(e.contains("is 104, its fields need 100"), "{e}");
    let e = err(&with_param_len(b, 40));
    assert!(e.contains("fixed fields alone need 76"), "{e}");
}

fn gain_map_err(f: impl FnOnce(&mut GainMap)) -> String {
    let mut g = gain_map();
    f(&mut g);
    err(&encode_list(&one(OpcodeKind::GainMap(g))))
}

#[test]
fn gain_map_fields_are_checked() {
    let e = gain_map_err(|g| g.points_v = 0);
    assert!(
        e.contains("GainMap (opcode 1 of 1): MapPointsV is 0"),
        "{e}"
    );
    let e = gain_map_err(|g| g.map_planes = 0);
    assert!(e.contains("MapPlanes is 0"), "{e}");
    let e = gain_map_err(|g| g.spacing_h = 0.0);
    assert!(e.contains("MapSpacingH is 0"), "{e}");
    let e = gain_map_err(|g| g.origin_v = f64::NAN);
    assert!(e.contains("MapOriginV is NaN"), "{e}");
    let e = gain_map_err(|g| g.gains[4] = f32::INFINITY);
    assert!(
        e.contains("MapGain at row 1, column 1, plane 0 is inf"),
        "{e}"
    );
    // Gains count must be V*H*planes: one plane more than the gains written.
    let e = gain_map_err(|g| g.map_planes = 2);
    assert!(e.contains("its fields need 124"), "{e}");
    let e = gain_map_err(|g| g.area.top = 3001);
    assert!(e.contains("Top 3001 is below Bottom 3000"), "{e}");
    let e = gain_map_err(|g| g.area.left = 4002);
    assert!(e.contains("Left 4002"), "{e}");
    let e = gain_map_err(|g| g.area.planes = 0);
    assert!(e.contains("Planes is 0"), "{e}");
    let e = gain_map_err(|g| g.area.row_pitch = 0);
    assert!(e.contains("RowPitch 0"), "{e}");
    let e = gain_map_err(|g| {
        g.area.plane = u32::MAX;
        g.area.planes = 2;
    });
    assert!(e.contains("overflows"), "{e}");
    let e = gain_map_err(|g| g.area.bottom = 0);
    assert!(e.contains("empty area with RowPitch 2"), "{e}");
    // One map point along an axis: spacing unused, accepted.
    let mut g = gain_map();
    g.points_v = 1;
    g.spacing_v = 0.0;
    g.gains.truncate(3);
    let l = one(OpcodeKind::GainMap(g));
    assert_eq!(parse_list(&encode_list(&l)).unwrap(), l);
    // A huge map is a limit, before its bytes are looked at.
    let e = parse_list(&encode_list(&one(OpcodeKind::GainMap(GainMap {
        points_v: 1 << 12,
        points_h: 1 << 12,
        map_planes: 4,
        gains: vec![],
        ..gain_map()
    }))))
    .unwrap_err();
    assert!(matches!(e, Error::Limits(_)), "{e}");
    assert!(
        e.to_string().contains(&MAX_GAIN_MAP_POINTS.to_string()),
        "{e}"
    );
}

#[test]
fn other_kinds_are_checked() {
    let e = err(&encode_list(&one(OpcodeKind::MapTable {
        area: area(0, 0, 4, 4),
        table: vec![],
    })));
    assert!(
        e.contains("MapTable (opcode 1 of 1): TableSize is 0"),
        "{e}"
    );
    let e = err(&encode_list(&one(OpcodeKind::MapPolynomial {
        area: area(0, 0, 4, 4),
        coefficients: vec![0.0; 10],
    })));
    assert!(e.contains("Degree 9 exceeds"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::MapPolynomial {
        area: area(0, 0, 4, 4),
        coefficients: vec![0.0, f64::NEG_INFINITY],
    })));
    assert!(e.contains("Coefficient 1 is -inf"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::DeltaPerRow {
        area: AreaSpec {
            row_pitch: 2,
            ..area(0, 0, 5, 4)
        },
        deltas: vec![0.0; 2],
    })));
    assert!(e.contains("Count is 2, the area has 3 row steps"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::ScalePerColumn {
        area: area(0, 0, 5, 4),
        scales: vec![1.0; 5],
    })));
    assert!(e.contains("Count is 5, the area has 4 column steps"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::WarpRectilinear {
        planes: vec![],
        center: [0.5, 0.5],
    })));
    assert!(e.contains("N (planes) is 0"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::WarpRectilinear {
        planes: vec![
            WarpPlane {
                kr: [1.0, 0.0, 0.0, 0.0],
                kt: [0.0, 0.0]
            };
            5
        ],
        center: [0.5, 0.5],
    })));
    assert!(e.contains("N (planes) is 5"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::FixVignetteRadial {
        k: [0.0; 5],
        center: [0.5, 1.5],
    })));
    assert!(e.contains("cy is 1.5"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::TrimBounds {
        bounds: [2, 0, 2, 4],
    })));
    assert!(e.contains("TrimBounds") && e.contains("empty"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::FixBadPixelsConstant {
        constant: 0,
        bayer_phase: 4,
    })));
    assert!(e.contains("BayerPhase is 4"), "{e}");
    let e = err(&encode_list(&one(OpcodeKind::FixBadPixelsList {
        bayer_phase: 0,
        points: vec![[1, 1]],
        rects: vec![[5, 0, 4, 2]],
    })));
    assert!(e.contains("BadRect 0") && e.contains("inverted"), "{e}");
    // Counts that do not fit the bytes.
    let mut b = encode_list(&one(OpcodeKind::FixBadPixelsList {
        bayer_phase: 0,
        points: vec![[1, 1]],
        rects: vec![],
    }));
    b[27] = 2; // BadPointCount 2, bytes for 1
    assert!(err(&b).contains("its fields need 28"), "{}", err(&b));
    b[24..28].copy_from_slice(&u32::MAX.to_be_bytes());
    let e = parse_list(&b).unwrap_err();
    assert!(matches!(e, Error::Limits(_)), "{e}");
}

#[test]
fn lists_name_the_tag() {
    let mut m = crate::raw::meta::RawMeta::new_bayer(crate::raw::Bayer::RGGB, 12, 0.0, 4095.0);
    assert_eq!(lists(&m).unwrap(), <[OpcodeList; 3]>::default());
    let good = one(OpcodeKind::GainMap(gain_map()));
    m.opcode_lists[1] = Some(encode_list(&good));
    let [l1, l2, l3] = lists(&m).unwrap();
    assert!(l1.opcodes.is_empty() && l3.opcodes.is_empty());
    assert_eq!(l2, good);
    let mut bad = gain_map();
    bad.points_h = 0;
    m.opcode_lists[2] = Some(encode_list(&one(OpcodeKind::GainMap(bad))));
    let e = lists(&m).unwrap_err().to_string();
    assert!(
        e.contains("OpcodeList3: GainMap (opcode 1 of 1): MapPointsH is 0"),
        "{e}"
    );
    let r = list_results(&m);
    assert!(r[0].is_none());
    assert!(matches!(r[1], Some(Ok(_))));
    assert!(matches!(r[2], Some(Err(_))));
}

// ---- property tests ----

fn finite64() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e6..1e6f64,
        Just(0.0),
        Just(-0.0),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE)
    ]
}

fn finite32() -> impl Strategy<Value = f32> {
    prop_oneof![-1e6..1e6f32, Just(0.0), Just(f32::MAX)]
}

fn unit() -> impl Strategy<Value = f64> {
    0.0..=1.0f64
}

fn arb_area() -> impl Strategy<Value = AreaSpec> {
    (
        0u32..100,
        0u32..100,
        0u32..100,
        0u32..100,
        0u32..4,
        1u32..4,
        1u32..5,
        1u32..5,
    )
        .prop_map(|(t, l, h, w, plane, planes, rp, cp)| {
            let empty = h == 0 || w == 0;
            AreaSpec {
                top: t,
                left: l,
                bottom: t + h,
                right: l + w,
                plane,
                planes,
                row_pitch: if empty { 1 } else { rp },
                col_pitch: if empty { 1 } else { cp },
            }
        })
}

fn arb_gain_map() -> impl Strategy<Value = GainMap> {
    (
        arb_area(),
        1u32..6,
        1u32..6,
        1u32..4,
        1e-3..1.0f64,
        1e-3..1.0f64,
        finite64(),
        finite64(),
    )
        .prop_flat_map(|(a, v, h, mp, sv, sh, ov, oh)| {
            proptest::collection::vec(finite32(), (v * h * mp) as usize).prop_map(move |gains| {
                GainMap {
                    area: a,
                    points_v: v,
                    points_h: h,
                    spacing_v: sv,
                    spacing_h: sh,
                    origin_v: ov,
                    origin_h: oh,
                    map_planes: mp,
                    gains,
                }
            })
        })
}

fn per_line(id: u32) -> impl Strategy<Value = OpcodeKind> {
    arb_area().prop_flat_map(move |a| {
        let n = if id == 10 || id == 12 {
            area_row_steps(&a)
        } else {
            area_col_steps(&a)
        };
        proptest::collection::vec(finite32(), n as usize).prop_map(move |v| match id {
            10 => OpcodeKind::DeltaPerRow { area: a, deltas: v },
            11 => OpcodeKind::DeltaPerColumn { area: a, deltas: v },
            12 => OpcodeKind::ScalePerRow { area: a, scales: v },
            _ => OpcodeKind::ScalePerColumn { area: a, scales: v },
        })
    })
}

fn arb_kind() -> impl Strategy<Value = OpcodeKind> {
    let warp_plane = (
        [finite64(), finite64(), finite64(), finite64()],
        [finite64(), finite64()],
    )
        .prop_map(|(kr, kt)| WarpPlane { kr, kt });
    prop_oneof![
        (
            proptest::collection::vec(warp_plane, 1..=4),
            [unit(), unit()]
        )
            .prop_map(|(planes, center)| OpcodeKind::WarpRectilinear { planes, center }),
        (
            proptest::collection::vec([finite64(), finite64(), finite64(), finite64()], 1..=4),
            [unit(), unit()]
        )
            .prop_map(|(planes, center)| OpcodeKind::WarpFisheye { planes, center }),
        (
            [finite64(), finite64(), finite64(), finite64(), finite64()],
            [unit(), unit()]
        )
            .prop_map(|(k, center)| OpcodeKind::FixVignetteRadial { k, center }),
        (any::<u32>(), 0u32..4).prop_map(|(constant, bayer_phase)| {
            OpcodeKind::FixBadPixelsConstant {
                constant,
                bayer_phase,
            }
        }),
        (
            0u32..4,
            proptest::collection::vec(any::<[u32; 2]>(), 0..5),
            proptest::collection::vec((0u32..1000, 0u32..1000, 0u32..10, 0u32..10), 0..5)
        )
            .prop_map(|(bayer_phase, points, r)| OpcodeKind::FixBadPixelsList {
                bayer_phase,
                points,
                rects: r
                    .into_iter()
                    .map(|(t, l, h, w)| [t, l, t + h, l + w])
                    .collect(),
            }),
        (0u32..100, 0u32..100, 1u32..100, 1u32..100).prop_map(|(t, l, h, w)| {
            OpcodeKind::TrimBounds {
                bounds: [t, l, t + h, l + w],
            }
        }),
        (arb_area(), proptest::collection::vec(any::<u16>(), 1..50))
            .prop_map(|(area, table)| OpcodeKind::MapTable { area, table }),
        (arb_area(), proptest::collection::vec(finite64(), 1..=9))
            .prop_map(|(area, coefficients)| OpcodeKind::MapPolynomial { area, coefficients }),
        arb_gain_map().prop_map(OpcodeKind::GainMap),
        per_line(10),
        per_line(11),
        per_line(12),
        per_line(13),
    ]
}

fn arb_opcode() -> impl Strategy<Value = Opcode> {
    let known = (arb_kind(), any::<[u8; 4]>(), any::<u32>()).prop_map(|(kind, v, flags)| {
        let mut op = Opcode::new(kind, flags);
        op.dng_version = v;
        op
    });
    let unknown = (
        prop_oneof![Just(0u32), 15u32..1000, Just(u32::MAX)],
        proptest::collection::vec(any::<u8>(), 0..40),
        any::<u32>(),
    )
        .prop_map(|(id, params, flags)| {
            let len = params.len();
            let mut op = Opcode::new(OpcodeKind::Unknown { params, len }, flags);
            op.id = id;
            op
        });
    prop_oneof![4 => known, 1 => unknown]
}

proptest! {
    #[test]
    fn encode_then_parse_is_identity(ops in proptest::collection::vec(arb_opcode(), 0..6)) {
        let l = OpcodeList { opcodes: ops };
        let b = encode_list(&l);
        let p = parse_list(&b).unwrap();
        prop_assert_eq!(&p, &l);
        prop_assert_eq!(encode_list(&p), b);
    }

    #[test]
    fn parse_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = parse_list(&bytes);
    }

    #[test]
    fn mutated_valid_lists_never_panic(
        ops in proptest::collection::vec(arb_opcode(), 1..4),
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
    ) {
        let mut b = encode_list(&OpcodeList { opcodes: ops });
        for (i, v) in edits {
            let at = i.index(b.len());
            b[at] = v;
        }
        if let Ok(l) = parse_list(&b) {
            // Whatever parses re-encodes to the same bytes.
            prop_assert_eq!(encode_list(&l), b);
        }
    }
}
