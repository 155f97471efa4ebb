//! Shared helpers for integration tests: where the validators and the shared real data are,
//! and how to run the built binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Committed fixtures folder.
pub fn fixtures() -> PathBuf {
    root().join("fixtures")
}

/// `../shared/data` (or `$D2N_SHARED_DATA`), if present. Prints why when absent (the
/// calling test then skips), or fails when `D2N_REQUIRE_SHARED_DATA=1` (`.ci/run` sets it
/// when `../shared/data` exists, so that a test silently skipping there is a failure).
pub fn shared_data() -> Option<PathBuf> {
    let p = std::env::var_os("D2N_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("../shared/data"));
    if p.is_dir() {
        Some(p)
    } else {
        skip_shared(&format!(
            "shared real-camera data not found at {} (set D2N_SHARED_DATA)",
            p.display()
        ));
        None
    }
}

/// A file of the shared data (`rel` inside [`shared_data`]), if present; like
/// [`shared_data`], prints why when absent, or fails under `D2N_REQUIRE_SHARED_DATA=1`.
pub fn shared_file(rel: &str) -> Option<PathBuf> {
    let p = shared_data()?.join(rel);
    if p.is_file() {
        Some(p)
    } else {
        skip_shared(&format!("shared file {} not found", p.display()));
        None
    }
}

fn skip_shared(why: &str) {
    if std::env::var("D2N_REQUIRE_SHARED_DATA").as_deref() == Ok("1") {
        panic!("{why} but D2N_REQUIRE_SHARED_DATA=1");
    }
    eprintln!("SKIP: {why}");
}

/// The Python interpreter of the validator virtualenv, if any. When
/// `D2N_REQUIRE_VALIDATORS=1` (set by scripts/test.sh) a missing interpreter is a failure,
/// otherwise the test prints why it skips.
pub fn python() -> Option<PathBuf> {
    let p = std::env::var_os("D2N_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join(".venv/bin/python"));
    if p.exists() {
        return Some(p);
    }
    if std::env::var("D2N_REQUIRE_VALIDATORS").as_deref() == Ok("1") {
        panic!(
            "validator Python {} missing but D2N_REQUIRE_VALIDATORS=1",
            p.display()
        );
    }
    eprintln!(
        "SKIP: validator Python not found at {} (run scripts/test.sh to set it up)",
        p.display()
    );
    None
}

/// Run `tests/validators/<script>` with the validator Python; returns its output.
pub fn run_validator(py: &Path, script: &str, args: &[&std::ffi::OsStr]) -> Output {
    Command::new(py)
        .arg(root().join("tests/validators").join(script))
        .args(args)
        .output()
        .expect("failed to start validator python")
}

/// exiftool, if installed (prints why when not).
pub fn exiftool() -> Option<PathBuf> {
    for dir in std::env::var("PATH").unwrap_or_default().split(':') {
        let p = Path::new(dir).join("exiftool");
        if p.is_file() {
            return Some(p);
        }
    }
    eprintln!("SKIP: exiftool not installed (Debian libimage-exiftool-perl; .ci/run installs it)");
    None
}

/// The built `day2night` binary.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_day2night"))
}

/// Run `day2night CMD INPUT -o OUT EXTRA...` and return its output (the shape of most CLI
/// calls in the tests).
pub fn cli(cmd: &str, input: &Path, out: &Path, extra: &[&str]) -> Output {
    bin()
        .arg(cmd)
        .arg(input)
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}
