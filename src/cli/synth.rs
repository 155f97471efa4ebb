//! `day2night synth` (in progress).
use super::CmdResult;

/// Arguments of `day2night synth`.
#[derive(Debug, clap::Args)]
pub struct SynthArgs {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

/// Run `day2night synth`.
pub fn run(args: SynthArgs) -> CmdResult {
    let _ = args;
    Err(super::usage("`synth` is not implemented yet"))
}
