//! SIGINT/SIGTERM: stop cleanly, leave no temporary file, exit 128 + the signal (130 for
//! SIGINT, 143 for SIGTERM). See docs/concurrency.md.
//!
//! A background thread receives the signals (signal-hook's iterator: no code runs inside
//! the signal handler itself). For `synth` and `dataset` the first signal asks the run to
//! stop ([`day2night::output::request_stop`]): no new input or variant is started, the
//! variants in flight stop at their next output and remove their temporary files, and
//! [`super::main`] prints the message and exits. Any other command, or a second signal,
//! exits at once after removing every temporary file still being written
//! ([`day2night::output::remove_temp_files_and_close`]).

/// The line printed when a run stops on a signal.
pub fn message(resumable: bool) -> &'static str {
    if resumable {
        "interrupted: rerun the same command to resume"
    } else {
        "interrupted"
    }
}

/// The exit code after `signal`: 128 + signal (130 for SIGINT, 143 for SIGTERM).
pub fn exit_code(signal: i32) -> u8 {
    u8::try_from(128 + signal.clamp(1, 127)).unwrap_or(130)
}

/// Start handling SIGINT and SIGTERM: gracefully (first signal stops new work) when
/// `graceful`, else by exiting at once. `resumable` selects the message.
#[cfg(unix)]
pub fn install(graceful: bool, resumable: bool) {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use signal_hook::iterator::Signals;
    let mut signals = match Signals::new([SIGINT, SIGTERM]) {
        Ok(s) => s,
        // Without a handler the default action (terminate) applies, as before.
        Err(_) => return,
    };
    let spawned = std::thread::Builder::new()
        .name("day2night-signals".into())
        .spawn(move || {
            for sig in signals.forever() {
                let first = day2night::output::request_stop(sig);
                if graceful && first {
                    continue;
                }
                day2night::output::remove_temp_files_and_close();
                eprintln!("day2night: {}", message(resumable));
                std::process::exit(i32::from(exit_code(sig)));
            }
        });
    // Could not start the thread: keep the default action rather than ignore signals.
    drop(spawned);
}

/// Signals are not handled on this platform (the default action applies).
#[cfg(not(unix))]
pub fn install(_graceful: bool, _resumable: bool) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes() {
        assert_eq!(exit_code(2), 130);
        assert_eq!(exit_code(15), 143);
        assert!(message(true).contains("rerun the same command to resume"));
    }
}
