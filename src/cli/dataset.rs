//! `day2night dataset` (in progress).
use super::CmdResult;

/// Arguments of `day2night dataset`.
#[derive(Debug, clap::Args)]
pub struct DatasetArgs {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

/// Run `day2night dataset`.
pub fn run(args: DatasetArgs) -> CmdResult {
    let _ = args;
    Err(super::usage("`dataset` is not implemented yet"))
}
