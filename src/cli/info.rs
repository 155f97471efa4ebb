//! `day2night info` (in progress).
use super::CmdResult;

/// Arguments of `day2night info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

/// Run `day2night info`.
pub fn run(args: InfoArgs) -> CmdResult {
    let _ = args;
    Err(super::usage("`info` is not implemented yet"))
}
