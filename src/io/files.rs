//! The files one command reads and writes, checked together before anything is written.
//!
//! Every command lists all its inputs and outputs in a [`FileSet`] — the files named by
//! its options, the pictures it writes into a folder, and standard output when it prints
//! there — and [`FileSet::check`] runs before the command reads or writes anything. It
//! refuses (exit code 2):
//!
//! * an output that is an input or another output: the same file after following
//!   symlinks (device and inode), or the same path yet to be created (`./a.csv` and
//!   `a.csv`, a dangling link and its target). Standard output counts as the file it is
//!   redirected to (`goniofit fit h.csv >> h.csv`); two outputs written through to the
//!   same stream (the report and `--residuals -`) are no conflict;
//! * an output path that cannot be used: a symlink the kernel would not follow, a loop of
//!   symlinks ([`super::output::sink_of`]), a name too long for the file system, a folder
//!   where a file is to be written, a file where a folder of pictures is to be made.

use super::output::{sink_of, Sink};
use super::shown;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The option naming standard output in messages.
const STDOUT: &str = "standard output";

/// Every file of one command: inputs, outputs and folders of pictures, each with the
/// option that names it (`"input"`, `"--out"`, `"--plot"`, ...).
#[derive(Debug, Default)]
pub(crate) struct FileSet {
    inputs: Vec<(String, PathBuf)>,
    outputs: Vec<(String, PathBuf)>,
    folders: Vec<(String, PathBuf)>,
}

impl FileSet {
    /// An empty set.
    pub(crate) fn new() -> FileSet {
        FileSet::default()
    }

    /// A file the command reads.
    pub(crate) fn input(mut self, option: &str, path: &Path) -> FileSet {
        self.inputs.push((option.to_string(), path.to_path_buf()));
        self
    }

    /// A file the command writes (`-`: standard output).
    pub(crate) fn output(mut self, option: &str, path: &Path) -> FileSet {
        self.outputs.push((option.to_string(), path.to_path_buf()));
        self
    }

    /// [`FileSet::output`] when `path` is given.
    pub(crate) fn output_opt(self, option: &str, path: Option<&Path>) -> FileSet {
        match path {
            Some(p) => self.output(option, p),
            None => self,
        }
    }

    /// Standard output, which the command prints to.
    pub(crate) fn stdout(self) -> FileSet {
        self.output(STDOUT, Path::new("-"))
    }

    /// A folder the command creates if needed and writes pictures into: `stem.png` and
    /// `stem.svg` for every stem.
    pub(crate) fn pictures(mut self, option: &str, dir: &Path, stems: &[&str]) -> FileSet {
        self.folders.push((option.to_string(), dir.to_path_buf()));
        for stem in stems {
            for ext in ["png", "svg"] {
                self = self.output(option, &dir.join(format!("{stem}.{ext}")));
            }
        }
        self
    }

    /// Refuse (exit code 2) an unusable output path or two files that are one (see the
    /// module docs); the first problem found is the error.
    pub(crate) fn check(&self) -> Result<()> {
        for (option, dir) in &self.folders {
            check_folder(option, dir)?;
        }
        let mut seen: Vec<Named> = Vec::new();
        for (option, path) in &self.inputs {
            seen.push(Named {
                output: false,
                option,
                path,
                id: input_identity(path),
            });
        }
        for (option, path) in &self.outputs {
            let b = Named {
                output: true,
                option,
                path,
                id: output_identity(option, path)?,
            };
            if let Some(a) = seen.iter().find(|a| a.clashes_with(&b)) {
                return Err(same_file(a, &b));
            }
            seen.push(b);
        }
        Ok(())
    }
}

/// Identity of a file: device and inode when it exists (after symlinks), otherwise the
/// absolute path it would be created at (its existing folders canonical).
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

/// One named file of a [`FileSet`] with its identity (`None`: no file that could be
/// destroyed, such as a terminal or `/dev/null`) and whether it is a stream written
/// through in order (standard output or error).
struct Named<'a> {
    output: bool,
    option: &'a str,
    path: &'a Path,
    id: Option<(Identity, bool)>,
}

impl Named<'_> {
    /// Whether writing the output `b` would destroy `self` (an input or an earlier output).
    fn clashes_with(&self, b: &Named) -> bool {
        match (&self.id, &b.id) {
            (Some((x, x_stream)), Some((y, y_stream))) => {
                x == y && !(self.output && *x_stream && *y_stream)
            }
            _ => false,
        }
    }

    /// How the file is named in messages.
    fn shown(&self) -> String {
        if self.option == STDOUT {
            STDOUT.to_string()
        } else {
            format!("{} {}", self.option, shown(self.path))
        }
    }
}

fn same_file(a: &Named, b: &Named) -> Error {
    Error::Usage(format!(
        "{} and {} are the same file: writing it would destroy {}; name another output",
        a.shown(),
        b.shown(),
        if a.output {
            "the other output"
        } else {
            "the input"
        },
    ))
}

/// The identity of a regular file (after symlinks); `None` for anything else.
fn file_identity(m: &std::fs::Metadata) -> Option<Identity> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        m.is_file().then(|| Identity::Inode(m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        None
    }
}

/// An input's identity: the file it is, or the path it names when it does not exist (the
/// reading will say so); `None` for standard input, devices and FIFOs.
fn input_identity(path: &Path) -> Option<(Identity, bool)> {
    if path.as_os_str() == "-" {
        return None;
    }
    match std::fs::metadata(path) {
        Ok(m) => file_identity(&m).map(|id| (id, false)),
        Err(_) => Some((Identity::Path(absolute(path)), false)),
    }
}

/// An output's identity, after checking that its path can be written (see the module
/// docs): the file a stream goes to when it is a regular file, the file to be replaced,
/// or the path to be created.
fn output_identity(option: &str, path: &Path) -> Result<Option<(Identity, bool)>> {
    let refused = |message: String| Error::File {
        path: path.to_path_buf(),
        message: format!("{option}: {message}"),
    };
    if path.as_os_str() != "-" {
        if let Err(e) = std::fs::symlink_metadata(path) {
            if is_name_too_long(&e) {
                return Err(refused(format!(
                    "the name is too long for the file system ({e}); name a shorter file"
                )));
            }
        }
    }
    Ok(match sink_of(path)? {
        Sink::Stdout => stream_identity(std::io::stdout()),
        Sink::Stderr => stream_identity(std::io::stderr()),
        Sink::Through(_) => None,
        Sink::Replace(target) => match std::fs::metadata(&target) {
            Ok(m) if m.is_dir() => {
                return Err(refused(
                    "is a folder (name a file to write, not a folder)".into(),
                ))
            }
            Ok(m) => file_identity(&m).map(|id| (id, false)),
            Err(_) => Some((Identity::Path(absolute(&target)), false)),
        },
    })
}

/// Whether `e` says a name is too long for the file system (`ENAMETOOLONG`).
fn is_name_too_long(e: &std::io::Error) -> bool {
    #[cfg(unix)]
    {
        e.raw_os_error() == Some(libc::ENAMETOOLONG)
    }
    #[cfg(not(unix))]
    {
        let _ = e;
        false
    }
}

/// The regular file a standard stream is redirected to, if it is one.
#[cfg(unix)]
fn stream_identity(stream: impl std::os::fd::AsFd) -> Option<(Identity, bool)> {
    let fd = stream.as_fd().try_clone_to_owned().ok()?;
    let m = std::fs::File::from(fd).metadata().ok()?;
    file_identity(&m).map(|id| (id, true))
}

#[cfg(not(unix))]
fn stream_identity<T>(_: T) -> Option<(Identity, bool)> {
    None
}

/// A folder of pictures: one that exists must be a folder (not the input file, say).
fn check_folder(option: &str, dir: &Path) -> Result<()> {
    match std::fs::metadata(dir) {
        Ok(m) if !m.is_dir() => Err(Error::File {
            path: dir.to_path_buf(),
            message: format!(
                "{option}: exists and is not a folder (the pictures go into a folder; name a new or existing folder)"
            ),
        }),
        Err(e) if is_name_too_long(&e) => Err(Error::File {
            path: dir.to_path_buf(),
            message: format!("{option}: the name is too long for the file system ({e})"),
        }),
        _ => Ok(()),
    }
}

/// `path` made absolute, with its longest existing ancestor canonical (symlinks and `..`
/// resolved) and the rest as written, `.` left out: two names of one file yet to be
/// created give the same path.
fn absolute(path: &Path) -> PathBuf {
    let mut rest = Vec::new();
    let mut head = path;
    loop {
        let probe = if head.as_os_str().is_empty() {
            Path::new(".")
        } else {
            head
        };
        if let Ok(c) = std::fs::canonicalize(probe) {
            let mut out = c;
            for part in rest.iter().rev() {
                out.push(part);
            }
            return out;
        }
        match (head.parent(), head.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                head = parent;
            }
            _ => return std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_names_of_a_file_yet_to_be_made_are_one() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let a = absolute(&d.join("new/./x.csv"));
        assert_eq!(a, absolute(&d.join("new/x.csv")));
        assert_eq!(a, std::fs::canonicalize(d).unwrap().join("new/x.csv"));
        let set = FileSet::new()
            .output("--out", &d.join("x.csv"))
            .output("--truth", &d.join("./x.csv"));
        let e = set.check().unwrap_err().to_string();
        assert!(e.contains("are the same file"), "{e}");
    }

    #[test]
    fn a_picture_in_a_folder_is_an_output_of_its_own() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let set = FileSet::new()
            .pictures("--plot", &d.join("p"), &["polar"])
            .output("--html", &d.join("p/polar.svg"));
        assert!(set.check().is_err());
        let input = d.join("h.csv");
        std::fs::write(&input, "x").unwrap();
        let set = FileSet::new()
            .input("input", &input)
            .pictures("--plot", &input, &["polar"]);
        let e = set.check().unwrap_err().to_string();
        assert!(e.contains("not a folder"), "{e}");
    }
}
