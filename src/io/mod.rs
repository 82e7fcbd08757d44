//! Reading measurements and writing tables.
//!
//! [`read_dataset`] reads either a CSV table ([`csv`]) or an ASTM E1392 file ([`astm`]) into
//! a [`Dataset`]: validated angles in our convention (docs/conventions.md: radians, θi ∈ [0, π/2),
//! θr ∈ [0, π/2], φr from the plane of incidence, φr = 0 the forward/specular side), the
//! measured values, and the raw rows for pass-through output.
//!
//! Format detection: a file that starts with the bytes `tensor_file\0` or is named
//! `*.bsdf` is an RGL measured BRDF ([`rgl`]); a file of MERL's size whose first 12 bytes
//! are the dimensions 90, 90, 180, or one named `*.binary`, is a MERL BRDF ([`merl`]); a
//! text file whose first non-blank line is `#DIM` is ALTA data ([`alta`]). A file is ASTM
//! E1392 when its extension is `.astm` (any case), or when
//! its first non-blank line starts with an upper-case `KEY` token (e.g. `LAB_NAME ...`) and
//! some line starts with `VARS`. Everything else is CSV.
//!
//! Writing ([`output`]): [`write_atomic`] replaces a regular file through a temporary in
//! its folder and a rename, so a failed or interrupted write leaves nothing behind, and
//! writes devices, FIFOs and `-` (stdout) straight through; [`write_csv`] writes a table
//! that way; [`FileSet`] checks every file of a command together before anything is
//! written (no output is an input or another output).
//!
//! ```
//! use goniofit::io::{read_dataset, ReadOptions};
//! let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/cornell/garnet_red.astm");
//! let opts = ReadOptions { channel: Some("550nm".into()), require_value: true, ..Default::default() };
//! let ds = read_dataset(&path, &opts)?;
//! assert_eq!(ds.len(), 1439);
//! assert_eq!(ds.wavelength.as_ref().unwrap()[0], 550.0); // nm, from the channel name
//! # Ok::<(), goniofit::Error>(())
//! ```
//!
//! Every reading error is an [`Error::Input`] (file, 1-based line, column, offending value),
//! an [`Error::File`] (the whole file: empty, no data rows, missing column) or an
//! [`Error::Io`]; no input makes the readers panic (proptest in `tests/io.rs`).

pub mod alta;
pub mod arrays;
pub mod astm;
pub mod csv;
pub mod files;
pub mod merl;
pub mod output;
mod quantity;
pub mod rgl;

pub use files::FileSet;
pub use output::{print_stdout, write_atomic, write_bytes};

use crate::error::{Error, Result};
use crate::geometry::{Quantity, Sample};
use std::io::Write;
use std::path::{Path, PathBuf};

/// How to read a file.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Angles in radians (CSV); ASTM files are always radians.
    pub radians: bool,
    /// θr < 0 means θr = |θr| on the opposite side (φr + 180°); at φr = 0 that is φr = 180°.
    pub signed_theta_r: bool,
    /// `--columns role=name` mappings; roles: theta_i, theta_r, phi_r, L, weight, sigma_L,
    /// wavelength, group (case-insensitive; `value` is accepted for `L`). CSV only.
    pub columns: Vec<(String, String)>,
    /// Whether column L (the measured value) must exist (fit: yes; eval: no).
    pub require_value: bool,
    /// One channel, or `all`. ASTM: a channel name such as `550nm`. CSV: a `group` label
    /// when the file has a `group` column, otherwise a wavelength (`0.532`, in the file's
    /// unit, or `532nm`) selecting the rows of that `wavelength`; `all` on a CSV without a
    /// `group` column makes each wavelength a channel (see [`select_csv_channel`]).
    pub channel: Option<String>,
    /// MERL tables: keep every k-th θd and φd cell (k² fewer samples; 0 or 1 keeps all).
    /// Other formats refuse k > 1.
    pub subsample: usize,
}

/// A dataset as read: angles validated, values parsed, raw rows kept for pass-through.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub path: PathBuf,
    /// Column names of `rows` (as in the file, surrounding whitespace removed).
    pub headers: Vec<String>,
    /// Raw fields per sample, for pass-through output.
    pub rows: Vec<Vec<String>>,
    /// 1-based source line of each sample.
    pub lines: Vec<usize>,
    /// Sample angles in radians, in the convention of docs/conventions.md.
    pub samples: Vec<Sample>,
    /// Measured L (or BRDF).
    pub value: Option<Vec<f64>>,
    /// Per-sample weight w (from `weight`, or 1/sigma_L²).
    pub weight: Option<Vec<f64>>,
    /// Standard uncertainty of the value, if given.
    pub sigma_l: Option<Vec<f64>>,
    /// Per-sample wavelength (a `wavelength` column in the file's unit, or from an ASTM
    /// channel name: `550nm` → 550, in nm).
    pub wavelength: Option<Vec<f64>>,
    /// Unit of `wavelength` when the file states it: `nm` for ASTM channel names, `µm` for
    /// the NIST PTFE layout; None for a plain `wavelength` column (unit unknown).
    pub wavelength_unit: Option<String>,
    /// Where `wavelength` comes from, in the report's words (e.g. `channel name`, `nominal
    /// wavelength of the sRGB channel`); None for a `wavelength` column.
    pub wavelength_origin: Option<&'static str>,
    /// Per-sample channel/group label (ASTM channel, or a `group` column).
    pub channel: Option<Vec<String>>,
    /// The measured quantity the file states (ASTM `MEAS_NAME BRDF`, NIST `f_r11`, a CSV
    /// `# quantity: brdf` comment or `brdf` value column), if any.
    pub quantity: Option<Quantity>,
}

impl Dataset {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether there are no samples (never true for a dataset returned by [`read_dataset`]).
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The distinct channel labels in first-appearance order (empty without channels).
    pub fn channel_names(&self) -> Vec<String> {
        self.channel_groups()
            .into_iter()
            .map(|(name, _)| name)
            .collect()
    }

    /// Every distinct channel label (first-appearance order) with the indices of its
    /// samples (ascending), found in one pass: O(n) for n samples however many groups
    /// (a texel batch has thousands). Empty without channels.
    pub fn channel_groups(&self) -> Vec<(String, Vec<usize>)> {
        let mut out: Vec<(String, Vec<usize>)> = Vec::new();
        let mut slot: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
        for (i, c) in self.channel.iter().flatten().enumerate() {
            let k = *slot.entry(c.as_str()).or_insert_with(|| {
                out.push((c.clone(), Vec::new()));
                out.len() - 1
            });
            out[k].1.push(i);
        }
        out
    }

    /// The samples at `idx` (in that order), every per-sample vector subset alike; used for
    /// per-channel fits. Indices must be `< self.len()`.
    pub fn subset(&self, idx: &[usize]) -> Dataset {
        fn pick<T: Clone>(v: &[T], idx: &[usize]) -> Vec<T> {
            idx.iter().map(|&i| v[i].clone()).collect()
        }
        Dataset {
            path: self.path.clone(),
            headers: self.headers.clone(),
            rows: if self.rows.is_empty() {
                Vec::new()
            } else {
                pick(&self.rows, idx)
            },
            lines: pick(&self.lines, idx),
            samples: pick(&self.samples, idx),
            value: self.value.as_deref().map(|v| pick(v, idx)),
            weight: self.weight.as_deref().map(|v| pick(v, idx)),
            sigma_l: self.sigma_l.as_deref().map(|v| pick(v, idx)),
            wavelength: self.wavelength.as_deref().map(|v| pick(v, idx)),
            wavelength_unit: self.wavelength_unit.clone(),
            wavelength_origin: self.wavelength_origin,
            channel: self.channel.as_deref().map(|v| pick(v, idx)),
            quantity: self.quantity,
        }
    }

    /// Release the per-sample vectors' spare capacity (after reading).
    pub fn shrink_to_fit(&mut self) {
        self.rows.shrink_to_fit();
        self.lines.shrink_to_fit();
        self.samples.shrink_to_fit();
        for v in [
            &mut self.value,
            &mut self.weight,
            &mut self.sigma_l,
            &mut self.wavelength,
        ]
        .into_iter()
        .flatten()
        {
            v.shrink_to_fit();
        }
        if let Some(c) = self.channel.as_mut() {
            c.shrink_to_fit();
        }
    }

    /// Indices of the samples with channel label `name`.
    pub fn channel_indices(&self, name: &str) -> Vec<usize> {
        match &self.channel {
            Some(ch) => (0..ch.len()).filter(|&i| ch[i] == name).collect(),
            None => Vec::new(),
        }
    }
}

/// Read a dataset, choosing the format by extension or content (see the module docs).
pub fn read_dataset(path: &Path, opts: &ReadOptions) -> Result<Dataset> {
    read_file(path, opts, true, &|_| Ok(()))
}

/// What a caller's progress callback says after each MiB or so read: go on, or stop with
/// the reason (e.g. "stopped: interrupted"; the read then ends with [`Error::Stopped`]).
pub type Progress<'f> = &'f dyn Fn(u64) -> std::result::Result<(), &'static str>;

/// [`read_dataset`] (with the raw rows only when `keep_rows`, see
/// [`read_dataset_columns`]), calling `progress(bytes read so far)` every MiB or so while
/// a CSV file is streamed (about 25,000 rows of a typical scan); when it returns a reason,
/// reading ends with [`Error::Stopped`] ("REASON while reading FILE …: nothing fitted").
pub fn read_dataset_with(
    path: &Path,
    opts: &ReadOptions,
    keep_rows: bool,
    progress: Progress,
) -> Result<Dataset> {
    read_file(path, opts, keep_rows, progress)
}

/// [`read_dataset`] without the raw rows (`rows` stays empty): what a fit needs when it
/// writes no residuals file. A CSV file is streamed record by record, so reading holds
/// one record's text at a time, not the file (a 1M-row scan is ~45 MB of text).
pub fn read_dataset_columns(path: &Path, opts: &ReadOptions) -> Result<Dataset> {
    read_file(path, opts, false, &|_| Ok(()))
}

fn read_file(
    path: &Path,
    opts: &ReadOptions,
    keep_rows: bool,
    progress: Progress,
) -> Result<Dataset> {
    use std::io::{BufRead, Read};
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io_err)?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut reader = std::io::BufReader::with_capacity(1 << 16, file);
    let head = reader.fill_buf().map_err(io_err)?;
    if merl::is_merl(head, len) || merl_by_extension(path) {
        return merl::read(path, reader, len, opts, opts.subsample);
    }
    refuse_subsample(path, opts)?;
    if !is_binary(path, head)
        && !astm_by_extension(path)
        && !alta::is_alta(head)
        && surely_csv(head)
    {
        let rows_hint = estimate_rows(head, len);
        let stated = quantity::from_comments(path, head)?;
        let stopped = std::cell::Cell::new(None);
        let counted = |inner| {
            std::io::BufReader::with_capacity(
                1 << 16,
                Counting {
                    inner,
                    done: 0,
                    reported: 0,
                    progress,
                    stopped: &stopped,
                },
            )
        };
        // A plain table is read by the plain reader; one it does not take is read again
        // from the start by the general one. A file the streamed reader refuses is read
        // whole again, so that every error message is the whole-file reader's (which
        // splits every record before reading any value, so a malformed record anywhere is
        // the error reported).
        let plain = csv::parse_plain(path, counted(reader), opts, keep_rows, rows_hint);
        let parsed = match plain {
            Some(ds) => Ok(ds),
            None if stopped.get().is_some() => Err(Error::file(path, String::new())),
            None => {
                let file = std::fs::File::open(path).map_err(io_err)?;
                let reader = std::io::BufReader::with_capacity(1 << 16, file);
                csv::parse_reader(path, counted(reader), opts, keep_rows, rows_hint)
            }
        };
        if let Some((why, done)) = stopped.get() {
            return Err(Error::Stopped(format!(
                "{why} while reading {} ({:.1} of {:.1} MB): nothing fitted",
                shown(path),
                done as f64 / 1e6,
                len as f64 / 1e6
            )));
        }
        if let Ok(mut ds) = parsed {
            ds.quantity = stated.or(ds.quantity);
            return select_csv_channel(ds, opts.channel.as_deref());
        }
        let bytes = std::fs::read(path).map_err(io_err)?;
        return read_bytes(path, &bytes, opts);
    }
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes).map_err(io_err)?;
    let mut ds = read_bytes(path, &bytes, opts)?;
    if !keep_rows {
        ds.rows = Vec::new();
    }
    Ok(ds)
}

/// A reader that reports the bytes read through it (every MiB), and fails once the
/// report says stop (the reason and the bytes read are left in `stopped`).
struct Counting<'f, R> {
    inner: R,
    done: u64,
    reported: u64,
    progress: Progress<'f>,
    stopped: &'f std::cell::Cell<Option<(&'static str, u64)>>,
}

impl<R: std::io::Read> std::io::Read for Counting<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.done += n as u64;
        if self.done - self.reported >= 1 << 20 {
            self.reported = self.done;
            if let Err(why) = (self.progress)(self.done) {
                self.stopped.set(Some((why, self.done)));
                return Err(std::io::Error::other(why));
            }
        }
        Ok(n)
    }
}

/// Whether the file is an RGL `.bsdf` tensor file: its content starts with the tensor
/// file's magic, or its extension is `.bsdf` (any case).
fn is_binary(path: &Path, head: &[u8]) -> bool {
    rgl::tensor::is_tensor_file(head)
        || path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("bsdf"))
}

/// `subsample` is for MERL tables only.
fn refuse_subsample(path: &Path, opts: &ReadOptions) -> Result<()> {
    if opts.subsample > 1 {
        return Err(Error::Usage(format!(
            "{}: --subsample thins MERL tables only (this file is not one)",
            shown(path)
        )));
    }
    Ok(())
}

/// Whether the extension says MERL (`.binary`, any case).
fn merl_by_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("binary"))
}

/// Whether the extension says ASTM E1392 (`.astm`, any case).
fn astm_by_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("astm"))
}

/// Whether the start of a file decides it is CSV by [`is_astm`]'s content rule: its first
/// non-blank line (complete within `head`) does not open with an ASTM `KEY` token
/// followed by more text.
fn surely_csv(head: &[u8]) -> bool {
    let head = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    for line in head.split(|&b| b == b'\n' || b == b'\r') {
        let Ok(text) = std::str::from_utf8(line) else {
            return false;
        };
        let t = text.trim();
        if t.is_empty() {
            continue;
        }
        let complete = line.len() < head.len();
        let key = t.split_whitespace().next().unwrap_or("");
        return complete && !(astm::is_key(key) && t.len() > key.len());
    }
    false
}

/// Rows of a file of `len` bytes, estimated from the line ends in its first bytes `head`
/// (5 % over, so that the columns rarely grow).
fn estimate_rows(head: &[u8], len: u64) -> usize {
    let lines = head.iter().filter(|&&b| b == b'\n').count().max(1);
    let per_line = head.len() as f64 / lines as f64;
    ((len as f64 / per_line.max(1.0)) * 1.05) as usize + 16
}

/// Read a dataset from bytes already in memory; `path` names it in messages and decides
/// the format by extension as [`read_dataset`] does.
pub fn read_bytes(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Dataset> {
    if merl::is_merl(bytes, bytes.len() as u64) || merl_by_extension(path) {
        return merl::read(path, bytes, bytes.len() as u64, opts, opts.subsample);
    }
    refuse_subsample(path, opts)?;
    if is_binary(path, bytes) {
        return rgl::read(path, bytes, opts);
    }
    let text = decode_utf8(path, bytes)?;
    if alta::is_alta(text.as_bytes()) {
        alta::parse(path, text, opts)
    } else if is_astm(path, text) {
        astm::parse(path, text, opts)
    } else {
        let stated = quantity::from_comments(path, text.as_bytes())?;
        let mut ds = csv::parse(path, text, opts)?;
        ds.quantity = stated.or(ds.quantity);
        select_csv_channel(ds, opts.channel.as_deref())
    }
}

/// `--channel` on a CSV dataset. With a `group` column: `all` keeps every group, a label
/// keeps that group. Without one: `all` labels each sample by its wavelength (one channel per
/// wavelength, e.g. `0.532µm`), and a wavelength (`0.532` in the file's unit, or with a unit
/// such as `532nm` when the file's unit is known) keeps the rows whose `wavelength` equals it
/// to 1e-9 relative. A channel that selects nothing is an error listing what there is.
pub fn select_csv_channel(ds: Dataset, channel: Option<&str>) -> Result<Dataset> {
    let Some(want) = channel.map(str::trim) else {
        return Ok(ds);
    };
    let all = want.eq_ignore_ascii_case("all");
    if ds.channel.is_some() {
        if all {
            return Ok(ds);
        }
        let names = ds.channel_names();
        let idx = ds.channel_indices(want);
        if idx.is_empty() {
            return Err(Error::Usage(format!(
                "{}: no group '{want}' (groups: {}; or 'all')",
                ds.path.display(),
                names.join(", ")
            )));
        }
        return Ok(ds.subset(&idx));
    }
    let Some(wl) = ds.wavelength.clone() else {
        return Err(Error::Usage(format!(
            "{}: --channel '{want}' needs a group column or a wavelength column to select by (the file has neither)",
            ds.path.display()
        )));
    };
    let unit = ds.wavelength_unit.clone().unwrap_or_default();
    let distinct = distinct_values(&wl);
    let label = |v: f64| format!("{v}{unit}");
    if all {
        let mut ds = ds;
        ds.channel = Some(wl.iter().map(|&v| label(v)).collect());
        return Ok(ds);
    }
    let listing = || {
        distinct
            .iter()
            .map(|&v| label(v))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (value, given_unit) = parse_length(want).map_err(|_| {
        Error::Usage(format!(
            "{}: --channel '{want}' is neither 'all' nor a wavelength (wavelengths: {})",
            ds.path.display(),
            listing()
        ))
    })?;
    let target = match (given_unit, ds.wavelength_unit.as_deref()) {
        (None, _) => value,
        (Some(u), Some(file_unit)) => value * nm_per(u) / nm_per(file_unit),
        (Some(u), None) => {
            return Err(Error::Usage(format!(
                "{}: --channel '{want}' has a unit ({u}) but the file's wavelength column states none: give the number in the column's unit (wavelengths: {})",
                ds.path.display(),
                listing()
            )))
        }
    };
    let idx: Vec<usize> = (0..wl.len())
        .filter(|&i| (wl[i] - target).abs() <= 1e-9 * target.abs())
        .collect();
    if idx.is_empty() {
        return Err(Error::Usage(format!(
            "{}: no rows at wavelength {want} (wavelengths: {})",
            ds.path.display(),
            listing()
        )));
    }
    let mut sub = ds.subset(&idx);
    sub.channel = Some(vec![label(target); idx.len()]);
    Ok(sub)
}

/// The distinct values of `v` in first-appearance order.
fn distinct_values(v: &[f64]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for &x in v {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

/// Length units goniofit understands, as written in reports: nanometres and micrometres.
pub const LENGTH_UNITS: [(&str, f64); 2] = [("nm", 1.0), ("µm", 1000.0)];

/// Nanometres per `unit` (`nm`, `µm`; 1 for anything else).
pub fn nm_per(unit: &str) -> f64 {
    LENGTH_UNITS
        .iter()
        .find(|(u, _)| *u == unit)
        .map_or(1.0, |(_, f)| *f)
}

/// A positive length such as `633nm`, `633 nm`, `0.633um`, `0.633µm` or a bare `0.633`:
/// the number and its unit (`nm`, `µm`; None for a bare number), within
/// [`crate::settings::LENGTH_RANGE`]. The error says what is accepted.
pub fn parse_length(text: &str) -> Result<(f64, Option<&'static str>)> {
    let t = text.trim();
    let lower = t.to_lowercase();
    let (num, unit) = if let Some(n) = lower.strip_suffix("nm") {
        (n.to_string(), Some("nm"))
    } else if let Some(n) = ["um", "µm", "μm", "micron"]
        .iter()
        .find_map(|s| lower.strip_suffix(s))
    {
        (n.to_string(), Some("µm"))
    } else {
        (lower.clone(), None)
    };
    let (lo, hi) = crate::settings::LENGTH_RANGE;
    match num.trim().parse::<f64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok((v, unit)),
        Ok(v) if v.is_finite() && v > 0.0 => Err(Error::Usage(format!(
            "'{t}': a length must lie within [{lo:e}, {hi:e}] (in any unit)"
        ))),
        _ => Err(Error::Usage(format!(
            "'{t}' is not a positive length: give a number with nm or um (633nm, 0.633um) or a bare number in the unit of the data's wavelength"
        ))),
    }
}

/// UTF-8 text without a leading byte-order mark; invalid UTF-8 is an error naming the line.
fn decode_utf8<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let good = &bytes[..e.valid_up_to()];
        let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
        Error::Input {
            path: path.to_path_buf(),
            line,
            column: "(text)".into(),
            message: format!(
                "invalid UTF-8 at byte {} (save the file as UTF-8 text)",
                e.valid_up_to()
            ),
        }
    })
}

/// Whether the file is ASTM E1392 (by extension or content).
pub fn is_astm(path: &Path, text: &str) -> bool {
    if path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("astm"))
    {
        return true;
    }
    let first = text.lines().map(str::trim).find(|l| !l.is_empty());
    let Some(first) = first else { return false };
    let key = first.split_whitespace().next().unwrap_or("");
    astm::is_key(key)
        && first.len() > key.len()
        && text
            .lines()
            .any(|l| l.split_whitespace().next() == Some("VARS"))
}

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

/// Format a value with full precision: the shortest decimal that parses back to the same
/// `f64`, in scientific notation (`1.2345e-3`, `5e-1`, `NaN`, `inf`).
pub fn format_value(v: f64) -> String {
    format!("{v:e}")
}

/// Parse a decimal field as a finite number; the message shows the value.
pub(crate) fn parse_finite(field: &str) -> std::result::Result<f64, String> {
    let graphic = |b: Option<&u8>| b.is_some_and(u8::is_ascii_graphic);
    let bytes = field.as_bytes();
    let t = match graphic(bytes.first()) && graphic(bytes.last()) {
        true => field,
        false => field.trim(),
    };
    if t.is_empty() {
        return Err("empty field (a number is needed)".into());
    }
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("'{t}' is not a finite number")),
        Err(_) => Err(format!("'{t}' is not a number")),
    }
}

/// Validate one sample's angles (in the file's unit) and convert them to radians in our
/// convention. `signed`: a negative polar angle means the opposite azimuth. Errors name
/// the column and show the value.
pub(crate) fn check_angles(
    theta_i: f64,
    theta_r: f64,
    phi_r: f64,
    radians: bool,
    signed: bool,
) -> std::result::Result<Sample, (&'static str, String)> {
    let (unit, right, full) = if radians {
        (
            " rad",
            std::f64::consts::FRAC_PI_2,
            2.0 * std::f64::consts::PI,
        )
    } else {
        ("°", 90.0, 360.0)
    };
    if !(0.0..right).contains(&theta_i) {
        return Err((
            "theta_i",
            format!(
                "theta_i = {theta_i}{unit} is outside [0, {right}{unit}){}",
                if theta_i < 0.0 && theta_i > -right {
                    " (incidence angles are measured from the normal and are never negative)"
                } else {
                    ""
                }
            ),
        ));
    }
    if theta_r.abs() > right || (theta_r < 0.0 && !signed) {
        return Err((
            "theta_r",
            format!(
                "theta_r = {theta_r}{unit} is outside [0, {right}{unit}]{}",
                if theta_r < 0.0 && theta_r >= -right {
                    " (for signed in-plane view angles use --signed-theta-r)"
                } else {
                    ""
                }
            ),
        ));
    }
    if phi_r.abs() > full * (1.0 + 1e-12) {
        return Err((
            "phi_r",
            format!("phi_r = {phi_r}{unit} is outside [-{full}{unit}, {full}{unit}]"),
        ));
    }
    let to_rad = |x: f64| if radians { x } else { x.to_radians() };
    let mut s = Sample {
        theta_i: to_rad(theta_i),
        theta_r: to_rad(theta_r.abs()),
        phi_r: to_rad(phi_r),
    };
    if theta_r < 0.0 {
        s.phi_r = crate::geometry::wrap_phi(s.phi_r + std::f64::consts::PI);
    }
    // Degrees → radians can round 90° − ε up to π/2 (never at or above it for θi < 90).
    s.theta_r = s.theta_r.min(std::f64::consts::FRAC_PI_2);
    if s.theta_i >= std::f64::consts::FRAC_PI_2 {
        s.theta_i = f64::from_bits(std::f64::consts::FRAC_PI_2.to_bits() - 1);
    }
    Ok(s)
}

/// A wavelength from a channel name such as `550nm`, `550 nm`, `0.55um`, `0.55µm` or a bare
/// number (taken as nm); the result is in nm. `None` when the name is not a wavelength.
pub fn wavelength_nm_of_channel(name: &str) -> Option<f64> {
    let (v, unit) = parse_length(name).ok()?;
    Some(v * unit.map_or(1.0, nm_per))
}

/// An empty BRDF table of a binary or ALTA file, without rows (its columns say
/// everything): a value column, `sigma_L` and weights when `sigma`, per-sample channel
/// labels when `labelled`, and per-sample wavelengths in nm when the channels are the
/// nominal sRGB ones (`rgb`).
pub(crate) fn empty_brdf(path: &Path, labelled: bool, sigma: bool, rgb: bool) -> Dataset {
    Dataset {
        path: path.to_path_buf(),
        headers: Vec::new(),
        rows: Vec::new(),
        lines: Vec::new(),
        samples: Vec::new(),
        value: Some(Vec::new()),
        weight: sigma.then(Vec::new),
        sigma_l: sigma.then(Vec::new),
        wavelength: rgb.then(Vec::new),
        wavelength_unit: rgb.then(|| "nm".to_string()),
        wavelength_origin: rgb.then_some(rgl::NOMINAL_ORIGIN),
        channel: labelled.then(Vec::new),
        quantity: Some(Quantity::Brdf),
    }
}

#[cfg(test)]
mod group_tests {
    use super::*;

    #[test]
    fn channel_groups_collect_interleaved_labels_in_first_appearance_order() {
        let text = b"theta_i,theta_r,phi_r,L,group\n10,20,0,1,b\n10,30,0,2,a\n10,40,0,3,b\n10,50,0,4,c\n10,60,0,5,a\n";
        let opts = ReadOptions {
            require_value: true,
            ..Default::default()
        };
        let ds = read_bytes(Path::new("t.csv"), text, &opts).unwrap();
        let groups = ds.channel_groups();
        let want: Vec<(String, Vec<usize>)> = vec![
            ("b".into(), vec![0, 2]),
            ("a".into(), vec![1, 4]),
            ("c".into(), vec![3]),
        ];
        assert_eq!(groups, want);
        assert_eq!(ds.channel_names(), ["b", "a", "c"]);
    }

    /// The streamed reader without rows gives the same columns as the whole-file reader.
    #[test]
    fn columns_only_reading_matches_the_whole_file_reader() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
        let opts = ReadOptions {
            require_value: true,
            ..Default::default()
        };
        for file in ["synthetic/kbs_inplane.csv", "nist-ptfe/PTFE.data.csv"] {
            let path = dir.join(file);
            let whole = read_dataset(&path, &opts).unwrap();
            let lean = read_dataset_columns(&path, &opts).unwrap();
            assert_eq!(whole.rows.len(), whole.len(), "{file}");
            assert!(lean.rows.is_empty(), "{file}");
            assert_eq!(lean.samples, whole.samples, "{file}");
            assert_eq!(lean.lines, whole.lines, "{file}");
            assert_eq!(lean.value, whole.value, "{file}");
            assert_eq!(lean.wavelength, whole.wavelength, "{file}");
            assert_eq!(lean.headers, whole.headers, "{file}");
            assert_eq!(lean.subset(&[1, 0]).samples, whole.subset(&[1, 0]).samples);
        }
    }
}
