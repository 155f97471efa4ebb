//! Release mechanics (docs/release.md): every place that carries the version agrees with
//! Cargo.toml, and scripts/bump-version.sh moves all of them at once.
//!
//! The places: Cargo.toml and python/Cargo.toml (`[package] version`), python/pyproject.toml
//! (`[project] version`), Cargo.lock, `day2night --version`, the Software tag
//! (`day2night::software_name`) and the sidecar's `version`, and CHANGELOG.md (an
//! [Unreleased] section above the release sections).

use crate::common;
use std::path::Path;
use std::process::Command;

/// The first `version = "..."` of a manifest ([package] / [project] comes first).
fn first_version(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .find_map(|l| l.strip_prefix("version = \""))
        .and_then(|rest| rest.strip_suffix('"'))
        .unwrap_or_else(|| panic!("{}: no version line", path.display()))
        .to_string()
}

/// The version Cargo.lock records for package `name`.
fn lock_version(lock: &str, name: &str) -> String {
    let head = format!("name = \"{name}\"\nversion = \"");
    let at = lock
        .find(&head)
        .unwrap_or_else(|| panic!("{name} not in Cargo.lock"))
        + head.len();
    lock[at..].split('"').next().unwrap().to_string()
}

#[test]
fn every_place_carries_the_version_of_cargo_toml() {
    let root = common::root();
    let v = first_version(&root.join("Cargo.toml"));
    assert_eq!(v, day2night::VERSION);
    assert_eq!(
        first_version(&root.join("python/Cargo.toml")),
        v,
        "python/Cargo.toml"
    );
    assert_eq!(
        first_version(&root.join("python/pyproject.toml")),
        v,
        "python/pyproject.toml"
    );
    let lock = std::fs::read_to_string(root.join("Cargo.lock")).unwrap();
    assert_eq!(lock_version(&lock, "day2night"), v, "Cargo.lock");
    assert_eq!(lock_version(&lock, "day2night-python"), v, "Cargo.lock");
    assert_eq!(day2night::software_name(), format!("day2night {v}"));

    let out = common::bin().arg("--version").output().unwrap();
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        format!("day2night {v}")
    );

    // The sidecar of a real synthesis, and the Software tag of its DNG.
    let dir = tempfile::tempdir().unwrap();
    let o = common::cli(
        "synth",
        &common::fixtures().join("day.dng"),
        dir.path(),
        &["--seed", "1"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sidecar = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "json"))
        .expect("synth wrote a sidecar");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sidecar).unwrap()).unwrap();
    assert_eq!(json["version"], v.as_str(), "{}", sidecar.display());
    let dng = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "dng"))
        .expect("synth wrote a DNG");
    let bytes = std::fs::read(&dng).unwrap();
    let tag = format!("day2night {v}\0");
    assert!(
        bytes.windows(tag.len()).any(|w| w == tag.as_bytes()),
        "{}: no Software tag {tag:?}",
        dng.display()
    );

    let changelog = std::fs::read_to_string(root.join("CHANGELOG.md")).unwrap();
    let sections: Vec<&str> = changelog
        .lines()
        .filter_map(|l| l.strip_prefix("## ["))
        .filter_map(|l| l.split(']').next())
        .collect();
    assert_eq!(
        sections.first(),
        Some(&"Unreleased"),
        "CHANGELOG.md: {sections:?}"
    );
    assert!(
        sections.len() > 2,
        "CHANGELOG.md: one section per release: {sections:?}"
    );
}

#[test]
fn bump_script_moves_every_manifest_and_the_changelog() {
    let root = common::root();
    let dir = tempfile::tempdir().unwrap();
    let t = dir.path();
    std::fs::create_dir_all(t.join("python")).unwrap();
    for f in [
        "Cargo.toml",
        "Cargo.lock",
        "CHANGELOG.md",
        "python/Cargo.toml",
        "python/pyproject.toml",
    ] {
        std::fs::copy(root.join(f), t.join(f)).unwrap();
    }
    let out = Command::new("bash")
        .arg(root.join("scripts/bump-version.sh"))
        .args(["9.8.7", "--no-fixtures"])
        .env("ROOT", t)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in ["Cargo.toml", "python/Cargo.toml", "python/pyproject.toml"] {
        assert_eq!(first_version(&t.join(f)), "9.8.7", "{f}");
    }
    let lock = std::fs::read_to_string(t.join("Cargo.lock")).unwrap();
    assert_eq!(lock_version(&lock, "day2night"), "9.8.7");
    assert_eq!(lock_version(&lock, "day2night-python"), "9.8.7");
    let changelog = std::fs::read_to_string(t.join("CHANGELOG.md")).unwrap();
    let first_two: Vec<&str> = changelog
        .lines()
        .filter(|l| l.starts_with("## ["))
        .take(2)
        .collect();
    assert_eq!(first_two[0], "## [Unreleased]");
    assert!(first_two[1].starts_with("## [9.8.7] - "), "{first_two:?}");
    // Not a version: refused, nothing changed.
    let bad = Command::new("bash")
        .arg(root.join("scripts/bump-version.sh"))
        .args(["next", "--no-fixtures"])
        .env("ROOT", t)
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert_eq!(first_version(&t.join("Cargo.toml")), "9.8.7");
}
