//! CSV measurement tables.
//!
//! A header row names the columns (case-insensitive, surrounding whitespace ignored):
//!
//! | role | header names | meaning |
//! |---|---|---|
//! | `theta_i` | `theta_i` | incidence angle from the normal |
//! | `theta_r` | `theta_r` | view angle from the normal |
//! | `phi_r` | `phi_r` | view azimuth from the plane of incidence, 0 = forward/specular side |
//! | `L` | `L`, `value` or `brdf` | measured radiance (or BRDF: a column named `brdf`, or a `# quantity: brdf` comment before the header, states a BRDF; see [`super::quantity`]) |
//! | `weight` | `weight` | per-sample weight w > 0 |
//! | `sigma_L` | `sigma_L` | standard uncertainty of L (> 0); w = 1/σ² |
//! | `wavelength` | `wavelength` | per-sample wavelength (> 0), unit of σ and T |
//! | `group` | `group` | a label; samples with the same label form a channel |
//!
//! `--columns role=name,...` maps other header names to roles (and overrides the names
//! above). Other columns are kept and passed through. Angles are degrees unless
//! `radians`. With `signed_theta_r`, θr < 0 means the view lies on the opposite side of the
//! normal: θr := |θr|, φr := φr + 180° (in-plane data: φr = 0 → 180°); in that mode the
//! `phi_r` column may be left out (in-plane data, φr = 0).
//!
//! Lines starting with `#` are comments; blank lines, CRLF line ends, a UTF-8 byte-order mark
//! and quoted fields are accepted. A `weight` and a `sigma_L` column together are an error
//! (one of them decides the weights). With `require_value`, a file whose values are all
//! zero is an error (nothing to fit).
//!
//! Values of L may be negative (background-subtracted data); they must be finite.
//!
//! Errors: a bad field is an `Error::Input` naming the 1-based line (as an editor counts
//! them, comments and blank lines included), the column's header name and the value; a
//! missing column is an `Error::Input` on the header line; an empty file or a header without
//! rows is an `Error::File`.
//!
//! NIST layout: a header with `thetai`, `thetar`, `phir` and no `theta_i` (Germer's PTFE
//! BRDF files, `lambda,thetai,phi,thetar,phir,f_r11,...`, also with `phii`/`fr11`) is read
//! in its own convention: azimuths are those of direction vectors pointing away from the
//! surface; a negative `thetai` puts the source at azimuth `phi` + 180°. So
//! θi = |thetai|, θr = thetar and φr = phir − φ_source − 180° (the mirror direction is then
//! φr = 0), value = `f_r11`, wavelength = `lambda` (µm in those files). An explicit
//! `--columns` mapping of any angle role turns this detection off.

use super::{check_angles, parse_finite, Dataset, ReadOptions};
use crate::error::{Error, Result};
use crate::geometry::Sample;
use std::path::Path;

/// Column roles of a measurement table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    ThetaI,
    ThetaR,
    PhiR,
    Value,
    Weight,
    SigmaL,
    Wavelength,
    Group,
}

const ROLES: [(Role, &str, &[&str]); 8] = [
    (Role::ThetaI, "theta_i", &["theta_i"]),
    (Role::ThetaR, "theta_r", &["theta_r"]),
    (Role::PhiR, "phi_r", &["phi_r"]),
    (Role::Value, "L", &["l", "value", "brdf"]),
    (Role::Weight, "weight", &["weight"]),
    (Role::SigmaL, "sigma_L", &["sigma_l"]),
    (Role::Wavelength, "wavelength", &["wavelength"]),
    (Role::Group, "group", &["group"]),
];

/// The role names `--columns` accepts, for help texts and messages.
pub const ROLE_NAMES: [&str; 8] = [
    "theta_i",
    "theta_r",
    "phi_r",
    "L",
    "weight",
    "sigma_L",
    "wavelength",
    "group",
];

fn role_name(r: Role) -> &'static str {
    ROLES.iter().find(|(x, _, _)| *x == r).map_or("?", |t| t.1)
}

fn parse_role(name: &str) -> Option<Role> {
    let n = name.trim().to_ascii_lowercase();
    if n == "value" {
        return Some(Role::Value);
    }
    ROLES
        .iter()
        .find(|(_, canon, _)| canon.eq_ignore_ascii_case(&n))
        .map(|t| t.0)
}

/// Parse `role=name,role=name` (the `--columns` syntax) into pairs, checking the roles.
pub fn parse_columns(text: &str) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    for part in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (role, name) = part.split_once('=').ok_or_else(|| {
            Error::Usage(format!(
                "--columns: '{part}' is not role=name (roles: {})",
                ROLE_NAMES.join(", ")
            ))
        })?;
        if parse_role(role).is_none() {
            return Err(Error::Usage(format!(
                "--columns: unknown role '{}' (roles: {})",
                role.trim(),
                ROLE_NAMES.join(", ")
            )));
        }
        out.push((role.trim().to_string(), name.trim().to_string()));
    }
    Ok(out)
}

/// Column index of each role (None: absent).
#[derive(Debug, Default)]
struct Columns {
    idx: [Option<usize>; 8],
}

impl Columns {
    fn get(&self, r: Role) -> Option<usize> {
        self.idx[r as usize]
    }
}

/// The NIST (Germer PTFE) layout: absolute azimuths of outward directions.
#[derive(Debug)]
struct Nist {
    theta_i: usize,
    phi_i: Option<usize>,
    theta_r: usize,
    phi_r: usize,
}

/// Parse a CSV table (text already decoded, BOM removed).
pub(crate) fn parse(path: &Path, text: &str, opts: &ReadOptions) -> Result<Dataset> {
    let records = split_records_limited(text, MAX_FIELDS)
        .map_err(|(line, m)| Error::input(path, line, "(row)", m))?;
    let n = records.len();
    parse_records(path, records.into_iter().map(Ok), opts, true, n)
}

/// Parse a CSV table streamed from `reader` record by record ([`RecordStream`]): the text
/// is never held whole, and the raw rows are kept only with `keep_rows` (the fit needs them
/// only for its residuals file). `rows_hint` sizes the columns (an estimate; 0 is fine).
pub(crate) fn parse_reader(
    path: &Path,
    reader: impl std::io::BufRead,
    opts: &ReadOptions,
    keep_rows: bool,
    rows_hint: usize,
) -> Result<Dataset> {
    parse_records(
        path,
        RecordStream::new(path, reader),
        opts,
        keep_rows,
        rows_hint,
    )
}

/// Parse CSV records (header first) into a dataset; see the module docs.
fn parse_records(
    path: &Path,
    records: impl Iterator<Item = Result<Record>>,
    opts: &ReadOptions,
    keep_rows: bool,
    rows_hint: usize,
) -> Result<Dataset> {
    let input_err = |line, column: &str, message| Error::input(path, line, column, message);
    let file_err = |message| Error::file(path, message);

    let mut records = records.peekable();
    let Some((header_line, headers)) = records.next().transpose()? else {
        return Err(file_err(
            "empty file: no header row (expected e.g. theta_i,theta_r,phi_r,L)".into(),
        ));
    };
    if records.peek().is_none() {
        return Err(file_err(format!(
            "no data rows after the header on line {header_line}"
        )));
    }

    // Resolve the columns.
    let find = |name: &str| -> Vec<usize> {
        headers
            .iter()
            .enumerate()
            .filter(|(_, h)| h.trim().eq_ignore_ascii_case(name.trim()))
            .map(|(i, _)| i)
            .collect()
    };
    let mut cols = Columns::default();
    let mut mapped = [false; 8];
    for (role_text, name) in &opts.columns {
        let role = parse_role(role_text).ok_or_else(|| {
            Error::Usage(format!(
                "--columns: unknown role '{role_text}' (roles: {})",
                ROLE_NAMES.join(", ")
            ))
        })?;
        let hits = find(name);
        let Some(&i) = hits.first() else {
            return Err(input_err(
                header_line,
                name,
                format!(
                    "no column named '{name}' (mapped to {} by --columns); the header has: {}",
                    role_name(role),
                    headers.join(", ")
                ),
            ));
        };
        if hits.len() > 1 {
            return Err(input_err(
                header_line,
                name,
                format!("the header names '{name}' {} times", hits.len()),
            ));
        }
        if mapped[role as usize] {
            return Err(Error::Usage(format!(
                "--columns maps {} twice",
                role_name(role)
            )));
        }
        mapped[role as usize] = true;
        cols.idx[role as usize] = Some(i);
    }
    for (role, canon, names) in ROLES {
        if mapped[role as usize] {
            continue;
        }
        let hits: Vec<usize> = names.iter().flat_map(|n| find(n)).collect();
        match hits.len() {
            0 => {}
            1 => cols.idx[role as usize] = Some(hits[0]),
            _ => {
                return Err(input_err(
                    header_line,
                    &headers[hits[1]],
                    format!(
                        "columns {} can all be {canon}; choose one with --columns {canon}=NAME",
                        hits.iter()
                            .map(|&i| format!("'{}'", headers[i]))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ))
            }
        }
    }

    // The NIST layout, when no standard angle columns are named or mapped.
    let angle_mapped = mapped[Role::ThetaI as usize]
        || mapped[Role::ThetaR as usize]
        || mapped[Role::PhiR as usize];
    let mut nist: Option<Nist> = None;
    if !angle_mapped && cols.get(Role::ThetaI).is_none() && cols.get(Role::ThetaR).is_none() {
        let one = |n: &str| find(n).first().copied();
        if let (Some(ti), Some(tr), Some(pr)) = (one("thetai"), one("thetar"), one("phir")) {
            nist = Some(Nist {
                theta_i: ti,
                phi_i: one("phi").or_else(|| one("phii")),
                theta_r: tr,
                phi_r: pr,
            });
            if !mapped[Role::Value as usize] && cols.get(Role::Value).is_none() {
                cols.idx[Role::Value as usize] = one("f_r11").or_else(|| one("fr11"));
            }
            if !mapped[Role::Wavelength as usize] && cols.get(Role::Wavelength).is_none() {
                cols.idx[Role::Wavelength as usize] = one("lambda");
            }
        }
    }

    let first_row = match records.peek() {
        Some(Ok((_, f))) => f.join(","),
        _ => String::new(),
    };
    if let Some(m) = delimiter_hint(&headers, &first_row) {
        return Err(input_err(header_line, "(header)", m));
    }
    let missing = |what: &str, hint: &str| {
        input_err(
            header_line,
            what,
            format!(
                "missing column {what}{hint}; the header has: {}",
                headers.join(", ")
            ),
        )
    };
    if nist.is_none() {
        if cols.get(Role::ThetaI).is_none() {
            return Err(missing(
                "theta_i",
                " (name it theta_i or map it with --columns theta_i=NAME)",
            ));
        }
        if cols.get(Role::ThetaR).is_none() {
            return Err(missing(
                "theta_r",
                " (name it theta_r or map it with --columns theta_r=NAME)",
            ));
        }
        if cols.get(Role::PhiR).is_none() && !opts.signed_theta_r {
            return Err(missing(
                "phi_r",
                " (name it phi_r, map it with --columns phi_r=NAME, or for in-plane data with signed view angles use --signed-theta-r)",
            ));
        }
    }
    if opts.require_value && cols.get(Role::Value).is_none() {
        return Err(missing(
            "L",
            " (the measured value: name it L, value or brdf, or map it with --columns L=NAME)",
        ));
    }
    if cols.get(Role::Weight).is_some() && cols.get(Role::SigmaL).is_some() {
        return Err(input_err(
            header_line,
            "sigma_L",
            "both a weight and a sigma_L column: give one (weights are 1/sigma_L²)".into(),
        ));
    }

    // The rows.
    let n = rows_hint;
    let mut ds = Dataset {
        path: path.to_path_buf(),
        headers: headers.clone(),
        rows: Vec::with_capacity(if keep_rows { n } else { 0 }),
        lines: Vec::with_capacity(n),
        samples: Vec::with_capacity(n),
        value: cols.get(Role::Value).map(|_| Vec::with_capacity(n)),
        weight: cols
            .get(Role::Weight)
            .or(cols.get(Role::SigmaL))
            .map(|_| Vec::with_capacity(n)),
        sigma_l: cols.get(Role::SigmaL).map(|_| Vec::with_capacity(n)),
        wavelength: cols.get(Role::Wavelength).map(|_| Vec::with_capacity(n)),
        // Germer's files give lambda in µm and f_r11, a BRDF.
        wavelength_unit: (nist.is_some()
            && !mapped[Role::Wavelength as usize]
            && cols.get(Role::Wavelength).is_some())
        .then(|| "µm".to_string()),
        channel: cols.get(Role::Group).map(|_| Vec::with_capacity(n)),
        quantity: if nist.is_some() && !mapped[Role::Value as usize] {
            Some(crate::geometry::Quantity::Brdf)
        } else {
            cols.get(Role::Value)
                .and_then(|i| super::quantity::from_column_name(&headers[i]))
        },
    };
    for record in records {
        let (line, fields) = record?;
        if fields.len() != headers.len() {
            return Err(input_err(
                line,
                "(row)",
                format!(
                    "row has {} fields, the header on line {header_line} has {}{}",
                    fields.len(),
                    headers.len(),
                    if fields.len() > headers.len() {
                        decimal_comma_hint(&fields.join(","))
                    } else {
                        ""
                    }
                ),
            ));
        }
        let num = |i: usize| -> Result<f64> {
            parse_finite(&fields[i]).map_err(|m| input_err(line, &headers[i], m))
        };
        let sample: Sample = if let Some(nc) = &nist {
            let ti = num(nc.theta_i)?;
            let pi = match nc.phi_i {
                Some(i) => num(i)?,
                None => 0.0,
            };
            let tr = num(nc.theta_r)?;
            let pr = num(nc.phi_r)?;
            nist_sample(ti, pi, tr, pr, opts.radians).map_err(|(c, m)| {
                let i = match c {
                    "theta_i" => nc.theta_i,
                    "theta_r" => nc.theta_r,
                    "phi_i" => nc.phi_i.unwrap_or(nc.phi_r),
                    _ => nc.phi_r,
                };
                input_err(line, &headers[i], m)
            })?
        } else {
            let ti_c = cols.get(Role::ThetaI).unwrap_or(0);
            let tr_c = cols.get(Role::ThetaR).unwrap_or(0);
            let ti = num(ti_c)?;
            let tr = num(tr_c)?;
            let pr = match cols.get(Role::PhiR) {
                Some(i) => num(i)?,
                None => 0.0,
            };
            check_angles(ti, tr, pr, opts.radians, opts.signed_theta_r).map_err(|(c, m)| {
                let i = match c {
                    "theta_i" => ti_c,
                    "theta_r" => tr_c,
                    _ => cols.get(Role::PhiR).unwrap_or(tr_c),
                };
                input_err(line, &headers[i], m)
            })?
        };
        if let (Some(i), Some(v)) = (cols.get(Role::Value), ds.value.as_mut()) {
            v.push(num(i)?);
        }
        if let Some(i) = cols.get(Role::Weight) {
            let w = num(i)?;
            if w <= 0.0 {
                return Err(input_err(
                    line,
                    &headers[i],
                    format!("weight {} must be positive", fields[i]),
                ));
            }
            if let Some(v) = ds.weight.as_mut() {
                v.push(w);
            }
        }
        if let Some(i) = cols.get(Role::SigmaL) {
            let s = num(i)?;
            let w = 1.0 / (s * s);
            if s <= 0.0 || !w.is_finite() || w == 0.0 {
                return Err(input_err(
                    line,
                    &headers[i],
                    format!(
                        "sigma_L {} must be positive (and 1/sigma_L² finite)",
                        fields[i]
                    ),
                ));
            }
            if let Some(v) = ds.sigma_l.as_mut() {
                v.push(s);
            }
            if let Some(v) = ds.weight.as_mut() {
                v.push(w);
            }
        }
        if let Some(i) = cols.get(Role::Wavelength) {
            let l = num(i)?;
            if l <= 0.0 {
                return Err(input_err(
                    line,
                    &headers[i],
                    format!("wavelength {} must be positive", fields[i]),
                ));
            }
            if let Some(v) = ds.wavelength.as_mut() {
                v.push(l);
            }
        }
        if let Some(i) = cols.get(Role::Group) {
            if let Some(v) = ds.channel.as_mut() {
                v.push(fields[i].clone());
            }
        }
        ds.samples.push(sample);
        ds.lines.push(line);
        if keep_rows {
            ds.rows.push(fields);
        }
    }
    ds.shrink_to_fit();

    if opts.require_value {
        if let Some(v) = &ds.value {
            if v.iter().all(|&x| x == 0.0) {
                let i = cols.get(Role::Value).unwrap_or(0);
                return Err(input_err(
                    header_line,
                    &headers[i],
                    format!(
                        "all {} values are zero: nothing to fit (wrong column?)",
                        v.len()
                    ),
                ));
            }
        }
    }
    Ok(ds)
}

/// One CSV record: the 1-based line it starts on, and its fields.
pub type Record = (usize, Vec<String>);

/// The most fields a header may have ([`split_records`]); a data row may have at most as
/// many as its header. Rows are cut off at that many fields while they are read, so a
/// hostile line of millions of fields is refused without holding them (reading stays
/// O(file size) in memory).
pub const MAX_FIELDS: usize = 10_000;

/// Split CSV text into records, each with the 1-based line it starts on. Unquoted fields are
/// trimmed of surrounding blanks; quoted fields are kept verbatim.
/// Skips blank (or whitespace-only) lines and lines whose first non-blank character is `#`.
/// Fields may be quoted (`"a, b"`, `""` for a quote, line breaks inside); line ends are
/// `\n`, `\r\n` or `\r`. Errors: (line, message) for an unterminated quote or text after
/// a closing quote.
/// At most [`MAX_FIELDS`] fields per record.
pub fn split_records(text: &str) -> std::result::Result<Vec<Record>, (usize, String)> {
    split(text, MAX_FIELDS, false)
}

/// [`split_records`] for a table: at most `max_fields` fields in the header (the first
/// record) and at most the header's count in every later record; a longer record is an
/// error as soon as its field `max + 1` starts, so it is never held field by field.
pub fn split_records_limited(
    text: &str,
    max_fields: usize,
) -> std::result::Result<Vec<Record>, (usize, String)> {
    split(text, max_fields, true)
}

fn split(
    text: &str,
    max_fields: usize,
    rows_by_header: bool,
) -> std::result::Result<Vec<Record>, (usize, String)> {
    let b = text.as_bytes();
    let n = b.len();
    let mut i = 0;
    let mut line = 1;
    let mut out: Vec<Record> = Vec::new();
    // Consume one line end at i (if any); returns whether one was consumed.
    let eol = |i: &mut usize, line: &mut usize| -> bool {
        if *i < n && b[*i] == b'\r' {
            *i += 1;
            if *i < n && b[*i] == b'\n' {
                *i += 1;
            }
            *line += 1;
            true
        } else if *i < n && b[*i] == b'\n' {
            *i += 1;
            *line += 1;
            true
        } else {
            false
        }
    };
    while i < n {
        // Start of a line: blank or comment?
        let mut j = i;
        while j < n && (b[j] == b' ' || b[j] == b'\t') {
            j += 1;
        }
        if j >= n {
            break;
        }
        if b[j] == b'\n' || b[j] == b'\r' || b[j] == b'#' {
            i = j;
            while i < n && b[i] != b'\n' && b[i] != b'\r' {
                i += 1;
            }
            eol(&mut i, &mut line);
            continue;
        }
        let start_line = line;
        let record_start = j;
        let mut fields = Vec::new();
        loop {
            while i < n && (b[i] == b' ' || b[i] == b'\t') {
                i += 1;
            }
            if i < n && b[i] == b'"' {
                let quote_line = line;
                i += 1;
                let mut f = String::new();
                let mut seg = i;
                loop {
                    if i >= n {
                        return Err((quote_line, "a quoted field is never closed".into()));
                    }
                    if b[i] == b'"' {
                        f.push_str(&text[seg..i]);
                        if i + 1 < n && b[i + 1] == b'"' {
                            f.push('"');
                            i += 2;
                            seg = i;
                            continue;
                        }
                        i += 1;
                        break;
                    }
                    if b[i] == b'\n' || (b[i] == b'\r' && !(i + 1 < n && b[i + 1] == b'\n')) {
                        line += 1;
                    }
                    i += 1;
                }
                while i < n && (b[i] == b' ' || b[i] == b'\t') {
                    i += 1;
                }
                if i < n && !matches!(b[i], b',' | b'\n' | b'\r') {
                    let rest: String = text[i..].chars().take(20).collect();
                    return Err((
                        line,
                        format!("unexpected text '{rest}' after a closing quote"),
                    ));
                }
                fields.push(f);
            } else {
                let s0 = i;
                while i < n && !matches!(b[i], b',' | b'\n' | b'\r') {
                    i += 1;
                }
                fields.push(text[s0..i].trim().to_string());
            }
            if i < n && b[i] == b',' {
                i += 1;
                let limit = match out.first() {
                    Some(h) if rows_by_header => h.1.len(),
                    _ => max_fields,
                };
                if fields.len() >= limit {
                    let m = too_many_fields(&out, limit, &text[record_start..], rows_by_header);
                    return Err((start_line, m));
                }
                continue;
            }
            eol(&mut i, &mut line);
            break;
        }
        if fields.iter().any(|f| !f.is_empty()) {
            out.push((start_line, fields));
        }
    }
    Ok(out)
}

/// Records read one at a time from a byte stream: the streaming form of [`split_records`]
/// (same fields, same 1-based line numbers, same errors), holding one record's text at a
/// time instead of the whole file. A record is one line, or several when a quoted field
/// holds line breaks. Invalid UTF-8 is an error naming the line and the byte offset.
pub(crate) struct RecordStream<'p, R> {
    path: &'p Path,
    reader: R,
    /// Line number of the next line to read (1-based).
    line: usize,
    /// Bytes consumed so far after the byte-order mark (for the UTF-8 message).
    offset: usize,
    /// Whether the first chunk has been read (a byte-order mark is skipped there).
    started: bool,
    buf: Vec<u8>,
    queue: std::collections::VecDeque<Record>,
    failed: bool,
}

impl<'p, R: std::io::BufRead> RecordStream<'p, R> {
    pub(crate) fn new(path: &'p Path, reader: R) -> Self {
        RecordStream {
            path,
            reader,
            line: 1,
            offset: 0,
            started: false,
            buf: Vec::new(),
            queue: std::collections::VecDeque::new(),
            failed: false,
        }
    }

    /// Read the next chunk of whole records (at least one line) and split it; false at the
    /// end of the stream.
    fn fill(&mut self) -> Result<bool> {
        self.buf.clear();
        loop {
            let got = self
                .reader
                .read_until(b'\n', &mut self.buf)
                .map_err(|source| Error::Io {
                    path: self.path.to_path_buf(),
                    source,
                })?;
            if got == 0 || !ends_inside_quotes(&self.buf) {
                break;
            }
        }
        if self.buf.is_empty() {
            return Ok(false);
        }
        let mut start = 0;
        if !self.started && self.buf.starts_with(b"\xEF\xBB\xBF") {
            start = 3;
        }
        self.started = true;
        let chunk = &self.buf[start..];
        let text = std::str::from_utf8(chunk).map_err(|e| {
            let good = &chunk[..e.valid_up_to()];
            Error::input(
                self.path,
                self.line + good.iter().filter(|&&b| b == b'\n').count(),
                "(text)",
                format!(
                    "invalid UTF-8 at byte {} (save the file as UTF-8 text)",
                    self.offset + e.valid_up_to()
                ),
            )
        })?;
        let first = self.line;
        let records = split_records(text)
            .map_err(|(l, m)| Error::input(self.path, first + l - 1, "(row)", m))?;
        self.queue
            .extend(records.into_iter().map(|(l, f)| (first + l - 1, f)));
        self.line += line_ends(chunk);
        self.offset += chunk.len();
        Ok(true)
    }
}

impl<R: std::io::BufRead> Iterator for RecordStream<'_, R> {
    type Item = Result<Record>;

    fn next(&mut self) -> Option<Result<Record>> {
        while self.queue.is_empty() && !self.failed {
            match self.fill() {
                Ok(true) => {}
                Ok(false) => return None,
                Err(e) => {
                    self.failed = true;
                    return Some(Err(e));
                }
            }
        }
        self.queue.pop_front().map(Ok)
    }
}

/// Line ends as [`split_records`] counts them: `\n`, `\r\n`, and a lone `\r`.
fn line_ends(b: &[u8]) -> usize {
    (0..b.len())
        .filter(|&i| b[i] == b'\n' || (b[i] == b'\r' && b.get(i + 1) != Some(&b'\n')))
        .count()
}

/// Whether the text ends inside a quoted field, by the rules of [`split_records`]: a quote
/// opens a field only at its start (after blanks), `""` inside is a quote, and a line whose
/// first non-blank character is `#` is a comment.
fn ends_inside_quotes(b: &[u8]) -> bool {
    let mut i = 0;
    let mut field_start = true;
    let mut line_start = true;
    while i < b.len() {
        if line_start {
            let mut j = i;
            while j < b.len() && (b[j] == b' ' || b[j] == b'\t') {
                j += 1;
            }
            if b.get(j) == Some(&b'#') {
                while j < b.len() && b[j] != b'\n' && b[j] != b'\r' {
                    j += 1;
                }
            }
            i = j;
            line_start = false;
            continue;
        }
        match b[i] {
            b' ' | b'\t' if field_start => i += 1,
            b'"' if field_start => {
                i += 1;
                loop {
                    if i >= b.len() {
                        return true;
                    }
                    if b[i] == b'"' {
                        if b.get(i + 1) == Some(&b'"') {
                            i += 2;
                            continue;
                        }
                        i += 1;
                        break;
                    }
                    i += 1;
                }
                field_start = false;
            }
            b',' => {
                field_start = true;
                i += 1;
            }
            b'\n' | b'\r' => {
                field_start = true;
                line_start = true;
                i += 1;
            }
            _ => {
                field_start = false;
                i += 1;
            }
        }
    }
    false
}

/// The message for a record cut off after `limit` fields; `line_text` is the record's
/// first line (from its first field on), `rows_by_header` whether `limit` is the header's
/// count.
fn too_many_fields(out: &[Record], limit: usize, line_text: &str, rows_by_header: bool) -> String {
    let line_text = line_text.split(['\n', '\r']).next().unwrap_or("");
    match out.first() {
        None => format!(
            "the header has more than {limit} fields (a measurement table has a few columns)"
        ),
        Some((line, header)) if rows_by_header => {
            if let Some(m) = delimiter_hint(header, line_text) {
                return m;
            }
            // The count (exact for unquoted fields) without holding the fields.
            let count = 1 + line_text.matches(',').count();
            format!(
                "row has {count} fields, the header on line {line} has {limit}{}",
                decimal_comma_hint(line_text)
            )
        }
        Some(_) => format!("a record has more than {limit} fields"),
    }
}

/// A hint when `text` looks like numbers written with decimal commas (`0,5`): a comma
/// between digits and no decimal point anywhere.
pub(crate) fn decimal_comma_hint(text: &str) -> &'static str {
    let b = text.as_bytes();
    let comma_between_digits = !text.contains('.')
        && (1..b.len().saturating_sub(1))
            .any(|k| b[k] == b',' && b[k - 1].is_ascii_digit() && b[k + 1].is_ascii_digit());
    if comma_between_digits {
        " (decimal commas? goniofit reads numbers with a decimal point, 0.5 not 0,5, and commas between fields)"
    } else {
        ""
    }
}

/// When a one-field header holds `;`, a tab or `|`: the message naming that delimiter
/// (goniofit reads only commas).
fn delimiter_hint(headers: &[String], row_text: &str) -> Option<String> {
    if headers.len() != 1 {
        return None;
    }
    let h = &headers[0];
    let (name, _) = [(";", ';'), ("tab", '\t'), ("|", '|')]
        .into_iter()
        .find(|(_, c)| h.contains(*c))?;
    let decimal = if decimal_comma_hint(row_text).is_empty() {
        ""
    } else {
        " with decimal commas"
    };
    Some(format!(
        "the header is one field '{}': the file seems to be separated by '{name}'{decimal}; goniofit reads comma-separated values with a decimal point (convert the file, e.g. save it as CSV with ',' between fields and '.' in numbers)",
        super::shown_text(h)
    ))
}

/// Convert NIST-convention angles (absolute azimuths of outward directions; θi < 0 puts the
/// source at φi + 180°) to ours.
fn nist_sample(
    theta_i: f64,
    phi_i: f64,
    theta_r: f64,
    phi_r: f64,
    radians: bool,
) -> std::result::Result<Sample, (&'static str, String)> {
    let half = if radians { std::f64::consts::PI } else { 180.0 };
    let full = 2.0 * half;
    if phi_i.abs() > full * (1.0 + 1e-12) {
        let unit = if radians { " rad" } else { "°" };
        return Err((
            "phi_i",
            format!("phi = {phi_i}{unit} is outside [-{full}{unit}, {full}{unit}]"),
        ));
    }
    let phi_source = if theta_i < 0.0 { phi_i + half } else { phi_i };
    // Relative azimuth from the mirror direction, wrapped to (−half, half].
    let mut rel = (phi_r - phi_source - half) % full;
    if rel <= -half {
        rel += full;
    } else if rel > half {
        rel -= full;
    }
    check_angles(theta_i.abs(), theta_r, rel, radians, false)
}

#[cfg(test)]
mod stream_tests {
    use super::*;

    /// The streamed records equal [`split_records`]'s, line numbers and errors included,
    /// whatever the chunking (one line at a time here).
    #[test]
    fn record_stream_matches_split_records() {
        let texts = [
            "a,b\n1,2\n",
            "a,b\r\n1,2\r\n\r\n# c, \"open\n3,4",
            "\u{feff}a,b\n\"x\ny\",2\n  # \"q\n\"a\"\"b\", 3\n",
            "a,\"b\n\nc\",d\n1,2,3\n",
            "h\r1\r2\r",
            "a,b\n\"never closed\n1,2\n",
            "a,b\n\"x\" y,2\n",
            "a,b\n1,\"2\" \n  \n3 , 4\n",
            "",
        ];
        let path = Path::new("t.csv");
        for text in texts {
            let body = text.strip_prefix('\u{feff}').unwrap_or(text);
            let want = split_records(body);
            let got: std::result::Result<Vec<Record>, (usize, String)> =
                RecordStream::new(path, std::io::BufReader::with_capacity(4, text.as_bytes()))
                    .map(|r| {
                        r.map_err(|e| match e {
                            Error::Input { line, message, .. } => (line, message),
                            e => (0, e.to_string()),
                        })
                    })
                    .collect();
            assert_eq!(got, want, "{text:?}");
        }
    }

    #[test]
    fn record_stream_names_the_line_of_invalid_utf8() {
        let bytes = b"a,b\n1,2\n3,\xff\n";
        let err = RecordStream::new(Path::new("t.csv"), &bytes[..])
            .find_map(|r| r.err())
            .expect("an error");
        match err {
            Error::Input { line, message, .. } => {
                assert_eq!(line, 3);
                assert!(message.contains("at byte 10"), "{message}");
            }
            e => panic!("unexpected error {e}"),
        }
    }
}
