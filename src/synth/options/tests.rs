//! The table against the library: defaults, sidecar names, names.

use super::*;
use crate::synth::burst::BurstOptions;
use crate::synth::SynthOptions;

/// The command line's view of a default: the text clap passes to the setter.
fn default_value(d: &OptionDef) -> Option<Value> {
    let text = d.default?;
    Some(match d.kind {
        Kind::Int { .. } => Value::Int(text.parse().unwrap()),
        Kind::Float => Value::Float(text.parse().unwrap()),
        Kind::Switch => Value::Switch(false),
        Kind::Path => Value::Path(text.into()),
        _ => Value::Text(text.into()),
    })
}

#[test]
fn defaults_are_the_libraries() {
    let mut d = Draft::new(1);
    for def in OPTIONS {
        let v = match def.kind {
            Kind::Switch => Some(Value::Switch(false)),
            _ => default_value(def),
        };
        if let Some(v) = v {
            d.set(def, v, Spelling::Cli).unwrap();
        }
    }
    assert_eq!(d.seed, 0);
    assert_eq!(d.finish(Spelling::Cli).unwrap(), JobConfig::default());
    assert_eq!(
        Draft::new(1).finish(Spelling::Python).unwrap(),
        JobConfig::default()
    );
}

#[test]
fn names_are_unique_and_found() {
    let mut seen = std::collections::HashSet::new();
    for d in OPTIONS {
        assert!(seen.insert(d.python_name()), "{} twice", d.name);
        if let Some(a) = d.python_alias {
            assert!(seen.insert(a.to_string()), "{a} twice");
        }
        assert!(std::ptr::eq(find(d.name).unwrap(), d));
        assert!(std::ptr::eq(find(&d.python_name()).unwrap(), d));
        assert!(
            !d.help.ends_with('.'),
            "{}: help ends with a period",
            d.name
        );
        if let (Kind::Choice(c), Some(v)) = (d.kind, d.default) {
            assert!(c.iter().any(|c| c.name == v), "{}: default {v}", d.name);
        }
    }
    assert!(find("formula").is_some());
    assert!(find("colour").is_none());
}

/// The serialized options with every optional part present.
fn serialized() -> serde_json::Value {
    let mut o = SynthOptions::default().release_compat().unwrap();
    o.burst = BurstOptions {
        frames: 3,
        ..BurstOptions::default()
    };
    o.bulbs = Some(1);
    o.local_lights = Some(1);
    o.day_neutral = Some([0.5, 1.0, 0.5]);
    o.opcodes = crate::isp::opcodes::OpcodeMode::Ignore;
    o.noise_gain = 2.0;
    serde_json::to_value(&o).unwrap()
}

#[test]
fn sidecar_fields_are_synth_options() {
    let json = serialized();
    for d in OPTIONS {
        let Some(path) = d.sidecar else { continue };
        let mut at = &json;
        for part in path.split('.') {
            at = at
                .get(part)
                .unwrap_or_else(|| panic!("{}: no field {path} in SynthOptions", d.name));
        }
    }
    for c in CONSTANTS {
        assert!(json.get(c.field).is_some(), "constant {}", c.field);
    }
    // the other way round: every field is an option's or a constant
    for key in json.as_object().unwrap().keys() {
        let by_option = OPTIONS
            .iter()
            .filter_map(|d| d.sidecar)
            .any(|p| p.split('.').next() == Some(key.as_str()));
        let constant = CONSTANTS.iter().any(|c| c.field == key);
        assert!(
            by_option || constant,
            "SynthOptions field {key} is neither an option nor a constant"
        );
    }
}

#[test]
fn errors_name_the_option() {
    let mut d = Draft::new(1);
    let e = d
        .set(
            find("mask-eval").unwrap(),
            Value::Text("fast".into()),
            Spelling::Cli,
        )
        .unwrap_err();
    assert!(e.to_string().starts_with("--mask-eval: "), "{e}");
    let e = d
        .set(
            find("dim_range").unwrap(),
            Value::Text("1".into()),
            Spelling::Python,
        )
        .unwrap_err();
    assert!(e.to_string().starts_with("dim_range: "), "{e}");
    let mut d = Draft::new(1);
    d.set(
        find("dim-range").unwrap(),
        Value::Numbers(vec![0.9, 0.5]),
        Spelling::Cli,
    )
    .unwrap();
    assert!(d
        .finish(Spelling::Cli)
        .unwrap_err()
        .to_string()
        .contains("dimming range"));
    let mut d = Draft::new(1);
    d.set(
        find("compat").unwrap(),
        Value::Text("release".into()),
        Spelling::Cli,
    )
    .unwrap();
    d.set(
        find("covariance").unwrap(),
        Value::Text("ml".into()),
        Spelling::Cli,
    )
    .unwrap();
    let e = d.finish(Spelling::Cli).unwrap_err().to_string();
    assert!(e.starts_with("--compat release: "), "{e}");
}

#[test]
fn new_options_set_their_fields() {
    let mut d = Draft::new(1);
    d.set(
        find("ambient-gain").unwrap(),
        Value::Float(0.1),
        Spelling::Cli,
    )
    .unwrap();
    d.set(
        find("bulb-gain").unwrap(),
        Value::Text("10,20".into()),
        Spelling::Cli,
    )
    .unwrap();
    d.set(
        find("dim-range").unwrap(),
        Value::Text("0.2,0.3".into()),
        Spelling::Cli,
    )
    .unwrap();
    let o = d.finish(Spelling::Cli).unwrap().options;
    assert_eq!(o.ambient_gain, 0.1);
    assert_eq!(o.bulb_gain, [10.0, 20.0]);
    assert_eq!(o.dim_range, [0.2, 0.3]);
}

#[test]
fn ranges_are_written_once() {
    for d in OPTIONS {
        if let Kind::Int { lo, hi, late, .. } = d.kind {
            // the help shows the kind's range: the text does not spell it again
            for spelled in [format!("{lo} to {hi}"), format!("{lo}..={hi}")] {
                assert!(
                    !d.help.contains(&spelled),
                    "{}: {spelled} in its help",
                    d.name
                );
            }
            if late {
                continue;
            }
            // and Draft::set checks it, naming the option
            let mut draft = Draft::new(1);
            let e = draft
                .set(d, Value::Int(i128::from(hi) + 1), Spelling::Python)
                .unwrap_err()
                .to_string();
            assert_eq!(
                e,
                format!(
                    "{}: {} is outside {lo}..={hi}",
                    d.python_name(),
                    u128::from(hi) + 1
                )
            );
            draft
                .set(d, Value::Int(i128::from(hi)), Spelling::Cli)
                .unwrap();
        }
    }
    let burst = find("burst").unwrap();
    assert!(burst.help_text().ends_with(" [range: 1..=64]"));
    assert_eq!(
        find("seed").unwrap().help_text(),
        find("seed").unwrap().help
    );
}
