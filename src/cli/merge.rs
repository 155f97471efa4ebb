//! `day2night merge` (in progress).
use super::CmdResult;

/// Arguments of `day2night merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

/// Run `day2night merge`.
pub fn run(args: MergeArgs) -> CmdResult {
    let _ = args;
    Err(super::usage("`merge` is not implemented yet"))
}
