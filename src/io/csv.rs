//! CSV measurement tables.
//!
//! A header row names the columns (case-insensitive, surrounding whitespace ignored):
//!
//! | role | header names | meaning |
//! |---|---|---|
//! | `theta_i` | `theta_i` | incidence angle from the normal |
//! | `theta_r` | `theta_r` | view angle from the normal |
//! | `phi_r` | `phi_r` | view azimuth from the plane of incidence, 0 = forward/specular side |
//! | `L` | `L` or `value` | measured radiance (or BRDF) |
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
    (Role::Value, "L", &["l", "value"]),
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
    let input_err = |line, column: &str, message| Error::input(path, line, column, message);
    let file_err = |message| Error::file(path, message);

    let mut records = split_records(text)
        .map_err(|(line, m)| input_err(line, "(row)", m))?
        .into_iter();
    let Some((header_line, headers)) = records.next() else {
        return Err(file_err(
            "empty file: no header row (expected e.g. theta_i,theta_r,phi_r,L)".into(),
        ));
    };
    let records: Vec<Record> = records.collect();
    if records.is_empty() {
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
            " (the measured value: name it L or value, or map it with --columns L=NAME)",
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
    let n = records.len();
    let mut ds = Dataset {
        path: path.to_path_buf(),
        headers: headers.clone(),
        rows: Vec::with_capacity(n),
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
        quantity: (nist.is_some() && !mapped[Role::Value as usize])
            .then_some(crate::geometry::Quantity::Brdf),
    };
    for (line, fields) in records {
        if fields.len() != headers.len() {
            return Err(input_err(
                line,
                "(row)",
                format!(
                    "row has {} fields, the header on line {header_line} has {}",
                    fields.len(),
                    headers.len()
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
        ds.rows.push(fields);
    }

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

/// Split CSV text into records, each with the 1-based line it starts on. Unquoted fields are
/// trimmed of surrounding blanks; quoted fields are kept verbatim.
/// Skips blank (or whitespace-only) lines and lines whose first non-blank character is `#`.
/// Fields may be quoted (`"a, b"`, `""` for a quote, line breaks inside); line ends are
/// `\n`, `\r\n` or `\r`. Errors: (line, message) for an unterminated quote or text after
/// a closing quote.
pub fn split_records(text: &str) -> std::result::Result<Vec<Record>, (usize, String)> {
    let b = text.as_bytes();
    let n = b.len();
    let mut i = 0;
    let mut line = 1;
    let mut out = Vec::new();
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
