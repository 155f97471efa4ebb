//! SIGINT/SIGTERM during `synth` and `dataset` (issue 13, point 6): the process stops,
//! exits 128 + signal (130, 143), removes its temporary files, and every output set it
//! left is whole (sidecar present); `dataset` says how to resume, and the rerun completes.
#![cfg(unix)]
use crate::common;
use crate::dngbuild;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

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

/// Wait until a file whose name ends with `suffix` shows up under `dir` ("" for any file,
/// temporary ones included: the run is writing).
fn wait_for(child: &mut Child, dir: &Path, suffix: &str) {
    let t0 = Instant::now();
    loop {
        if all_names(dir)
            .iter()
            .any(|p| p.to_string_lossy().ends_with(suffix))
        {
            return;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before writing"
        );
        assert!(t0.elapsed() < Duration::from_secs(60), "nothing written");
        std::thread::sleep(Duration::from_millis(5));
    }
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
        let mut child = common::bin()
            .arg("synth")
            .args(&ins)
            .arg("-o")
            .arg(&out)
            .args(["--iso", "1600,3200", "--target", "both", "--jobs", "2"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // After the first whole set, while the next ones are being made.
        wait_for(&mut child, &out, ".json");
        kill(&child, sig);
        let t0 = Instant::now();
        let o = child.wait_with_output().unwrap();
        let stopped_in = t0.elapsed().as_secs_f64();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{err}");
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
        assert!(
            sets >= 1 && sets < ins.len(),
            "{sets} sets: the signal came after the whole run"
        );
        eprintln!("{sig}: stopped {stopped_in:.2} s after the signal, {sets} whole sets");
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
            .args(["--iso", "1600", "--jobs", "2", "-q"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        c
    };
    let mut child = run().spawn().unwrap();
    wait_for(&mut child, &out.join("train").join("meta"), ".json");
    kill(&child, "-INT");
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("day2night: interrupted: rerun the same command to resume"),
        "{err}"
    );
    no_temp_files(&out);
    let o = run().output().unwrap();
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
    let mut child = common::bin()
        .arg("synth")
        .args(&ins)
        .arg("-o")
        .arg(&out)
        .args(["--iso", "1600,3200", "--target", "both", "--jobs", "2"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&mut child, &out, "");
    kill(&child, "-TERM");
    kill(&child, "-TERM");
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(143), "{err}");
    assert!(err.contains("day2night: interrupted"), "{err}");
    no_temp_files(&out);
}

/// A `w` x `h` 16-bit RGGB DNG (uncompressed strips) at `path`, varied by `k`.
fn big_dng(path: &Path, w: usize, h: usize, k: u16) {
    let mut b = dngbuild::Builder::new(w, h, 16);
    b.layout = dngbuild::Pixels::Strips { rows: 256 };
    for (i, p) in b.pixels.iter_mut().enumerate() {
        *p = (((i * 2654435761) >> 7) as u16 & 0x3fff).wrapping_add(k * 97) | 0x400;
    }
    std::fs::write(path, b.build()).unwrap();
}

/// Start `args` with stdout and stderr on pipes, then close both pipes (as when the reader
/// of a pipeline dies), let it work 0.1 s (it must still be running then), send
/// `sig`, and assert it exits with 128 + signal within a second, leaving no temporary or
/// lock file under `watch`.
fn stops_with_closed_pipes(what: &str, args: &[&std::ffi::OsStr], watch: &Path, sig: &str) {
    let mut child = common::bin()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    drop(child.stderr.take());
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(100) {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "{what}: ended before the signal: the input is too small to test the interrupt"
    );
    kill(&child, sig);
    let t1 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t1.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: still running 10 s after {sig}");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let took = t1.elapsed();
    let code = if sig == "-INT" { 130 } else { 143 };
    eprintln!(
        "{what} {sig}: exited {status} {:.3} s after the signal",
        took.as_secs_f64()
    );
    assert_eq!(status.code(), Some(code), "{what} {sig}");
    assert!(took < Duration::from_secs(1), "{what} {sig}: {took:?}");
    no_temp_files(watch);
}

#[test]
fn every_command_stops_within_a_second_with_closed_pipes() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let (w, h) = (6000usize, 4000usize);
    let day = d.join("day");
    std::fs::create_dir_all(&day).unwrap();
    let frames: Vec<PathBuf> = (0..4u16)
        .map(|k| {
            let p = day.join(format!("f{k}.dng"));
            big_dng(&p, w, h, k);
            p
        })
        .collect();
    // two display images for eval
    let img = |k: f32| day2night::isp::RgbImage {
        width: w,
        height: h,
        data: (0..3 * w * h)
            .map(|i| ((i % 997) as f32 / 997.0 * k).min(1.0))
            .collect(),
    };
    let (pa, pb) = (d.join("a.png"), d.join("b.png"));
    let png = day2night::encode::png::PngOptions::default();
    let policy = day2night::output::OutputPolicy::default();
    day2night::encode::png::write_png(&img(1.0), &pa, &png, &policy).unwrap();
    day2night::encode::png::write_png(&img(0.9), &pb, &png, &policy).unwrap();
    // a dataset for report (3 images of 3000x2000)
    let rday = d.join("rday");
    std::fs::create_dir_all(&rday).unwrap();
    for k in 0..3u16 {
        big_dng(&rday.join(format!("r{k}.dng")), 3000, 2000, k);
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
    // a lossless-JPEG DNG for convert (decoding and encoding it takes longer)
    let lj = d.join("lj.dng");
    let made = common::bin()
        .arg("convert")
        .arg(&frames[0])
        .arg("-o")
        .arg(&lj)
        .args(["--compression", "ljpeg"])
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let o = |p: &Path| p.as_os_str().to_owned();
    let f0 = o(&frames[0]);
    for (i, sig) in ["-TERM", "-INT"].into_iter().enumerate() {
        let out = d.join(format!("out{i}"));
        std::fs::create_dir_all(&out).unwrap();
        let os = |s: &str| std::ffi::OsString::from(s);
        let runs: Vec<(&str, Vec<std::ffi::OsString>)> = vec![
            (
                "render",
                vec![os("render"), f0.clone(), os("-o"), o(&out.join("r.exr"))],
            ),
            (
                "synth",
                vec![
                    os("synth"),
                    f0.clone(),
                    os("-o"),
                    o(&out),
                    os("--target"),
                    os("both"),
                ],
            ),
            (
                "dataset",
                vec![os("dataset"), o(&day), os("-o"), o(&out.join("set"))],
            ),
            ("eval", vec![os("eval"), o(&pa), o(&pb)]),
            (
                "calibrate",
                vec![
                    os("calibrate"),
                    os("brightness"),
                    o(&frames[0]),
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
                    o(&frames[0]),
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
                    o(&lj),
                    os("-o"),
                    o(&out.join("c.dng")),
                    os("--compression"),
                    os("ljpeg"),
                ],
            ),
        ];
        for (what, args) in &runs {
            let a: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
            stops_with_closed_pipes(what, &a, &out, sig);
        }
        let report = [os("report"), o(&rset), os("--day-dir"), o(&rday)];
        let a: Vec<&std::ffi::OsStr> = report.iter().map(|s| s.as_os_str()).collect();
        stops_with_closed_pipes("report", &a, &rset, sig);
    }
}
