//! `day2night convert` (in progress).
use super::CmdResult;

/// Arguments of `day2night convert`.
#[derive(Debug, clap::Args)]
pub struct ConvertArgs {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

/// Run `day2night convert`.
pub fn run(args: ConvertArgs) -> CmdResult {
    let _ = args;
    Err(super::usage("`convert` is not implemented yet"))
}
