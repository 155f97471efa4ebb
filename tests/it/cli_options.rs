//! The option table (src/synth/options/table.rs) against its readers: every option is a
//! flag of `synth` and `dataset`, and every flag of theirs is an option or one of the
//! command's own; docs/python.md's option section names every option (it is generated from
//! Python's signatures by python/tests/test_python_signatures.py); docs/synthesis.md names
//! every constant. Python's keywords are checked against the table by
//! python/tests/test_options_table.py, the sidecar fields by the library's unit tests
//! (src/synth/options/tests.rs).
use crate::common;
use day2night::synth::options::{CONSTANTS, OPTIONS};
use std::collections::BTreeSet;

/// The long flags a command's `--help` lists.
fn flags(cmd: &str) -> BTreeSet<String> {
    let out = common::bin().args([cmd, "--help"]).output().unwrap();
    assert!(out.status.success());
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l
                .strip_prefix("-o, ")
                .or(l.strip_prefix("-q, "))
                .unwrap_or(l);
            let name = l.strip_prefix("--")?;
            Some(name.split([' ', ',']).next()?.to_string())
        })
        .collect()
}

fn check_command(cmd: &str, own: &[&str]) {
    let have = flags(cmd);
    let table: BTreeSet<String> = OPTIONS.iter().map(|d| d.name.to_string()).collect();
    for name in &table {
        assert!(
            have.contains(name),
            "option {name} is not a flag of `{cmd}`"
        );
    }
    for flag in &have {
        assert!(
            table.contains(flag) || own.contains(&flag.as_str()),
            "`{cmd} --{flag}` is neither an option of the table nor one of {cmd}'s own flags"
        );
    }
}

#[test]
fn cli_flags_are_the_table() {
    let common = [
        "max-pixels",
        "help",
        "output",
        "variants",
        "jobs",
        "overwrite",
        "wait",
        "quiet",
    ];
    check_command("synth", &common);
    let dataset = [
        &common[..],
        &["val", "val-fraction", "shard", "report", "json"],
    ]
    .concat();
    check_command("dataset", &dataset);
}

/// docs/python.md's option section is generated from Python's signatures
/// (python/tests/test_python_signatures.py, which fails when it is stale); this checks,
/// without Python, that it lists every option of the table by its keyword and flag.
#[test]
fn python_md_lists_the_table() {
    let doc = std::fs::read_to_string(common::root().join("docs/python.md")).unwrap();
    let start = doc
        .find("<!-- synth-options:")
        .expect("docs/python.md: no synth-options block");
    let end = doc[start..]
        .find("<!-- /synth-options -->")
        .expect("docs/python.md: synth-options block not closed");
    let block = &doc[start..start + end];
    for d in OPTIONS {
        let row = format!("| `{}`", d.python_name());
        assert!(
            block.contains(&row) && block.contains(&format!("`--{}`", d.name)),
            "docs/python.md's option section has no row for --{}: run `D2N_BLESS=1 python -m \
             pytest python/tests/test_python_signatures.py`",
            d.name
        );
    }
    for c in CONSTANTS {
        assert!(block.contains(&format!("| `{}` |", c.field)), "{}", c.field);
    }
}

#[test]
fn synthesis_md_names_the_constants() {
    let doc = std::fs::read_to_string(common::root().join("docs/synthesis.md")).unwrap();
    for c in CONSTANTS {
        assert!(
            doc.contains(&format!("`{}`", c.field)),
            "docs/synthesis.md does not name the constant {}",
            c.field
        );
    }
}
