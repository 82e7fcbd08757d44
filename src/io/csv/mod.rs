//! CSV measurement tables.
//!
//! A header row names the columns (case-insensitive, surrounding whitespace ignored):
//!
//! | role | header names | meaning |
//! |---|---|---|
//! | `theta_i` | `theta_i` | incidence angle from the normal |
//! | `theta_r` | `theta_r` | view angle from the normal |
//! | `phi_r` | `phi_r` | view azimuth from the plane of incidence, 0 = forward/specular side |
//! | `L` | `L`, `value` or `brdf` | measured radiance (or BRDF: a column named `brdf`, or a `# quantity: brdf` comment before the header, states a BRDF; see `io::quantity`) |
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
//! Records are split by the `csv` crate's parser with a measurement file's rules on top
//! ([`split_records`]): lines whose first non-blank character is `#` are comments; blank
//! lines, CRLF line ends, a UTF-8 byte-order mark and quoted fields (a field is quoted when
//! its first character is `"`) are accepted; unquoted fields are trimmed. A `weight` and a
//! `sigma_L` column together are an error (one of them decides the weights). With
//! `require_value`, a file whose values are all zero is an error (nothing to fit).
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

mod plain;
mod records;

pub(crate) use plain::parse_plain;
#[cfg(test)]
pub(crate) use records::{split_records, split_records_limited};
pub(crate) use records::{Fault, Limit, Records};
pub(crate) use records::{Record, MAX_FIELDS};

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
pub(crate) const ROLE_NAMES: [&str; 8] = [
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

/// Parse a CSV table (text already decoded, BOM removed). Every record is split before
/// any is interpreted, so a malformed record anywhere is the error reported.
pub(crate) fn parse(path: &Path, text: &str, opts: &ReadOptions) -> Result<Dataset> {
    let records = Records::new(text.as_bytes(), Limit::Table(MAX_FIELDS))
        .collect::<std::result::Result<Vec<Record>, Fault>>()
        .map_err(|f| fault_error(path, f))?;
    let n = records.len();
    parse_records(path, records.into_iter().map(Ok), opts, true, n)
}

/// Parse a CSV table streamed from `reader` record by record ([`Records`]): the text is
/// never held whole, and the raw rows are kept only with `keep_rows` (the fit needs them
/// only for its residuals file). `rows_hint` sizes the columns (an estimate; 0 is fine).
pub(crate) fn parse_reader(
    path: &Path,
    reader: impl std::io::BufRead,
    opts: &ReadOptions,
    keep_rows: bool,
    rows_hint: usize,
) -> Result<Dataset> {
    let records =
        Records::new(reader, Limit::Table(MAX_FIELDS)).map(|r| r.map_err(|f| fault_error(path, f)));
    parse_records(path, records, opts, keep_rows, rows_hint)
}

/// A record fault as the reader's error: malformed CSV on its line (column `(row)`),
/// bytes that are not UTF-8 (column `(text)`), or the read's I/O error.
fn fault_error(path: &Path, fault: Fault) -> Error {
    match fault {
        Fault::Row(line, m) => Error::input(path, line, "(row)", m),
        Fault::Text(line, m) => Error::input(path, line, "(text)", m),
        Fault::Io(source) => Error::Io {
            path: path.to_path_buf(),
            source,
        },
    }
}

/// Parse CSV records (header first) into a dataset; see the module docs. The stages: the
/// header's columns ([`map_columns`], the NIST layout), their checks, then every record.
fn parse_records(
    path: &Path,
    records: impl Iterator<Item = Result<Record>>,
    opts: &ReadOptions,
    keep_rows: bool,
    rows_hint: usize,
) -> Result<Dataset> {
    let mut records = records.peekable();
    let Some((header_line, headers)) = records.next().transpose()? else {
        return Err(Error::file(
            path,
            "empty file: no header row (expected e.g. theta_i,theta_r,phi_r,L)".into(),
        ));
    };
    if records.peek().is_none() {
        return Err(Error::file(
            path,
            format!("no data rows after the header on line {header_line}"),
        ));
    }
    let table = Table::of(path, header_line, &headers, opts)?;
    let first_row = match records.peek() {
        Some(Ok((_, f))) => f.join(","),
        _ => String::new(),
    };
    table.check(path, &first_row, opts)?;
    let mut ds = table.empty_dataset(path, keep_rows, rows_hint);
    for record in records {
        let (line, fields) = record?;
        table.push_record(path, opts, (line, &fields), &mut ds, keep_rows)?;
    }
    table.finish(path, opts, ds)
}

/// Fields joined by commas (as a message shows a record).
fn joined<F: AsRef<str>>(fields: &[F]) -> String {
    let parts: Vec<&str> = fields.iter().map(AsRef::as_ref).collect();
    parts.join(",")
}

/// What the header says about the table: its columns' roles, which `--columns` mapped, and
/// the NIST layout when the file is one.
struct Table<'h> {
    header_line: usize,
    headers: &'h [String],
    cols: Columns,
    mapped: [bool; 8],
    nist: Option<Nist>,
}

/// The header's columns named `name` (trimmed, case-insensitive).
fn find_column(headers: &[String], name: &str) -> Vec<usize> {
    headers
        .iter()
        .enumerate()
        .filter(|(_, h)| h.trim().eq_ignore_ascii_case(name.trim()))
        .map(|(i, _)| i)
        .collect()
}

/// The columns of each role: first those `--columns` maps, then the usual names; a role
/// that two columns could fill is an error naming both.
fn map_columns(
    path: &Path,
    header_line: usize,
    headers: &[String],
    opts: &ReadOptions,
) -> Result<(Columns, [bool; 8])> {
    let input_err = |column: &str, message| Error::input(path, header_line, column, message);
    let mut cols = Columns::default();
    let mut mapped = [false; 8];
    for (role_text, name) in &opts.columns {
        let role = parse_role(role_text).ok_or_else(|| {
            Error::Usage(format!(
                "--columns: unknown role '{role_text}' (roles: {})",
                ROLE_NAMES.join(", ")
            ))
        })?;
        let hits = find_column(headers, name);
        let Some(&i) = hits.first() else {
            let m = format!(
                "no column named '{name}' (mapped to {} by --columns); the header has: {}",
                role_name(role),
                headers.join(", ")
            );
            return Err(input_err(name, m));
        };
        if hits.len() > 1 {
            let m = format!("the header names '{name}' {} times", hits.len());
            return Err(input_err(name, m));
        }
        if mapped[role as usize] {
            let m = format!("--columns maps {} twice", role_name(role));
            return Err(Error::Usage(m));
        }
        mapped[role as usize] = true;
        cols.idx[role as usize] = Some(i);
    }
    for (role, canon, names) in ROLES {
        if mapped[role as usize] {
            continue;
        }
        let hits: Vec<usize> = names.iter().flat_map(|n| find_column(headers, n)).collect();
        match hits.len() {
            0 => {}
            1 => cols.idx[role as usize] = Some(hits[0]),
            _ => {
                let named: Vec<String> =
                    hits.iter().map(|&i| format!("'{}'", headers[i])).collect();
                let m = format!(
                    "columns {} can all be {canon}; choose one with --columns {canon}=NAME",
                    named.join(", ")
                );
                return Err(input_err(&headers[hits[1]], m));
            }
        }
    }
    Ok((cols, mapped))
}

impl<'h> Table<'h> {
    /// The table of a header: its columns, and the NIST layout when no standard angle
    /// columns are named or mapped and its `thetai`, `thetar`, `phir` columns are there.
    fn of(
        path: &Path,
        header_line: usize,
        headers: &'h [String],
        opts: &ReadOptions,
    ) -> Result<Self> {
        let (mut cols, mapped) = map_columns(path, header_line, headers, opts)?;
        let angle_mapped = mapped[Role::ThetaI as usize]
            || mapped[Role::ThetaR as usize]
            || mapped[Role::PhiR as usize];
        let mut nist: Option<Nist> = None;
        if !angle_mapped && cols.get(Role::ThetaI).is_none() && cols.get(Role::ThetaR).is_none() {
            let one = |n: &str| find_column(headers, n).first().copied();
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
        Ok(Table {
            header_line,
            headers,
            cols,
            mapped,
            nist,
        })
    }

    /// The columns a read needs are there (angles, the value when required) and do not
    /// contradict each other; a header that looks split by the wrong delimiter says so.
    fn check(&self, path: &Path, first_row: &str, opts: &ReadOptions) -> Result<()> {
        let (headers, cols) = (self.headers, &self.cols);
        let input_err =
            |column: &str, message| Error::input(path, self.header_line, column, message);
        if let Some(m) = delimiter_hint(headers, first_row) {
            return Err(input_err("(header)", m));
        }
        let missing = |what: &str, hint: &str| {
            let m = format!(
                "missing column {what}{hint}; the header has: {}",
                headers.join(", ")
            );
            input_err(what, m)
        };
        if self.nist.is_none() {
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
                "sigma_L",
                "both a weight and a sigma_L column: give one (weights are 1/sigma_L²)".into(),
            ));
        }
        Ok(())
    }

    /// A dataset with the table's columns and room for `n` rows.
    fn empty_dataset(&self, path: &Path, keep_rows: bool, n: usize) -> Dataset {
        let (cols, nist) = (&self.cols, self.nist.is_some());
        let with = |r: Role| cols.get(r).map(|_| Vec::with_capacity(n));
        Dataset {
            path: path.to_path_buf(),
            headers: self.headers.to_vec(),
            rows: Vec::with_capacity(if keep_rows { n } else { 0 }),
            lines: Vec::with_capacity(n),
            samples: Vec::with_capacity(n),
            value: with(Role::Value),
            weight: cols
                .get(Role::Weight)
                .or(cols.get(Role::SigmaL))
                .map(|_| Vec::with_capacity(n)),
            sigma_l: with(Role::SigmaL),
            wavelength: with(Role::Wavelength),
            // Germer's files give lambda in µm and f_r11, a BRDF.
            wavelength_unit: (nist
                && !self.mapped[Role::Wavelength as usize]
                && cols.get(Role::Wavelength).is_some())
            .then(|| "µm".to_string()),
            wavelength_origin: None,
            channel: cols.get(Role::Group).map(|_| Vec::with_capacity(n)),
            quantity: if nist && !self.mapped[Role::Value as usize] {
                Some(crate::geometry::Quantity::Brdf)
            } else {
                cols.get(Role::Value)
                    .and_then(|i| super::quantity::from_column_name(&self.headers[i]))
            },
        }
    }

    /// The dataset read, its columns trimmed to size; with `require_value`, values that
    /// are all zero are an error on the header line (nothing to fit).
    fn finish(&self, path: &Path, opts: &ReadOptions, mut ds: Dataset) -> Result<Dataset> {
        ds.shrink_to_fit();
        if opts.require_value {
            if let Some(v) = &ds.value {
                if v.iter().all(|&x| x == 0.0) {
                    let i = self.cols.get(Role::Value).unwrap_or(0);
                    let m = format!(
                        "all {} values are zero: nothing to fit (wrong column?)",
                        v.len()
                    );
                    return Err(Error::input(path, self.header_line, &self.headers[i], m));
                }
            }
        }
        Ok(ds)
    }

    /// Read one record (`line`, `fields`) into `ds`: its sample and the columns the table
    /// has, each checked (weights, σ_L and wavelengths positive).
    fn push_record<F: AsRef<str>>(
        &self,
        path: &Path,
        opts: &ReadOptions,
        (line, fields): (usize, &[F]),
        ds: &mut Dataset,
        keep_rows: bool,
    ) -> Result<()> {
        let headers = self.headers;
        let input_err = |column: &str, message| Error::input(path, line, column, message);
        if fields.len() != headers.len() {
            let hint = if fields.len() > headers.len() {
                decimal_comma_hint(&joined(fields))
            } else {
                ""
            };
            let m = format!(
                "row has {} fields, the header on line {} has {}{hint}",
                fields.len(),
                self.header_line,
                headers.len(),
            );
            return Err(input_err("(row)", m));
        }
        let num = |i: usize| -> Result<f64> {
            parse_finite(fields[i].as_ref()).map_err(|m| input_err(&headers[i], m))
        };
        let sample = self
            .sample(&num, opts)
            .map_err(|(i, m)| input_err(&headers[i], m))?;
        let positive = |i: usize, what: &str| -> Result<f64> {
            let v = num(i)?;
            match v > 0.0 {
                true => Ok(v),
                false => Err(input_err(
                    &headers[i],
                    format!("{what} {} must be positive", fields[i].as_ref()),
                )),
            }
        };
        if let (Some(i), Some(v)) = (self.cols.get(Role::Value), ds.value.as_mut()) {
            v.push(num(i)?);
        }
        if let (Some(i), Some(v)) = (self.cols.get(Role::Weight), ds.weight.as_mut()) {
            v.push(positive(i, "weight")?);
        }
        if let Some(i) = self.cols.get(Role::SigmaL) {
            let s = num(i)?;
            let w = 1.0 / (s * s);
            if s <= 0.0 || !w.is_finite() || w == 0.0 {
                let m = format!(
                    "sigma_L {} must be positive (and 1/sigma_L² finite)",
                    fields[i].as_ref()
                );
                return Err(input_err(&headers[i], m));
            }
            if let (Some(sv), Some(wv)) = (ds.sigma_l.as_mut(), ds.weight.as_mut()) {
                sv.push(s);
                wv.push(w);
            }
        }
        if let (Some(i), Some(v)) = (self.cols.get(Role::Wavelength), ds.wavelength.as_mut()) {
            v.push(positive(i, "wavelength")?);
        }
        if let (Some(i), Some(v)) = (self.cols.get(Role::Group), ds.channel.as_mut()) {
            v.push(fields[i].as_ref().to_string());
        }
        ds.samples.push(sample);
        ds.lines.push(line);
        if keep_rows {
            ds.rows
                .push(fields.iter().map(|f| f.as_ref().to_string()).collect());
        }
        Ok(())
    }

    /// A record's sample from its angle columns (`num` reads column i), checked; an error
    /// names the column at fault.
    fn sample(
        &self,
        num: &dyn Fn(usize) -> Result<f64>,
        opts: &ReadOptions,
    ) -> std::result::Result<Sample, (usize, String)> {
        let read = |i: usize| num(i).map_err(|e| (i, input_message(e)));
        if let Some(nc) = &self.nist {
            let ti = read(nc.theta_i)?;
            let pi = nc.phi_i.map_or(Ok(0.0), read)?;
            let (tr, pr) = (read(nc.theta_r)?, read(nc.phi_r)?);
            return nist_sample(ti, pi, tr, pr, opts.radians).map_err(|(c, m)| {
                let i = match c {
                    "theta_i" => nc.theta_i,
                    "theta_r" => nc.theta_r,
                    "phi_i" => nc.phi_i.unwrap_or(nc.phi_r),
                    _ => nc.phi_r,
                };
                (i, m)
            });
        }
        let ti_c = self.cols.get(Role::ThetaI).unwrap_or(0);
        let tr_c = self.cols.get(Role::ThetaR).unwrap_or(0);
        let (ti, tr) = (read(ti_c)?, read(tr_c)?);
        let pr = self.cols.get(Role::PhiR).map_or(Ok(0.0), read)?;
        check_angles(ti, tr, pr, opts.radians, opts.signed_theta_r).map_err(|(c, m)| {
            let i = match c {
                "theta_i" => ti_c,
                "theta_r" => tr_c,
                _ => self.cols.get(Role::PhiR).unwrap_or(tr_c),
            };
            (i, m)
        })
    }
}

/// The message of a value's error, for re-locating it at its column.
fn input_message(e: Error) -> String {
    match e {
        Error::Input { message, .. } => message,
        other => other.to_string(),
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
