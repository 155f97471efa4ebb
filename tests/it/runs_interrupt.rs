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
