//! A plain CSV table read at the speed of its bytes: every record on one line, no quoted
//! field, `\n` or `\r\n` line ends, UTF-8. Lines are split at commas in place and the
//! numbers parsed from the line's text; no field is allocated (a group label is, as the
//! dataset keeps it).
//!
//! Any text this reader does not handle as [`super::Records`] would (a quote anywhere in a
//! record, a lone `\r`, bytes that are not UTF-8, a line of more than [`MAX_FIELDS`]
//! fields or [`MAX_LINE_BYTES`] bytes) and any error in the table makes it give up: the general reader then reads the
//! file again from its start, so that every dataset and every message is the general
//! reader's. What it skips as [`super::Records`] does: blank lines, lines of empty fields,
//! and comments (a line whose first character other than a blank is `#`).

use super::{joined, Table, MAX_FIELDS};
use crate::io::{Dataset, ReadOptions};
use std::io::{BufRead, Read};
use std::path::Path;

/// The dataset of a plain table (see the module docs) read from `reader` (a UTF-8
/// byte-order mark at its start is skipped), or None when the text is not plain or holds
/// an error. `keep_rows` and `rows_hint` as for [`super::parse_reader`].
pub(crate) fn parse_plain(
    path: &Path,
    reader: impl BufRead,
    opts: &ReadOptions,
    keep_rows: bool,
    rows_hint: usize,
) -> Option<Dataset> {
    let mut lines = Lines::new(reader);
    let (header_line, headers) = {
        let (line, fields) = lines.next().ok()??;
        (line, fields.to_strings())
    };
    let table = Table::of(path, header_line, &headers, opts).ok()?;
    let mut ds = table.empty_dataset(path, keep_rows, rows_hint);
    let mut rows = 0usize;
    let mut spare: Vec<&str> = Vec::with_capacity(headers.len());
    while let Some((line, record)) = lines.next().ok()? {
        if record.len() > headers.len() {
            return None;
        }
        let mut fields = emptied(std::mem::take(&mut spare));
        fields.extend(record.iter());
        if rows == 0 {
            table.check(path, &joined(&fields), opts).ok()?;
        }
        table
            .push_record(path, opts, (line, &fields), &mut ds, keep_rows)
            .ok()?;
        rows += 1;
        spare = emptied(fields);
    }
    if rows == 0 {
        return None;
    }
    table.finish(path, opts, ds).ok()
}

/// `v` emptied, its allocation kept for slices of another lifetime.
fn emptied<'b>(mut v: Vec<&str>) -> Vec<&'b str> {
    v.clear();
    v.into_iter().map(|_| "").collect()
}

/// `s` trimmed of surrounding whitespace (at once when it opens and ends with a printable
/// ASCII character, as a number does), as [`super::Records`] trims unquoted fields.
fn trim(s: &str) -> &str {
    let graphic = |b: Option<&u8>| b.is_some_and(u8::is_ascii_graphic);
    if graphic(s.as_bytes().first()) && graphic(s.as_bytes().last()) {
        s
    } else {
        s.trim()
    }
}

/// The longest line the plain reader holds (a row of [`MAX_FIELDS`] numbers of up to 100
/// characters): a longer one is left to the general reader, which never holds a record
/// beyond its field cap.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Text [`parse_plain`] does not read (the general reader does).
struct NotPlain;

/// A record's line and where its fields lie in it (byte ranges, trimmed).
struct Fields<'t> {
    text: &'t str,
    ranges: &'t [(usize, usize)],
}

impl<'t> Fields<'t> {
    fn len(&self) -> usize {
        self.ranges.len()
    }

    fn iter(&self) -> impl Iterator<Item = &'t str> + '_ {
        self.ranges.iter().map(|&(a, b)| &self.text[a..b])
    }

    fn to_strings(&self) -> Vec<String> {
        self.iter().map(str::to_string).collect()
    }
}

/// The records of a plain table, one per line: each with its 1-based line number and its
/// fields; comments, blank lines and lines of empty fields skipped.
struct Lines<R> {
    input: R,
    buf: Vec<u8>,
    ranges: Vec<(usize, usize)>,
    /// The number of the next line.
    line: usize,
}

impl<R: BufRead> Lines<R> {
    fn new(mut input: R) -> Self {
        super::records::skip_bom(&mut input);
        Lines {
            input,
            buf: Vec::with_capacity(256),
            ranges: Vec::new(),
            line: 1,
        }
    }

    /// The next record (its line number and fields), None at the end of the input.
    fn next(&mut self) -> Result<Option<(usize, Fields<'_>)>, NotPlain> {
        loop {
            self.buf.clear();
            let n = (&mut self.input)
                .take(MAX_LINE_BYTES as u64)
                .read_until(b'\n', &mut self.buf)
                .map_err(|_| NotPlain)?;
            if n == 0 {
                return Ok(None);
            }
            if n == MAX_LINE_BYTES && self.buf.last() != Some(&b'\n') {
                return Err(NotPlain);
            }
            let line = self.line;
            self.line += 1;
            let mut end = self.buf.len();
            if self.buf[end - 1] == b'\n' {
                end -= 1;
            }
            if end > 0 && self.buf[end - 1] == b'\r' {
                end -= 1;
            }
            let text = std::str::from_utf8(&self.buf[..end]).map_err(|_| NotPlain)?;
            let opening = match text.as_bytes().first() {
                Some(b' ' | b'\t') => text.trim_start_matches([' ', '\t']),
                _ => text,
            };
            let quoted = split(text, &mut self.ranges)?;
            if opening.starts_with('#') {
                // A comment from its first byte ends at the line end whatever it holds; one
                // after blanks is a record, whose quotes the general reader follows.
                if quoted && opening.len() != text.len() {
                    return Err(NotPlain);
                }
                continue;
            }
            if quoted {
                return Err(NotPlain);
            }
            if self.ranges.iter().all(|(a, b)| a == b) {
                continue;
            }
            let text = std::str::from_utf8(&self.buf[..end]).map_err(|_| NotPlain)?;
            return Ok(Some((
                line,
                Fields {
                    text,
                    ranges: &self.ranges,
                },
            )));
        }
    }
}

/// Split a line at its commas into `ranges` (emptied first: each field's byte range,
/// trimmed); whether the line holds a quote. A `\r` in it is text the plain reader does
/// not read (a lone carriage return, a line end of its own to the general reader).
fn split(text: &str, ranges: &mut Vec<(usize, usize)>) -> Result<bool, NotPlain> {
    ranges.clear();
    let bytes = text.as_bytes();
    let (mut quote, mut cr) = (false, false);
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        quote |= b == b'"';
        cr |= b == b'\r';
        if b == b',' {
            if ranges.len() == MAX_FIELDS {
                return Err(NotPlain);
            }
            ranges.push(trimmed_range(text, start, i));
            start = i + 1;
        }
    }
    ranges.push(trimmed_range(text, start, bytes.len()));
    if cr {
        return Err(NotPlain);
    }
    Ok(quote)
}

/// The byte range of `text[a..b]` trimmed ([`trim`]).
fn trimmed_range(text: &str, a: usize, b: usize) -> (usize, usize) {
    let field = &text[a..b];
    let t = trim(field);
    let lead = t.as_ptr() as usize - field.as_ptr() as usize;
    (a + lead, a + lead + t.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every text the plain reader takes gives the general reader's dataset (samples,
    /// lines, values, groups, rows); every other gives None.
    #[test]
    fn the_plain_reader_reads_as_the_general_one_or_not_at_all() {
        let path = Path::new("t.csv");
        let opts = ReadOptions::default();
        let plain_texts = [
            "theta_i,theta_r,phi_r,L\n10,20,0,1.5\n30,40,180,2\n",
            "\u{feff}# quantity: radiance\n\ntheta_i , theta_r,phi_r,L,group\r\n  # note\r\n10, 20 ,0,1e-3,a\r\n,,,,\r\n30,40,-90,2,b",
            "theta_i,theta_r,phi_r,L\n# a \"quoted\" comment\n10,20,0,1\n",
        ];
        for text in plain_texts {
            let plain = parse_plain(path, text.as_bytes(), &opts, true, 0).expect(text);
            let general =
                super::super::parse(path, text.trim_start_matches('\u{feff}'), &opts).expect(text);
            assert_eq!(format!("{plain:?}"), format!("{general:?}"), "{text:?}");
        }
        let not_plain = [
            "theta_i,theta_r,phi_r,L\n10,20,0,\"1\"\n",
            "theta_i,theta_r,phi_r,L\r10,20,0,1\r",
            "theta_i,theta_r,phi_r,L\n  # a, \"b\n10,20,0,1\"\n10,20,0,1\n",
            "theta_i,theta_r,phi_r,L\n10,20,0,x\n",
            "theta_i,theta_r,phi_r,L\n10,20,0,1,5\n",
            "theta_i,theta_r,phi_r,L\n",
        ];
        for text in not_plain {
            assert!(
                parse_plain(path, text.as_bytes(), &opts, false, 0).is_none(),
                "{text:?}"
            );
        }
        let wide = format!(
            "theta_i,theta_r,phi_r,L{}\n10,20,0,1\n",
            ",x".repeat(MAX_FIELDS)
        );
        assert!(parse_plain(path, wide.as_bytes(), &opts, false, 0).is_none());
        let long = format!(
            "theta_i,theta_r,phi_r,L\n10,20,0,1{}\n",
            " ".repeat(MAX_LINE_BYTES)
        );
        assert!(parse_plain(path, long.as_bytes(), &opts, false, 0).is_none());
        let not_utf8 = b"theta_i,theta_r,phi_r,L\n10,20,0,\xff\n";
        assert!(parse_plain(path, &not_utf8[..], &opts, false, 0).is_none());
    }
}
