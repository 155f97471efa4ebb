//! `day2night render` (in progress).
use super::CmdResult;

/// Arguments of `day2night render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

/// Run `day2night render`.
pub fn run(args: RenderArgs) -> CmdResult {
    let _ = args;
    Err(super::usage("`render` is not implemented yet"))
}
