//! Argument parsing and error mapping shared by several subcommands (one home, so that no
//! subcommand borrows another's).

use super::{usage, Failure};
use clap::builder::{PossibleValue, TypedValueParser};
use clap::{Arg, Command};
use day2night::choice::Choice;
use day2night::encode::exr::ExrOptions;
use std::ffi::OsStr;
use std::marker::PhantomData;
use std::str::FromStr;

/// A choice as typed on the command line: its value and its spelling. `--isp release`
/// compares spellings, as Python's keyword arguments are compared (`--demosaic malvar` names
/// a demosaicer, not the default: docs/isp.md).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Typed<T> {
    /// The value.
    pub value: T,
    /// The text given (or the default's name).
    pub text: String,
}

impl<T: Choice + Default> Default for Typed<T> {
    fn default() -> Self {
        let value = T::default();
        Typed {
            value,
            text: T::name_of(value).to_string(),
        }
    }
}

impl<T> std::fmt::Display for Typed<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// The value parser of an option whose values are a [`Choice`]'s: `--help` lists its names
/// (`[possible values: ...]`; aliases accepted, not listed; no help per value, which would
/// turn `--help` into the long layout), and a value is parsed by its `FromStr` (its aliases,
/// case rule and error message, which names the values). clap shows the default from
/// [`Typed`]'s `Display`.
pub struct ChoiceParser<T>(PhantomData<fn() -> T>);

impl<T> Clone for ChoiceParser<T> {
    fn clone(&self) -> Self {
        ChoiceParser(PhantomData)
    }
}

/// The [`ChoiceParser`] of `T`.
pub fn choice<T: Choice>() -> ChoiceParser<T> {
    ChoiceParser(PhantomData)
}

impl<T> TypedValueParser for ChoiceParser<T>
where
    T: Choice + FromStr<Err = day2night::Error> + Send + Sync,
{
    type Value = Typed<T>;

    fn parse_ref(
        &self,
        cmd: &Command,
        arg: Option<&Arg>,
        value: &OsStr,
    ) -> Result<Typed<T>, clap::Error> {
        // clap's own message for a function parser: "invalid value 'x' for '--opt <V>': ..."
        let parse = |s: &str| -> Result<Typed<T>, String> {
            s.parse::<T>()
                .map(|value| Typed {
                    value,
                    text: s.to_string(),
                })
                .map_err(|e| match e {
                    // the message alone: clap says it is an invalid value
                    day2night::Error::InvalidParam(m) => m,
                    e => e.to_string(),
                })
        };
        parse.parse_ref(cmd, arg, value)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        let names = T::NAMES
            .iter()
            .map(|n| PossibleValue::new(n.name).aliases(n.aliases.iter().copied()));
        Some(Box::new(names))
    }
}

/// `--max-pixels N` (global): a pixel count with an optional K/M/G suffix.
pub fn parse_max_pixels(s: &str) -> Result<u64, String> {
    day2night::limits::Limits::parse_pixels(s).map_err(|e| e.to_string())
}

/// `--neutral R,G,B` (render): three positive finite numbers.
pub fn parse_neutral(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--neutral {s:?}: expected three numbers R,G,B"))?;
    match v.as_slice() {
        [r, g, b] if [r, g, b].iter().all(|x| x.is_finite() && **x > 0.0) => Ok([*r, *g, *b]),
        _ => Err(format!(
            "--neutral {s:?}: expected three positive numbers R,G,B"
        )),
    }
}

/// A library error as a failure with exit code 1 (its Display already names the file and
/// the whole cause chain).
pub fn lib(e: day2night::Error) -> Failure {
    Failure {
        code: 1,
        error: anyhow::Error::msg(e.to_string()),
    }
}

/// `--exr-zip-level`, checked as the EXR writer checks it.
pub fn parse_zip_level(level: u8) -> Result<u8, Failure> {
    ExrOptions {
        zip_level: level,
        ..ExrOptions::default()
    }
    .validate()
    .map(|_| level)
    .map_err(|e| usage(format!("--exr-zip-level: {}", e)))
}
