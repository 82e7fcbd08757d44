//! ASTM E1392-style BRDF files (as published by Cornell's Light Measurement Lab).
//!
//! Layout: key/value header lines (`LAB_NAME ...`, `NUM_POINTS 1439`, ...), a `VARS` line
//! naming the comma-separated columns, then one data row per geometry:
//!
//! ```text
//! VARS theta_i,phi_i,theta_s,phi_s,400nm,410nm,...,700nm
//! 0.872665,0.000000,0.573513,0.000000,0.023025,...
//! ```
//!
//! Angles are radians (whatever [`ReadOptions::radians`] says); `--columns` does not apply.
//! Values are BRDF in 1/sr. Data rows may be separated by commas or whitespace. `#` lines
//! and blank lines are skipped. When `NUM_POINTS` is given, the number of data rows must
//! match it (a truncated file is an error, not a smaller dataset).
//!
//! Azimuth convention (verified on the Cornell files: at every θi the largest value sits at
//! φs = 180°, θs ≈ θi): φi and φs are azimuths of direction vectors pointing *away* from the
//! surface, so the mirror direction of a source at φi is φs = φi + 180°. In our convention
//! (specular at φr = 0):
//!
//! ```text
//! θi := theta_i,  θr := theta_s,  φr := wrap(phi_s − phi_i − π)  ∈ (−π, π]
//! ```
//!
//! With `signed_theta_r`, a negative θs means |θs| at φs + π (and likewise a negative θi
//! means |θi| at φi + π); otherwise negative polar angles are errors.
//!
//! Channels are the VARS names after the four angles. A channel name with a wavelength
//! (`550nm`, `0.55um`) gives the per-sample wavelength in nm. `channel: Some("550nm")` reads
//! that channel; `Some("all")` reads every channel, one sample per (row, channel), labelled;
//! `None` is fine for a one-channel file and an error listing the channels otherwise.
//!
//! Missing values: a value field that is empty or not a finite number is an error naming
//! line, channel and value (E1392 has no missing-value marker; silently dropping rows would
//! bias a fit). Exact zeros (a clipped noise floor, common in these files) are kept.
//!
//! The dataset's pass-through table has the columns `theta_i, phi_i, theta_s, phi_s`
//! (the VARS names), `channel` and the measured quantity (the `MEAS_NAME`, e.g. `BRDF`, or
//! `value`), one row per sample.

use super::{
    check_angles, parse_finite, shown, shown_text, wavelength_nm_of_channel, Dataset, ReadOptions,
};
use crate::error::{Error, Result};
use std::f64::consts::PI;
use std::path::Path;

/// Whether `token` looks like an ASTM header key (upper-case letters, digits, `_`, starting
/// with a letter), e.g. `LAB_NAME`, `NUM_POINTS`, `VARS`.
pub(crate) fn is_key(token: &str) -> bool {
    let mut chars = token.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_uppercase())
        && chars.all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        && !token.eq_ignore_ascii_case("nan")
        && !token.eq_ignore_ascii_case("inf")
}

/// Split a data row on commas, or on whitespace when it has no comma; `Err(())` as soon as
/// it has more than `max` fields (so a hostile line is never held field by field).
fn split_row(line: &str, max: usize) -> std::result::Result<Vec<&str>, ()> {
    let mut out = Vec::new();
    let mut push = |f| {
        if out.len() == max {
            return Err(());
        }
        out.push(f);
        Ok(())
    };
    if line.contains(',') {
        line.split(',').map(str::trim).try_for_each(&mut push)?;
    } else {
        line.split_whitespace().try_for_each(&mut push)?;
    }
    Ok(out)
}

/// The parsed header of an ASTM file.
#[derive(Debug, Clone, Default)]
pub(crate) struct Header {
    /// Key/value pairs in file order (VARS included).
    pub keys: Vec<(String, String)>,
    /// Column names from VARS.
    pub vars: Vec<String>,
    /// 1-based line of VARS.
    pub vars_line: usize,
    /// Every key line: key, 1-based line, value (for messages about repeated keys).
    lines: Vec<(String, usize, String)>,
}

/// Refuse VARS lines that name a column twice (case-insensitively, as columns are found):
/// `--channel all` would merge two columns under one name and one scale.
fn check_vars(path: &Path, line: usize, vars: &[String]) -> Result<()> {
    for (j, v) in vars.iter().enumerate() {
        if let Some(i) = vars[..j].iter().position(|u| u.eq_ignore_ascii_case(v)) {
            return Err(Error::input(
                path,
                line,
                v,
                format!(
                    "VARS names column '{}' twice (columns {} and {}): each channel needs its own name",
                    shown_text(v),
                    i + 1,
                    j + 1
                ),
            ));
        }
    }
    Ok(())
}

impl Header {
    /// The value of a header key (first occurrence, case-sensitive as in the standard).
    pub(crate) fn get(&self, key: &str) -> Option<&str> {
        self.keys
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// Parse an ASTM file (text already decoded, BOM removed): the header, the columns it
/// names, the row count it states, then every data row.
pub(crate) fn parse(path: &Path, text: &str, opts: &ReadOptions) -> Result<Dataset> {
    let (header, data) = split_header(path, text)?;
    let cols = columns(path, &header, opts)?;
    if data.is_empty() {
        return Err(Error::file(
            path,
            format!(
                "no data rows after the VARS line (line {})",
                header.vars_line
            ),
        ));
    }
    check_row_count(path, text, &header, data.len())?;
    let mut ds = empty_dataset(path, &header, &cols, data.len());
    for (line_no, line) in data {
        push_row(path, (&header, &cols), opts, (line_no, line), &mut ds)?;
    }
    if opts.require_value {
        if let Some(v) = &ds.value {
            if v.iter().all(|&x| x == 0.0) {
                return Err(Error::file(
                    path,
                    format!(
                        "all {} values of the selected channel(s) are zero: nothing to fit",
                        v.len()
                    ),
                ));
            }
        }
    }
    Ok(ds)
}

/// The header (KEY value lines up to and with VARS) and the data lines after it (1-based
/// line number, trimmed text); blank and `#` lines are skipped.
fn split_header<'t>(path: &Path, text: &'t str) -> Result<(Header, Vec<(usize, &'t str)>)> {
    let mut header = Header::default();
    let mut data: Vec<(usize, &str)> = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line_no = k + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let first = line.split_whitespace().next().unwrap_or("");
        if data.is_empty() && is_key(first) && !first.contains(',') {
            header_line(
                path,
                &mut header,
                line_no,
                first,
                line[first.len()..].trim(),
            )?;
            continue;
        }
        if header.vars.is_empty() {
            return Err(Error::input(
                path,
                line_no,
                "(header)",
                format!(
                    "'{}' before the VARS line (an ASTM E1392 header of KEY value lines ending with VARS is expected)",
                    clip(line)
                ),
            ));
        }
        data.push((line_no, line));
    }
    if header.keys.is_empty() && data.is_empty() {
        return Err(Error::file(path, "empty file: no ASTM header".into()));
    }
    if header.vars.is_empty() {
        return Err(Error::file(
            path,
            "no VARS line (expected e.g. VARS theta_i,phi_i,theta_s,phi_s,550nm)".into(),
        ));
    }
    Ok((header, data))
}

/// Add the header line `key value` at `line_no` to `header` (VARS: its column names, once;
/// NUM_POINTS: not contradicting an earlier one).
fn header_line(
    path: &Path,
    header: &mut Header,
    line_no: usize,
    key: &str,
    value: &str,
) -> Result<()> {
    let input_err = |column: &str, message| Error::input(path, line_no, column, message);
    if key == "VARS" {
        if !header.vars.is_empty() {
            return Err(input_err("VARS", "a second VARS line".into()));
        }
        let max = super::csv::MAX_FIELDS;
        header.vars = split_row(value, max)
            .map_err(|_| {
                input_err(
                    "VARS",
                    format!("more than {max} column names (a BRDF file has a few dozen)"),
                )
            })?
            .into_iter()
            .filter(|v| !v.is_empty())
            .map(str::to_string)
            .collect();
        header.vars_line = line_no;
        check_vars(path, line_no, &header.vars)?;
    }
    if let Some((_, earlier, old)) = header.lines.iter().find(|(k, _, _)| k == key) {
        if key == "NUM_POINTS" && old != value {
            return Err(input_err(
                "NUM_POINTS",
                format!(
                    "a second NUM_POINTS line says '{value}', line {earlier} said '{old}': which is the row count?"
                ),
            ));
        }
    }
    header
        .lines
        .push((key.to_string(), line_no, value.to_string()));
    header.keys.push((key.to_string(), value.to_string()));
    Ok(())
}

/// The columns of an ASTM file: the four angles, the channels selected, their wavelengths.
struct Columns {
    /// θi, φi, θs, φs.
    angles: [usize; 4],
    selected: Vec<usize>,
    /// Each selected channel's wavelength in nm, from its name.
    wavelength: Vec<Option<f64>>,
}

/// The angle columns VARS names, and the value columns `opts.channel` selects (one
/// channel needs no choice).
fn columns(path: &Path, header: &Header, opts: &ReadOptions) -> Result<Columns> {
    let vars = &header.vars;
    let find = |names: &[&str]| {
        vars.iter()
            .position(|v| names.iter().any(|n| v.eq_ignore_ascii_case(n)))
    };
    let separator = match vars.as_slice() {
        [one] if one.contains(';') => {
            " (the names seem to be separated by ';': ASTM files use commas or blanks)"
        }
        [one] if one.contains('|') => {
            " (the names seem to be separated by '|': ASTM files use commas or blanks)"
        }
        _ => "",
    };
    let missing = |what: &str| {
        let have = vars.join(", ");
        let m = format!("VARS has no {what} column (it has: {have}){separator}");
        Error::input(path, header.vars_line, what, m)
    };
    let angles = [
        find(&["theta_i"]).ok_or_else(|| missing("theta_i"))?,
        find(&["phi_i"]).ok_or_else(|| missing("phi_i"))?,
        find(&["theta_s", "theta_r"]).ok_or_else(|| missing("theta_s"))?,
        find(&["phi_s", "phi_r"]).ok_or_else(|| missing("phi_s"))?,
    ];
    let channels: Vec<usize> = (0..vars.len()).filter(|i| !angles.contains(i)).collect();
    if channels.is_empty() {
        return Err(Error::input(
            path,
            header.vars_line,
            "VARS",
            "no value column after the angles (expected e.g. 550nm)".into(),
        ));
    }
    let selected = select_channels(path, vars, &channels, opts.channel.as_deref())?;
    let wavelength = selected
        .iter()
        .map(|&i| wavelength_nm_of_channel(&vars[i]))
        .collect();
    Ok(Columns {
        angles,
        selected,
        wavelength,
    })
}

/// The value columns `channel` selects among `channels` (indices into `vars`).
fn select_channels(
    path: &Path,
    vars: &[String],
    channels: &[usize],
    channel: Option<&str>,
) -> Result<Vec<usize>> {
    let channel_list = || {
        let names: Vec<&str> = channels.iter().map(|&i| vars[i].as_str()).collect();
        names.join(", ")
    };
    match channel.map(str::trim) {
        Some(c) if c.eq_ignore_ascii_case("all") => Ok(channels.to_vec()),
        Some(c) => match channels.iter().find(|&&i| vars[i].eq_ignore_ascii_case(c)) {
            Some(&i) => Ok(vec![i]),
            None => Err(Error::Usage(format!(
                "{}: no channel '{c}' (channels: {}; or 'all')",
                shown(path),
                channel_list()
            ))),
        },
        None if channels.len() == 1 => Ok(channels.to_vec()),
        None => Err(Error::Usage(format!(
            "{}: {} channels; choose one with --channel NAME or all with --channel all (channels: {})",
            shown(path),
            channels.len(),
            channel_list()
        ))),
    }
}

/// The file's NUM_POINTS, if stated, is its count of data rows.
fn check_row_count(path: &Path, text: &str, header: &Header, rows: usize) -> Result<()> {
    let Some(np) = header.get("NUM_POINTS") else {
        return Ok(());
    };
    match np.trim().parse::<usize>() {
        Ok(n) if n == rows => Ok(()),
        Ok(n) => Err(Error::file(
            path,
            format!(
                "NUM_POINTS says {n} rows but the file has {rows} data rows (truncated or damaged?)"
            ),
        )),
        Err(_) => {
            let line = text
                .lines()
                .position(|l| l.trim_start().starts_with("NUM_POINTS"))
                .map_or(1, |p| p + 1);
            let m = format!("'{}' is not a row count", np.trim());
            Err(Error::input(path, line, "NUM_POINTS", m))
        }
    }
}

/// A dataset with room for `rows` data rows of the selected channels: pass-through
/// columns the four angles, the channel and the value (named by MEAS_NAME).
fn empty_dataset(path: &Path, header: &Header, cols: &Columns, rows: usize) -> Dataset {
    let value_name = header
        .get("MEAS_NAME")
        .map(str::trim)
        .filter(|s| !s.is_empty() && !s.contains(','))
        .unwrap_or("value")
        .to_string();
    let mut headers: Vec<String> = cols
        .angles
        .iter()
        .map(|&i| header.vars[i].clone())
        .collect();
    headers.push("channel".into());
    headers.push(value_name);
    let have_wl = cols.wavelength.iter().all(Option::is_some);
    let n = rows * cols.selected.len();
    Dataset {
        path: path.to_path_buf(),
        headers,
        rows: Vec::with_capacity(n),
        lines: Vec::with_capacity(n),
        samples: Vec::with_capacity(n),
        value: Some(Vec::with_capacity(n)),
        weight: None,
        sigma_l: None,
        wavelength: have_wl.then(|| Vec::with_capacity(n)),
        wavelength_unit: have_wl.then(|| "nm".to_string()),
        wavelength_origin: have_wl.then_some("channel name"),
        channel: Some(Vec::with_capacity(n)),
        quantity: stated_quantity(header.get("MEAS_NAME")),
    }
}

/// Read the data row `line` (at `line_no`) into `ds`: its angles, checked and turned into
/// goniofit's convention, and one sample per selected channel.
fn push_row(
    path: &Path,
    (header, cols): (&Header, &Columns),
    opts: &ReadOptions,
    (line_no, line): (usize, &str),
    ds: &mut Dataset,
) -> Result<()> {
    let input_err = |column: &str, message| Error::input(path, line_no, column, message);
    let (vars, vars_line) = (&header.vars, header.vars_line);
    let fields = split_row(line, vars.len()).map_err(|()| {
        input_err(
            "(row)",
            format!(
                "row has more than {} fields, VARS (line {vars_line}) names {}{}",
                vars.len(),
                vars.len(),
                super::csv::decimal_comma_hint(line)
            ),
        )
    })?;
    if fields.len() != vars.len() {
        let m = format!(
            "row has {} fields, VARS (line {vars_line}) names {}",
            fields.len(),
            vars.len()
        );
        return Err(input_err("(row)", m));
    }
    let num =
        |i: usize| -> Result<f64> { parse_finite(fields[i]).map_err(|m| input_err(&vars[i], m)) };
    let sample = row_sample(path, line_no, vars, cols.angles, &num, opts.signed_theta_r)?;
    for (k, &c) in cols.selected.iter().enumerate() {
        let v = num(c)?;
        if let Some(vals) = ds.value.as_mut() {
            vals.push(v);
        }
        if let Some(w) = ds.wavelength.as_mut() {
            w.push(cols.wavelength[k].unwrap_or(f64::NAN));
        }
        if let Some(ch) = ds.channel.as_mut() {
            ch.push(vars[c].clone());
        }
        let mut row: Vec<String> = cols.angles.iter().map(|&i| fields[i].to_string()).collect();
        row.push(vars[c].clone());
        row.push(fields[c].to_string());
        ds.rows.push(row);
        ds.lines.push(line_no);
        ds.samples.push(sample);
    }
    Ok(())
}

/// The sample of a row's angles (radians; `num` reads column i), checked and converted to
/// goniofit's convention (φr = φs − φi − π).
fn row_sample(
    path: &Path,
    line_no: usize,
    vars: &[String],
    [c_ti, c_pi, c_ts, c_ps]: [usize; 4],
    num: &dyn Fn(usize) -> Result<f64>,
    signed_theta_r: bool,
) -> Result<crate::geometry::Sample> {
    let input_err = |column: &str, message| Error::input(path, line_no, column, message);
    let (mut ti, mut pi) = (num(c_ti)?, num(c_pi)?);
    let (ts, ps) = (num(c_ts)?, num(c_ps)?);
    if ti < 0.0 && signed_theta_r {
        ti = -ti;
        pi += PI;
    }
    for (name, c, v) in [("phi_i", c_pi, pi), ("phi_s", c_ps, ps)] {
        if v.abs() > 2.0 * PI * (1.0 + 1e-12) {
            let m = format!("{name} = {v} rad is outside [-2π, 2π] (ASTM angles are radians)");
            return Err(input_err(&vars[c], m));
        }
    }
    let phi_r = crate::geometry::wrap_phi(ps - pi - PI);
    check_angles(ti, ts, phi_r, true, signed_theta_r).map_err(|(c, m)| {
        let col = match c {
            "theta_i" => c_ti,
            "theta_r" => c_ts,
            _ => c_ps,
        };
        input_err(&vars[col], format!("{m} (ASTM angles are radians)"))
    })
}

/// The quantity a `MEAS_NAME` states: `BRDF` (any case) is a BRDF, a name with `radiance`
/// a radiance; anything else states nothing.
fn stated_quantity(meas_name: Option<&str>) -> Option<crate::geometry::Quantity> {
    let m = meas_name?.trim().to_ascii_lowercase();
    if m == "brdf" || m.starts_with("brdf ") {
        Some(crate::geometry::Quantity::Brdf)
    } else if m.contains("radiance") {
        Some(crate::geometry::Quantity::Radiance)
    } else {
        None
    }
}

/// At most 60 characters of a line, for messages.
fn clip(line: &str) -> String {
    if line.chars().count() <= 60 {
        line.to_string()
    } else {
        format!("{}…", line.chars().take(60).collect::<String>())
    }
}
