//! The option table (src/synth/options/table.rs) against its readers: every option is a
//! flag of `synth` and `dataset`, and every flag of theirs is an option or one of the
//! command's own; docs/python.md's option list is the table's (generated below:
//! `D2N_BLESS=1 cargo test --test it cli_options` rewrites it); docs/synthesis.md names
//! every constant. Python's keywords are checked against the table by
//! python/tests/test_options_table.py, the sidecar fields by the library's unit tests
//! (src/synth/options/tests.rs).
use crate::common;
use day2night::synth::options::{Kind, OptionDef, Python, CONSTANTS, OPTIONS};
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

/// An option's Python value as docs/python.md describes it.
fn value_text(d: &OptionDef) -> String {
    match d.kind {
        Kind::Switch => "bool".into(),
        Kind::Int { lo, hi, .. } => format!("int, {lo}..={hi}"),
        Kind::Float => "number".into(),
        Kind::Text => "str".into(),
        Kind::Isos => "`\"1600,3200\"`, `\"none\"`, an int or a sequence of ints".into(),
        Kind::Numbers(n) => format!(
            "{n} numbers (a sequence, or `\"{}\"` text)",
            d.value_name.to_ascii_lowercase()
        ),
        Kind::Path => "path".into(),
        Kind::Choice(c) => c
            .iter()
            .map(|c| format!("`\"{}\"`", c.name))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// docs/python.md's generated block.
fn python_block() -> String {
    let mut s = String::from(
        "<!-- synth-options: generated from src/synth/options/table.rs; \
D2N_BLESS=1 cargo test --test it cli_options rewrites it -->\n\
| Keyword | Flag | Value | Default | Taken by |\n|---|---|---|---|---|\n",
    );
    for d in OPTIONS {
        let mut kw = format!("`{}`", d.python_name());
        if let Some(a) = d.python_alias {
            kw.push_str(&format!(" (or `{a}`)"));
        }
        let by = match d.python {
            Python::Keyword => "every synthesis function".to_string(),
            Python::Files => "`write_unit`, `write_units`".to_string(),
            Python::Parameter(p) => {
                format!("`synthesize`/`night_pair` as parameter `{p}`; `write_unit`, `write_units`")
            }
            Python::Absent(why) => format!("not an option: {why}"),
        };
        let default = match (d.kind, d.default) {
            (Kind::Switch, _) => "`False`".to_string(),
            (_, Some(v)) => format!("`{v}`"),
            (_, None) => "unset".to_string(),
        };
        s.push_str(&format!(
            "| {kw} | `--{}` | {} | {default} | {by} |\n",
            d.name,
            value_text(d)
        ));
    }
    s.push_str(
        "\nNot options (the same in every run; docs/synthesis.md, \"Options and constants\"):\n\n",
    );
    s.push_str("| Sidecar field | Value | Why |\n|---|---|---|\n");
    for c in CONSTANTS {
        s.push_str(&format!("| `{}` | {} | {} |\n", c.field, c.value, c.why));
    }
    s.push_str("<!-- /synth-options -->\n");
    s
}

#[test]
fn python_md_lists_the_table() {
    let path = common::root().join("docs/python.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let want = python_block();
    let start = doc
        .find("<!-- synth-options:")
        .expect("docs/python.md: no synth-options block");
    let end = doc[start..]
        .find("<!-- /synth-options -->\n")
        .map(|e| start + e + "<!-- /synth-options -->\n".len())
        .expect("docs/python.md: synth-options block not closed");
    if doc[start..end] != want {
        if std::env::var_os("D2N_BLESS").is_some() {
            let new = format!("{}{want}{}", &doc[..start], &doc[end..]);
            std::fs::write(&path, new).unwrap();
        } else {
            panic!(
                "docs/python.md's option list differs from the table: run \
                 `D2N_BLESS=1 cargo test --test it cli_options`; want:\n{want}"
            );
        }
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
