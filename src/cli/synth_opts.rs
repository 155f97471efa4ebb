//! The synthesis and output flags of `synth` and `dataset`, made from the library's option
//! table ([`day2night::synth::options::OPTIONS`]): one clap argument per entry, with its
//! name, placeholder, parser, choices, default and help. This file knows clap, the table
//! knows the options.

use super::{usage, Failure};
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::error::ErrorKind;
use clap::{value_parser, Arg, ArgAction, ArgMatches, Command};
use day2night::synth::config::JobConfig;
use day2night::synth::job::SynthJob;
use day2night::synth::options::{Draft, Kind, Name, OptionDef, Spelling, Value, Width, OPTIONS};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

/// The synthesis and output flags given (or defaulted), in table order: the same flags,
/// values and defaults in `synth` and `dataset`.
#[derive(Debug, Clone)]
pub struct SynthOpts {
    values: Vec<(&'static OptionDef, Value)>,
}

/// The clap argument of one option.
fn arg(d: &'static OptionDef) -> Arg {
    let a = Arg::new(d.name).long(d.name).help(d.help_text());
    if matches!(d.kind, Kind::Switch) {
        return a.action(ArgAction::SetTrue);
    }
    let a = a.action(ArgAction::Set).value_name(d.value_name);
    let a = match d.kind {
        Kind::Int { width, .. } => match width {
            Width::U8 => a.value_parser(value_parser!(u8)),
            Width::U32 => a.value_parser(value_parser!(u32)),
            Width::U64 => a.value_parser(value_parser!(u64)),
        },
        Kind::Float { .. } => a.value_parser(value_parser!(f64)),
        Kind::Path => a.value_parser(value_parser!(PathBuf)),
        Kind::Choice(choices) => a.value_parser(ChoiceParser::new(choices)),
        Kind::Switch | Kind::Text | Kind::Isos | Kind::Numbers(_) | Kind::Pair { .. } => {
            a.value_parser(value_parser!(String))
        }
    };
    match d.default_text() {
        Some(v) => a.default_value(v),
        None => a,
    }
}

/// The values of a [`Kind::Choice`] option: clap's list of its names (with their help and
/// aliases, shown in `--help` and in the error for another value), and a name that takes a
/// parameter (`truncated:K`) followed by one, which the option's setter parses.
#[derive(Clone)]
struct ChoiceParser {
    choices: &'static [Name],
    names: PossibleValuesParser,
}

impl ChoiceParser {
    fn new(choices: &'static [Name]) -> ChoiceParser {
        let names = choices.iter().map(|c| {
            PossibleValue::new(c.shown())
                .help(c.help)
                .aliases(c.aliases.iter().copied())
        });
        ChoiceParser {
            choices,
            names: PossibleValuesParser::new(names),
        }
    }
}

impl TypedValueParser for ChoiceParser {
    type Value = String;

    fn parse_ref(
        &self,
        cmd: &Command,
        arg: Option<&Arg>,
        value: &OsStr,
    ) -> Result<String, clap::Error> {
        match value.to_str() {
            Some(t)
                if self
                    .choices
                    .iter()
                    .any(|c| c.param.is_some() && c.accepts(t)) =>
            {
                Ok(t.to_string())
            }
            _ => self.names.parse_ref(cmd, arg, value),
        }
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        self.names.possible_values()
    }
}

/// One option's value in `m`, if given or defaulted.
fn value_of(m: &ArgMatches, d: &OptionDef) -> Result<Option<Value>, clap::Error> {
    let bad = |e: clap::parser::MatchesError| clap::Error::raw(ErrorKind::ValueValidation, e);
    Ok(match d.kind {
        Kind::Switch => m
            .try_get_one::<bool>(d.name)
            .map_err(bad)?
            .map(|b| Value::Switch(*b)),
        Kind::Int { width, .. } => match width {
            Width::U8 => m
                .try_get_one::<u8>(d.name)
                .map_err(bad)?
                .map(|n| i128::from(*n)),
            Width::U32 => m
                .try_get_one::<u32>(d.name)
                .map_err(bad)?
                .map(|n| i128::from(*n)),
            Width::U64 => m
                .try_get_one::<u64>(d.name)
                .map_err(bad)?
                .map(|n| i128::from(*n)),
        }
        .map(Value::Int),
        Kind::Float { .. } => m
            .try_get_one::<f64>(d.name)
            .map_err(bad)?
            .map(|x| Value::Float(*x)),
        Kind::Path => m
            .try_get_one::<PathBuf>(d.name)
            .map_err(bad)?
            .map(|p| Value::Path(p.clone())),
        Kind::Choice(_) | Kind::Text | Kind::Isos | Kind::Numbers(_) | Kind::Pair { .. } => m
            .try_get_one::<String>(d.name)
            .map_err(bad)?
            .map(|s| Value::Text(s.clone())),
    })
}

impl clap::FromArgMatches for SynthOpts {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut values = Vec::new();
        for d in OPTIONS {
            if let Some(v) = value_of(m, d)? {
                values.push((d, v));
            }
        }
        Ok(SynthOpts { values })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for SynthOpts {
    fn augment_args(cmd: Command) -> Command {
        OPTIONS.iter().fold(cmd, |cmd, d| cmd.arg(arg(d)))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl SynthOpts {
    /// The value of the option `name`, if given or defaulted.
    fn get(&self, name: &str) -> Option<&Value> {
        self.values
            .iter()
            .find(|(d, _)| d.name == name)
            .map(|(_, v)| v)
    }

    /// `--seed`.
    pub fn seed(&self) -> u64 {
        match self.get("seed") {
            Some(Value::Int(n)) => u64::try_from(*n).unwrap_or_default(),
            _ => 0,
        }
    }

    /// `--replay`.
    pub fn replay(&self) -> Option<&Path> {
        match self.get("replay") {
            Some(Value::Path(p)) => Some(p),
            _ => None,
        }
    }

    /// The library's [`JobConfig`] these flags spell (nothing loaded yet).
    pub fn config(&self, variants: u32) -> Result<JobConfig, Failure> {
        let mut draft = Draft::new(variants);
        for (d, v) in &self.values {
            draft.set(d, v.clone(), Spelling::Cli).map_err(usage)?;
        }
        draft.finish(Spelling::Cli).map_err(usage)
    }

    /// The job these flags describe, calibration files loaded.
    pub fn job(&self, variants: u32) -> Result<SynthJob, Failure> {
        Ok(self.config(variants)?.build()?)
    }
}
