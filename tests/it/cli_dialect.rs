//! One command-line dialect (issue 13, point 8), checked on the built binary: the output
//! option's spellings, clear refusals of wrong outputs and empty inputs, the files `synth`
//! lists, the `day2night: <file>: <reason>` error form, and `info`'s numbers and sniffing.
use crate::common;

use std::path::Path;
use std::process::Output;

fn run(args: &[&std::ffi::OsStr]) -> Output {
    common::bin().args(args).output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Every non-empty stderr line of a failed run names the program, then a file, then why.
fn error_lines_have_the_form(o: &Output, file: &Path) {
    let err = text(&o.stderr);
    assert!(!err.trim().is_empty());
    for line in err.lines().filter(|l| !l.trim().is_empty()) {
        let rest = line
            .strip_prefix("day2night: ")
            .unwrap_or_else(|| panic!("not `day2night: ...`: {line:?}"));
        let f = file.display().to_string();
        assert!(
            rest.starts_with(&format!("{f}: ")),
            "line does not name {f}: {line:?}"
        );
    }
}

#[test]
fn every_output_option_has_the_three_spellings() {
    for cmd in [
        &["synth"][..],
        &["convert"],
        &["render"],
        &["merge"],
        &["dataset"],
        &["calibrate", "illuminants"],
        &["calibrate", "brightness"],
        &["calibrate", "noise"],
    ] {
        let o = common::bin().args(cmd).arg("--help").output().unwrap();
        let help = text(&o.stdout);
        assert!(o.status.success(), "{cmd:?}");
        assert!(
            help.contains("-o, --output <"),
            "{cmd:?} has no -o/--output:\n{help}"
        );
        assert!(
            help.contains("[alias: --out]"),
            "{cmd:?} has no --out alias:\n{help}"
        );
    }
}

#[test]
fn synth_accepts_each_spelling_and_lists_what_it_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    for (i, flag) in ["-o", "--output", "--out"].iter().enumerate() {
        let out = tmp.path().join(format!("o{i}"));
        let o = run(&[
            "synth".as_ref(),
            day.as_os_str(),
            flag.as_ref(),
            out.as_os_str(),
            "--iso".as_ref(),
            "none".as_ref(),
            "--target".as_ref(),
            "none".as_ref(),
        ]);
        assert!(o.status.success(), "{flag}: {}", text(&o.stderr));
        let err = text(&o.stderr);
        for f in ["day_clean.dng", "day.json"] {
            assert!(out.join(f).is_file());
            let line = format!("wrote {}", out.join(f).display());
            assert!(
                err.lines().any(|l| l == line),
                "{flag}: no {line:?} in {err}"
            );
        }
        assert!(o.stdout.is_empty());
    }
    // -q silences the list.
    let out = tmp.path().join("quiet");
    let o = run(&[
        "synth".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--iso".as_ref(),
        "none".as_ref(),
        "--target".as_ref(),
        "none".as_ref(),
        "-q".as_ref(),
    ]);
    assert!(o.status.success());
    assert!(o.stderr.is_empty(), "{}", text(&o.stderr));
    assert!(out.join("day.json").is_file());
}

#[test]
fn synth_refuses_a_file_as_output_and_leaves_no_empty_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let file = tmp.path().join("night.dng");
    std::fs::write(&file, b"x").unwrap();
    let o = run(&[
        "synth".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        file.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("the output must be a directory"),
        "{}",
        text(&o.stderr)
    );
    error_lines_have_the_form(&o, &file);
    assert_eq!(std::fs::read(&file).unwrap(), b"x");

    // Every input fails: no output folder appears.
    let bad = tmp.path().join("bad.dng");
    std::fs::write(&bad, b"not a dng at all").unwrap();
    let out = tmp.path().join("never");
    let o = run(&[
        "synth".as_ref(),
        bad.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!out.exists(), "an empty output folder was left");
    let err = text(&o.stderr);
    for line in err.lines() {
        assert!(line.starts_with("day2night: "), "{line:?}");
        let rest = &line["day2night: ".len()..];
        assert!(
            rest.starts_with(&format!("{}: ", bad.display()))
                || rest.starts_with(&format!("{}: ", out.display())),
            "{line:?}"
        );
    }
}

#[test]
fn dataset_without_dngs_and_report_of_a_missing_folder_are_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let day = tmp.path().join("empty");
    std::fs::create_dir_all(&day).unwrap();
    std::fs::write(day.join("notes.txt"), b"no raws here").unwrap();
    let out = tmp.path().join("set");
    let o = run(&[
        "dataset".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("no DNG file found"));
    error_lines_have_the_form(&o, &day);
    assert!(!out.exists());

    let missing = tmp.path().join("no_such_set");
    let o = run(&["report".as_ref(), missing.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("no such folder"),
        "{}",
        text(&o.stderr)
    );
    error_lines_have_the_form(&o, &missing);
    assert!(!missing.exists());
}

#[test]
fn info_prints_short_noise_numbers_and_names_foreign_formats() {
    let tmp = tempfile::tempdir().unwrap();
    let day = common::fixtures().join("day.dng");
    let out = tmp.path().join("n");
    let o = run(&[
        "synth".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--iso".as_ref(),
        "1600".as_ref(),
        "-q".as_ref(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = run(&["info".as_ref(), out.join("day_iso1600.dng").as_os_str()]);
    assert!(o.status.success());
    let info = text(&o.stdout);
    let line = info
        .lines()
        .find(|l| l.contains("noise profile:"))
        .unwrap()
        .to_string();
    // Every number has at most 6 significant digits (no 3.1999999999999997e-4).
    for tok in line.split(['=', ' ', ';']).filter(|t| t.contains('e')) {
        if let Some((m, _)) = tok.split_once('e') {
            if let Ok(v) = m.parse::<f64>() {
                let digits = m.chars().filter(|c| c.is_ascii_digit()).count();
                assert!(digits <= 6 && v != 0.0, "{tok} in {line}");
            }
        }
    }
    let o = run(&["info".as_ref(), out.join("day_target.exr").as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("not a DNG: this is an OpenEXR image"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn convert_takes_its_output_as_an_argument_or_an_option() {
    let dir = tempfile::tempdir().unwrap();
    let input = common::root().join("fixtures/day.dng");
    let a = dir.path().join("a.dng");
    let b = dir.path().join("b.dng");
    let o = run(&["convert".as_ref(), input.as_os_str(), a.as_os_str()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for (flag, out) in [
        ("-o", &b),
        ("--output", &dir.path().join("c.dng")),
        ("--out", &dir.path().join("d.dng")),
    ] {
        let o = run(&[
            "convert".as_ref(),
            input.as_os_str(),
            flag.as_ref(),
            out.as_os_str(),
        ]);
        assert!(o.status.success(), "{flag}: {}", text(&o.stderr));
        assert_eq!(
            std::fs::read(out).unwrap(),
            std::fs::read(&a).unwrap(),
            "{flag}"
        );
    }
    // both, or neither: usage errors
    let o = run(&[
        "convert".as_ref(),
        input.as_os_str(),
        a.as_os_str(),
        "-o".as_ref(),
        b.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&["convert".as_ref(), input.as_os_str()]);
    assert_eq!(o.status.code(), Some(2));
}

/// docs/cli.md's conventions for a refused output: `day2night: <file>: <reason>` (the file
/// first, then the refusal), exit code 1 (a refused output, not bad usage: issue 43).
#[test]
fn refused_outputs_name_the_file_first_and_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let input = common::root().join("fixtures/day.dng");
    let a = dir.path().join("a.dng");
    std::fs::write(&a, b"not yet").unwrap();
    let o = run(&["convert".as_ref(), input.as_os_str(), a.as_os_str()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    error_lines_have_the_form(&o, &a);
    assert!(
        text(&o.stderr).contains(": refusing to overwrite: it exists"),
        "{}",
        text(&o.stderr)
    );
    // a non-empty folder that is not a dataset
    let days = dir.path().join("days");
    std::fs::create_dir(&days).unwrap();
    std::fs::copy(&input, days.join("day.dng")).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();
    let o = run(&[
        "dataset".as_ref(),
        days.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "-q".as_ref(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    error_lines_have_the_form(&o, &out);
}
