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

use super::shown;
use crate::error::{Error, Result};
use std::io::{ErrorKind, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::Mutex;

/// Temporaries that exist (or are about to be made) right now, removed by
/// [`remove_temporaries`] on an interrupt; `closed` once it ran (the process is ending).
struct Temporaries {
    paths: Vec<PathBuf>,
    closed: bool,
}

static TEMPORARIES: Mutex<Temporaries> = Mutex::new(Temporaries {
    paths: Vec::new(),
    closed: false,
});

/// The list, also after a thread panicked while holding it.
fn temporaries() -> std::sync::MutexGuard<'static, Temporaries> {
    TEMPORARIES
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Remove every temporary file an unfinished [`write_atomic`] holds. The interrupt handler
/// calls this just before it ends the process, so that Ctrl-C never leaves a hidden
/// `.goniofit-*.tmp` behind, whatever the moment: a temporary is listed before it is
/// created and created, renamed into place or removed only while the list is held, so the
/// handler sees each one either not yet made (and then never made: after this call no
/// temporary is created nor renamed into place, the writing thread waits for the end of
/// the process) or made and not yet renamed (removed here). Safe to call from any thread
/// at any time.
pub fn remove_temporaries() {
    let mut list = temporaries();
    list.closed = true;
    for p in &list.paths {
        let _ = std::fs::remove_file(p);
    }
}

/// The thread of a [`write_atomic`] that came after [`remove_temporaries`]: the process is
/// ending; wait for it without touching any file.
fn wait_for_the_end() -> ! {
    loop {
        std::thread::park();
    }
}

/// A registered temporary: listed from before it is created, removed (unless renamed into
/// place by [`Registered::persist`]) and unlisted on drop.
struct Registered {
    path: PathBuf,
    file: std::fs::File,
    persisted: bool,
}

impl Registered {
    /// Create a new hidden temporary in `dir`, listed before it exists.
    fn create_in(dir: &Path) -> std::io::Result<Registered> {
        static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let mut open = std::fs::OpenOptions::new();
        open.write(true).create_new(true);
        // An ordinary output file: 0o666 less the umask, not a temporary's private 0o600.
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            open.mode(0o666);
        }
        let mut tries = 0;
        loop {
            let k = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let salt: u32 = rand::random();
            let path = dir.join(format!(
                ".goniofit-{}-{k}-{salt:08x}.tmp",
                std::process::id()
            ));
            let mut list = temporaries();
            if list.closed {
                drop(list);
                wait_for_the_end();
            }
            list.paths.push(path.clone());
            match open.open(&path) {
                Ok(file) => {
                    return Ok(Registered {
                        path,
                        file,
                        persisted: false,
                    })
                }
                Err(e) => {
                    list.paths.pop();
                    tries += 1;
                    if e.kind() != ErrorKind::AlreadyExists || tries >= 100 {
                        return Err(e);
                    }
                }
            }
        }
    }

    /// Rename the temporary over `target` (atomic on one file system).
    fn persist(mut self, target: &Path) -> std::io::Result<()> {
        let list = temporaries();
        if list.closed {
            drop(list);
            wait_for_the_end();
        }
        std::fs::rename(&self.path, target)?;
        self.persisted = true;
        Ok(())
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        let mut list = temporaries();
        if !self.persisted {
            let _ = std::fs::remove_file(&self.path);
        }
        list.paths.retain(|p| p != &self.path);
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
        Some(d) if !d.is_dir() => format!("no such directory: {}", shown(d)),
        Some(d) => format!(
            "cannot create a file in directory {}: {}",
            shown(d),
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
    let tmp = Registered::create_in(&dir).map_err(|e| open_error(path, Some(&dir), e))?;
    {
        let mut w = std::io::BufWriter::new(&tmp.file);
        f(&mut w).map_err(write_err)?;
        w.flush().map_err(write_err)?;
    }
    tmp.file.sync_all().map_err(write_err)?;
    tmp.persist(target).map_err(write_err)?;
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
