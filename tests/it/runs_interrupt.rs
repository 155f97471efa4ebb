//! SIGINT/SIGTERM during `synth` and `dataset` (issue 13, point 6): the process stops,
//! exits 128 + signal (130, 143), removes its temporary files, and every output set it
//! left is whole (sidecar present); `dataset` says how to resume, and the rerun completes.
//!
//! No clock decides anything here (issue 36): a run is held where the test wants it by an
//! output set locked as if another process were writing it (the run waits for it with
//! `--wait` and cannot finish), or by an input that is a FIFO the test keeps open without
//! writing (the command blocks reading it); the test learns that the run got there from
//! the run's own stderr lines, or from the FIFO's open. How long a stop takes is measured
//! in docs/benchmarks.md ("Stopping on a signal"), not asserted.
#![cfg(unix)]
use crate::common;
use crate::dngbuild;

use day2night::output::OutputSetLock;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStderr, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// `n` distinct synthetic DNGs of `w` x `h` in `dir`.
fn inputs(dir: &Path, n: usize, w: usize, h: usize) -> Vec<PathBuf> {
    std::fs::create_dir_all(dir).unwrap();
    (0..n)
        .map(|i| {
            let mut b = dngbuild::Builder::new(w, h, 12);
            b.layout = dngbuild::Pixels::Strips { rows: 64 };
            b.pixels
                .iter_mut()
                .for_each(|p| *p = (*p + i as u16) & 0xfff);
            let p = dir.join(format!("img{i:02}.dng"));
            std::fs::write(&p, b.build()).unwrap();
            p
        })
        .collect()
}

/// Every file name under `dir`, recursively.
fn all_names(dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else {
        return v;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            v.extend(all_names(&p));
        } else {
            v.push(p);
        }
    }
    v
}

/// Read `err` line by line until a line satisfies `until`; the lines read. Fails, with
/// what it read, if the stream ends first (the run ended).
fn read_until(err: &mut BufReader<ChildStderr>, until: impl Fn(&str) -> bool) -> Vec<String> {
    let mut lines = Vec::new();
    loop {
        let mut l = String::new();
        let n = err.read_line(&mut l).unwrap();
        assert!(
            n > 0,
            "the run ended before the signal:\n{}",
            lines.join("")
        );
        let hit = until(l.trim_end());
        lines.push(l);
        if hit {
            return lines;
        }
    }
}

/// Wait for `child` and return its status and whole stderr (`said` read before, then the
/// rest of `err`).
fn finish(
    mut child: Child,
    mut err: BufReader<ChildStderr>,
    said: Vec<String>,
) -> (ExitStatus, String) {
    let mut rest = String::new();
    err.read_to_string(&mut rest).unwrap();
    let status = child.wait().unwrap();
    (status, said.concat() + &rest)
}

/// Hold the output set `base` in `dir` as another process writing it would.
fn hold(dir: &Path, base: &str) -> OutputSetLock {
    std::fs::create_dir_all(dir).unwrap();
    OutputSetLock::acquire(dir, base, false).unwrap()
}

fn kill(child: &Child, sig: &str) {
    let st = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
}

fn no_temp_files(dir: &Path) {
    let tmp: Vec<_> = all_names(dir)
        .into_iter()
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.contains(".tmp-") || n.ends_with(".lock")
        })
        .collect();
    assert!(tmp.is_empty(), "left behind: {tmp:?}");
}

#[test]
fn synth_stops_on_sigint_and_sigterm_leaving_whole_sets_only() {
    let tmp = tempfile::tempdir().unwrap();
    let ins = inputs(&tmp.path().join("day"), 6, 1024, 768);
    for (sig, code) in [("-INT", 130), ("-TERM", 143)] {
        let out = tmp.path().join(format!("out{sig}"));
        // The last input's set is locked: the run (--wait) cannot finish.
        let held = hold(&out, "img05");
        let mut child = common::bin()
            .arg("synth")
            .args(&ins)
            .arg("-o")
            .arg(&out)
            .args([
                "--iso",
                "1600,3200",
                "--target",
                "both",
                "--jobs",
                "2",
                "--wait",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut err = BufReader::new(child.stderr.take().unwrap());
        // After the first whole set (its sidecar listed), while the next ones are made.
        let said = read_until(&mut err, |l| {
            l.starts_with("wrote ") && l.ends_with(".json")
        });
        kill(&child, sig);
        let (status, err) = finish(child, err, said);
        drop(held);
        assert_eq!(status.code(), Some(code), "{err}");
        assert!(err.contains("day2night: interrupted"), "{err}");
        no_temp_files(&out);
        // Every set present is whole: its sidecar lists exactly the files there.
        let names: Vec<String> = all_names(&out)
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        let sets = names.iter().filter(|n| n.ends_with(".json")).count();
        // clean, two noisy, EXR and PNG targets, sidecar
        assert_eq!(names.len(), sets * 6, "partial set: {names:?}");
        assert!((1..ins.len()).contains(&sets), "{sets} sets");
    }
}

#[test]
fn dataset_stops_on_sigint_and_the_rerun_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let day = tmp.path().join("day");
    let ins = inputs(&day, 6, 1024, 768);
    let out = tmp.path().join("set");
    let run = || {
        let mut c = common::bin();
        c.arg("dataset")
            .arg(&day)
            .arg("-o")
            .arg(&out)
            .args(["--iso", "1600", "--jobs", "2"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        c
    };
    // The last input's unit is locked: the first run (--wait) cannot finish. --overwrite:
    // the lock file makes the new OUT non-empty.
    let held = hold(&out, "img05");
    let mut child = run().args(["--wait", "--overwrite"]).spawn().unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    // Its progress line for the first input: that input is in the manifest.
    let said = read_until(&mut err, |l| l.starts_with("dataset: [1/6]"));
    kill(&child, "-INT");
    let (status, err) = finish(child, err, said);
    drop(held);
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(
        err.contains("day2night: interrupted: rerun the same command to resume"),
        "{err}"
    );
    no_temp_files(&out);
    let o = run().arg("-q").output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains(&format!("{} images", ins.len())), "{err}");
    no_temp_files(&out);
    // The resumed run skipped what the first one had finished and computed the rest.
    let skipped: usize = err
        .split(" computed, ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no summary in {err}"));
    assert!(skipped >= 1 && skipped < ins.len(), "{err}");
}

#[test]
fn a_second_signal_stops_synth_at_once_and_still_cleans_up() {
    // The immediate path (also every command but synth and dataset on their first signal):
    // registered temporary files removed, exit 128 + signal.
    let tmp = tempfile::tempdir().unwrap();
    let ins = inputs(&tmp.path().join("day"), 3, 1024, 768);
    let out = tmp.path().join("out");
    let held = hold(&out, "img02");
    let mut child = common::bin()
        .arg("synth")
        .args(&ins)
        .arg("-o")
        .arg(&out)
        .args([
            "--iso",
            "1600,3200",
            "--target",
            "both",
            "--jobs",
            "2",
            "--wait",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let said = read_until(&mut err, |l| l.starts_with("wrote "));
    kill(&child, "-TERM");
    kill(&child, "-TERM");
    let (status, err) = finish(child, err, said);
    drop(held);
    assert_eq!(status.code(), Some(143), "{err}");
    assert!(err.contains("day2night: interrupted"), "{err}");
    no_temp_files(&out);
}

/// A small 16-bit RGGB DNG (uncompressed strips) at `path`, varied by `k`.
fn small_dng(path: &Path, k: u16) {
    let mut b = dngbuild::Builder::new(256, 192, 16);
    b.layout = dngbuild::Pixels::Strips { rows: 64 };
    for (i, p) in b.pixels.iter_mut().enumerate() {
        *p = (((i * 2654435761) >> 7) as u16 & 0x3fff).wrapping_add(k * 97) | 0x400;
    }
    std::fs::write(path, b.build()).unwrap();
}

/// A new FIFO at `path`.
fn fifo(path: &Path) {
    let _ = std::fs::remove_file(path);
    let st = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(st.success(), "mkfifo {}", path.display());
}

/// Start `args`, one of whose inputs is the FIFO `gate`, with stdout and stderr on pipes
/// that are closed at once (as when the reader of a pipeline dies). The test opens `gate`
/// for writing, which returns once the command opened it to read (its signal handling is
/// set up by then: it is installed before any command runs), and keeps it open without
/// writing, so the command is blocked reading its input. Then `sig`: the command must exit
/// with 128 + signal, leaving no temporary or lock file under `watch`.
fn stops_with_closed_pipes(
    what: &str,
    args: &[std::ffi::OsString],
    gate: &Path,
    watch: &Path,
    sig: &str,
) {
    fifo(gate);
    let mut child = common::bin()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    drop(child.stderr.take());
    let pid = child.id();
    // The child is waited for on its own thread; if it ends before opening the FIFO, the
    // thread opens it to read instead, which ends the test's open for writing.
    let ended = Arc::new(AtomicBool::new(false));
    let waiter = {
        let (ended, gate) = (ended.clone(), gate.to_path_buf());
        std::thread::spawn(move || {
            let status = child.wait().unwrap();
            ended.store(true, Ordering::SeqCst);
            drop(std::fs::File::open(&gate));
            status
        })
    };
    let writer = std::fs::OpenOptions::new().write(true).open(gate).unwrap();
    assert!(
        !ended.load(Ordering::SeqCst),
        "{what}: ended before reading its input ({:?})",
        waiter.join().unwrap()
    );
    let st = Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let status = waiter.join().unwrap();
    drop(writer);
    let code = if sig == "-INT" { 130 } else { 143 };
    assert_eq!(status.code(), Some(code), "{what} {sig}");
    no_temp_files(watch);
}

#[test]
fn every_command_stops_on_a_signal_with_closed_pipes() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let day = d.join("day");
    std::fs::create_dir_all(&day).unwrap();
    let frames: Vec<PathBuf> = (0..4u16)
        .map(|k| {
            let p = day.join(format!("f{k}.dng"));
            small_dng(&p, k);
            p
        })
        .collect();
    // a display image for eval
    let w = 64;
    let img = day2night::isp::RgbImage {
        width: w,
        height: w,
        data: (0..3 * w * w).map(|i| (i % 97) as f32 / 97.0).collect(),
    };
    let pa = d.join("a.png");
    let png = day2night::encode::png::PngOptions::default();
    let policy = day2night::output::OutputPolicy::default();
    day2night::encode::png::write_png(&img, &pa, &png, &policy).unwrap();
    // a dataset for report (2 images); its second day image becomes the gate later
    let rday = d.join("rday");
    std::fs::create_dir_all(&rday).unwrap();
    for k in 0..2u16 {
        small_dng(&rday.join(format!("r{k}.dng")), k);
    }
    let rset = d.join("rset");
    let made = common::bin()
        .arg("dataset")
        .arg(&rday)
        .arg("-o")
        .arg(&rset)
        .args(["--iso", "1600", "-q"])
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let o = |p: &Path| p.as_os_str().to_owned();
    let os = |s: &str| std::ffi::OsString::from(s);
    for (i, sig) in ["-TERM", "-INT"].into_iter().enumerate() {
        let out = d.join(format!("out{i}"));
        std::fs::create_dir_all(&out).unwrap();
        let g = d.join("gate.dng");
        let gate = o(&g);
        let runs: Vec<(&str, Vec<std::ffi::OsString>)> = vec![
            (
                "render",
                vec![os("render"), gate.clone(), os("-o"), o(&out.join("r.exr"))],
            ),
            (
                "synth",
                vec![
                    os("synth"),
                    gate.clone(),
                    os("-o"),
                    o(&out),
                    os("--target"),
                    os("both"),
                ],
            ),
            (
                // the noise model is read before any input
                "dataset",
                vec![
                    os("dataset"),
                    o(&day),
                    os("-o"),
                    o(&out.join("set")),
                    os("--noise-model"),
                    gate.clone(),
                ],
            ),
            ("eval", vec![os("eval"), gate.clone(), o(&pa)]),
            (
                "calibrate",
                vec![
                    os("calibrate"),
                    os("brightness"),
                    gate.clone(),
                    o(&frames[1]),
                    o(&frames[2]),
                    o(&frames[3]),
                    os("-o"),
                    o(&out.join("b.json")),
                ],
            ),
            (
                "merge",
                vec![
                    os("merge"),
                    gate.clone(),
                    o(&frames[1]),
                    o(&frames[2]),
                    o(&frames[3]),
                    os("-o"),
                    o(&out.join("m.dng")),
                ],
            ),
            (
                "convert",
                vec![
                    os("convert"),
                    gate.clone(),
                    os("-o"),
                    o(&out.join("c.dng")),
                    os("--compression"),
                    os("ljpeg"),
                ],
            ),
        ];
        for (what, args) in &runs {
            stops_with_closed_pipes(what, args, &g, &out, sig);
        }
        // report: a day image of the dataset is the gate
        let r1 = rday.join("r1.dng");
        let kept = std::fs::read(&r1).unwrap();
        let report = [os("report"), o(&rset), os("--day-dir"), o(&rday)];
        stops_with_closed_pipes("report", &report, &r1, &rset, sig);
        std::fs::remove_file(&r1).unwrap();
        std::fs::write(&r1, kept).unwrap();
    }
}
