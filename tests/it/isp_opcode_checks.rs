//! The checks of opcode lists around renders (docs/isp.md, "Checks before and after
//! rendering"): without a render, lists a render could not apply only warn (`synth
//! --target none`, `dataset`); opcodes whose parameters make their samples constant warn
//! before rendering, naming the list and position (the issue's negative GainMap and
//! empty-area MapPolynomial); a render that comes out constant warns (a random set of
//! opcode lists: every constant render warned, every warning was true); an OpcodeList3
//! TrimBounds that changes the target's size is said and recorded in the sidecar.
use crate::common;
use crate::dngbuild::Builder;

use day2night::dng::opcodes::{
    encode_list, AreaSpec, GainMap, Opcode, OpcodeKind, OpcodeList, WarpPlane,
};
use day2night::encode::read::read_image;
use std::path::{Path, PathBuf};
use std::process::Output;

fn area(top: u32, left: u32, bottom: u32, right: u32, planes: u32) -> AreaSpec {
    AreaSpec {
        top,
        left,
        bottom,
        right,
        plane: 0,
        planes,
        row_pitch: 1,
        col_pitch: 1,
    }
}

fn list(ops: Vec<OpcodeKind>) -> Vec<u8> {
    encode_list(&OpcodeList {
        opcodes: ops.into_iter().map(|k| Opcode::new(k, 0)).collect(),
    })
}

/// A 16-bit `w x h` DNG at `dir/name` with the list bytes given (1, 2, 3).
fn dng(dir: &Path, name: &str, (w, h): (usize, usize), lists: &[(u8, Vec<u8>)]) -> PathBuf {
    let mut b = Builder::new(w, h, 16);
    for (n, bytes) in lists {
        b = b.opcode_list(*n, bytes.clone());
    }
    let p = dir.join(name);
    std::fs::write(&p, b.build()).unwrap();
    p
}

fn run(args: &[&std::ffi::OsStr]) -> (Output, String) {
    let r = common::bin().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    (r, err)
}

fn os<'a>(v: &'a [&'a str]) -> Vec<&'a std::ffi::OsStr> {
    v.iter().map(std::ffi::OsStr::new).collect()
}

fn sidecar(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

fn negative_gain(w: u32, h: u32) -> OpcodeKind {
    OpcodeKind::GainMap(GainMap {
        area: area(0, 0, h, w, 1),
        points_v: 2,
        points_h: 2,
        spacing_v: 1.0,
        spacing_h: 1.0,
        origin_v: 0.0,
        origin_h: 0.0,
        map_planes: 1,
        gains: vec![-2.0; 4],
    })
}

#[test]
fn without_a_render_unusable_lists_warn_and_with_one_they_fail() {
    let t = tempfile::tempdir().unwrap();
    // A mandatory opcode OpcodeList3 cannot apply (bad pixels are fixed on the mosaic).
    let bad_pixels = Opcode::new(
        OpcodeKind::FixBadPixelsConstant {
            constant: 0,
            bayer_phase: 0,
        },
        0,
    );
    let f = dng(
        t.path(),
        "bad.dng",
        (24, 16),
        &[
            (2, vec![0, 0, 0, 1, 0, 0, 0, 9]), // malformed: a count of 1, no opcode
            (
                3,
                encode_list(&OpcodeList {
                    opcodes: vec![bad_pixels],
                }),
            ),
        ],
    );
    let o = t.path().join("none");
    let (r, err) = run(&os(&[
        "synth",
        f.to_str().unwrap(),
        "-o",
        o.to_str().unwrap(),
        "--iso",
        "1600",
        "--target",
        "none",
    ]));
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("warning[opcode-list-malformed]: bad.dng: OpcodeList2: ")
            && err.contains("the list is malformed; no render was requested"),
        "{err}"
    );
    assert!(
        err.contains(
            "warning[opcode-not-applied]: bad.dng: OpcodeList3: FixBadPixelsConstant (id 4) is not optional"
        ),
        "{err}"
    );
    let sc = sidecar(&o.join("bad.json"));
    let skipped = &sc["report"]["opcodes"]["skipped"];
    assert_eq!(skipped[0]["list"], "OpcodeList2");
    assert_eq!(skipped[0]["name"], "(malformed list)");
    assert_eq!(skipped[1]["name"], "FixBadPixelsConstant");
    assert!(skipped[1]["reason"]
        .as_str()
        .unwrap()
        .contains("not optional (no render was requested)"));
    // The two opcode warnings, with their codes, about the input (the fixture's noise
    // calibration adds its own: not this test's).
    let opcode_warnings: Vec<(&str, &str)> = sc["report"]["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|w| w["message"].as_str().unwrap().starts_with("OpcodeList"))
        .map(|w| (w["code"].as_str().unwrap(), w["subject"].as_str().unwrap()))
        .collect();
    assert_eq!(
        opcode_warnings,
        [
            ("opcode-list-malformed", "bad.dng"),
            ("opcode-not-applied", "bad.dng")
        ],
        "{}",
        sc["report"]["warnings"]
    );
    assert!(!sc["stages"]
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s == "apply_opcodes"));
    assert!(o.join("bad_clean.dng").exists() && o.join("bad_iso1600.dng").exists());
    // With a render (the default target, or only the network input) it is an error, as
    // before, naming the list, and nothing is written.
    for extra in [
        &["--target", "exr"][..],
        &["--target", "none", "--input-exr"][..],
    ] {
        let o = t.path().join(format!("with{}", extra.len()));
        let mut a = vec![
            "synth",
            f.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
            "--iso",
            "none",
        ];
        a.extend(extra);
        let (r, err) = run(&os(&a));
        assert!(!r.status.success(), "{extra:?}");
        assert!(
            err.contains("bad.dng") && err.contains("OpcodeList2"),
            "{err}"
        );
        assert!(!o.join("bad.json").exists() && !o.join("bad_clean.dng").exists());
    }
    // dataset without a target: the unit is made, the sidecar records the skips.
    let day = t.path().join("day");
    std::fs::create_dir(&day).unwrap();
    std::fs::copy(&f, day.join("bad.dng")).unwrap();
    let out = t.path().join("ds");
    let (r, err) = run(&os(&[
        "dataset",
        day.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--iso",
        "none",
        "--target",
        "none",
        "-q",
    ]));
    assert!(r.status.success(), "{err}");
    let meta: Vec<PathBuf> = walk(&out)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    assert_eq!(meta.len(), 1, "{meta:?}");
    assert_eq!(
        sidecar(&meta[0])["report"]["opcodes"]["skipped"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![];
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// Per plane, the one value of `img` when it holds one everywhere.
fn constant_planes(path: &Path) -> [Option<f32>; 3] {
    let img = read_image(path).unwrap().image;
    [0, 1, 2].map(|c| {
        let v0 = img.data[c];
        img.data
            .iter()
            .skip(c)
            .step_by(3)
            .all(|&v| v == v0)
            .then_some(v0)
    })
}

#[test]
fn the_issues_silent_blacks_warn_before_and_after_rendering() {
    let t = tempfile::tempdir().unwrap();
    let poly = OpcodeKind::MapPolynomial {
        area: area(0, 7, 48, 7, 1), // left == right: the whole image (the SDK's rule)
        coefficients: vec![-0.5],
    };
    for (name, l, want) in [
        ("gain.dng", (2, list(vec![negative_gain(64, 48)])), "OpcodeList2: GainMap (opcode 1 of 1): every gain is <= 0 (the largest is -2): the whole image becomes 0 (black)"),
        ("poly.dng", (2, list(vec![poly.clone()])), "OpcodeList2: MapPolynomial (opcode 1 of 1): the polynomial is <= 0 for every value in [0, 1]: the whole image becomes 0 (black)"),
    ] {
        let f = dng(t.path(), name, (64, 48), &[l]);
        let out = t.path().join(format!("{name}.exr"));
        let (r, err) = run(&os(&["render", f.to_str().unwrap(), "-o", out.to_str().unwrap(), "--float"]));
        assert!(r.status.success(), "{err}");
        assert!(err.contains(want), "{name}: {err}");
        assert!(err.contains("warning[render-constant]: ") && err.contains(": the render is constant: R, G and B are 0 in every pixel (all black)"), "{name}: {err}");
        assert_eq!(constant_planes(&out), [Some(0.0); 3]);
        // synth: the plan says it before, the run after; the CLI prints both.
        let o = t.path().join(format!("{name}.synth"));
        let (r, err) = run(&os(&["synth", f.to_str().unwrap(), "-o", o.to_str().unwrap(), "--iso", "none"]));
        assert!(r.status.success(), "{err}");
        assert!(err.contains(want) && err.contains("the target render is constant"), "{err}");
        let stem = name.trim_end_matches(".dng");
        let sc = sidecar(&o.join(format!("{stem}.json")));
        assert!(sc["report"]["warnings"].to_string().contains("(opcode 1 of 1)"));
        assert!(sc["run"]["warnings"][0]["message"].as_str().unwrap().starts_with("the target render is constant"));
        assert_eq!(sc["run"]["warnings"][0]["code"], "render-constant");
        // info: not "ready" without a word.
        let r = common::bin().arg("info").arg(&f).output().unwrap();
        assert!(String::from_utf8_lossy(&r.stdout).contains("ready, with warnings"));
        // ignored lists: a normal render, no word.
        let (r, err) = run(&os(&["render", f.to_str().unwrap(), "-o", out.to_str().unwrap(), "--overwrite", "--opcodes", "ignore"]));
        assert!(r.status.success() && !err.contains("warning"), "{err}");
    }
}

/// A small deterministic generator (SplitMix64).
struct Rand(u64);

impl Rand {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn f(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Often exactly 0 or negative: the values that blacken a render.
    fn value(&mut self, lo: f64, hi: f64) -> f64 {
        match self.below(4) {
            0 => 0.0,
            1 => -self.f(0.1, 3.0),
            _ => self.f(lo, hi),
        }
    }
}

/// A random area of a `w x h` stage with `planes` planes: whole, empty (the whole image by
/// the SDK's rule) or a part, pitch 1 or 2.
fn random_area(g: &mut Rand, w: u32, h: u32, planes: u32) -> AreaSpec {
    let p = planes.max(1);
    let plane = g.below(u64::from(p)) as u32;
    let n = 1 + g.below(u64::from(p - plane)) as u32;
    let mut a = match g.below(4) {
        0 => area(0, 3, h, 3, 0), // empty: the whole image
        1 => {
            let t = g.below(u64::from(h / 2)) as u32;
            let l = g.below(u64::from(w / 2)) as u32;
            area(
                t,
                l,
                t + 1 + g.below(u64::from(h - t)) as u32,
                l + 1 + g.below(u64::from(w - l)) as u32,
                0,
            )
        }
        _ => area(0, 0, h, w, 0),
    };
    a.plane = plane;
    a.planes = n;
    if a.bottom > a.top && a.right > a.left && g.below(4) == 0 {
        a.row_pitch = 2;
        a.col_pitch = 2;
    }
    a
}

fn per_line(g: &mut Rand, a: &AreaSpec, rows: bool, delta: bool) -> OpcodeKind {
    let n = if rows {
        a.bottom.saturating_sub(a.top).div_ceil(a.row_pitch)
    } else {
        a.right.saturating_sub(a.left).div_ceil(a.col_pitch)
    } as usize;
    let one = if delta {
        g.value(-70000.0, 70000.0)
    } else {
        g.value(0.0, 3.0)
    };
    let v: Vec<f32> = (0..n)
        .map(|_| {
            if g.below(8) == 0 {
                g.value(-1.0, 3.0) as f32
            } else {
                one as f32
            }
        })
        .collect();
    match (rows, delta) {
        (true, true) => OpcodeKind::DeltaPerRow {
            area: *a,
            deltas: v,
        },
        (false, true) => OpcodeKind::DeltaPerColumn {
            area: *a,
            deltas: v,
        },
        (true, false) => OpcodeKind::ScalePerRow {
            area: *a,
            scales: v,
        },
        (false, false) => OpcodeKind::ScalePerColumn {
            area: *a,
            scales: v,
        },
    }
}

/// One random opcode for list `n` of a `w x h` CFA frame.
fn random_opcode(g: &mut Rand, n: u8, w: u32, h: u32) -> OpcodeKind {
    let planes = if n == 3 { 3 } else { 1 };
    let a = random_area(g, w, h, planes);
    match g.below(if n == 3 { 9 } else { 7 }) {
        0 => {
            let (pv, ph, mp) = (
                1 + g.below(3) as u32,
                1 + g.below(3) as u32,
                1 + g.below(u64::from(planes)) as u32,
            );
            let base = g.value(0.2, 3.0) as f32;
            let gains = (0..pv * ph * mp)
                .map(|_| {
                    if g.below(3) == 0 {
                        g.value(-2.0, 3.0) as f32
                    } else {
                        base
                    }
                })
                .collect();
            OpcodeKind::GainMap(GainMap {
                area: a,
                points_v: pv,
                points_h: ph,
                spacing_v: 0.5,
                spacing_h: 0.5,
                origin_v: 0.0,
                origin_h: 0.0,
                map_planes: mp,
                gains,
            })
        }
        1 => {
            let deg = g.below(3) as usize;
            OpcodeKind::MapPolynomial {
                area: a,
                coefficients: (0..=deg).map(|_| g.value(-1.0, 2.0)).collect(),
            }
        }
        2 => {
            let len = 1 + g.below(4) as usize;
            let v0 = g.below(65536) as u16;
            OpcodeKind::MapTable {
                area: a,
                table: (0..len)
                    .map(|_| {
                        if g.below(2) == 0 {
                            v0
                        } else {
                            g.below(65536) as u16
                        }
                    })
                    .collect(),
            }
        }
        3 => per_line(g, &a, true, false),
        4 => per_line(g, &a, false, false),
        5 => {
            let rows = g.below(2) == 0;
            per_line(g, &a, rows, true)
        }
        6 => OpcodeKind::FixVignetteRadial {
            k: [g.value(-3.0, 1.0), g.value(-1.0, 1.0), 0.0, 0.0, 0.0],
            center: [g.f(0.0, 1.0), g.f(0.0, 1.0)],
        },
        7 => OpcodeKind::WarpRectilinear {
            planes: vec![WarpPlane {
                kr: [1.0, g.f(-0.2, 0.2), 0.0, 0.0],
                kt: [0.0, 0.0],
            }],
            center: [0.5, 0.5],
        },
        _ => {
            let t = g.below(u64::from(h / 2)) as u32;
            let l = g.below(u64::from(w / 2)) as u32;
            OpcodeKind::TrimBounds {
                bounds: [
                    t,
                    l,
                    h - g.below(u64::from(h / 2 - 1)) as u32,
                    w - g.below(u64::from(w / 2 - 1)) as u32,
                ],
            }
        }
    }
}

#[test]
fn every_constant_render_of_random_opcode_lists_warned() {
    let t = tempfile::tempdir().unwrap();
    let (w, h) = (24u32, 16u32);
    let mut g = Rand(0x5eed_0026);
    let (mut constant, mut varied, mut static_warned) = (0, 0, 0);
    let cases = 200;
    for case in 0..cases {
        let mut lists = vec![];
        for n in 1..=3u8 {
            if g.below(2) == 0 {
                continue;
            }
            let k = 1 + g.below(3);
            let mut ops: Vec<OpcodeKind> = (0..k).map(|_| random_opcode(&mut g, n, w, h)).collect();
            // One TrimBounds at most (a second one must lie inside the first).
            let mut trims = 0;
            ops.retain(|o| {
                trims += usize::from(matches!(o, OpcodeKind::TrimBounds { .. }));
                trims <= 1 || !matches!(o, OpcodeKind::TrimBounds { .. })
            });
            lists.push((n, list(ops)));
        }
        let name = format!("r{case}.dng");
        let f = dng(t.path(), &name, (w as usize, h as usize), &lists);
        let out = t.path().join(format!("r{case}.exr"));
        let (r, err) = run(&os(&[
            "render",
            f.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--float",
        ]));
        assert!(r.status.success(), "case {case}: {err}");
        let planes = constant_planes(&out);
        let said = err.contains(": the render is constant")
            || err.contains(": the render has a constant plane");
        assert_eq!(said, err.contains("warning[render-constant]: "), "{err}");
        if said {
            static_warned += usize::from(err.contains("(opcode "));
        }
        if planes.iter().any(Option::is_some) {
            constant += 1;
            assert!(
                said,
                "case {case}: constant planes {planes:?}, no warning: {err}"
            );
            for (c, v) in planes.iter().enumerate() {
                if let Some(v) = v {
                    let name = ["R", "G", "B"][c];
                    let v = if *v == 0.0 {
                        "0".to_string()
                    } else {
                        format!("{v}")
                    };
                    assert!(
                        err.contains(&format!("{name} is {v}"))
                            || err.contains(&format!("are {v} in every pixel"))
                            || err.contains(&format!("{name} {v}")),
                        "case {case}: {planes:?}: {err}"
                    );
                }
            }
        } else {
            varied += 1;
            assert!(!said, "case {case}: warned, but the render varies: {err}");
        }
        // The same file through synth: the sidecar's run warnings say the same (a tenth).
        if case % 10 == 0 {
            let o = t.path().join(format!("s{case}"));
            let (r, err) = run(&os(&[
                "synth",
                f.to_str().unwrap(),
                "-o",
                o.to_str().unwrap(),
                "--iso",
                "none",
                "--mode",
                "day",
            ]));
            assert!(r.status.success(), "case {case}: {err}");
            let sc = sidecar(&o.join(format!("r{case}.json")));
            let target = o.join(format!("r{case}_target.exr"));
            let flat = read_image(&target).unwrap().image;
            let run_warned = !sc["run"]["warnings"].as_array().unwrap().is_empty();
            let any_flat = [0, 1, 2].iter().any(|&c| {
                let v0 = flat.data[c];
                flat.data.iter().skip(c).step_by(3).all(|&v| v == v0)
            });
            // The EXR is half: values that differ in f32 may round alike, never the reverse.
            if run_warned {
                assert!(any_flat, "case {case}: sidecar warned, target varies");
            }
        }
    }
    eprintln!("{cases} random lists: {constant} constant renders (all warned), {varied} varied, {static_warned} of the warned named an opcode first");
    assert!(
        constant >= 30 && varied >= 30,
        "the set must hold both kinds: {constant} / {varied}"
    );
}

#[test]
fn a_trim_that_changes_the_target_size_is_said_and_recorded() {
    let t = tempfile::tempdir().unwrap();
    let f = dng(
        t.path(),
        "trim.dng",
        (64, 48),
        &[(
            3,
            list(vec![OpcodeKind::TrimBounds {
                bounds: [8, 16, 24, 48],
            }]),
        )],
    );
    let o = t.path().join("s");
    let (r, err) = run(&os(&[
        "synth",
        f.to_str().unwrap(),
        "-o",
        o.to_str().unwrap(),
        "--iso",
        "1600",
    ]));
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("warning[opcode-trim]: ") && err.contains(": OpcodeList3: TrimBounds (opcode 1 of 1) keeps rows 8..24, columns 16..48 of the active area: rendered images are 32x16 pixels where the raw's default crop is 64x48"),
        "{err}"
    );
    let sc = sidecar(&o.join("trim.json"));
    assert_eq!(sc["report"]["target_size"], serde_json::json!([32, 16]));
    assert_eq!(
        (
            sc["plan"]["active_width"].as_u64(),
            sc["plan"]["active_height"].as_u64()
        ),
        (Some(64), Some(48))
    );
    let target = read_image(&o.join("trim_target.exr")).unwrap().image;
    assert_eq!((target.width, target.height), (32, 16));
    let night = day2night::dng::read_dng(&o.join("trim_iso1600.dng")).unwrap();
    assert_eq!((night.width, night.height), (64, 48));
    // Replay: the sidecar (with its target size) replays byte for byte.
    let o2 = t.path().join("replay");
    let (r, err) = run(&os(&[
        "synth",
        f.to_str().unwrap(),
        "-o",
        o2.to_str().unwrap(),
        "--replay",
        o.join("trim.json").to_str().unwrap(),
    ]));
    assert!(r.status.success(), "{err}");
    for n in [
        "trim.json",
        "trim_target.exr",
        "trim_clean.dng",
        "trim_iso1600.dng",
    ] {
        assert_eq!(
            std::fs::read(o.join(n)).unwrap(),
            std::fs::read(o2.join(n)).unwrap(),
            "{n}"
        );
    }
    // render says it too; without a render there is nothing to say.
    let (r, err) = run(&os(&[
        "render",
        f.to_str().unwrap(),
        "-o",
        t.path().join("t.png").to_str().unwrap(),
    ]));
    assert!(
        r.status.success() && err.contains("rendered images are 32x16 pixels"),
        "{err}"
    );
    let (r, err) = run(&os(&[
        "synth",
        f.to_str().unwrap(),
        "-o",
        t.path().join("n").to_str().unwrap(),
        "--iso",
        "none",
        "--target",
        "none",
    ]));
    assert!(r.status.success() && !err.contains("TrimBounds"), "{err}");
    assert!(sidecar(&t.path().join("n/trim.json"))["report"]["target_size"].is_null());
}

/// A list as long as the reader accepts (4096 opcodes) is sampled, written and replayed:
/// the plan's bounds on a replayed sidecar allow every opcode the reader does (they were
/// 1000 entries, so `synth` refused such a file that `render` took).
#[test]
fn the_longest_lists_synthesize_and_replay() {
    let t = tempfile::tempdir().unwrap();
    let ops = (0..day2night::limits::MAX_OPCODES_PER_LIST)
        .map(|i| OpcodeKind::FixBadPixelsConstant {
            constant: 65535 - (i % 7),
            bayer_phase: 0,
        })
        .collect();
    let f = dng(t.path(), "long.dng", (32, 24), &[(1, list(ops))]);
    let a = t.path().join("a");
    let (r, err) = run(&os(&[
        "synth",
        f.to_str().unwrap(),
        "-o",
        a.to_str().unwrap(),
        "--iso",
        "800",
    ]));
    assert!(r.status.success(), "{err}");
    let sc = sidecar(&a.join("long.json"));
    let applied = sc["report"]["opcodes"]["applied"].as_array().unwrap().len();
    let dropped = sc["report"]["opcodes"]["dropped"]
        .as_array()
        .map_or(0, |d| d.len());
    // Every opcode is accounted for: applied, or dropped as a repeat that changes nothing.
    assert_eq!(
        applied + dropped,
        4096,
        "{applied} applied, {dropped} dropped"
    );
    let b = t.path().join("b");
    let (r, err) = run(&os(&[
        "synth",
        f.to_str().unwrap(),
        "-o",
        b.to_str().unwrap(),
        "--replay",
        a.join("long.json").to_str().unwrap(),
    ]));
    assert!(r.status.success(), "{err}");
    for n in [
        "long_clean.dng",
        "long_iso800.dng",
        "long_target.exr",
        "long.json",
    ] {
        assert_eq!(
            std::fs::read(a.join(n)).unwrap(),
            std::fs::read(b.join(n)).unwrap(),
            "{n}"
        );
    }
}
