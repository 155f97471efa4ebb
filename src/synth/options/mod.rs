//! The synthesis options, each declared once ([`OPTIONS`], in `table.rs`): its name, kind,
//! default, range or choices, help text, how Python spells and reaches it, the sidecar field
//! it lands in, and how its value sets a [`JobConfig`]. The command line's `synth` and
//! `dataset` flags (src/cli/synth.rs), Python's keyword arguments (python/src/synth_options.rs)
//! and the option lists of docs/cli.md and docs/python.md are made from this table, and a
//! test (tests/it/cli_options.rs, python/tests/test_options_table.py) fails when one of them
//! differs from it. The model is ripgrep's flag definitions: one definition per flag, read
//! by the parser and the docs.
//! docs/architecture.md ("Adding a synthesis option") shows what adding one touches.
//!
//! Values arrive as [`Value`]s (the parser of each front end checks the type and, for
//! integers, the range) and are applied to a [`Draft`] in any order; [`Draft::finish`]
//! applies what depends on several options (the release preset, the burst's checks) and
//! checks the whole.

mod table;

pub use table::{CONSTANTS, OPTIONS};

use super::burst::checks::{BurstRequest, Names};
use super::config::JobConfig;
use crate::error::{Error, Result};
use crate::isp::opcodes::OpcodeMode;
use std::path::PathBuf;

/// What an option's value is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A switch: present or not (Python: a bool).
    Switch,
    /// An integer within `lo..=hi`, parsed on the command line as [`Width`] (its own
    /// message for a value that does not fit). With `late`, Python checks only the type:
    /// the range is part of a check of several options in [`Draft::finish`].
    Int {
        /// Lowest value.
        lo: u64,
        /// Highest value.
        hi: u64,
        /// The command line's integer type.
        width: Width,
        /// The range is checked in [`Draft::finish`], not by the front end.
        late: bool,
    },
    /// A number (checked by the setter or [`Draft::finish`]).
    Float,
    /// Text the setter parses (a list, a neutral, a mode with a parameter...).
    Text,
    /// A comma-separated list of ISOs, or `none` (Python: also an int or a sequence of ints).
    Isos,
    /// `n` comma-separated numbers (Python: also a sequence of `n` numbers).
    Numbers(usize),
    /// A file path (some options also take a name, e.g. `paper`).
    Path,
    /// One of a few names.
    Choice(&'static [Choice]),
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

/// One value of a [`Kind::Choice`] option.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Choice {
    /// The value as typed.
    pub name: &'static str,
    /// What it means (one line).
    pub help: &'static str,
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
    /// The default as typed on the command line (shown as `[default: ...]`); None: the
    /// option is unset unless given (its help says what that means).
    pub default: Option<&'static str>,
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

    /// The help text with what the kind says of the value: an integer's range when it is
    /// narrower than its type (`[range: 1..=64]`). The range is written once, in the kind:
    /// [`Draft::set`] checks it and the help shows it.
    pub fn help_text(&self) -> String {
        match self.kind {
            Kind::Int { lo, hi, width, .. } if (lo, hi) != (0, width.max()) => {
                format!("{} [range: {lo}..={hi}]", self.help)
            }
            _ => self.help.to_string(),
        }
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
    /// An integer (Python's may be outside the range when it is checked late).
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
    /// The burst options, checked together.
    burst: BurstRequest,
}

impl Draft {
    /// A draft with every option at its default, for `variants` variants per input.
    pub fn new(variants: u32) -> Draft {
        let mut d = Draft::default();
        d.config.variants = variants;
        d
    }

    /// Apply `value` to the option `def`; an error names the option in `spelling`. An
    /// integer is checked against its kind's range here (the one check of it; a `late`
    /// range is part of a check of several options in [`Draft::finish`]).
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
        if let (
            Kind::Int {
                lo,
                hi,
                late: false,
                ..
            },
            Value::Int(n),
        ) = (def.kind, &value)
        {
            if *n < i128::from(lo) || *n > i128::from(hi) {
                return Err(named(Error::invalid(format!("{n} is outside {lo}..={hi}"))));
            }
        }
        (def.set)(self, value).map_err(named)
    }

    /// The configuration: the release preset applied (it checks the options it fixes),
    /// then `--opcodes`, the burst options checked together, the whole validated.
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
        let names = match spelling {
            Spelling::Cli => Names::CLI,
            Spelling::Python => Names::PYTHON,
        };
        let whole = |error| OptionError {
            option: None,
            error,
        };
        self.config.options.burst = self.burst.resolve(&names).map_err(whole)?;
        self.config.options.validate().map_err(whole)?;
        self.config
            .exr
            .validate()
            .map_err(|e| named("exr-zip-level", e))?;
        Ok(self.config)
    }
}

#[cfg(test)]
mod tests;
