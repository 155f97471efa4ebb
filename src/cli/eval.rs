//! `day2night eval` (in progress).
use super::CmdResult;

/// Arguments of `day2night eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

/// Run `day2night eval`.
pub fn run(args: EvalArgs) -> CmdResult {
    let _ = args;
    Err(super::usage("`eval` is not implemented yet"))
}
