//! `day2night calibrate ...` (in progress).
use super::CmdResult;

/// Calibration subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum CalibrateCommand {
    /// Night illuminant dictionary from gray-card shots (not implemented yet).
    Illuminants {
        /// Arguments.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        rest: Vec<String>,
    },
}

/// Run a calibration subcommand.
pub fn run(cmd: CalibrateCommand) -> CmdResult {
    let _ = cmd;
    Err(super::usage("`calibrate` is not implemented yet"))
}
