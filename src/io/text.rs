//! Text in and out: file names and labels as printed in messages and reports, and CSV
//! tables written with [`super::write_atomic`].

use super::write_atomic;
use crate::error::Result;
use std::io::Write;
use std::path::Path;

/// Write a CSV table (headers + rows) with [`write_atomic`] (`-` is standard output).
/// Fields are quoted where reading them back needs it (see [`csv_field`]), so the readers
/// here return exactly the fields written.
pub fn write_csv(path: &Path, headers: &[String], rows: &[Vec<String>]) -> Result<()> {
    write_atomic(path, |w: &mut dyn Write| -> std::io::Result<()> {
        write_record(w, headers)?;
        for r in rows {
            write_record(w, r)?;
        }
        Ok(())
    })
}

/// Write one CSV record, comma-separated, `\n`-terminated.
pub fn write_record(w: &mut dyn Write, fields: &[String]) -> std::io::Result<()> {
    for (k, f) in fields.iter().enumerate() {
        if k > 0 {
            w.write_all(b",")?;
        }
        w.write_all(csv_field(f, k == 0).as_bytes())?;
    }
    w.write_all(b"\n")
}

/// A field as written to CSV: quoted (`"` doubled) when it holds a comma, quote or line
/// break, has surrounding blanks (the reader trims unquoted fields), or, as the first field
/// of a record, starts with `#` (the reader would take the line for a comment).
pub fn csv_field(f: &str, first: bool) -> std::borrow::Cow<'_, str> {
    let blank = |c: char| c == ' ' || c == '\t';
    let needs = f.contains([',', '"', '\n', '\r'])
        || f.starts_with(blank)
        || f.ends_with(blank)
        || (first && f.starts_with('#'));
    if needs {
        format!("\"{}\"", f.replace('"', "\"\"")).into()
    } else {
        f.into()
    }
}

/// `s` as printed in messages and reports: line breaks, tabs and other control characters,
/// and the bidirectional-text controls (U+061C, U+200E, U+200F, U+202A–U+202E,
/// U+2066–U+2069) are written as escapes (`\n`, `\u{202e}`), everything else as is; so a
/// file or group name cannot fake a line of a report or reverse the text after it.
pub fn shown_text(s: &str) -> std::borrow::Cow<'_, str> {
    let hostile = |c: char| {
        c.is_control()
            || matches!(c, '\u{061c}' | '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
    };
    if !s.chars().any(hostile) {
        return s.into();
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if hostile(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out.into()
}

/// A path as printed in messages and reports: [`shown_text`] of its text (invalid UTF-8
/// shown as U+FFFD).
pub fn shown(path: &Path) -> String {
    shown_text(&path.to_string_lossy()).into_owned()
}
