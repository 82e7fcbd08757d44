//! Helpers shared by the CLI test files.

use assert_cmd::Command;

/// The goniofit binary.
pub fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

/// Run goniofit with `args`, expect exit 0, and return its standard output as text.
pub fn success_stdout<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> String {
    let out = goniofit().args(args).output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Run goniofit with `args`, expect exit 0, and parse its standard output as JSON.
#[allow(dead_code)]
pub fn fit_json(args: &[&str]) -> serde_json::Value {
    serde_json::from_str(&success_stdout(args)).unwrap()
}

/// A file of the bundled `data/` folder.
#[allow(dead_code)]
pub fn data(p: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(p)
}
