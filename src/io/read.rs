//! Reading a file: the format chosen by extension or content ([`super::sniff`]), a CSV
//! file streamed with a progress callback, everything else read whole.

use super::sniff::{
    astm_by_extension, estimate_rows, is_astm, is_binary, merl_by_extension, surely_csv,
};
use super::{
    alta, astm, csv, merl, quantity, rgl, select_csv_channel, shown, Dataset, ReadOptions,
};
use crate::error::{Error, Result};
use std::path::Path;

/// Read a dataset, choosing the format by extension or content (see the module docs).
pub(crate) fn read_dataset(path: &Path, opts: &ReadOptions) -> Result<Dataset> {
    read_file(path, opts, true, &|_| Ok(()))
}

/// What a caller's progress callback says after each MiB or so read: go on, or stop with
/// the reason (e.g. "stopped: interrupted"; the read then ends with [`Error::Stopped`]).
pub(crate) type Progress<'f> = &'f dyn Fn(u64) -> std::result::Result<(), &'static str>;

/// [`read_dataset`] (with the raw rows only when `keep_rows`, see
/// [`read_dataset_columns`]), calling `progress(bytes read so far)` every MiB or so while
/// a CSV file is streamed (about 25,000 rows of a typical scan); when it returns a reason,
/// reading ends with [`Error::Stopped`] ("REASON while reading FILE …: nothing fitted").
pub(crate) fn read_dataset_with(
    path: &Path,
    opts: &ReadOptions,
    keep_rows: bool,
    progress: Progress,
) -> Result<Dataset> {
    read_file(path, opts, keep_rows, progress)
}

/// Read a measurement file into its samples as `goniofit fit` does: CSV, ASTM E1392, NIST
/// PTFE, RGL `.bsdf`, MERL `.binary` or ALTA data, told apart by name and content; the rows
/// `opts` selects (channel, columns, angle unit), checked (angles in range, finite values).
/// The file's raw rows are not kept (`rows` stays empty). Errors name the file and, for
/// text formats, the line.
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

/// Read a dataset from bytes already in memory; `path` names it in messages and decides
/// the format by extension as [`read_dataset`] does.
pub(crate) fn read_bytes(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Dataset> {
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

#[cfg(test)]
mod tests {
    use super::*;

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
