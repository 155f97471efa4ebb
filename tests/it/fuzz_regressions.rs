//! Replays every committed fuzzer reproducer (tests/fuzz_regressions/) and the fuzz files of
//! ../shared/data/dng-bad: each must give an error (or a valid image), never a panic.
use crate::common;

use day2night::dng::read::{inspect_bytes, read_dng_bytes};

fn replay(p: &std::path::Path) {
    let bytes = std::fs::read(p).unwrap();
    let r = read_dng_bytes(&bytes);
    let _ = inspect_bytes(&bytes);
    if let Err(e) = r {
        assert!(!e.to_string().is_empty(), "{}", p.display());
    }
}

#[test]
fn committed_reproducers() {
    let dir = common::root().join("tests/fuzz_regressions");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "bin") {
            replay(&p);
            n += 1;
        }
    }
    eprintln!("replayed {n} reproducers from {}", dir.display());
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn shared_fuzz_files() {
    let d = common::shared_data();
    for e in std::fs::read_dir(d.join("dng-bad")).unwrap() {
        let p = e.unwrap().path();
        let bytes = std::fs::read(&p).unwrap();
        // The LinearRaw file is read (its synthesis is refused: dng_bad_files.rs).
        let linear_raw = p.to_string_lossy().contains("linearraw");
        assert!(
            read_dng_bytes(&bytes).is_err() != linear_raw,
            "{} must be {}",
            p.display(),
            if linear_raw { "read" } else { "refused" }
        );
        replay(&p);
    }
}
