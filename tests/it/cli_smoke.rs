//! The binary starts, prints help, and rejects bad usage with exit code 2.
use crate::common;

#[test]
fn help_and_usage_errors() {
    let out = common::bin().arg("--help").output().unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("synth"));
    let out = common::bin().arg("no-such-command").output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}
