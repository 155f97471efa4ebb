//! Decompression bombs and the pixel limit: tiny DNGs that claim a 268-megapixel image by
//! pointing every tile or strip at the same bytes are refused by every command at once
//! (exit 1, a named error, little memory, no temporary file left; the time is printed, not
//! asserted), and the pixel limit is enforced and can be raised (--max-pixels,
//! D2N_MAX_PIXELS).
//! The bomb files are generated here (tests/it/dngbuild), never committed.

use crate::common;
use crate::dngbuild;

use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

/// Run the binary with `args` under GNU time (required); returns the peak RSS in KiB too.
fn run(args: &[&std::ffi::OsStr]) -> (Output, Duration, u64) {
    let time = common::gnu_time();
    let t0 = Instant::now();
    let out = std::process::Command::new(time)
        .arg("-v")
        .arg(env!("CARGO_BIN_EXE_day2night"))
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let rss = err
        .lines()
        .find_map(|l| {
            l.trim()
                .strip_prefix("Maximum resident set size (kbytes): ")
        })
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("no peak RSS line from GNU time: {err}"));
    (out, t0.elapsed(), rss)
}

fn leftovers(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    for e in walk(dir) {
        let n = e.file_name().unwrap().to_string_lossy().to_string();
        if n.contains(".tmp") {
            v.push(e.display().to_string());
        }
    }
    v
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(walk(&p));
            }
            out.push(p);
        }
    }
    out
}

fn check_all_commands(bomb: &[u8], name: &str, expect: &str) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join(name);
    std::fs::write(&input, bomb).unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let i = input.as_os_str();
    let conv = out_dir.join("c.dng");
    let rend = out_dir.join("r.exr");
    let synth_out = out_dir.join("synth");
    let cases: Vec<(&str, Vec<&std::ffi::OsStr>)> = vec![
        ("info", vec!["info".as_ref(), i]),
        ("info --json", vec!["info".as_ref(), "--json".as_ref(), i]),
        ("convert", vec!["convert".as_ref(), i, conv.as_os_str()]),
        (
            "render",
            vec!["render".as_ref(), i, "-o".as_ref(), rend.as_os_str()],
        ),
        (
            "synth",
            vec![
                "synth".as_ref(),
                i,
                "-o".as_ref(),
                synth_out.as_os_str(),
                "--iso".as_ref(),
                "none".as_ref(),
            ],
        ),
    ];
    for (what, args) in cases {
        let (o, took, rss) = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        let stdout = String::from_utf8_lossy(&o.stdout);
        eprintln!(
            "{name} {what}: {took:?}, peak RSS {rss} KiB, exit {:?}",
            o.status.code()
        );
        assert_eq!(o.status.code(), Some(1), "{what}: {err}\n{stdout}");
        assert!(
            err.contains(expect) || stdout.contains(expect),
            "{what}: expected {expect:?} in\n{err}\n{stdout}"
        );
        // No time limit here (timings belong in benchmarks): a bomb that were decoded would
        // allocate gigabytes, which the peak-RSS bound below catches.
        assert!(rss < 400 * 1024, "{what}: peak RSS {rss} KiB");
        assert_eq!(leftovers(dir.path()), Vec::<String>::new(), "{what}");
        assert!(!conv.exists() && !rend.exists(), "{what} left an output");
    }
}

#[test]
#[cfg_attr(d2n_missing = "time", ignore = "needs GNU time (D2N_ALLOW_MISSING)")]
fn lj92_tile_bomb_is_refused_by_every_command() {
    let bomb = dngbuild::bomb_lj92_tiles();
    assert!(bomb.len() < 45_000, "{}", bomb.len());
    check_all_commands(&bomb, "tiles.dng", "tiles 0 and 1 overlap");
}

#[test]
#[cfg_attr(d2n_missing = "time", ignore = "needs GNU time (D2N_ALLOW_MISSING)")]
fn strip_bomb_is_refused_by_every_command() {
    let bomb = dngbuild::bomb_strips();
    assert!(bomb.len() < 170_000, "{}", bomb.len());
    check_all_commands(&bomb, "strips.dng", "strips 0 and 1 overlap");
}

#[test]
fn the_bombs_are_well_formed_dngs_but_for_the_shared_data() {
    // Control: each bomb parses as a DNG claiming a 16384 x 16384 raw whose every block
    // lies inside the file; only the overlap rule refuses it.
    for (bomb, kind) in [
        (dngbuild::bomb_lj92_tiles(), "tiles"),
        (dngbuild::bomb_strips(), "strips"),
    ] {
        let info = day2night::dng::read::inspect_bytes(&bomb).unwrap();
        assert_eq!(info.ifds[0].width, Some(16384));
        assert_eq!(info.ifds[0].height, Some(16384));
        let err = info.error.unwrap();
        assert!(err.contains(&format!("{kind} 0 and 1 overlap")), "{err}");
    }
}

#[test]
fn pixel_limit_is_enforced_and_can_be_raised() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("small.dng");
    std::fs::write(&p, dngbuild::Builder::new(64, 48, 12).build()).unwrap();
    let ok = common::bin().arg("info").arg(&p).output().unwrap();
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    // Through the environment.
    let o = common::bin()
        .env("D2N_MAX_PIXELS", "3000")
        .arg("info")
        .arg(&p)
        .output()
        .unwrap();
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(o.status.code(), Some(1), "{all}");
    assert!(
        all.contains("64x48 = 3072 pixels exceeds the limit of 3000 pixels"),
        "{all}"
    );
    // The option wins over the environment.
    let o = common::bin()
        .env("D2N_MAX_PIXELS", "3000")
        .args(["--max-pixels", "4000", "info"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A bad value is a usage error.
    let o = common::bin()
        .args(["--max-pixels", "lots", "info"])
        .arg(&p)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = common::bin()
        .env("D2N_MAX_PIXELS", "lots")
        .arg("info")
        .arg(&p)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
