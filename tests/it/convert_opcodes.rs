//! `convert` of files whose opcode lists day2night's renders cannot use (docs/dng-support.md,
//! "Opcode lists"): valid lists are mutated (truncations, bad counts and byte counts,
//! unknown mandatory and optional opcodes, byte flips); whatever `convert` writes, with
//! `--bad-opcode-lists refuse` (the default) or `drop`, day2night reads and renders, and
//! passes the Adobe DNG SDK (dngpy) whenever the input did. A refusal names the list.
use crate::common;
use crate::dngbuild::Builder;

use day2night::dng::opcodes::{
    encode_list, AreaSpec, GainMap, Opcode, OpcodeKind, OpcodeList, WarpPlane,
};
use std::path::{Path, PathBuf};

fn whole(w: u32, h: u32, planes: u32) -> AreaSpec {
    AreaSpec {
        top: 0,
        left: 0,
        bottom: h,
        right: w,
        plane: 0,
        planes,
        row_pitch: 1,
        col_pitch: 1,
    }
}

/// Valid lists for a 64x48 frame: (list number, bytes).
fn valid_lists() -> Vec<(u8, Vec<u8>)> {
    let (w, h) = (64, 48);
    let op = |k| Opcode::new(k, 0);
    vec![
        (
            1,
            encode_list(&OpcodeList {
                opcodes: vec![op(OpcodeKind::ScalePerRow {
                    area: whole(w, h, 1),
                    scales: vec![1.01; 48],
                })],
            }),
        ),
        (
            2,
            encode_list(&OpcodeList {
                opcodes: vec![op(OpcodeKind::GainMap(GainMap {
                    area: whole(w, h, 1),
                    points_v: 2,
                    points_h: 2,
                    spacing_v: 1.0,
                    spacing_h: 1.0,
                    origin_v: 0.0,
                    origin_h: 0.0,
                    map_planes: 1,
                    gains: vec![1.0, 1.2, 1.4, 1.6],
                }))],
            }),
        ),
        (
            3,
            encode_list(&OpcodeList {
                opcodes: vec![
                    op(OpcodeKind::MapPolynomial {
                        area: whole(w, h, 3),
                        coefficients: vec![0.0, 1.1],
                    }),
                    op(OpcodeKind::WarpRectilinear {
                        planes: vec![WarpPlane {
                            kr: [1.0, 0.01, 0.0, 0.0],
                            kt: [0.0, 0.0],
                        }],
                        center: [0.5, 0.5],
                    }),
                ],
            }),
        ),
    ]
}

fn be32(v: &mut [u8], at: usize, x: u32) {
    v[at..at + 4].copy_from_slice(&x.to_be_bytes());
}

/// Mutations of one list's bytes: (what, bytes).
fn mutations(bytes: &[u8], seed: u64) -> Vec<(String, Vec<u8>)> {
    let mut out = vec![];
    for cut in [0, 2, 4, 10, 20, bytes.len() / 2, bytes.len() - 1] {
        out.push((format!("truncated to {cut}"), bytes[..cut].to_vec()));
    }
    for count in [0u32, 2, 3, 0xffff_ffff] {
        let mut m = bytes.to_vec();
        be32(&mut m, 0, count);
        out.push((format!("count {count}"), m));
    }
    // First opcode: id at 4, version at 8, flags at 12, byte count at 16.
    for (id, flags) in [(200u32, 0u32), (200, 1), (14, 0), (6, 0)] {
        let mut m = bytes.to_vec();
        be32(&mut m, 4, id);
        be32(&mut m, 12, flags);
        out.push((format!("opcode id {id}, flags {flags}"), m));
    }
    for delta in [-4i64, 4] {
        let mut m = bytes.to_vec();
        let n = u32::from_be_bytes([m[16], m[17], m[18], m[19]]);
        be32(&mut m, 16, (i64::from(n) + delta) as u32);
        out.push((format!("byte count {delta:+}"), m));
    }
    let mut s = seed;
    for k in 0..6 {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let at = (s >> 33) as usize % bytes.len();
        let mut m = bytes.to_vec();
        m[at] ^= 1 << (k % 8);
        out.push((format!("flip at {at}"), m));
    }
    out
}

fn run(args: &[&std::ffi::OsStr]) -> (bool, String) {
    let r = common::bin().args(args).output().unwrap();
    (
        r.status.success(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

fn renders(dng: &Path, dir: &Path) -> (bool, String) {
    let out = dir.join("probe.exr");
    let _ = std::fs::remove_file(&out);
    run(&[
        "render".as_ref(),
        dng.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--overwrite".as_ref(),
    ])
}

/// The SDK's verdict on each file (its padding warnings about tiny frames aside).
fn sdk(py: &Path, files: &[PathBuf]) -> Vec<(bool, Vec<String>)> {
    let args: Vec<&std::ffi::OsStr> = files.iter().map(|f| f.as_os_str()).collect();
    let out = common::run_validator(py, "sdk_accepts.py", &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let msgs: Vec<String> = v["messages"]
                .as_array()
                .unwrap()
                .iter()
                .map(|m| m.as_str().unwrap().to_string())
                .filter(|m| !m.contains("Too little padding"))
                .collect();
            (msgs.is_empty(), msgs)
        })
        .collect()
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn whatever_convert_writes_from_mutated_lists_renders_and_passes_the_sdk() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path();
    // (input, outputs written from it)
    let mut written: Vec<(PathBuf, Vec<PathBuf>)> = vec![];
    let (mut refused, mut dropped, mut kept) = (0, 0, 0);
    let lists = valid_lists();
    for (li, (n, bytes)) in lists.iter().enumerate() {
        for (mi, (what, m)) in mutations(bytes, li as u64 + 1).into_iter().enumerate() {
            let mut b = Builder::new(64, 48, 16);
            for (k, (n2, b2)) in lists.iter().enumerate() {
                b = b.opcode_list(*n2, if k == li { m.clone() } else { b2.clone() });
            }
            let input = dir.join(format!("in_{n}_{mi}.dng"));
            std::fs::write(&input, b.build()).unwrap();
            let case = format!("OpcodeList{n} {what}");
            let render_in = renders(&input, dir).0;
            let mut outs = vec![];
            // Default: refuse, naming the list, or write a file that renders.
            let out = dir.join(format!("out_{n}_{mi}.dng"));
            let (ok, err) = run(&["convert".as_ref(), input.as_os_str(), out.as_os_str()]);
            if ok {
                kept += 1;
                let (r, rerr) = renders(&out, dir);
                assert!(r, "{case}: convert wrote a file render refuses: {rerr}");
                assert_eq!(
                    render_in, r,
                    "{case}: the input did not render, yet convert kept it"
                );
                outs.push(out);
            } else {
                refused += 1;
                assert!(!render_in, "{case}: refused a file that renders: {err}");
                assert!(
                    err.contains(&format!("OpcodeList{n}"))
                        && err.contains("--bad-opcode-lists drop"),
                    "{case}: {err}"
                );
                assert!(!out.exists(), "{case}: refused, yet written");
            }
            // drop: always written, renders; the warning names the list when it dropped it.
            let out = dir.join(format!("drop_{n}_{mi}.dng"));
            let (ok, err) = run(&[
                "convert".as_ref(),
                input.as_os_str(),
                out.as_os_str(),
                "--bad-opcode-lists".as_ref(),
                "drop".as_ref(),
            ]);
            assert!(ok, "{case}: {err}");
            let (r, rerr) = renders(&out, dir);
            assert!(r, "{case}: {rerr}");
            if !render_in {
                dropped += 1;
                assert!(
                    err.contains("warning[opcode-list-dropped]: ")
                        && err.contains(&format!("OpcodeList{n} dropped")),
                    "{case}: {err}"
                );
                let back = day2night::dng::read_dng(&out).unwrap();
                assert!(
                    back.meta.opcode_lists[usize::from(*n) - 1].is_none(),
                    "{case}"
                );
            } else {
                assert!(!err.contains("dropped"), "{case}: {err}");
            }
            outs.push(out);
            written.push((input, outs));
        }
    }
    eprintln!(
        "convert: {kept} kept, {refused} refused ({dropped} dropped with --bad-opcode-lists drop)"
    );
    assert!(refused >= 10 && kept >= 5, "{refused} refused, {kept} kept");
    // The Adobe DNG SDK: every output of an input it accepts passes too.
    let py = common::python();
    let inputs: Vec<PathBuf> = written.iter().map(|(i, _)| i.clone()).collect();
    let verdicts = sdk(&py, &inputs);
    let mut checked = vec![];
    for ((input, outs), (ok, _)) in written.iter().zip(&verdicts) {
        if *ok {
            checked.extend(outs.iter().map(|o| (input.clone(), o.clone())));
        }
    }
    let outs: Vec<PathBuf> = checked.iter().map(|(_, o)| o.clone()).collect();
    for ((input, out), (ok, msgs)) in checked.iter().zip(sdk(&py, &outs)) {
        assert!(
            ok,
            "{} (from {}) fails the SDK: {msgs:?}",
            out.display(),
            input.display()
        );
    }
    eprintln!(
        "SDK: {} of {} inputs accepted; their {} outputs accepted",
        verdicts.iter().filter(|v| v.0).count(),
        inputs.len(),
        outs.len()
    );
}
