//! The `day2night` command-line program: parse, run, map errors to exit codes
//! (1 = bad input or failed work, 2 = bad usage).
#![forbid(unsafe_code)]

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    cli::main()
}
