//! The format of a file from its extension and its first bytes: RGL tensor files, MERL
//! tables, ASTM E1392 (the rules are in the [module docs](super)), and the row count a
//! CSV file's start suggests.

use super::{astm, rgl};
use std::path::Path;

/// Whether the file is an RGL `.bsdf` tensor file: its content starts with the tensor
/// file's magic, or its extension is `.bsdf` (any case).
pub(super) fn is_binary(path: &Path, head: &[u8]) -> bool {
    rgl::tensor::is_tensor_file(head)
        || path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("bsdf"))
}

/// Whether the extension says MERL (`.binary`, any case).
pub(super) fn merl_by_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("binary"))
}

/// Whether the extension says ASTM E1392 (`.astm`, any case).
pub(super) fn astm_by_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("astm"))
}

/// Whether the start of a file decides it is CSV by [`is_astm`]'s content rule: its first
/// non-blank line (complete within `head`) does not open with an ASTM `KEY` token
/// followed by more text.
pub(super) fn surely_csv(head: &[u8]) -> bool {
    let head = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    for line in head.split(|&b| b == b'\n' || b == b'\r') {
        let Ok(text) = std::str::from_utf8(line) else {
            return false;
        };
        let t = text.trim();
        if t.is_empty() {
            continue;
        }
        let complete = line.len() < head.len();
        let key = t.split_whitespace().next().unwrap_or("");
        return complete && !(astm::is_key(key) && t.len() > key.len());
    }
    false
}

/// Rows of a file of `len` bytes, estimated from the line ends in its first bytes `head`
/// (5 % over, so that the columns rarely grow).
pub(super) fn estimate_rows(head: &[u8], len: u64) -> usize {
    let lines = head.iter().filter(|&&b| b == b'\n').count().max(1);
    let per_line = head.len() as f64 / lines as f64;
    ((len as f64 / per_line.max(1.0)) * 1.05) as usize + 16
}

/// Whether the file is ASTM E1392 (by extension or content).
pub(crate) fn is_astm(path: &Path, text: &str) -> bool {
    if path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("astm"))
    {
        return true;
    }
    let first = text.lines().map(str::trim).find(|l| !l.is_empty());
    let Some(first) = first else { return false };
    let key = first.split_whitespace().next().unwrap_or("");
    astm::is_key(key)
        && first.len() > key.len()
        && text
            .lines()
            .any(|l| l.split_whitespace().next() == Some("VARS"))
}
