//! Helpers shared by the integration tests.

use std::process::Command;

/// Run the organtex binary: whether it succeeded, its stdout and stderr.
pub fn organtex(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_organtex"))
        .args(args)
        .output()
        .expect("run organtex");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
