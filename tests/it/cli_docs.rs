//! docs/cli.md is generated from the binary's --help texts (scripts/gen-cli-doc.sh); this test
//! fails when a command's help changed and the doc was not regenerated.
use crate::common;

#[test]
fn docs_cli_md_matches_help_output() {
    let doc = std::fs::read_to_string(common::root().join("docs/cli.md")).unwrap();
    let cmds: &[&[&str]] = &[
        &[],
        &["info"],
        &["convert"],
        &["synth"],
        &["render"],
        &["eval"],
        &["calibrate"],
        &["calibrate", "illuminants"],
        &["calibrate", "brightness"],
        &["calibrate", "noise"],
        &["merge"],
        &["dataset"],
        &["real-pairs"],
        &["report"],
    ];
    for cmd in cmds {
        let out = common::bin().args(*cmd).arg("--help").output().unwrap();
        assert!(out.status.success(), "{cmd:?} --help failed");
        let help = String::from_utf8(out.stdout).unwrap();
        let block = format!("```text\n{help}```");
        assert!(
            doc.contains(&block),
            "docs/cli.md is stale for `day2night {}`: run scripts/gen-cli-doc.sh",
            cmd.join(" ")
        );
    }
}

/// Every warning code is documented in docs/warnings.md with its summary, and the doc lists
/// no other code; docs/cli.md points there.
#[test]
fn every_warning_code_is_documented_and_no_other() {
    let doc = std::fs::read_to_string(common::root().join("docs/warnings.md")).unwrap();
    for c in day2night::Code::ALL {
        let row = format!("| `{}` | {} |", c.as_str(), c.summary());
        assert!(doc.contains(&row), "docs/warnings.md lacks the row {row}");
    }
    let listed: Vec<&str> = doc
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .collect();
    for name in &listed {
        assert!(
            day2night::Code::from_name(name).is_some(),
            "docs/warnings.md lists `{name}`, which is no warning code"
        );
    }
    assert_eq!(listed.len(), day2night::Code::ALL.len(), "{listed:?}");
    let cli = std::fs::read_to_string(common::root().join("docs/cli.md")).unwrap();
    assert!(
        cli.contains("`warning[CODE]: <subject>: <message>`") && cli.contains("docs/warnings.md")
    );
}
