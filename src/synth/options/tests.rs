//! The table against the library: defaults, sidecar names, names.

use super::*;
use crate::synth::burst::BurstOptions;
use crate::synth::SynthOptions;

#[test]
fn defaults_are_the_libraries() {
    // SynthOptions' are made from the table (with_defaults); the job's other settings
    // (targets, compression, EXR) are JobConfig's own
    let mut d = Draft::new(1);
    for def in OPTIONS {
        let v = match def.kind {
            Kind::Switch => Some(Value::Switch(false)),
            _ => def.default_value(),
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
        if let (Kind::Choice(c), Some(v)) = (d.kind, d.default_text()) {
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
        ..crate::synth::options::burst_defaults()
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
    let e = Draft::new(1)
        .set(
            find("dim-range").unwrap(),
            Value::Numbers(vec![0.9, 0.5]),
            Spelling::Cli,
        )
        .unwrap_err();
    assert_eq!(e.to_string(), "--dim-range: LO 0.9 is above HI 0.5");
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
        if let Kind::Int { lo, hi, .. } = d.kind {
            // the help shows the kind's range: the text does not spell it again
            for spelled in [format!("{lo} to {hi}"), format!("{lo}..={hi}")] {
                assert!(
                    !d.help.contains(&spelled),
                    "{}: {spelled} in its help",
                    d.name
                );
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

#[test]
fn every_default_sets_its_field() {
    // with_defaults ignores a default that does not set (in a release build): none does
    let mut d = Draft::new(1);
    for def in OPTIONS {
        if let Some(v) = def.default_value() {
            assert!(!matches!(v, Value::Text(_)) || !matches!(def.kind, Kind::Int { .. }));
            d.set(def, v, Spelling::Cli)
                .unwrap_or_else(|e| panic!("{}: {e}", def.name));
        }
        if let (Kind::Float { range, field }, Some(text)) = (def.kind, def.default_text()) {
            let x: f64 = text.parse().unwrap();
            assert!(
                range.contains(x),
                "{}: default {x} outside {range}",
                def.name
            );
            if let Some(get) = field {
                assert_eq!(get(&SynthOptions::default()), x, "{}", def.name);
            }
        }
    }
}

#[test]
fn default_options_serialize_as_before() {
    // SynthOptions::default() is made from the table's defaults: its JSON (what sidecars
    // and dataset fingerprints hold) is pinned here.
    let json = serde_json::to_string(&SynthOptions::default()).unwrap();
    // noise_gain, compat, opcodes and burst are left out at their defaults.
    assert_eq!(
        json,
        r#"{"mode":"local","formula":"release","bulbs":null,"local_lights":null,"isos":[1600,3200],"truncate":false,"keep_negative":false,"keep_highlights":false,"dim_range":[0.55,0.9],"ambient_gain":0.05,"bulb_gain":[50.0,100.0],"sampler":{"floor":0.001,"max_mahalanobis":3.0,"max_tries":1000},"covariance":"unbiased","day_neutral":null,"mask_eval":{"eval":"separable"}}"#
    );
}

#[test]
fn number_ranges_are_written_once() {
    let mut checked = 0;
    for d in OPTIONS {
        let Kind::Float { range, field } = d.kind else {
            continue;
        };
        if range == Range::ANY {
            assert_eq!(d.help_text(), d.help, "{}", d.name);
            continue;
        }
        // the help shows the kind's range, the text does not spell it again
        let shown = range.to_string();
        assert!(!d.help.contains(&shown), "{}: {shown} in its help", d.name);
        assert!(
            d.help_text().ends_with(&format!(" [range: {shown}]")),
            "{}",
            d.name
        );
        // Draft::set refuses a value outside, naming the option and the range
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let e = Draft::new(1)
                .set(d, Value::Float(bad), Spelling::Cli)
                .unwrap_err()
                .to_string();
            assert!(e.starts_with(&format!("--{}: ", d.name)), "{e}");
        }
        // and validate refuses the field outside (a sidecar's), naming flag and keyword
        let get = field.expect("a number option with a range sets a field");
        let mut draft = Draft::new(1);
        (d.set)(&mut draft, Value::Float(-1.0)).unwrap(); // the setter alone: no check
        let o = draft.config.options;
        assert_eq!(get(&o), -1.0);
        let e = o.validate().unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "--{} (Python {}): -1 is ",
                d.name,
                d.python_name()
            )),
            "{e}"
        );
        checked += 1;
    }
    assert!(checked >= 2);
    assert_eq!(
        find("noise-gain").unwrap().help_text().rsplit('[').next(),
        Some("range: > 0]")
    );
    assert_eq!(
        find("ambient-gain").unwrap().help_text().rsplit('[').next(),
        Some("range: >= 0]")
    );
    let e = Draft::new(1)
        .set(
            find("noise-gain").unwrap(),
            Value::Float(0.0),
            Spelling::Python,
        )
        .unwrap_err()
        .to_string();
    assert_eq!(e, "noise_gain: 0 is not > 0");
}

#[test]
fn choices_are_checked_from_their_list() {
    // Draft::set checks a choice's name against the entry's list, the one spelling of them
    for (name, bad, list) in [
        ("target", "jpeg", "exr, png, both or none"),
        ("compression", "zip", "none or ljpeg"),
        ("compat", "paper", "release"),
        ("relight-formula", "new", "release or paper"),
    ] {
        let e = Draft::new(1)
            .set(find(name).unwrap(), Value::Text(bad.into()), Spelling::Cli)
            .unwrap_err()
            .to_string();
        assert_eq!(e, format!("--{name}: {bad:?} (use {list})"));
    }
    // and each name of each list sets
    for d in OPTIONS {
        if let Kind::Choice(choices) = d.kind {
            for c in choices {
                let text = match c.param {
                    Some(_) => format!("{}:3", c.name),
                    None => c.name.to_string(),
                };
                let mut draft = Draft::new(1);
                draft
                    .set(d, Value::Text(text), Spelling::Cli)
                    .unwrap_or_else(|e| panic!("{e}"));
            }
        }
    }
    let mut d = Draft::new(1);
    for (name, value) in [("target", "both"), ("compression", "ljpeg")] {
        d.set(
            find(name).unwrap(),
            Value::Text(value.into()),
            Spelling::Cli,
        )
        .unwrap();
    }
    assert_eq!(d.config.target, crate::synth::job::Target::Both);
    assert_eq!(d.config.compression, crate::dng::write::Compression::Ljpeg);
}

#[test]
fn pair_ranges_are_written_once() {
    let mut checked = 0;
    for d in OPTIONS {
        let Kind::Pair { range, field } = d.kind else {
            continue;
        };
        assert!(
            !d.help.contains("LO <=") && !d.help.contains(&range.to_string()),
            "{}: its range in its help",
            d.name
        );
        assert!(d.help_text().contains("[range: LO <= HI"), "{}", d.name);
        let default: Vec<f64> = d
            .default_text()
            .unwrap()
            .split(',')
            .map(|x| x.parse().unwrap())
            .collect();
        let get = field.expect("a pair sets a field");
        assert_eq!(
            get(&SynthOptions::default()).to_vec(),
            default,
            "{}",
            d.name
        );
        for bad in [vec![-1.0, 1.0], vec![2.0, 1.0], vec![1.0, f64::NAN]] {
            let e = Draft::new(1)
                .set(d, Value::Numbers(bad.clone()), Spelling::Python)
                .unwrap_err()
                .to_string();
            assert!(e.starts_with(&format!("{}: ", d.python_name())), "{e}");
            // validate refuses the same field (a sidecar's), naming flag and keyword
            let mut draft = Draft::new(1);
            (d.set)(&mut draft, Value::Numbers(bad)).unwrap();
            let e = draft.config.options.validate().unwrap_err().to_string();
            assert!(
                e.contains(&format!("--{} (Python {}): ", d.name, d.python_name())),
                "{e}"
            );
        }
        checked += 1;
    }
    assert_eq!(checked, 2);
    assert!(find("dim-range")
        .unwrap()
        .help_text()
        .ends_with(" [range: LO <= HI, each > 0]"));
    let e = Draft::new(1)
        .set(
            find("bulb-gain").unwrap(),
            Value::Text("-1,2".into()),
            Spelling::Cli,
        )
        .unwrap_err()
        .to_string();
    assert_eq!(e, "--bulb-gain: LO -1 is not >= 0");
}

#[test]
fn every_entry_has_a_default_and_every_fixed_set_is_a_choice() {
    // Issue 43: the table's defaults are values or an explicit none, never help text; an
    // option whose values are a fixed set of names is a Choice (its names checked once).
    for d in OPTIONS {
        let help = d.help.to_ascii_lowercase();
        assert!(
            !help.contains("default"),
            "{}: its help speaks of a default: give it in the entry's `default`",
            d.name
        );
        match d.default {
            OptDefault::Value(t) => {
                assert!(!t.is_empty(), "{}", d.name);
                let v = d.default_value().unwrap();
                Draft::new(1)
                    .set(d, v, Spelling::Cli)
                    .unwrap_or_else(|e| panic!("{}: default {t:?}: {e}", d.name));
            }
            OptDefault::Derived(how) => assert!(!how.trim().is_empty(), "{}", d.name),
            OptDefault::Off => {}
        }
        match d.kind {
            Kind::Text => {
                // free text: its help lists no names to pick from ("a, b or c")
                assert!(
                    !help.contains(" or ") && !help.contains("one of"),
                    "{}: Kind::Text with a fixed set of values in its help: make it a Choice",
                    d.name
                );
            }
            Kind::Choice(choices) => {
                for c in choices {
                    let example = match c.param {
                        Some(_) => format!("{}:1", c.name),
                        None => c.name.to_string(),
                    };
                    assert!(c.accepts(&example), "{}: {}", d.name, c.name);
                    for a in c.aliases {
                        assert!(c.accepts(a), "{}: alias {a}", d.name);
                    }
                }
                // and its help does not list them again
                let listed = choices.iter().filter(|c| help.contains(c.name)).count();
                assert!(listed < 2, "{}: its help lists its choices", d.name);
            }
            _ => {}
        }
    }
    // the five that were text (issue 43)
    for name in [
        "mask-eval",
        "exr-compression",
        "opcodes",
        "motion",
        "warp-interp",
    ] {
        assert!(
            matches!(find(name).unwrap().kind, Kind::Choice(_)),
            "{name}"
        );
    }
    assert!(!OPTIONS.iter().any(|d| matches!(d.kind, Kind::Text)));
}

#[test]
fn a_choice_with_a_parameter_and_aliases_set() {
    let mut d = Draft::new(1);
    d.set(
        find("mask-eval").unwrap(),
        Value::Text("truncated:5".into()),
        Spelling::Cli,
    )
    .unwrap();
    d.set(
        find("warp-interp").unwrap(),
        Value::Text("cubic".into()),
        Spelling::Cli,
    )
    .unwrap();
    d.set(find("burst").unwrap(), Value::Int(3), Spelling::Cli)
        .unwrap();
    let o = d.finish(Spelling::Cli).unwrap().options;
    assert_eq!(o.mask_eval, crate::synth::MaskEval::Truncated { k: 5.0 });
    assert_eq!(o.burst.interp, crate::synth::burst::Interp::CatmullRom);
    let e = Draft::new(1)
        .set(
            find("mask-eval").unwrap(),
            Value::Text("fast".into()),
            Spelling::Python,
        )
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "mask_eval: \"fast\" (use separable, exact, truncated:K or release)"
    );
    let e = Draft::new(1)
        .set(
            find("motion").unwrap(),
            Value::Text("tripod".into()),
            Spelling::Python,
        )
        .unwrap_err()
        .to_string();
    assert_eq!(e, "motion: \"tripod\" (use none or shake)");
}

#[test]
fn the_burst_defaults_and_ranges_are_the_tables() {
    let b = burst_defaults();
    for (name, text) in [
        ("burst", b.frames.to_string()),
        ("shake-step", b.shake.step_px.to_string()),
        ("shake-roll", b.shake.roll_deg.to_string()),
        ("warp-interp", b.interp.name().to_string()),
    ] {
        assert_eq!(
            find(name).unwrap().default_text(),
            Some(text.as_str()),
            "{name}"
        );
    }
    assert_eq!(b.motion, crate::synth::burst::Motion::Shake);
    // a sidecar's burst out of range is refused by the table's check, naming the option
    let mut o = SynthOptions::default();
    o.burst.frames = 65;
    let e = o.validate().unwrap_err().to_string();
    assert!(
        e.contains("--burst (Python burst): 65 is outside 1..=64"),
        "{e}"
    );
    o.burst.frames = 3;
    o.burst.shake.roll_deg = 6.0;
    let e = o.validate().unwrap_err().to_string();
    assert!(
        e.contains("--shake-roll (Python shake_roll): 6 is outside 0..=5"),
        "{e}"
    );
    // a value at its default is not "given": passing every default is passing none
    let mut d = Draft::new(1);
    for def in OPTIONS {
        if let Some(v) = def.default_value() {
            d.set(def, v, Spelling::Python).unwrap();
        }
    }
    assert_eq!(d.finish(Spelling::Python).unwrap(), JobConfig::default());
}

#[test]
fn a_serialized_single_frame_reads_back_with_the_burst_defaults() {
    // a single frame's JSON has no burst: reading it back must give the table's burst, not
    // BurstOptions' blank (0 frames), or every sidecar's options would fail validate
    let json = serde_json::to_string(&SynthOptions::default()).unwrap();
    assert!(!json.contains("burst"));
    let back: SynthOptions = serde_json::from_str(&json).unwrap();
    assert_eq!(back, SynthOptions::default());
    back.validate().unwrap();
    let partial: crate::synth::burst::BurstOptions =
        serde_json::from_str(r#"{"frames": 3}"#).unwrap();
    assert_eq!(partial.shake, burst_defaults().shake);
}
