//! CSV tables written with [`super::write_atomic`], fields quoted so that the readers
//! return them as written.

use super::write_atomic;
use crate::error::Result;
use std::io::Write;
use std::path::Path;

/// Write a CSV table (headers + rows) with [`write_atomic`] (`-` is standard output).
/// Fields are quoted where reading them back needs it (see [`csv_field`]), so the readers
/// here return exactly the fields written.
pub(crate) fn write_csv(path: &Path, headers: &[String], rows: &[Vec<String>]) -> Result<()> {
    write_atomic(path, |w: &mut dyn Write| -> std::io::Result<()> {
        write_record(w, headers)?;
        for r in rows {
            write_record(w, r)?;
        }
        Ok(())
    })
}

/// Write one CSV record, comma-separated, `\n`-terminated.
pub(crate) fn write_record(w: &mut dyn Write, fields: &[String]) -> std::io::Result<()> {
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
pub(crate) fn csv_field(f: &str, first: bool) -> std::borrow::Cow<'_, str> {
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
