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

/// Fail the calling test: `what` is missing. A test needing a requirement never returns
/// early as passed; it fails naming the requirement, or, when the developer declared it
/// absent at build time (`D2N_ALLOW_MISSING=NAME`, see build.rs and tests/README.md), it
/// carries `#[cfg_attr(d2n_missing = "NAME", ignore = "...")]` and is reported as ignored.
pub fn missing(what: &str, name: &str, how: &str) -> ! {
    panic!(
        "needs {what}: {how}; or declare it absent with D2N_ALLOW_MISSING={name} \
         (the tests needing it are then reported as ignored; tests/README.md)"
    )
}

/// `../shared/data` (or `$D2N_SHARED_DATA`). Tests that need it carry
/// `#[cfg_attr(d2n_missing = "shared-data", ignore = ...)]`: build.rs declares the data
/// absent when it is not found at build time (a fresh clone), so those tests are reported
/// as ignored there; found at build time but missing now, the test fails.
pub fn shared_data() -> PathBuf {
    let p = std::env::var_os("D2N_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("../shared/data"));
    if !p.is_dir() {
        missing(
            &format!("the real-camera files at {}", p.display()),
            "shared-data",
            "set D2N_SHARED_DATA to their folder",
        );
    }
    p
}

/// A file of the shared data (`rel` inside [`shared_data`]); fails when absent.
pub fn shared_file(rel: &str) -> PathBuf {
    let p = shared_data().join(rel);
    if !p.is_file() {
        panic!(
            "shared file {} not found (the real-camera data is incomplete)",
            p.display()
        );
    }
    p
}

/// The Python interpreter of the validator virtualenv (`$D2N_PYTHON`, else `.venv` of the
/// checkout, which scripts/test.sh makes); fails when absent.
pub fn python() -> PathBuf {
    let p = std::env::var_os("D2N_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join(".venv/bin/python"));
    if !p.exists() {
        missing(
            &format!("the validators (no Python at {})", p.display()),
            "validators",
            "run scripts/test.sh or set D2N_PYTHON to a venv with tests/validators/requirements.txt",
        );
    }
    p
}

/// `name` on PATH, if any.
pub fn on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var("PATH").unwrap_or_default();
    path.split(':')
        .map(|dir| Path::new(dir).join(name))
        .find(|p| p.is_file())
}

/// Run `tests/validators/<script>` with the validator Python; returns its output.
pub fn run_validator(py: &Path, script: &str, args: &[&std::ffi::OsStr]) -> Output {
    Command::new(py)
        .arg(root().join("tests/validators").join(script))
        .args(args)
        .output()
        .expect("failed to start validator python")
}

/// exiftool; fails when absent.
pub fn exiftool() -> PathBuf {
    on_path("exiftool").unwrap_or_else(|| {
        missing(
            "exiftool",
            "exiftool",
            "install it (Debian libimage-exiftool-perl; .ci/run installs it)",
        )
    })
}

/// Debian `chromium` (or another Chromium) on PATH; fails when absent.
pub fn chromium() -> PathBuf {
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find_map(on_path)
        .unwrap_or_else(|| {
            missing(
                "chromium (headless page-load check)",
                "chromium",
                "install it (Debian chromium; .ci/run installs it)",
            )
        })
}

/// GNU time (`/usr/bin/time`, for peak RSS); fails when absent.
pub fn gnu_time() -> PathBuf {
    let p = PathBuf::from("/usr/bin/time");
    if !p.is_file() {
        missing(
            "GNU time at /usr/bin/time",
            "time",
            "install it (Debian time; .ci/run installs it)",
        );
    }
    p
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
