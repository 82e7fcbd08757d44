//! CSV records of a measurement table: the `csv-core` parser (the state machine of the
//! `csv` crate's reader) with a measurement file's rules on top.
//!
//! The parser splits fields (RFC 4180: a field is quoted when its first character is `"`,
//! `""` inside is a quote, line breaks inside are kept; records end at `\n`, `\r\n` or
//! `\r`; empty lines and lines whose first character is `#` are skipped). On top of it:
//! - every record carries the 1-based line it starts on (as an editor counts lines,
//!   comments and blank lines included, any of the three line ends counted once);
//! - unquoted fields are trimmed of surrounding whitespace, quoted fields kept verbatim;
//!   blanks between a closing quote and the next comma are allowed;
//! - a record whose first field is unquoted and starts with `#` after blanks is a comment
//!   too, and a record whose fields are all empty (a line of blanks or commas) is skipped;
//! - a quoted field that is never closed, and text after a closing quote, are errors
//!   (the parser itself prefers some parse to none);
//! - the fields of a record are capped ([`Limit`]): the record is refused as soon as the
//!   field past the cap starts, and the rest of it is only counted, never held;
//! - bytes that are not UTF-8 are an error naming their line and byte offset.
//!
//! A record is read field by field from any [`BufRead`], so a file is never held whole.

use std::io::BufRead;

/// One CSV record: the 1-based line it starts on, and its fields.
pub(crate) type Record = (usize, Vec<String>);

/// The most fields a header may have ([`split_records`]); a data row may have at most as
/// many as its header. Rows are cut off at that many fields while they are read, so a
/// hostile line of millions of fields is refused without holding them (reading stays
/// O(file size) in memory).
pub(crate) const MAX_FIELDS: usize = 10_000;

/// Split CSV text into records, each with the 1-based line it starts on, by the rules of
/// the module docs. Errors: (line, message) for an unterminated quote, text after a
/// closing quote, or a record of more than [`MAX_FIELDS`] fields.
#[cfg(test)]
pub(crate) fn split_records(text: &str) -> std::result::Result<Vec<Record>, (usize, String)> {
    split(text, Limit::Each(MAX_FIELDS))
}

/// [`split_records`] for a table: at most `max_fields` fields in the header (the first
/// record) and at most the header's count in every later record; a longer record is an
/// error as soon as its field `max + 1` starts, so it is never held field by field.
#[cfg(test)]
pub(crate) fn split_records_limited(
    text: &str,
    max_fields: usize,
) -> std::result::Result<Vec<Record>, (usize, String)> {
    split(text, Limit::Table(max_fields))
}

#[cfg(test)]
fn split(text: &str, limit: Limit) -> std::result::Result<Vec<Record>, (usize, String)> {
    Records::new(text.as_bytes(), limit)
        .map(|r| {
            r.map_err(|fault| match fault {
                Fault::Row(line, m) | Fault::Text(line, m) => (line, m),
                Fault::Io(e) => (0, e.to_string()),
            })
        })
        .collect()
}

/// How many fields a record may have.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Limit {
    /// At most this many in every record (the tests' whole-text splitter).
    #[cfg_attr(not(test), allow(dead_code))]
    Each(usize),
    /// At most this many in the header (the first record), the header's count after it.
    Table(usize),
}

/// Why reading records stopped.
#[derive(Debug)]
pub(crate) enum Fault {
    /// Malformed CSV or too many fields: the line and the message.
    Row(usize, String),
    /// Bytes that are not UTF-8: their line and the message.
    Text(usize, String),
    /// The reader failed.
    Io(std::io::Error),
}

/// One field as the parser gave it, with the rules above applied.
struct Field {
    text: String,
    /// Unquoted and opening with `#` after blanks (a comment when it opens a record).
    hash: bool,
    /// Whether the record ends with this field.
    record_end: bool,
    /// The 1-based line the field starts on.
    line: usize,
}

/// The records of a CSV byte stream (see the module docs); after the first fault the
/// iterator ends.
pub(crate) struct Records<R> {
    input: R,
    core: csv_core::Reader,
    limit: Limit,
    /// The first record (the header of a table): its line and fields.
    header: Option<(usize, Vec<String>)>,
    /// The line of the next unread byte, and whether the byte before it was a `\r`.
    line: usize,
    after_cr: bool,
    /// Bytes consumed after the byte-order mark.
    offset: usize,
    done: bool,
    /// A field's bytes as read (`raw`) and as the parser unquoted them (`out`).
    raw: Vec<u8>,
    out: Vec<u8>,
    /// The parser's output buffer (a field longer than it is copied out in pieces).
    scratch: Box<[u8; 4096]>,
}

/// Skip a UTF-8 byte-order mark at the start of `input` when its first read holds it whole
/// (any buffer of 3 bytes or more). A read error here shows again on the next read.
pub(crate) fn skip_bom<R: BufRead>(input: &mut R) {
    if input
        .fill_buf()
        .is_ok_and(|b| b.starts_with(b"\xEF\xBB\xBF"))
    {
        input.consume(3);
    }
}

impl<R: BufRead> Records<R> {
    /// The records of `input`; a UTF-8 byte-order mark is skipped when the first read
    /// holds it whole (any buffer of 3 bytes or more).
    pub(crate) fn new(mut input: R, limit: Limit) -> Self {
        skip_bom(&mut input);
        Records {
            input,
            core: csv_core::ReaderBuilder::new().comment(Some(b'#')).build(),
            limit,
            header: None,
            line: 1,
            after_cr: false,
            offset: 0,
            done: false,
            raw: Vec::new(),
            out: Vec::new(),
            scratch: Box::new([0; 4096]),
        }
    }

    /// The next record that is neither a comment nor empty, or None at the end.
    fn record(&mut self) -> Result<Option<Record>, Fault> {
        loop {
            let Some(first) = self.field(true, true)? else {
                return Ok(None);
            };
            let (line, comment) = (first.line, first.hash);
            let mut end = first.record_end;
            let mut fields = vec![first.text];
            while !end {
                let f = self.field(false, !comment)?.ok_or_else(|| self.cut(line))?;
                end = f.record_end;
                if comment {
                    continue;
                }
                if fields.len() == self.cap() {
                    return Err(self.too_many(line, fields, f));
                }
                fields.push(f.text);
            }
            if comment || fields.iter().all(|f| f.is_empty()) {
                continue;
            }
            if self.header.is_none() {
                self.header = Some((line, fields.clone()));
            }
            return Ok(Some((line, fields)));
        }
    }

    /// The most fields the next record may have.
    fn cap(&self) -> usize {
        match (self.limit, &self.header) {
            (Limit::Table(_), Some((_, h))) => h.len(),
            (Limit::Table(n) | Limit::Each(n), _) => n,
        }
    }

    /// A record the parser ended without its last field (it never does).
    fn cut(&self, line: usize) -> Fault {
        Fault::Row(line, "the record ends in the middle".into())
    }

    /// The fault for a record (starting on `line`) whose field `cap + 1` is `next`: the
    /// rest of the record is read and counted (its text kept up to 1 MiB for the hints).
    fn too_many(&mut self, line: usize, fields: Vec<String>, next: Field) -> Fault {
        let cap = fields.len();
        let Some((header_line, header)) = self.header.clone() else {
            return Fault::Row(
                line,
                format!(
                    "the header has more than {cap} fields (a measurement table has a few columns)"
                ),
            );
        };
        if let Limit::Each(_) = self.limit {
            return Fault::Row(line, format!("a record has more than {cap} fields"));
        }
        let mut text = fields.join(",");
        let (mut count, mut end) = (cap, false);
        let mut field = Some(next);
        while let Some(f) = field.take() {
            count += 1;
            end = f.record_end;
            if text.len() < 1 << 20 {
                text.push(',');
                text.push_str(&f.text);
            }
            if !end {
                match self.field(false, false) {
                    Ok(next) => field = next,
                    Err(fault) => return fault,
                }
            }
        }
        if !end {
            return self.cut(line);
        }
        if let Some(m) = super::delimiter_hint(&header, &text) {
            return Fault::Row(line, m);
        }
        Fault::Row(
            line,
            format!(
                "row has {count} fields, the header on line {header_line} has {cap}{}",
                super::decimal_comma_hint(&text)
            ),
        )
    }

    /// The next field from the parser (None at the end of the input), its line, text and
    /// whether it ends its record; `first`: the field opens a record (the blank and comment
    /// lines before it are skipped), `check`: the quoting rules are enforced.
    fn field(&mut self, first: bool, check: bool) -> Result<Option<Field>, Fault> {
        let (start_line, start_offset) = (self.line, self.offset);
        self.raw.clear();
        self.out.clear();
        let record_end = loop {
            let input = match self.input.fill_buf() {
                Ok(input) => input,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(Fault::Io(e)),
            };
            let at_end = input.is_empty();
            let (res, nin, nout) = self.core.read_field(input, &mut self.scratch[..]);
            self.raw.extend_from_slice(&input[..nin]);
            self.out.extend_from_slice(&self.scratch[..nout]);
            self.input.consume(nin);
            self.offset += nin;
            match res {
                csv_core::ReadFieldResult::Field { record_end } => break Some(record_end),
                csv_core::ReadFieldResult::End => break None,
                _ if at_end => break None,
                _ => {}
            }
        };
        // The blank and comment lines the parser skipped before a record.
        let skipped = match first.then(|| skipped_lines(&self.raw)) {
            None => 0,
            Some(Ok(skipped)) => skipped,
            Some(Err(at)) => {
                let mut cr = self.after_cr;
                return Err(Fault::Row(
                    start_line + line_ends(&self.raw[..at], &mut cr),
                    "a comment line ends with a lone carriage return (\\r) and would hide the lines after it: save the file with \\n or \\r\\n line ends".into(),
                ));
            }
        };
        let out = match (
            std::str::from_utf8(&self.raw[..skipped]),
            std::str::from_utf8(&self.out),
        ) {
            (Ok(_), Ok(out)) => out,
            _ => return Err(self.utf8_fault(start_line, start_offset)),
        };
        let line = start_line + line_ends(&self.raw[..skipped], &mut self.after_cr);
        let body = &self.raw[skipped..];
        let cr_before = self.after_cr;
        self.line = line + line_ends(body, &mut self.after_cr);
        let Some(record_end) = record_end else {
            return Ok(None);
        };
        let text = if body.first() == Some(&b'"') {
            let kept = if check {
                quoted_len(body, line, cr_before, out.len())?
            } else {
                out.len()
            };
            out.get(..kept).unwrap_or(out).to_string()
        } else {
            trimmed(out)
        };
        let hash = body.first() != Some(&b'"')
            && self.out.iter().find(|&&b| b != b' ' && b != b'\t') == Some(&b'#');
        Ok(Some(Field {
            text,
            hash,
            record_end,
            line,
        }))
    }
}

impl<R> Records<R> {
    /// The fault for the field just read (from `line`, byte `offset` on) when its bytes
    /// are not UTF-8: the line and offset of the first bad byte.
    fn utf8_fault(&self, line: usize, offset: usize) -> Fault {
        let good = match std::str::from_utf8(&self.raw) {
            Ok(_) => self.raw.len(),
            Err(e) => e.valid_up_to(),
        };
        Fault::Text(
            line + line_ends(&self.raw[..good], &mut self.after_cr.clone()),
            format!(
                "invalid UTF-8 at byte {} (save the file as UTF-8 text)",
                offset + good
            ),
        )
    }
}

/// `s` trimmed of surrounding whitespace (at once when it opens and ends with a printable
/// ASCII character, as a number does).
fn trimmed(s: &str) -> String {
    let printable = |b: Option<&u8>| b.is_some_and(u8::is_ascii_graphic);
    if printable(s.as_bytes().first()) && printable(s.as_bytes().last()) {
        s.to_string()
    } else {
        s.trim().to_string()
    }
}

impl<R: BufRead> Iterator for Records<R> {
    type Item = Result<Record, Fault>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let next = self.record().transpose();
        self.done = !matches!(next, Some(Ok(_)));
        next
    }
}

/// The length of a quoted field's text within the `out` bytes the parser made of `body`
/// (the field's bytes from its opening quote on): the text between the quotes, without the
/// blanks the parser appended after the closing quote. A quote never closed, or text
/// after the closing quote, is a fault; `line` is the line the field starts on and
/// `after_cr` whether the byte before `body` is a `\r`.
fn quoted_len(body: &[u8], line: usize, after_cr: bool, out: usize) -> Result<usize, Fault> {
    // The closing quote: the first quote after the opening one that is not doubled.
    let mut i = 1;
    let close = loop {
        match (body.get(i), body.get(i + 1)) {
            (None, _) => {
                return Err(Fault::Row(line, "a quoted field is never closed".into()));
            }
            (Some(b'"'), Some(b'"')) => i += 2,
            (Some(b'"'), _) => break i,
            _ => i += 1,
        }
    };
    let after = &body[close + 1..];
    let blanks = after
        .iter()
        .take_while(|&&b| b == b' ' || b == b'\t')
        .count();
    match after.get(blanks) {
        None | Some(b',' | b'\r' | b'\n') => Ok(out.saturating_sub(blanks)),
        Some(_) => {
            let rest = &after[blanks..];
            let junk = rest.split(|b| matches!(b, b',' | b'\r' | b'\n')).next();
            let rest: String = String::from_utf8_lossy(junk.unwrap_or(rest))
                .chars()
                .take(20)
                .collect();
            let mut cr = after_cr;
            Err(Fault::Row(
                line + line_ends(&body[..close], &mut cr),
                format!("unexpected text '{rest}' after a closing quote"),
            ))
        }
    }
}

/// The bytes the parser skips before a record: line ends, and lines opening with `#`.
/// Err: the offset of a comment line that holds a lone `\r` with text after it (the
/// parser ends a comment at `\n` only, so in a file with `\r` line ends the comment
/// would hide the lines after it).
fn skipped_lines(raw: &[u8]) -> Result<usize, usize> {
    let mut i = 0;
    loop {
        match raw.get(i) {
            Some(b'\r' | b'\n') => i += 1,
            Some(b'#') => {
                let end = raw[i..]
                    .iter()
                    .position(|&b| b == b'\n')
                    .map_or(raw.len(), |k| i + k + 1);
                let comment = &raw[i..end];
                if comment.windows(2).any(|w| w[0] == b'\r' && w[1] != b'\n') {
                    return Err(i);
                }
                i = end;
            }
            _ => return Ok(i),
        }
    }
}

/// The line ends in `b` (`\n`, `\r\n` and a lone `\r` each count once); `after_cr` says
/// whether the byte before `b` was a `\r`, and is left saying it for the byte after.
fn line_ends(b: &[u8], after_cr: &mut bool) -> usize {
    let Some(&last) = b.last() else {
        return 0;
    };
    let count = |c: u8| b.iter().filter(|&&x| x == c).count();
    let (lf, cr) = (count(b'\n'), count(b'\r'));
    let crlf = if cr == 0 {
        0
    } else {
        b.windows(2).filter(|w| w == b"\r\n").count()
    };
    let joined = usize::from(*after_cr && b[0] == b'\n');
    *after_cr = last == b'\r';
    lf + cr - crlf - joined
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The records of a stream handed out a few bytes at a time equal those of the
    /// whole text, line numbers and faults included.
    #[test]
    fn records_do_not_depend_on_how_the_input_is_cut() {
        let texts = [
            "a,b\n1,2\n",
            "a,b\r\n1,2\r\n\r\n# c, \"open\n3,4",
            "\u{feff}a,b\n\"x\ny\",2\n  # q\n\"a\"\"b\", 3\n",
            "a,\"b\n\nc\",d\n1,2,3\n",
            "h\r1\r2\r",
            "a,b\n\"never closed\n1,2\n",
            "a,b\n\"x\" y,2\n",
            "a,b\n1,\"2\" \n  \n3 , 4\n",
            "",
        ];
        for text in texts {
            let whole: Vec<_> = Records::new(text.as_bytes(), Limit::Table(16))
                .map(|r| r.map_err(|f| format!("{f:?}")))
                .collect();
            for cap in [3, 4, 5, 7] {
                let cut = std::io::BufReader::with_capacity(cap, text.as_bytes());
                let got: Vec<_> = Records::new(cut, Limit::Table(16))
                    .map(|r| r.map_err(|f| format!("{f:?}")))
                    .collect();
                assert_eq!(got, whole, "{text:?} read {cap} bytes at a time");
            }
        }
    }

    #[test]
    fn records_carry_the_line_they_start_on() {
        let r = split_records("# c\n\na,b\r\n\"x\ny\",2\r\n  # note\n3,4\rh\r").unwrap();
        let lines: Vec<usize> = r.iter().map(|(l, _)| *l).collect();
        assert_eq!(lines, [3, 4, 7, 8]);
        assert_eq!(r[1].1, ["x\ny", "2"]);
        assert_eq!(r[3].1, ["h"]);
    }

    #[test]
    fn quoted_fields_are_verbatim_and_unquoted_ones_trimmed() {
        let r = split_records(" a , \" b \" ,\" c \"  ,\"#d\"\n,,\n\"\"\n").unwrap();
        // A quote opens a field only as its first character.
        assert_eq!(
            r,
            [(
                1,
                vec!["a".into(), "\" b \"".into(), " c ".into(), "#d".into()]
            )]
        );
    }

    #[test]
    fn a_comment_hiding_lines_behind_a_lone_carriage_return_is_refused() {
        let e = split_records("h\r1\r# c\r2\r").unwrap_err();
        assert_eq!(e.0, 3);
        assert!(e.1.contains("lone carriage return"), "{}", e.1);
        // A comment ending in \r\n, or a lone \r at the end of the text, hides nothing.
        assert_eq!(split_records("# c\r\nh\r1\r# end\r").unwrap().len(), 2);
    }

    #[test]
    fn bad_quotes_name_their_line() {
        let e = split_records("a,b\n1,\"x\n\ny\n").unwrap_err();
        assert_eq!(e, (2, "a quoted field is never closed".into()));
        let e = split_records("a,b\n\"1\n2\"x,3\n").unwrap_err();
        assert_eq!(e, (3, "unexpected text 'x' after a closing quote".into()));
    }

    #[test]
    fn invalid_utf8_names_its_line_and_byte() {
        let bytes = b"a,b\n1,2\n3,\xff\n";
        let fault = Records::new(&bytes[..], Limit::Table(16))
            .find_map(|r| r.err())
            .expect("a fault");
        match fault {
            Fault::Text(line, m) => {
                assert_eq!(line, 3);
                assert!(m.contains("at byte 10"), "{m}");
            }
            f => panic!("unexpected fault {f:?}"),
        }
    }
}
