//! Helpers shared by the CLI test files.

use assert_cmd::Command;

/// The goniofit binary.
pub fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

/// Run goniofit with `args`, expect exit 0, and parse its standard output as JSON.
pub fn fit_json(args: &[&str]) -> serde_json::Value {
    let out = goniofit().args(args).output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}
