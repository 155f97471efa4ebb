//! Peak memory of `day2night dataset` on 12 MP inputs for 1 and 2 jobs (slow: ignored by
//! default, run by `scripts/test.sh --slow`). Inputs are 4000 x 3000 DNGs made by tiling the fixture day.dng (phase kept).
//! Measured with GNU time's "Maximum resident set size"; the numbers are printed and go into
//! docs/dataset.md.

use crate::common;

use std::path::Path;

fn make_12mp(dir: &Path, n: usize) {
    let day = day2night::dng::read::read_dng(&common::fixtures().join("day.dng")).unwrap();
    let (w, h) = (4000usize, 3000usize);
    let mut data = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            // Tile the active area (even offsets and sizes keep the Bayer phase).
            let a = day.active_area();
            let rr = a.top as usize + r % a.height();
            let cc = a.left as usize + c % a.width();
            data.push(day.data[rr * day.width + cc]);
        }
    }
    let mut meta = day.meta.clone();
    meta.active_area = None;
    meta.default_crop_origin = None;
    meta.default_crop_size = None;
    let img = day2night::RawImage {
        width: w,
        height: h,
        data,
        meta,
    };
    let bytes = day2night::dng::write::encode_dng(&img, &Default::default()).unwrap();
    for i in 0..n {
        std::fs::write(dir.join(format!("IMG_{i:02}.dng")), &bytes).unwrap();
    }
}

fn peak_rss_kib(day: &Path, out: &Path, jobs: usize) -> (u64, f64) {
    let t0 = std::time::Instant::now();
    let o = std::process::Command::new(common::gnu_time())
        .arg("-v")
        .arg(env!("CARGO_BIN_EXE_day2night"))
        .arg("dataset")
        .arg(day)
        .arg("-o")
        .arg(out)
        .args(["--quiet", "--jobs", &jobs.to_string()])
        .output()
        .unwrap();
    let secs = t0.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let kib = err
        .lines()
        .find_map(|l| {
            l.trim()
                .strip_prefix("Maximum resident set size (kbytes): ")
        })
        .and_then(|v| v.trim().parse().ok())
        .expect("no RSS line from /usr/bin/time");
    (kib, secs)
}

#[test]
#[ignore = "slow: peak memory of dataset on 12 MP inputs (scripts/test.sh --slow)"]
fn slow_peak_memory_on_12mp_inputs() {
    let day = tempfile::tempdir().unwrap();
    make_12mp(day.path(), 4);
    let mut results = Vec::new();
    for jobs in [1usize, 2, 4] {
        let out = tempfile::tempdir().unwrap();
        let (kib, secs) = peak_rss_kib(day.path(), out.path(), jobs);
        println!("dataset --jobs {jobs}, 4 inputs of 12 MP, default options: peak RSS {} MiB, {secs:.1} s", kib / 1024);
        results.push((jobs, kib));
    }
    // Bounded memory: peak grows with jobs (images in flight), not with the input count;
    // each job holds at most a few 12 MP images.
    for (jobs, kib) in results {
        assert!(
            kib / 1024 < 1200 * jobs as u64,
            "--jobs {jobs}: {} MiB",
            kib / 1024
        );
    }
}
