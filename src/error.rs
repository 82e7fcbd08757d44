//! The one error type of the library. Every variant says what failed, shows the offending
//! value, and where it came from (file, line, column) when it came from a file; names and
//! values from files are printed with [`shown`] and [`shown_text`].

use std::path::PathBuf;

/// Errors from reading input, building models and running fits.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A value in an input file could not be used.
    #[error(
        "{}:{line}: column {}: {}",
        shown(path),
        shown_text(column),
        shown_text(message)
    )]
    Input {
        /// The input file.
        path: PathBuf,
        /// 1-based line number in the file.
        line: usize,
        /// The column's name (as in the file's header, or the role it plays).
        column: String,
        /// What is wrong with the value, showing it.
        message: String,
    },
    /// An element of an input array could not be used (arrays handed over by a program,
    /// such as the Python package; `index` is 0-based).
    #[error("{array}[{index}]: {message}")]
    Element {
        /// The array's name: the input it holds (`L`, `weights`, `sigma_L`, …).
        array: String,
        /// 0-based position of the element in the array.
        index: usize,
        /// What is wrong with the element, showing it.
        message: String,
    },
    /// A whole input file is unusable (empty, header only, missing column, ...).
    #[error("{}: {}", shown(path), shown_text(message))]
    File {
        /// The file.
        path: PathBuf,
        /// What makes it unusable.
        message: String,
    },
    /// An I/O failure while reading or writing a file.
    #[error("{}: {source}", shown(path))]
    Io {
        /// The file being read or written.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// Writing an output failed after it started (disk full, I/O error): not the user's
    /// input, exit code 1. (A path that cannot be created is an [`Error::File`].)
    #[error("{}: writing failed: {source}", shown(path))]
    Write {
        /// The output being written.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A model name that goniofit does not know.
    #[error("unknown model '{0}' (known: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular)")]
    UnknownModel(String),
    /// A parameter name the model does not have, or a value outside its domain.
    #[error("parameter {name}: {message}")]
    Param {
        /// The parameter's name (with a `[channel]` suffix where per channel).
        name: String,
        /// What is wrong with it, showing the value.
        message: String,
    },
    /// A usage error: inconsistent options or arguments.
    #[error("{}", shown_text(.0))]
    Usage(String),
    /// A picture could not be drawn or written.
    #[error("{}: drawing failed: {message}", shown(path))]
    Plot {
        /// The picture's output file (or the bundled font that could not be loaded).
        path: PathBuf,
        /// What failed: the drawing backend's error, in words.
        message: String,
    },
    /// A stop request (Ctrl-C, SIGTERM, SIGHUP, a time limit) came before any point of the
    /// fit was evaluated on the whole data: there is no fit to report (CLI exit code 3).
    #[error("{0}")]
    Stopped(String),
    /// A numerical failure inside the library (a bug, or a domain violation that slipped through).
    #[error("numerical failure: {0}")]
    Numerical(String),
}

impl Error {
    /// [`Error::Input`]: `message` about the value in `column` at `line` of `path`.
    pub fn input(path: &std::path::Path, line: usize, column: &str, message: String) -> Self {
        Error::Input {
            path: path.to_path_buf(),
            line,
            column: column.to_string(),
            message,
        }
    }

    /// [`Error::Element`]: `message` about element `index` (0-based) of `array`.
    pub fn element(array: &str, index: usize, message: String) -> Self {
        Error::Element {
            array: array.to_string(),
            index,
            message,
        }
    }

    /// [`Error::File`]: `message` about the whole of `path`.
    pub fn file(path: &std::path::Path, message: String) -> Self {
        Error::File {
            path: path.to_path_buf(),
            message,
        }
    }

    /// Whether the error is the user's input or usage (CLI exit code 2) rather than an
    /// internal failure (exit code 1).
    pub fn is_user_error(&self) -> bool {
        !matches!(
            self,
            Error::Numerical(_) | Error::Plot { .. } | Error::Write { .. } | Error::Stopped(_)
        )
    }
}

/// Result with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// `s` as printed in messages and reports: line breaks, tabs and other control characters,
/// and the bidirectional-text controls (U+061C, U+200E, U+200F, U+202A–U+202E,
/// U+2066–U+2069) are written as escapes (`\n`, `\u{202e}`), everything else as is; so a
/// file or group name cannot fake a line of a report or reverse the text after it.
pub(crate) fn shown_text(s: &str) -> std::borrow::Cow<'_, str> {
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
pub(crate) fn shown(path: &std::path::Path) -> String {
    shown_text(&path.to_string_lossy()).into_owned()
}

/// A number as printed compactly in titles, legends and messages (at most 4 significant
/// digits: `5`, `0.125`, `12.35`, `2.5e-7`).
pub fn fmt_num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        // Mantissa with trailing zeros trimmed: 1e-6, 2.5e-7.
        let s = format!("{v:.3e}");
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    }
}
