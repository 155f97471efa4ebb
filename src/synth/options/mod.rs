//! The synthesis options, each declared once ([`OPTIONS`], in `table.rs`): its name, kind,
//! default ([`OptDefault`]: a value, or an explicit "none"), range or choices, help text,
//! how Python spells and reaches it, the sidecar field it lands in, and how its value sets a
//! [`JobConfig`]. The command line's `synth` and
//! `dataset` flags (src/cli/synth.rs), Python's keyword arguments (python/src/synth_options.rs)
//! and the option lists of docs/cli.md and docs/python.md are made from this table, and a
//! test (tests/it/cli_options.rs, python/tests/test_options_table.py) fails when one of them
//! differs from it. The model is ripgrep's flag definitions: one definition per flag, read
//! by the parser and the docs.
//! docs/architecture.md ("Adding a synthesis option") shows what adding one touches.
//!
//! Values arrive as [`Value`]s (the parser of each front end checks the type) and are
//! applied to a [`Draft`] in any order: [`Draft::set`] checks what the kind says (an
//! integer's or a number's range, a choice's name), [`Draft::finish`] applies what depends
//! on several options (the release preset, the burst's checks) and checks the whole. The
//! table's defaults are [`crate::synth::SynthOptions`]'s ([`with_defaults`]), and its number
//! ranges are what [`crate::synth::SynthOptions::validate`] checks ([`check_fields`]). The
//! burst's options are entries like the others: their defaults, ranges and choices are here,
//! and src/synth/burst keeps only the rules between them ([`crate::synth::burst::checks`]).

mod table;

pub use table::{CONSTANTS, MAX_FRAMES, MAX_ROLL_DEG, MAX_STEP_PX, OPTIONS};

use super::config::JobConfig;
use super::SynthOptions;
use crate::bounds::short;
pub use crate::choice::Name;
use crate::error::{Error, Result};
use crate::isp::opcodes::OpcodeMode;
use std::ops::Bound;
use std::path::PathBuf;

/// What an option's value is.
#[derive(Debug, Clone, Copy)]
pub enum Kind {
    /// A switch: present or not (Python: a bool).
    Switch,
    /// An integer within `lo..=hi`, parsed on the command line as [`Width`] (its own
    /// message for a value that does not fit); [`Draft::set`] checks the range.
    Int {
        /// Lowest value.
        lo: u64,
        /// Highest value.
        hi: u64,
        /// The command line's integer type.
        width: Width,
        /// The [`SynthOptions`] field it sets (unset: 0), which [`SynthOptions::validate`]
        /// checks against `lo..=hi` (a sidecar can hold any value); None: not a field.
        field: Option<fn(&SynthOptions) -> u64>,
    },
    /// A finite number within `range`, which [`Draft::set`] checks and the help shows.
    Float {
        /// The values it takes.
        range: Range,
        /// The [`SynthOptions`] field it sets, which [`SynthOptions::validate`] checks
        /// against `range` (a sidecar can hold any value); None: not a field.
        field: Option<fn(&SynthOptions) -> f64>,
    },
    /// Free text the setter parses. An option whose values are a fixed set of names is a
    /// [`Kind::Choice`] instead (a test walks the table for it); no entry is text today.
    Text,
    /// A comma-separated list of ISOs, or `none` (Python: also an int or a sequence of ints).
    Isos,
    /// `n` comma-separated numbers (Python: also a sequence of `n` numbers).
    Numbers(usize),
    /// `LO,HI`: two numbers (Python: also a sequence of two), each within `range`, with
    /// `LO <= HI`; checked and shown as a [`Kind::Float`]'s range is.
    Pair {
        /// The values each of LO and HI takes.
        range: Range,
        /// The [`SynthOptions`] field it sets, which [`SynthOptions::validate`] checks.
        field: Option<fn(&SynthOptions) -> [f64; 2]>,
    },
    /// A file path (some options also take a name, e.g. `paper`).
    Path,
    /// One of a few names (a name may take a parameter, `truncated:K`, or have aliases).
    Choice(&'static [Name]),
}

/// The values of a [`Kind::Float`] option: finite numbers within two bounds, each included,
/// excluded or absent. Written once, in the kind: [`Draft::set`] checks a value given,
/// [`SynthOptions::validate`] the field, and [`OptionDef::help_text`] shows it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// The lower bound.
    pub lo: Bound<f64>,
    /// The upper bound.
    pub hi: Bound<f64>,
}

impl Range {
    /// Every finite number.
    pub const ANY: Range = Range {
        lo: Bound::Unbounded,
        hi: Bound::Unbounded,
    };

    /// The numbers above `lo`.
    pub const fn above(lo: f64) -> Range {
        Range {
            lo: Bound::Excluded(lo),
            hi: Bound::Unbounded,
        }
    }

    /// The numbers from `lo` to `hi`, both included.
    pub const fn between(lo: f64, hi: f64) -> Range {
        Range {
            lo: Bound::Included(lo),
            hi: Bound::Included(hi),
        }
    }

    /// The numbers from `lo` up.
    pub const fn at_least(lo: f64) -> Range {
        Range {
            lo: Bound::Included(lo),
            hi: Bound::Unbounded,
        }
    }

    /// Whether `x` is finite and within the bounds.
    pub fn contains(&self, x: f64) -> bool {
        let above = match self.lo {
            Bound::Included(lo) => x >= lo,
            Bound::Excluded(lo) => x > lo,
            Bound::Unbounded => true,
        };
        let below = match self.hi {
            Bound::Included(hi) => x <= hi,
            Bound::Excluded(hi) => x < hi,
            Bound::Unbounded => true,
        };
        x.is_finite() && above && below
    }

    /// Error unless `x` is in the range: what is wrong with it and the range
    /// (`0 is not > 0`, `2000 is outside 0..=1000`, `NaN is not a finite number`); the
    /// caller names the option.
    pub fn check(&self, x: f64) -> Result<()> {
        match self.fault(x) {
            Some(m) => Err(Error::invalid(m)),
            None => Ok(()),
        }
    }

    /// What is wrong with the pair `[lo, hi]` of a [`Kind::Pair`] option (`LO 0 is not > 0`,
    /// `LO 0.9 is above HI 0.5`), or None when each is in the range and `lo <= hi`.
    fn pair_fault(&self, [lo, hi]: [f64; 2]) -> Option<String> {
        for (name, x) in [("LO", lo), ("HI", hi)] {
            if let Some(m) = self.fault(x) {
                return Some(format!("{name} {m}"));
            }
        }
        (lo > hi).then(|| format!("LO {} is above HI {}", short(lo), short(hi)))
    }

    /// What [`Range::check`] says of `x`, or None when it is in the range.
    fn fault(&self, x: f64) -> Option<String> {
        if self.contains(x) {
            return None;
        }
        if !x.is_finite() {
            return Some(format!("{x} is not a finite number"));
        }
        // A value just past a bound is shown with every digit it needs.
        let mut shown = short(x);
        if [self.lo, self.hi].iter().any(|b| match b {
            Bound::Included(v) | Bound::Excluded(v) => short(*v) == shown,
            Bound::Unbounded => false,
        }) {
            shown = format!("{x}");
        }
        let bounded = |b: Bound<f64>| !matches!(b, Bound::Unbounded);
        let verb = if bounded(self.lo) && bounded(self.hi) {
            "is outside"
        } else {
            "is not"
        };
        Some(format!("{shown} {verb} {self}"))
    }
}

impl std::fmt::Display for Range {
    /// `> 0`, `>= 0.5`, `< 1`, `0..=1000`, `0..1`, `> 0 and <= 1`; `any finite number`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use Bound::{Excluded, Included, Unbounded};
        match (self.lo, self.hi) {
            (Unbounded, Unbounded) => write!(f, "any finite number"),
            (Included(a), Included(b)) => write!(f, "{}..={}", short(a), short(b)),
            (Included(a), Excluded(b)) => write!(f, "{}..{}", short(a), short(b)),
            (lo, hi) => {
                let lo = match lo {
                    Included(a) => Some(format!(">= {}", short(a))),
                    Excluded(a) => Some(format!("> {}", short(a))),
                    Unbounded => None,
                };
                let hi = match hi {
                    Included(b) => Some(format!("<= {}", short(b))),
                    Excluded(b) => Some(format!("< {}", short(b))),
                    Unbounded => None,
                };
                let parts: Vec<String> = lo.into_iter().chain(hi).collect();
                write!(f, "{}", parts.join(" and "))
            }
        }
    }
}

/// The command line's integer type of an [`Kind::Int`] option.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Width {
    /// `u8`.
    U8,
    /// `u32`.
    U32,
    /// `u64`.
    U64,
}

impl Width {
    /// The type's largest value.
    pub fn max(self) -> u64 {
        match self {
            Width::U8 => u64::from(u8::MAX),
            Width::U32 => u64::from(u32::MAX),
            Width::U64 => u64::MAX,
        }
    }
}

/// An option's default: a value, or an explicit "none" (the option is unset unless given).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OptDefault {
    /// The default as typed on the command line (`--help` shows `[default: ...]`).
    Value(&'static str),
    /// None: the option is off unless given (a switch, a file not read, no preset).
    Off,
    /// None: unset unless given, and then worked out from the other options or the input as
    /// the text says (`--help` shows `[default: <text>]`); e.g. `--bulbs`: 5 with the
    /// release formula, 0 with the paper's.
    Derived(&'static str),
}

/// Where Python reaches an option.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Python {
    /// A keyword argument of every synthesis function (`synthesize`, `night_pair`,
    /// `NightPairs`, `write_unit`, `write_units`).
    Keyword,
    /// A keyword argument of the functions that write files (`write_unit`, `write_units`);
    /// the in-memory functions have no files to set it for.
    Files,
    /// A parameter of its own of the in-memory functions, each spelling it as its signature
    /// says (`synthesize(..., isos=...)`, `night_pair(..., iso, ...)`), and a keyword
    /// argument of `write_unit` and `write_units`.
    Parameter,
    /// Not an option in Python: the reason (where Python takes it instead).
    Absent(&'static str),
}

/// One synthesis option.
#[derive(Debug, Clone, Copy)]
pub struct OptionDef {
    /// The long flag without `--` (Python: the same with `_` for `-`).
    pub name: &'static str,
    /// The value's placeholder in `--help` (clap's default is the name in upper snake
    /// case; a switch has none).
    pub value_name: &'static str,
    /// What the value is.
    pub kind: Kind,
    /// The default: a value, or an explicit none (off, or worked out as its text says).
    pub default: OptDefault,
    /// Help text (one paragraph, no final period: the `--help` line).
    pub help: &'static str,
    /// Where Python reaches it.
    pub python: Python,
    /// Another Python keyword for it (kept for callers that use it).
    pub python_alias: Option<&'static str>,
    /// Applies to `synth` only (not `dataset`).
    pub synth_only: bool,
    /// The serialized [`crate::synth::SynthOptions`] field it sets (dotted into nested
    /// objects), as the sidecar's `options` spells it; None: not recorded there (files,
    /// output settings, the seed).
    pub sidecar: Option<&'static str>,
    /// Apply a value.
    pub set: fn(&mut Draft, Value) -> Result<()>,
}

impl OptionDef {
    /// The Python keyword.
    pub fn python_name(&self) -> String {
        self.name.replace('-', "_")
    }

    /// The default's text as typed on the command line, or None when the option is unset by
    /// default ([`OptDefault::Off`], [`OptDefault::Derived`]).
    pub fn default_text(&self) -> Option<&'static str> {
        match self.default {
            OptDefault::Value(t) => Some(t),
            OptDefault::Off | OptDefault::Derived(_) => None,
        }
    }

    /// The help text with what the kind says of the value: an integer's range when it is
    /// narrower than its type (`[range: 1..=64]`), a number's when it has a bound
    /// (`[range: > 0]`); and a default that is not a value (`[default: none]`, or how it is
    /// worked out). The range is written once, in the kind: [`Draft::set`] checks it and the
    /// help shows it; a value default is shown by the front end (clap's `[default: ...]`).
    pub fn help_text(&self) -> String {
        let text = self.help_with_range();
        match (self.default, self.kind) {
            (OptDefault::Derived(how), _) => format!("{text} [default: {how}]"),
            (OptDefault::Off, Kind::Switch) | (OptDefault::Value(_), _) => text,
            (OptDefault::Off, _) => format!("{text} [default: none]"),
        }
    }

    /// The help text with the kind's range.
    fn help_with_range(&self) -> String {
        match self.kind {
            Kind::Int { lo, hi, width, .. } if (lo, hi) != (0, width.max()) => {
                format!("{} [range: {lo}..={hi}]", self.help)
            }
            Kind::Float { range, .. } if range != Range::ANY => {
                format!("{} [range: {range}]", self.help)
            }
            Kind::Pair { range, .. } if range != Range::ANY => {
                format!("{} [range: LO <= HI, each {range}]", self.help)
            }
            Kind::Pair { .. } => format!("{} [range: LO <= HI]", self.help),
            _ => self.help.to_string(),
        }
    }

    /// The default as the command line's parser hands it to [`Draft::set`] (an integer, a
    /// number, a path or text), or None when the option is unset by default.
    pub fn default_value(&self) -> Option<Value> {
        let text = self.default_text()?;
        Some(match self.kind {
            Kind::Int { .. } => text
                .parse()
                .map_or_else(|_| Value::Text(text.into()), Value::Int),
            Kind::Float { .. } => text
                .parse()
                .map_or_else(|_| Value::Text(text.into()), Value::Float),
            Kind::Switch => Value::Switch(text == "true"),
            Kind::Path => Value::Path(text.into()),
            Kind::Text | Kind::Isos | Kind::Numbers(_) | Kind::Pair { .. } | Kind::Choice(_) => {
                Value::Text(text.into())
            }
        })
    }

    /// This option's name as `spelling` writes it.
    pub fn spelled(&self, spelling: Spelling) -> String {
        match spelling {
            Spelling::Cli => format!("--{}", self.name),
            Spelling::Python => self.python_name(),
        }
    }
}

/// A synthesis field that is not an option: its value is fixed for every run (a replayed
/// sidecar keeps whatever it records).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Constant {
    /// The serialized [`crate::synth::SynthOptions`] field (dotted into nested objects).
    pub field: &'static str,
    /// Its value.
    pub value: &'static str,
    /// Why it is not an option.
    pub why: &'static str,
}

/// `blank` with every option of the table that sets one of its fields at its default, set
/// as the command line sets it: the defaults of [`SynthOptions`] are the table's, written
/// once (`SynthOptions::default()` is this of its fields at their types' defaults; the
/// fields that are not options keep those).
pub fn with_defaults(blank: SynthOptions) -> SynthOptions {
    let mut draft = Draft {
        config: JobConfig::of(blank),
        seed: 0,
        replay: None,
        release: false,
        opcodes: None,
    };
    for def in OPTIONS.iter().filter(|d| d.sidecar.is_some()) {
        if let Some(v) = def.default_value() {
            let done = draft.set(def, v, Spelling::Cli);
            // Each default sets (src/synth/options/tests.rs): an error is a table's bug.
            debug_assert!(done.is_ok(), "{}: {:?}", def.name, done.err());
        }
    }
    draft.config.options
}

/// The burst options at the table's defaults (`SynthOptions::default().burst`; what a
/// sidecar's burst without a field holds for it).
pub fn burst_defaults() -> crate::synth::burst::BurstOptions {
    SynthOptions::default().burst
}

/// Error unless each field of `o` that an [`Kind::Int`], [`Kind::Float`] or [`Kind::Pair`]
/// option sets is in the option's range: the one check of the range, as [`Draft::set`]
/// makes it, for options that did not come through the table (a sidecar's, a library
/// caller's). The message names the flag and the Python keyword.
pub fn check_fields(o: &SynthOptions) -> Result<()> {
    check_fields_of(
        o,
        |_| true,
        |def| {
            format!(
                "{} (Python {})",
                def.spelled(Spelling::Cli),
                def.python_name()
            )
        },
    )
}

/// [`check_fields`] for the options `which` selects, each named as `name` spells it (a
/// sidecar's plan: `plan field burst.shake.step_px`).
pub fn check_fields_of(
    o: &SynthOptions,
    which: impl Fn(&OptionDef) -> bool,
    name: impl Fn(&OptionDef) -> String,
) -> Result<()> {
    for def in OPTIONS.iter().filter(|d| which(d)) {
        let fault = match def.kind {
            Kind::Int {
                lo,
                hi,
                field: Some(get),
                ..
            } => {
                let n = get(o);
                (!(lo..=hi).contains(&n)).then(|| format!("{n} is outside {lo}..={hi}"))
            }
            Kind::Float {
                range,
                field: Some(get),
            } => range.fault(get(o)),
            Kind::Pair {
                range,
                field: Some(get),
            } => range.pair_fault(get(o)),
            _ => None,
        };
        if let Some(m) = fault {
            return Err(Error::invalid(format!("{}: {m}", name(def))));
        }
    }
    Ok(())
}

/// The option named `name` (a flag name or a Python keyword or alias).
pub fn find(name: &str) -> Option<&'static OptionDef> {
    let name = name.strip_prefix("--").unwrap_or(name);
    OPTIONS
        .iter()
        .find(|d| d.name == name || d.python_name() == name || d.python_alias == Some(name))
}

/// An option's value, from the command line or from Python.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// Python's None: the option's unset state (no ISO for `iso`).
    Unset,
    /// A switch.
    Switch(bool),
    /// An integer (Python's may be outside the range: [`Draft::set`] checks it).
    Int(i128),
    /// A number.
    Float(f64),
    /// Text (a choice's name, or text the setter parses).
    Text(String),
    /// A path.
    Path(PathBuf),
    /// Numbers given as a sequence (Python).
    Numbers(Vec<f64>),
    /// ISOs given as a sequence (Python), each already in range.
    Isos(Vec<u32>),
}

/// Whose spelling the messages use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spelling {
    /// `--relight-formula`.
    Cli,
    /// `relight_formula`.
    Python,
}

/// An error of one option (`option`, as the caller spells it) or of the options together
/// (`option` None; the message names the options).
#[derive(Debug)]
pub struct OptionError {
    /// The option, spelled as its caller spells it.
    pub option: Option<String>,
    /// What is wrong.
    pub error: Error,
}

impl std::fmt::Display for OptionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (&self.option, self.error.root()) {
            (Some(o), Error::InvalidParam(m)) => write!(f, "{o}: {m}"),
            (Some(o), e) => write!(f, "{o}: {e}"),
            (None, e) => write!(f, "{e}"),
        }
    }
}

/// A [`JobConfig`] being made from options, and what the options decide together.
#[derive(Debug, Clone, Default)]
pub struct Draft {
    /// The configuration so far (its defaults are the options' defaults).
    pub config: JobConfig,
    /// The master seed (`--seed`: not part of the job).
    pub seed: u64,
    /// A sidecar to replay (`synth --replay`).
    pub replay: Option<PathBuf>,
    /// `--compat release` was asked for.
    release: bool,
    /// `--opcodes`, applied after the release preset.
    opcodes: Option<OpcodeMode>,
}

impl Draft {
    /// A draft with every option at its default, for `variants` variants per input.
    pub fn new(variants: u32) -> Draft {
        let mut d = Draft::default();
        d.config.variants = variants;
        d
    }

    /// Apply `value` to the option `def`; an error names the option in `spelling`. What
    /// the kind says of the value is checked here, the one check of it: an integer's range,
    /// a number's range, a choice's name (so a setter reads only names of its list).
    pub fn set(
        &mut self,
        def: &OptionDef,
        value: Value,
        spelling: Spelling,
    ) -> std::result::Result<(), OptionError> {
        let named = |error| OptionError {
            option: Some(def.spelled(spelling)),
            error,
        };
        match (def.kind, &value) {
            (Kind::Int { lo, hi, .. }, Value::Int(n))
                if *n < i128::from(lo) || *n > i128::from(hi) =>
            {
                return Err(named(Error::invalid(format!("{n} is outside {lo}..={hi}"))));
            }
            (Kind::Float { range, .. }, v) => {
                if let Some(x) = number(v) {
                    range.check(x).map_err(named)?;
                }
            }
            (Kind::Pair { range, .. }, v) => {
                if let Some(m) = numbers(v).and_then(|n| range.pair_fault(n.try_into().ok()?)) {
                    return Err(named(Error::invalid(m)));
                }
            }
            (Kind::Choice(choices), Value::Text(t)) if !choices.iter().any(|c| c.accepts(t)) => {
                let names: Vec<&str> = choices.iter().map(Name::shown).collect();
                let list = match names.split_last() {
                    Some((last, [])) => last.to_string(),
                    Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                    None => String::new(),
                };
                return Err(named(Error::invalid(format!("{t:?} (use {list})"))));
            }
            _ => {}
        }
        (def.set)(self, value).map_err(named)
    }

    /// The configuration: the release preset applied (it checks the options it fixes),
    /// then `--opcodes`, the rules between the burst options, the whole validated.
    pub fn finish(mut self, spelling: Spelling) -> std::result::Result<JobConfig, OptionError> {
        let named = |name: &str, error: Error| OptionError {
            option: Some(match spelling {
                Spelling::Cli => format!("--{name}"),
                Spelling::Python => name.replace('-', "_"),
            }),
            error,
        };
        if self.release {
            let options = std::mem::take(&mut self.config.options);
            self.config.options = options.release_compat().map_err(|e| match spelling {
                Spelling::Cli => OptionError {
                    option: Some("--compat release".into()),
                    error: e,
                },
                Spelling::Python => named("compat", e),
            })?;
        }
        if let Some(m) = self.opcodes {
            self.config.options.opcodes = m;
        }
        let whole = |error| OptionError {
            option: None,
            error,
        };
        let spell = |name: &str| find(name).map_or_else(|| name.into(), |d| d.spelled(spelling));
        crate::synth::burst::checks::check_rules(
            &self.config.options.burst,
            &burst_defaults(),
            &spell,
        )
        .map_err(whole)?;
        self.config.options.validate().map_err(whole)?;
        self.config
            .exr
            .validate()
            .map_err(|e| named("exr-zip-level", e))?;
        Ok(self.config)
    }
}

/// The number a [`Kind::Float`] option's value is, if it is one (text that is not a number
/// is the setter's error).
fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Int(n) => Some(*n as f64),
        Value::Text(s) => s.trim().parse().ok(),
        _ => None,
    }
}

/// The numbers of a [`Kind::Pair`] option's value, if it is numbers (text that is not is the
/// setter's error).
fn numbers(v: &Value) -> Option<Vec<f64>> {
    match v {
        Value::Numbers(n) => Some(n.clone()),
        Value::Text(s) => s.split(',').map(|p| p.trim().parse().ok()).collect(),
        _ => None,
    }
}

#[cfg(test)]
mod tests;
