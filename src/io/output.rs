//! Output files that never destroy anything.
//!
//! Every file goniofit writes (tables, truth JSON, pictures) goes through [`write_atomic`]:
//!
//! * `-` is standard output.
//! * A regular file, a path that does not exist yet, or a symlink to either is replaced
//!   atomically: the bytes go to a hidden temporary (`.goniofit-*.tmp`) in the folder of the
//!   final target (a symlink's target, not the link), which is renamed over the target only
//!   when everything was written and synced. An error leaves the old file untouched and no
//!   temporary behind; so does an interrupt (Ctrl-C, SIGTERM: see [`remove_temporaries`]).
//! * Anything else (a character device such as `/dev/null` or `/dev/full`, a FIFO, a
//!   socket) and every path under `/dev` or `/proc` is written straight through, never
//!   replaced; `/dev/stdout`, `/dev/stderr` and `/dev/fd/1`, `/dev/fd/2` are the process's
//!   own standard streams.
//!
//! New files get mode 0o666 less the umask (0644 under the usual umask 022), the mode of a
//! file made by `>` in a shell; a replaced file gets the same, whatever it had.
//!
//! Faults, the same for every command: a path that cannot be created (no such folder,
//! permission denied, a folder, a read-only file system) is an [`Error::File`] (exit code 2:
//! bad usage); a write that fails once started (disk full, I/O error) is an
//! [`Error::Write`] (exit code 1). A closed pipe (`goniofit eval … | head`, a FIFO whose
//! reader went away) is not an error: the rest of that output is dropped and the command
//! goes on (its exit code is its own).
//!
//! [`check_distinct`] refuses an output that is one of the inputs or another output (same
//! file after following symlinks, or the same path yet to be created), before anything is
//! written.

use crate::error::{Error, Result};
use std::io::{ErrorKind, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::Mutex;

/// Temporaries being written right now, removed by [`remove_temporaries`] on an interrupt.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Remove every temporary file an unfinished [`write_atomic`] holds. The interrupt handler
/// calls this before it ends the process, so that Ctrl-C never leaves a hidden
/// `.goniofit-*.tmp` behind. Safe to call from any thread at any time (a temporary that was
/// already renamed into place is not touched: its name no longer exists).
pub fn remove_temporaries() {
    let list = match TEMPORARIES.lock() {
        Ok(l) => l,
        Err(poisoned) => poisoned.into_inner(),
    };
    for p in list.iter() {
        let _ = std::fs::remove_file(p);
    }
}

/// A registered temporary: listed while alive, unlisted on drop.
struct Registered(PathBuf);

impl Registered {
    fn new(path: &Path) -> Self {
        if let Ok(mut l) = TEMPORARIES.lock() {
            l.push(path.to_path_buf());
        }
        Registered(path.to_path_buf())
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        if let Ok(mut l) = TEMPORARIES.lock() {
            l.retain(|p| p != &self.0);
        }
    }
}

/// Where the bytes of an output go.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Sink {
    /// The process's standard output (`-`, `/dev/stdout`, `/dev/fd/1`).
    Stdout,
    /// The process's standard error (`/dev/stderr`, `/dev/fd/2`).
    Stderr,
    /// A regular file (or one yet to be made), replaced atomically; the path is the final
    /// target after following symlinks.
    Replace(PathBuf),
    /// A device, FIFO, socket or anything under `/dev` or `/proc`: opened and written.
    Through(PathBuf),
}

/// Decide how `path` is written (see the module docs).
pub fn sink_of(path: &Path) -> Sink {
    if path.as_os_str() == "-" {
        return Sink::Stdout;
    }
    let s = path.to_string_lossy();
    match s.as_ref() {
        "/dev/stdout" | "/dev/fd/1" | "/proc/self/fd/1" => return Sink::Stdout,
        "/dev/stderr" | "/dev/fd/2" | "/proc/self/fd/2" => return Sink::Stderr,
        _ => {}
    }
    let target = follow_symlinks(path);
    if under_system_folder(path) || under_system_folder(&target) {
        return Sink::Through(path.to_path_buf());
    }
    match std::fs::metadata(&target) {
        Ok(m) if !m.is_file() && !m.is_dir() => Sink::Through(path.to_path_buf()),
        _ => Sink::Replace(target),
    }
}

/// Whether `path` (absolute) lies under `/dev` or `/proc`, whose entries alias devices and
/// open files and must never be replaced.
fn under_system_folder(path: &Path) -> bool {
    let mut c = path.components();
    c.next() == Some(Component::RootDir)
        && matches!(c.next(), Some(Component::Normal(n)) if n == "dev" || n == "proc")
}

/// `path` with every symlink of its last component followed (at most 40, as the kernel);
/// the result may not exist (a dangling link names the file to create).
fn follow_symlinks(path: &Path) -> PathBuf {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => match std::fs::read_link(&p) {
                Ok(t) if t.is_absolute() => p = t,
                Ok(t) => {
                    p = p.parent().map_or_else(|| t.clone(), |d| d.join(&t));
                }
                Err(_) => break,
            },
            _ => break,
        }
    }
    p
}

/// Whether an I/O error means the path itself is unusable (the user's choice of output,
/// exit 2) rather than a failure while writing (exit 1).
fn is_path_fault(kind: ErrorKind) -> bool {
    matches!(
        kind,
        ErrorKind::NotFound
            | ErrorKind::PermissionDenied
            | ErrorKind::IsADirectory
            | ErrorKind::NotADirectory
            | ErrorKind::ReadOnlyFilesystem
            | ErrorKind::AlreadyExists
    )
}

/// The error for a failure to open or create `path` (`dir`: the folder it goes in).
fn open_error(path: &Path, dir: Option<&Path>, e: std::io::Error) -> Error {
    if !is_path_fault(e.kind()) {
        return Error::Write {
            path: path.to_path_buf(),
            source: e,
        };
    }
    let why = match dir {
        Some(d) if !d.is_dir() => format!("no such directory: {}", d.display()),
        Some(d) => format!(
            "cannot create a file in directory {}: {}",
            d.display(),
            e.kind()
        ),
        None => format!("cannot open: {}", e.kind()),
    };
    Error::File {
        path: path.to_path_buf(),
        message: why,
    }
}

/// Run `f` on `w`, flush; a closed pipe ends the output quietly.
fn pour(
    w: &mut dyn Write,
    f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    match f(w).and_then(|()| w.flush()) {
        Err(e) if e.kind() == ErrorKind::BrokenPipe => Ok(()),
        r => r,
    }
}

/// Write an output file (or stream) without ever leaving a half-written or destroyed file:
/// see the module docs for what each kind of path gets. `f` writes the content (through a
/// buffer); its errors and the file system's are reported with the path.
pub fn write_atomic(
    path: &Path,
    f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let write_err = |name: &Path| {
        let name = name.to_path_buf();
        move |source| Error::Write { path: name, source }
    };
    match sink_of(path) {
        Sink::Stdout => {
            let mut w = std::io::BufWriter::new(std::io::stdout().lock());
            pour(&mut w, f).map_err(write_err(Path::new("<standard output>")))
        }
        Sink::Stderr => {
            let mut w = std::io::BufWriter::new(std::io::stderr().lock());
            pour(&mut w, f).map_err(write_err(Path::new("<standard error>")))
        }
        Sink::Through(p) => {
            let file = std::fs::OpenOptions::new()
                .write(true)
                .open(&p)
                .map_err(|e| open_error(path, None, e))?;
            let mut w = std::io::BufWriter::new(file);
            pour(&mut w, f).map_err(write_err(path))
        }
        Sink::Replace(target) => replace(path, &target, f),
    }
}

/// The atomic replacement of the regular file `target` (named `path` on the command line).
fn replace(
    path: &Path,
    target: &Path,
    f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let write_err = |source| Error::Write {
        path: path.to_path_buf(),
        source,
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if target.is_dir() {
        return Err(Error::File {
            path: path.to_path_buf(),
            message: "is a directory (name a file to write)".into(),
        });
    }
    let mut builder = tempfile::Builder::new();
    builder.prefix(".goniofit-").suffix(".tmp");
    // An ordinary output file: 0o666 less the umask, not the temporary's private 0o600.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(&dir)
        .map_err(|e| open_error(path, Some(&dir), e))?;
    let _listed = Registered::new(tmp.path());
    {
        let mut w = std::io::BufWriter::new(tmp.as_file());
        f(&mut w).map_err(write_err)?;
        w.flush().map_err(write_err)?;
    }
    tmp.as_file().sync_all().map_err(write_err)?;
    tmp.persist(target).map_err(|e| write_err(e.error))?;
    Ok(())
}

/// [`write_atomic`] of bytes already in memory.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// Print `text` on standard output; a closed pipe is not an error (see the module docs),
/// any other failure (a full disk behind a redirection) is an [`Error::Write`].
pub fn print_stdout(text: &str) -> Result<()> {
    write_atomic(Path::new("-"), |w| w.write_all(text.as_bytes()))
}

/// Identity of a file for [`check_distinct`]: device and inode when it exists (after
/// symlinks), otherwise the absolute path it would be created at.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

fn identity(path: &Path) -> Option<Identity> {
    if path.as_os_str() == "-" {
        return None;
    }
    #[cfg(unix)]
    if let Ok(m) = std::fs::metadata(path) {
        use std::os::unix::fs::MetadataExt;
        // Devices and FIFOs (`/dev/null` twice) are not files that could be destroyed.
        return m.is_file().then(|| Identity::Inode(m.dev(), m.ino()));
    }
    let target = follow_symlinks(path);
    let name = target.file_name()?;
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    Some(Identity::Path(dir.join(name)))
}

/// Refuse (a usage error, exit code 2) when two of the named files are the same file:
/// `inputs` are read, `outputs` written; each comes with the option that named it
/// (`"input"`, `"--out"`, ...). Checked before anything is written, so that
/// `goniofit eval X.csv -o X.csv` cannot destroy X.csv.
pub fn check_distinct(inputs: &[(&str, &Path)], outputs: &[(&str, &Path)]) -> Result<()> {
    let ids: Vec<(bool, &str, &Path, Option<Identity>)> = inputs
        .iter()
        .map(|&(o, p)| (false, o, p, identity(p)))
        .chain(outputs.iter().map(|&(o, p)| (true, o, p, identity(p))))
        .collect();
    for (j, b) in ids.iter().enumerate() {
        if !b.0 {
            continue;
        }
        for a in &ids[..j] {
            if a.3.is_some() && a.3 == b.3 {
                return Err(Error::Usage(format!(
                    "{} {} and {} {} are the same file: writing it would destroy {}; name another output",
                    a.1,
                    a.2.display(),
                    b.1,
                    b.2.display(),
                    if a.0 { "the other output" } else { "the input" },
                )));
            }
        }
    }
    Ok(())
}
