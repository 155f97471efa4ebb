//! The `day2night` command-line program: parse, run, map errors to exit codes
//! (1 = bad input or failed work, 2 = bad usage).
#![forbid(unsafe_code)]

// Printing never panics or stops the program. std's `print!`/`println!`/`eprint!`/
// `eprintln!` panic when the write fails, and with SIGPIPE ignored (Rust's runtime does)
// a closed pipe on stdout or stderr makes every write fail with EPIPE: a reader that
// died would turn any message into a panic (before, the signal thread died in its
// `eprintln!` and SIGTERM was ignored). These definitions shadow std's in every module of
// the binary (`mod cli` comes after them); a failed write is dropped, like a message
// nobody reads. (docs/concurrency.md, "Interrupts")
macro_rules! print {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($t)*);
    }};
}
macro_rules! println {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}
#[allow(unused_macros)]
macro_rules! eprint {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stderr(), $($t)*);
    }};
}
macro_rules! eprintln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    cli::main()
}
