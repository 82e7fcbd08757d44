//! What a CSV file states it holds: a radiance or a BRDF.
//!
//! A file states a BRDF by a comment line before its header, `# quantity: brdf` (or
//! `# quantity: radiance`; key and value case-insensitive, blanks free), or by naming its
//! value column `brdf`, as an ASTM file does with `MEAS_NAME BRDF`. The comment wins over
//! the column name; `--quantity` wins over both.

use crate::error::{Error, Result};
use crate::geometry::Quantity;
use std::path::Path;

/// The quantity stated by a `# quantity: …` comment among the comment and blank lines
/// that open `head` (the first bytes of a CSV file, a byte-order mark allowed); None when
/// no such comment precedes the first other line. A value other than `brdf` or `radiance`
/// is an [`Error::Input`] naming the line. Lines cut off at the end of `head` are ignored.
pub(crate) fn from_comments(path: &Path, head: &[u8]) -> Result<Option<Quantity>> {
    let head = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    let mut stated = None;
    let mut lines = head.split(|&b| b == b'\n').peekable();
    let mut number = 0;
    while let Some(line) = lines.next() {
        number += 1;
        if lines.peek().is_none() {
            break; // the last piece may be cut off
        }
        let Ok(text) = std::str::from_utf8(line) else {
            break;
        };
        let t = text.trim();
        if t.is_empty() {
            continue;
        }
        let Some(comment) = t.strip_prefix('#') else {
            break;
        };
        let Some((key, value)) = comment.split_once(':') else {
            continue;
        };
        if !key.trim().eq_ignore_ascii_case("quantity") {
            continue;
        }
        stated = Some(match value.trim().to_ascii_lowercase().as_str() {
            "brdf" => Quantity::Brdf,
            "radiance" => Quantity::Radiance,
            other => {
                return Err(Error::input(
                    path,
                    number,
                    "(comment)",
                    format!("'# quantity: {other}' states neither brdf nor radiance"),
                ))
            }
        });
    }
    Ok(stated)
}

/// The quantity a value column's header name states: `brdf` (any case) is a BRDF.
pub(crate) fn from_column_name(header: &str) -> Option<Quantity> {
    header
        .trim()
        .eq_ignore_ascii_case("brdf")
        .then_some(Quantity::Brdf)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Option<Quantity>> {
        from_comments(Path::new("t.csv"), text.as_bytes())
    }

    #[test]
    fn a_quantity_comment_before_the_header_states_the_quantity() {
        let q = read("# CUReT\n\n#  Quantity :  BRDF \r\ntheta_i,theta_r,phi_r,L\n1,2,3,4\n");
        assert_eq!(q.unwrap(), Some(Quantity::Brdf));
        let q = read("\u{feff}# quantity: radiance\ntheta_i,theta_r,phi_r,L\n");
        assert_eq!(q.unwrap(), Some(Quantity::Radiance));
        assert_eq!(read("# a note: not this\ntheta_i\n").unwrap(), None);
        // After the header a comment is not a statement about the file.
        assert_eq!(read("theta_i,L\n# quantity: brdf\n1,2\n").unwrap(), None);
        // A line cut off at the end of the head is not read.
        assert_eq!(read("# quantity: brdf").unwrap(), None);
    }

    #[test]
    fn an_unknown_quantity_is_refused_with_its_line() {
        let e = read("# x\n# quantity: reflectance\nL\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains(":2") && e.contains("reflectance"), "{e}");
    }

    #[test]
    fn a_value_column_named_brdf_states_a_brdf() {
        assert_eq!(from_column_name(" BRDF "), Some(Quantity::Brdf));
        assert_eq!(from_column_name("L"), None);
    }
}
