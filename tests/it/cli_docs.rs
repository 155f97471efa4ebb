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
