//! The docs that describe the house (issue 43): docs/architecture.md names every Python
//! subpackage and top-level module of python/pysrc/day2night, and docs/benchmarks.md opens
//! with one table of today's figures, at most 40 lines, before its dated history.
use crate::common;

#[test]
fn architecture_md_names_every_python_subpackage_and_module() {
    let doc = std::fs::read_to_string(common::root().join("docs/architecture.md")).unwrap();
    let pkg = common::root().join("python/pysrc/day2night");
    let mut named = 0;
    for entry in std::fs::read_dir(&pkg).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let spelled = if path.is_dir() && path.join("__init__.py").exists() {
            format!("`{name}/`")
        } else if name.ends_with(".py") {
            format!("`{name}`")
        } else {
            continue; // the compiled extension, caches
        };
        assert!(
            doc.contains(&spelled),
            "docs/architecture.md (\"The Python package\") does not name {spelled} of \
             python/pysrc/day2night: say what it holds and where it sits in the flow"
        );
        named += 1;
    }
    assert!(named >= 5, "{named} Python modules found");
}

#[test]
fn benchmarks_md_opens_with_todays_figures() {
    let doc = std::fs::read_to_string(common::root().join("docs/benchmarks.md")).unwrap();
    let first = doc
        .find("\n## ")
        .expect("docs/benchmarks.md has no section");
    let rest = &doc[first + 1..];
    assert!(
        rest.starts_with("## Today's figures\n"),
        "docs/benchmarks.md must open with \"## Today's figures\""
    );
    let end = rest[1..].find("\n## ").map_or(rest.len(), |i| i + 1);
    let section = &rest[..end];
    let lines = section.lines().count();
    assert!(
        lines <= 40,
        "the current-figures section has {lines} lines (at most 40)"
    );
    let rows: Vec<&str> = section
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| figure"))
        .collect();
    assert!(rows.len() >= 5, "{} figures", rows.len());
    for row in rows {
        // figure | value | command | machine, date
        let cells: Vec<&str> = row.trim_matches('|').split(" | ").collect();
        assert_eq!(cells.len(), 4, "{row}");
        assert!(
            cells.iter().all(|c| !c.trim().is_empty()),
            "an empty cell: {row}"
        );
    }
    assert!(
        rest[end..].trim_start().starts_with("## Appendix"),
        "the dated runs follow as an appendix"
    );
}
