//! Helpers shared by the CLI test files.
// Each test binary uses some of these helpers.
#![allow(dead_code)]

use assert_cmd::Command;

/// The README's fit of the garnet paint's 550 nm channel (append the file).
pub(crate) const GARNET_550: [&str; 7] = [
    "fit",
    "--model",
    "kbs+lambert",
    "--channel",
    "550nm",
    "--residual",
    "log",
];

/// The default fit of a real paint or CUReT file: kbs+lambert on the BRDF, log residuals
/// (append the selection and the file).
pub(crate) const PAINT_BRDF_LOG: [&str; 7] = [
    "fit",
    "--model",
    "kbs+lambert",
    "--quantity",
    "brdf",
    "--residual",
    "log",
];

/// The goniofit binary.
pub(crate) fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

/// Run goniofit with `args`, expect exit 0, and return its standard output as text.
pub(crate) fn success_stdout<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> String {
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
pub(crate) fn fit_json(args: &[&str]) -> serde_json::Value {
    serde_json::from_str(&success_stdout(args)).unwrap()
}

/// A file of the bundled `data/` folder.
pub(crate) fn data(p: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(p)
}

/// Run goniofit with `args` and `--json`, whatever its exit code: (exit code, parsed
/// report); panics with its standard error when the output is not one JSON document.
pub(crate) fn run_json<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> (Option<i32>, serde_json::Value) {
    let out = goniofit().args(args).arg("--json").output().unwrap();
    let v = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out.stderr)));
    (out.status.code(), v)
}

/// The rows of a committed reference table `tests/ref/NAME` (CSV after `#` comment lines),
/// each as column name → text.
pub(crate) fn reference_rows(name: &str) -> Vec<std::collections::HashMap<String, String>> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/ref")
        .join(name);
    let text = std::fs::read_to_string(path).unwrap();
    let body: String = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    let mut rdr = csv::Reader::from_reader(body.as_bytes());
    let headers = rdr.headers().unwrap().clone();
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            headers
                .iter()
                .zip(r.iter())
                .map(|(h, v)| (h.to_string(), v.to_string()))
                .collect()
        })
        .collect()
}

/// Standard error without the progress lines a run longer than 2 s writes when standard
/// error is not a terminal ("goniofit: 7 s: fitting …").
pub(crate) fn without_progress(err: &str) -> String {
    err.lines()
        .filter(|l| {
            let rest = l.strip_prefix("goniofit: ").unwrap_or("");
            let secs = rest.split(" s: ").next().unwrap_or("");
            !(rest.contains(" s: ") && !secs.is_empty() && secs.bytes().all(|b| b.is_ascii_digit()))
        })
        .map(|l| format!("{l}\n"))
        .collect()
}

/// The width and height a PNG file's header states (its signature and IHDR checked).
pub(crate) fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(bytes.len() > 33, "PNG too short");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    (w, h)
}

/// An SVG document with text whose embedded images carry a MIME type.
pub(crate) fn assert_svg(text: &str) {
    assert!(text.starts_with("<svg"), "starts with <svg");
    assert!(text.trim_end().ends_with("</svg>"), "ends with </svg>");
    assert!(text.contains("<text"), "has text");
    assert!(
        !text.contains("data:png;"),
        "embedded images carry a MIME type"
    );
}
