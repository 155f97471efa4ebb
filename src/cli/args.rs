//! Argument parsing and error mapping shared by several subcommands (one home, so that no
//! subcommand borrows another's).

use super::{usage, Failure};
use day2night::encode::exr::ExrOptions;

/// `--isp` (render, real-pairs): the ISP of a rendered target. Its values have no doc
/// comments: they would be clap's help of each value, which turns `--help` into the long
/// layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum IspArg {
    // day2night's ISP (docs/isp.md).
    #[value(name = "day2night")]
    Day2night,
    // The authors' release's target render reproduced (docs/isp.md).
    Release,
}

/// The value parser of an option whose values are an enum's names: its `FromStr` (names,
/// aliases, case) and its error message; clap shows the default from its `Display`.
pub fn choice<T: std::str::FromStr>(s: &str) -> Result<T, String>
where
    T::Err: std::fmt::Display,
{
    s.parse().map_err(|e: T::Err| e.to_string())
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
