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
/// an error. `keep_rows` and `rows_hint` as for [`super::parse_reader`]. On a pool of more
/// than one thread the records are read in pieces of [`PIECE_BYTES`] parsed side by side,
/// a few pieces at a time (the text held is bounded, as in one thread's streaming).
pub(crate) fn parse_plain(
    path: &Path,
    reader: impl BufRead,
    opts: &ReadOptions,
    keep_rows: bool,
    rows_hint: usize,
) -> Option<Dataset> {
    let pieces = (rayon::current_num_threads() > 1).then_some(PIECE_BYTES);
    parse_plain_by(path, reader, opts, (keep_rows, rows_hint), pieces)
}

/// [`parse_plain`], its records read in pieces of `piece_bytes` when given, else one by
/// one.
fn parse_plain_by(
    path: &Path,
    reader: impl BufRead,
    opts: &ReadOptions,
    (keep_rows, rows_hint): (bool, usize),
    piece_bytes: Option<usize>,
) -> Option<Dataset> {
    let mut lines = Lines::new(reader);
    let (header_line, headers) = {
        let (line, fields) = lines.next().ok()??;
        (line, fields.to_strings())
    };
    let table = Table::of(path, header_line, &headers, opts).ok()?;
    let mut ds = table.empty_dataset(path, keep_rows, rows_hint);
    let read = Reading {
        path,
        opts,
        table: &table,
        keep_rows,
    };
    let first = match piece_bytes {
        Some(bytes) => read.in_pieces(lines, bytes, &mut ds)?,
        None => read.records(&mut lines, &mut ds)?,
    };
    // The first record is checked as a whole (e.g. a decimal comma) before it counts.
    table.check(path, &first?, opts).ok()?;
    table.finish(path, opts, ds).ok()
}

/// Bytes of text in one piece of a table parsed on its own (the last line completed).
pub(super) const PIECE_BYTES: usize = 1 << 20;

/// What reading a plain table's records needs.
struct Reading<'a> {
    path: &'a Path,
    opts: &'a ReadOptions,
    table: &'a Table<'a>,
    keep_rows: bool,
}

impl Reading<'_> {
    /// The records of `lines` into `ds`: None when the text is not plain or holds an
    /// error; otherwise the first record's text (None for no record).
    fn records<R: BufRead>(
        &self,
        lines: &mut Lines<R>,
        ds: &mut Dataset,
    ) -> Option<Option<String>> {
        let width = self.table.headers.len();
        let mut first = None;
        let mut spare: Vec<&str> = Vec::with_capacity(width);
        while let Some((line, record)) = lines.next().ok()? {
            if record.len() > width {
                return None;
            }
            let mut fields = emptied(std::mem::take(&mut spare));
            fields.extend(record.iter());
            if first.is_none() {
                first = Some(joined(&fields));
            }
            self.table
                .push_record(self.path, self.opts, (line, &fields), ds, self.keep_rows)
                .ok()?;
            spare = emptied(fields);
        }
        Some(first)
    }

    /// [`Self::records`] of `lines` read in pieces of `bytes`, each piece's records parsed into a
    /// dataset of its own on the pool's threads (while the next pieces are read) and
    /// appended to `ds` in order. The pieces' texts and datasets are two sets of buffers
    /// used in turn (one parsed while the other is read or appended), so reading holds a
    /// fixed amount of memory beside `ds` and allocates it once.
    fn in_pieces<R: BufRead>(
        &self,
        mut lines: Lines<R>,
        bytes: usize,
        ds: &mut Dataset,
    ) -> Option<Option<String>> {
        let batch = 2 * rayon::current_num_threads();
        let mut first: Option<String> = None;
        let mut line = lines.line;
        let (mut texts, mut spare_texts) = (Vec::new(), Vec::new());
        let (mut parts, mut parsed_parts) = (Vec::new(), Vec::new());
        let mut parsed: Vec<Option<Piece>> = Vec::new();
        lines.pieces(&mut texts, batch, bytes).ok()?;
        while !texts.is_empty() || !parsed.is_empty() {
            let mut now = Vec::new();
            let (read, appended) =
                rayon::in_place_scope(|scope| {
                    scope.spawn(|_| now = self.parse_pieces(&texts, &mut parts));
                    let appended = parsed.drain(..).zip(parsed_parts.iter_mut()).try_for_each(
                        |(piece, part)| {
                            let piece = piece?;
                            first = first.take().or(piece.first);
                            ds.append_from_line(part, line);
                            line += piece.lines;
                            Some(())
                        },
                    );
                    (lines.pieces(&mut spare_texts, batch, bytes), appended)
                });
            appended?;
            read.ok()?;
            parsed = now;
            std::mem::swap(&mut texts, &mut spare_texts);
            std::mem::swap(&mut parts, &mut parsed_parts);
        }
        Some(first)
    }

    /// Each piece's records parsed into the dataset of `parts` at its index (emptied first;
    /// added while there are fewer), its lines numbered from 1: the first record's text and
    /// the piece's line count, or None for a piece that is not plain or holds an error.
    fn parse_pieces(&self, texts: &[Vec<u8>], parts: &mut Vec<Dataset>) -> Vec<Option<Piece>> {
        use rayon::prelude::*;
        while parts.len() < texts.len() {
            let rows = texts[parts.len()].len() / 32;
            parts.push(self.table.empty_dataset(self.path, self.keep_rows, rows));
        }
        texts
            .par_iter()
            .zip(parts.par_iter_mut())
            .map(|(text, part)| {
                part.clear();
                let mut lines = Lines::at(&text[..], 1);
                let first = self.records(&mut lines, part)?;
                Some(Piece {
                    first,
                    lines: lines.line - 1,
                })
            })
            .collect()
    }
}

/// What parsing one piece of a table found beside its records.
struct Piece {
    /// The text of its first record, if any.
    first: Option<String>,
    /// Its number of lines.
    lines: usize,
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
pub(super) const MAX_LINE_BYTES: usize = 1 << 20;

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
        Lines::at(input, 1)
    }

    /// The records of `input`, whose first line is line `line` of the file.
    fn at(input: R, line: usize) -> Self {
        Lines {
            input,
            buf: Vec::with_capacity(256),
            ranges: Vec::new(),
            line,
        }
    }

    /// The next `count` pieces of the text into `texts` (fewer at its end, none after it),
    /// each `bytes` and the rest of the line it ends in, reusing the buffers `texts` holds.
    /// Err when the input fails or a line runs past [`MAX_LINE_BYTES`].
    fn pieces(
        &mut self,
        texts: &mut Vec<Vec<u8>>,
        count: usize,
        bytes: usize,
    ) -> Result<(), NotPlain> {
        texts.resize_with(count, || Vec::with_capacity(bytes + 256));
        for k in 0..count {
            let text = &mut texts[k];
            text.clear();
            (&mut self.input)
                .take(bytes as u64)
                .read_to_end(text)
                .map_err(|_| NotPlain)?;
            if text.is_empty() {
                texts.truncate(k);
                break;
            }
            if text.last() != Some(&b'\n') {
                let cut = text.len();
                (&mut self.input)
                    .take(MAX_LINE_BYTES as u64)
                    .read_until(b'\n', text)
                    .map_err(|_| NotPlain)?;
                if text.len() - cut == MAX_LINE_BYTES && text.last() != Some(&b'\n') {
                    return Err(NotPlain);
                }
            }
        }
        Ok(())
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

    /// Record by record, and in pieces of 1 byte (a line each), 7 and 64 bytes and more
    /// than the text.
    const PIECES: [Option<usize>; 5] = [None, Some(1), Some(7), Some(64), Some(1 << 20)];

    /// A table of many records read in pieces is the table read record by record: every
    /// sample, value, group and line number, wherever the pieces' ends fall (in comments,
    /// blank lines and `\r\n` line ends among them); an error in any piece gives None.
    #[test]
    fn pieces_read_the_records_of_one_by_one() {
        let path = Path::new("t.csv");
        let opts = ReadOptions::default();
        let mut text = String::from("theta_i,theta_r,phi_r,L,group\r\n");
        for i in 0..400 {
            let extra = match i % 37 {
                0 => "# a comment, with a comma\r\n",
                1 => "\r\n",
                2 => ",,,,\r\n",
                _ => "",
            };
            let row = format!(
                "{}, {},{},{:e},g{}\r\n",
                i % 80,
                (i * 7) % 85,
                i % 360,
                1.0 + i as f64,
                i % 3
            );
            text.push_str(extra);
            text.push_str(&row);
        }
        let whole = parse_plain_by(path, text.as_bytes(), &opts, (true, 0), None).unwrap();
        assert_eq!(whole.len(), 400);
        for bytes in [1, 7, 64, 100, 1000, 1 << 20] {
            let pieces = parse_plain_by(path, text.as_bytes(), &opts, (true, 0), Some(bytes));
            assert_eq!(
                format!("{:?}", pieces.unwrap()),
                format!("{whole:?}"),
                "{bytes}"
            );
        }
        let bad = text.replacen("g1\r\n", "g1,extra\r\n", 50);
        let bad = bad.replacen("g1,extra", "g1", 49);
        for bytes in [7, 64, 1000] {
            let pieces = parse_plain_by(path, bad.as_bytes(), &opts, (false, 0), Some(bytes));
            assert!(pieces.is_none(), "{bytes}");
        }
    }

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
            let general =
                super::super::parse(path, text.trim_start_matches('\u{feff}'), &opts).expect(text);
            for pieces in PIECES {
                let plain = parse_plain_by(path, text.as_bytes(), &opts, (true, 0), pieces);
                let plain = plain.expect(text);
                assert_eq!(
                    format!("{plain:?}"),
                    format!("{general:?}"),
                    "{text:?} {pieces:?}"
                );
            }
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
            for pieces in PIECES {
                let plain = parse_plain_by(path, text.as_bytes(), &opts, (false, 0), pieces);
                assert!(plain.is_none(), "{text:?} {pieces:?}");
            }
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
