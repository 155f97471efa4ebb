//! SIGINT/SIGTERM: stop cleanly, leave no temporary file, exit 128 + the signal (130 for
//! SIGINT, 143 for SIGTERM), within a second whatever stdout and stderr are (closed pipes,
//! full pipes, a terminal). See docs/concurrency.md.
//!
//! A background thread receives the signals (signal-hook's iterator: no code runs inside
//! the signal handler itself). For `synth` and `dataset` the first signal asks the run to
//! stop ([`day2night::output::request_stop`]): no new input or variant is started, the
//! variants in flight stop at their next output and remove their temporary files, and
//! [`super::main`] prints the message and exits. If the run has not exited [`GRACE`] after
//! the signal (a long stage still computing, or a print blocked on a full pipe), or on a
//! second signal, or on the first signal for any other command, this thread exits itself:
//! it removes every temporary file still being written
//! ([`day2night::output::remove_temp_files_and_close`], which lets an output set whose
//! renames have begun finish first, for at most [`day2night::output::SET_GRACE`]), then
//! prints the message from a helper thread without waiting more than [`PRINT_WAIT`] for
//! it, and exits. Nothing on this path depends on being able to print.

use std::time::Duration;

/// How long a graceful stop (`synth`, `dataset`) may take before the process exits anyway.
pub const GRACE: Duration = Duration::from_millis(400);

/// How long the exit waits for its message to be written (stderr may be a full pipe).
pub const PRINT_WAIT: Duration = Duration::from_millis(100);

/// The line printed when a run stops on a signal.
pub fn message(resumable: bool) -> &'static str {
    if resumable {
        "interrupted: rerun the same command to resume"
    } else {
        "interrupted"
    }
}

/// Print `day2night: <message>` once per process (the main thread's graceful end and the
/// signal thread's exit may both get there).
pub fn print_once(resumable: bool) {
    static SAID: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    if !SAID.swap(true, std::sync::atomic::Ordering::SeqCst) {
        eprintln!("day2night: {}", message(resumable));
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
            if let Some(sig) = signals.forever().next() {
                day2night::output::request_stop(sig);
                if graceful {
                    // The run stops by itself (main exits); past the grace, or on a
                    // second signal, exit from here.
                    let t0 = std::time::Instant::now();
                    while t0.elapsed() < GRACE && signals.pending().next().is_none() {
                        std::thread::sleep(Duration::from_millis(10));
                    }
                }
                exit_now(sig, resumable);
            }
        });
    // Could not start the thread: keep the default action rather than ignore signals.
    drop(spawned);
}

/// Remove the temporary files, say why (without waiting long for stderr) and exit with
/// 128 + the first signal.
#[cfg(unix)]
fn exit_now(sig: i32, resumable: bool) -> ! {
    day2night::output::remove_temp_files_and_close();
    let code = day2night::output::stop_requested().unwrap_or(sig);
    let (tx, rx) = std::sync::mpsc::channel();
    let printer = std::thread::Builder::new().spawn(move || {
        print_once(resumable);
        let _ = tx.send(());
    });
    if printer.is_ok() {
        let _ = rx.recv_timeout(PRINT_WAIT);
    }
    std::process::exit(i32::from(exit_code(code)));
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
