//! Every option whose values are a few names spells them once, in its enum's `choices!` list
//! (src/choice.rs): each name and alias parses to its value under the type's case rule,
//! `Display` gives the name back, an unknown name is refused by a message that names every
//! value, the synthesis table's choice columns are the enums' own lists, and docs/cli.md
//! (generated from `--help`) lists the names of each option that takes them.
use crate::common;
use day2night::choice::{Choice, Name};
use day2night::synth::options::{Kind, OPTIONS};
use std::fmt::{Debug, Display};
use std::str::FromStr;

/// Each name and alias of `T` parses to its value (in upper case too when the type ignores
/// case, and not otherwise), `Display` is the name, and an unknown name's message names
/// every value.
fn walk<T>()
where
    T: Choice + FromStr + Display + Debug,
    T::Err: Display,
{
    assert_eq!(T::NAMES.len(), T::VALUES.len());
    for (n, v) in T::NAMES.iter().zip(T::VALUES) {
        assert_eq!(v.to_string(), n.name, "{v:?}");
        assert_eq!(T::name_of(*v), n.name);
        for s in std::iter::once(n.name).chain(n.aliases.iter().copied()) {
            assert_eq!(s.parse::<T>().ok(), Some(*v), "{s}");
            let upper = s.to_ascii_uppercase();
            if upper != s {
                assert_eq!(upper.parse::<T>().is_ok(), T::IGNORE_CASE, "{upper}");
            }
        }
    }
    let values: Vec<_> = T::VALUES.iter().collect();
    for (i, v) in values.iter().enumerate() {
        assert!(!values[..i].contains(v), "{v:?} is named twice");
    }
    let e = match "no-such-value".parse::<T>() {
        Ok(v) => panic!("no-such-value parsed as {v:?}"),
        Err(e) => e.to_string(),
    };
    for n in T::NAMES {
        assert!(e.contains(n.name), "{e}: lacks {}", n.name);
    }
}

#[test]
fn every_choice_type_parses_its_names_and_shows_them() {
    walk::<day2night::isp::Demosaic>();
    walk::<day2night::isp::tone::DisplayTone>();
    walk::<day2night::isp::opcodes::OpcodeMode>();
    walk::<day2night::isp::release::Isp>();
    walk::<day2night::encode::exr::ExrCompression>();
    walk::<day2night::metrics::SsimWindow>();
    walk::<day2night::metrics::NonFinite>();
    walk::<day2night::synth::Mode>();
    walk::<day2night::synth::RelightFormula>();
    walk::<day2night::synth::Covariance>();
    walk::<day2night::synth::burst::Interp>();
    walk::<day2night::synth::burst::Motion>();
    walk::<day2night::synth::job::Target>();
    walk::<day2night::dng::write::Compression>();
    walk::<day2night::synth::config::Preset>();
}

#[test]
fn mask_eval_parses_its_names_and_its_parameter() {
    use day2night::synth::MaskEval;
    for n in MaskEval::NAMES {
        let text = match n.param {
            Some(_) => format!("{}:2.5", n.name),
            None => n.name.to_string(),
        };
        assert!(text.parse::<MaskEval>().is_ok(), "{text}");
    }
    assert!("truncated:0".parse::<MaskEval>().is_err());
    let e = "nope".parse::<MaskEval>().unwrap_err().to_string();
    for n in MaskEval::NAMES {
        assert!(e.contains(n.shown()), "{e}");
    }
}

/// The enum list of each choice option of the synthesis table.
fn table_lists() -> Vec<(&'static str, &'static [Name])> {
    use day2night::synth as s;
    vec![
        ("mode", s::Mode::NAMES),
        ("relight-formula", s::RelightFormula::NAMES),
        ("covariance", s::Covariance::NAMES),
        ("mask-eval", s::MaskEval::NAMES),
        (
            "exr-compression",
            day2night::encode::exr::ExrCompression::NAMES,
        ),
        ("opcodes", day2night::isp::opcodes::OpcodeMode::NAMES),
        ("motion", s::burst::Motion::NAMES),
        ("warp-interp", s::burst::Interp::NAMES),
        ("target", s::job::Target::NAMES),
        ("compression", day2night::dng::write::Compression::NAMES),
        ("compat", s::config::Preset::NAMES),
    ]
}

#[test]
fn the_synthesis_table_choices_are_the_enums_lists() {
    let lists = table_lists();
    for d in OPTIONS {
        let Kind::Choice(names) = d.kind else {
            continue;
        };
        let Some((_, want)) = lists.iter().find(|(o, _)| *o == d.name) else {
            panic!("{}: a choice option without its enum in this test", d.name);
        };
        assert_eq!(names, *want, "{}", d.name);
        if let Some(v) = d.default_text() {
            assert!(names.iter().any(|n| n.accepts(v)), "{}: {v}", d.name);
        }
    }
    assert_eq!(
        lists.len(),
        OPTIONS
            .iter()
            .filter(|d| matches!(d.kind, Kind::Choice(_)))
            .count()
    );
}

/// The text of `flag`'s entry in the `## day2night CMD` section of docs/cli.md.
fn entry<'a>(doc: &'a str, cmd: &str, flag: &str) -> &'a str {
    let head = format!("\n## day2night {cmd}\n");
    let section = &doc[doc.find(&head).unwrap_or_else(|| panic!("{cmd}")) + head.len()..];
    let section = &section[..section.find("\n## ").unwrap_or(section.len())];
    let start = section
        .find(&format!("--{flag} <"))
        .unwrap_or_else(|| panic!("{cmd} --{flag}"));
    let rest = &section[start..];
    let end = rest[1..].find("\n      --").map_or(rest.len(), |i| i + 1);
    &rest[..end]
}

#[test]
fn docs_cli_md_lists_every_choice() {
    let doc = std::fs::read_to_string(common::root().join("docs/cli.md")).unwrap();
    let shown = |names: &[Name]| names.iter().map(Name::shown).collect::<Vec<_>>();
    let short: Vec<(&str, &str, Vec<&str>)> = vec![
        ("render", "demosaic", shown(day2night::isp::Demosaic::NAMES)),
        (
            "render",
            "exr-compression",
            shown(day2night::encode::exr::ExrCompression::NAMES),
        ),
        (
            "render",
            "tone",
            shown(day2night::isp::tone::DisplayTone::NAMES),
        ),
        (
            "render",
            "opcodes",
            shown(day2night::isp::opcodes::OpcodeMode::NAMES),
        ),
        ("render", "isp", shown(day2night::isp::release::Isp::NAMES)),
        (
            "real-pairs",
            "isp",
            shown(day2night::isp::release::Isp::NAMES),
        ),
        (
            "eval",
            "ssim-window",
            shown(day2night::metrics::SsimWindow::NAMES),
        ),
        (
            "eval",
            "nonfinite",
            shown(day2night::metrics::NonFinite::NAMES),
        ),
    ];
    for (cmd, flag, names) in short {
        let e = entry(&doc, cmd, flag);
        let list = format!("[possible values: {}]", names.join(", "));
        assert!(
            e.contains(&list),
            "docs/cli.md, {cmd} --{flag}: {list} not in {e}"
        );
    }
    // synth and dataset list each value on its own line with its help
    for cmd in ["synth", "dataset"] {
        for (flag, names) in table_lists() {
            let e = entry(&doc, cmd, flag);
            for n in names {
                let line = format!("- {}:", n.shown());
                assert!(
                    e.contains(&line),
                    "docs/cli.md, {cmd} --{flag}: {line} not in {e}"
                );
            }
        }
    }
}
