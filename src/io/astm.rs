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
pub fn is_key(token: &str) -> bool {
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
pub struct Header {
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
    pub fn get(&self, key: &str) -> Option<&str> {
        self.keys
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// Parse an ASTM file (text already decoded, BOM removed).
pub(crate) fn parse(path: &Path, text: &str, opts: &ReadOptions) -> Result<Dataset> {
    let input_err = |line, column: &str, message| Error::input(path, line, column, message);
    let file_err = |message| Error::file(path, message);

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
            let value = line[first.len()..].trim().to_string();
            if first == "VARS" {
                if !header.vars.is_empty() {
                    return Err(input_err(line_no, "VARS", "a second VARS line".into()));
                }
                header.vars = split_row(&value, super::csv::MAX_FIELDS)
                    .map_err(|_| {
                        input_err(
                            line_no,
                            "VARS",
                            format!(
                                "more than {} column names (a BRDF file has a few dozen)",
                                super::csv::MAX_FIELDS
                            ),
                        )
                    })?
                    .into_iter()
                    .filter(|v| !v.is_empty())
                    .map(str::to_string)
                    .collect();
                header.vars_line = line_no;
                check_vars(path, line_no, &header.vars)?;
            }
            if let Some((_, earlier, old)) = header.lines.iter().find(|(k, _, _)| k == first) {
                if first == "NUM_POINTS" && old != &value {
                    return Err(input_err(
                        line_no,
                        "NUM_POINTS",
                        format!(
                            "a second NUM_POINTS line says '{value}', line {earlier} said '{old}': which is the row count?"
                        ),
                    ));
                }
            }
            header
                .lines
                .push((first.to_string(), line_no, value.clone()));
            header.keys.push((first.to_string(), value));
            continue;
        }
        if header.vars.is_empty() {
            return Err(input_err(
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
        return Err(file_err("empty file: no ASTM header".into()));
    }
    if header.vars.is_empty() {
        return Err(file_err(
            "no VARS line (expected e.g. VARS theta_i,phi_i,theta_s,phi_s,550nm)".into(),
        ));
    }
    let vars_line = header.vars_line;
    let find = |names: &[&str]| {
        header
            .vars
            .iter()
            .position(|v| names.iter().any(|n| v.eq_ignore_ascii_case(n)))
    };
    let separator = match header.vars.as_slice() {
        [one] if one.contains(';') => {
            " (the names seem to be separated by ';': ASTM files use commas or blanks)"
        }
        [one] if one.contains('|') => {
            " (the names seem to be separated by '|': ASTM files use commas or blanks)"
        }
        _ => "",
    };
    let missing = |what: &str| {
        input_err(
            vars_line,
            what,
            format!(
                "VARS has no {what} column (it has: {}){separator}",
                header.vars.join(", ")
            ),
        )
    };
    let c_ti = find(&["theta_i"]).ok_or_else(|| missing("theta_i"))?;
    let c_pi = find(&["phi_i"]).ok_or_else(|| missing("phi_i"))?;
    let c_ts = find(&["theta_s", "theta_r"]).ok_or_else(|| missing("theta_s"))?;
    let c_ps = find(&["phi_s", "phi_r"]).ok_or_else(|| missing("phi_s"))?;
    let angle_cols = [c_ti, c_pi, c_ts, c_ps];
    let channels: Vec<usize> = (0..header.vars.len())
        .filter(|i| !angle_cols.contains(i))
        .collect();
    if channels.is_empty() {
        return Err(input_err(
            vars_line,
            "VARS",
            "no value column after the angles (expected e.g. 550nm)".into(),
        ));
    }
    let channel_list = || {
        channels
            .iter()
            .map(|&i| header.vars[i].as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let selected: Vec<usize> = match opts.channel.as_deref().map(str::trim) {
        Some(c) if c.eq_ignore_ascii_case("all") => channels.clone(),
        Some(c) => match channels
            .iter()
            .find(|&&i| header.vars[i].eq_ignore_ascii_case(c))
        {
            Some(&i) => vec![i],
            None => {
                return Err(Error::Usage(format!(
                    "{}: no channel '{c}' (channels: {}; or 'all')",
                    shown(path),
                    channel_list()
                )))
            }
        },
        None if channels.len() == 1 => channels.clone(),
        None => {
            return Err(Error::Usage(format!(
                "{}: {} channels; choose one with --channel NAME or all with --channel all (channels: {})",
                shown(path),
                channels.len(),
                channel_list()
            )))
        }
    };

    if data.is_empty() {
        return Err(file_err(format!(
            "no data rows after the VARS line (line {vars_line})"
        )));
    }
    if let Some(np) = header.get("NUM_POINTS") {
        match np.trim().parse::<usize>() {
            Ok(n) if n == data.len() => {}
            Ok(n) => {
                return Err(file_err(format!(
                "NUM_POINTS says {n} rows but the file has {} data rows (truncated or damaged?)",
                data.len()
            )))
            }
            Err(_) => {
                let line = text
                    .lines()
                    .position(|l| l.trim_start().starts_with("NUM_POINTS"))
                    .map_or(1, |p| p + 1);
                return Err(input_err(
                    line,
                    "NUM_POINTS",
                    format!("'{}' is not a row count", np.trim()),
                ));
            }
        }
    }

    let value_name = header
        .get("MEAS_NAME")
        .map(str::trim)
        .filter(|s| !s.is_empty() && !s.contains(','))
        .unwrap_or("value")
        .to_string();
    let mut headers: Vec<String> = angle_cols.iter().map(|&i| header.vars[i].clone()).collect();
    headers.push("channel".into());
    headers.push(value_name);

    let wl: Vec<Option<f64>> = selected
        .iter()
        .map(|&i| wavelength_nm_of_channel(&header.vars[i]))
        .collect();
    let have_wl = wl.iter().all(Option::is_some);

    let n = data.len() * selected.len();
    let mut ds = Dataset {
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
    };
    for (line_no, line) in data {
        let fields = split_row(line, header.vars.len()).map_err(|()| {
            input_err(
                line_no,
                "(row)",
                format!(
                    "row has more than {} fields, VARS (line {vars_line}) names {}{}",
                    header.vars.len(),
                    header.vars.len(),
                    super::csv::decimal_comma_hint(line)
                ),
            )
        })?;
        if fields.len() != header.vars.len() {
            return Err(input_err(
                line_no,
                "(row)",
                format!(
                    "row has {} fields, VARS (line {vars_line}) names {}",
                    fields.len(),
                    header.vars.len()
                ),
            ));
        }
        let num = |i: usize| -> Result<f64> {
            parse_finite(fields[i]).map_err(|m| input_err(line_no, &header.vars[i], m))
        };
        let (mut ti, mut pi) = (num(c_ti)?, num(c_pi)?);
        let (ts, ps) = (num(c_ts)?, num(c_ps)?);
        if ti < 0.0 && opts.signed_theta_r {
            ti = -ti;
            pi += PI;
        }
        for (name, c, v) in [("phi_i", c_pi, pi), ("phi_s", c_ps, ps)] {
            if v.abs() > 2.0 * PI * (1.0 + 1e-12) {
                return Err(input_err(
                    line_no,
                    &header.vars[c],
                    format!("{name} = {v} rad is outside [-2π, 2π] (ASTM angles are radians)"),
                ));
            }
        }
        let phi_r = crate::geometry::wrap_phi(ps - pi - PI);
        let sample = check_angles(ti, ts, phi_r, true, opts.signed_theta_r).map_err(|(c, m)| {
            let col = match c {
                "theta_i" => c_ti,
                "theta_r" => c_ts,
                _ => c_ps,
            };
            input_err(
                line_no,
                &header.vars[col],
                format!("{m} (ASTM angles are radians)"),
            )
        })?;
        for (k, &c) in selected.iter().enumerate() {
            let v = num(c)?;
            if let Some(vals) = ds.value.as_mut() {
                vals.push(v);
            }
            if let Some(w) = ds.wavelength.as_mut() {
                w.push(wl[k].unwrap_or(f64::NAN));
            }
            if let Some(ch) = ds.channel.as_mut() {
                ch.push(header.vars[c].clone());
            }
            let mut row: Vec<String> = angle_cols.iter().map(|&i| fields[i].to_string()).collect();
            row.push(header.vars[c].clone());
            row.push(fields[c].to_string());
            ds.rows.push(row);
            ds.lines.push(line_no);
            ds.samples.push(sample);
        }
    }
    if opts.require_value {
        if let Some(v) = &ds.value {
            if v.iter().all(|&x| x == 0.0) {
                return Err(file_err(format!(
                    "all {} values of the selected channel(s) are zero: nothing to fit",
                    v.len()
                )));
            }
        }
    }
    Ok(ds)
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
