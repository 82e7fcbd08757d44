//! Output files that never destroy anything.
//!
//! Every file goniofit writes (tables, truth JSON, pictures) goes through [`write_atomic`]:
//!
//! * `-` is standard output.
//! * A regular file, a path that does not exist yet, or a symlink to either is replaced
//!   atomically: the bytes go to a hidden temporary (`.goniofit-*.tmp`) in the folder of the
//!   final target (a symlink's target, not the link; see below), which is renamed over the target only
//!   when everything was written and synced. An error leaves the old file untouched and no
//!   temporary behind; so does an interrupt (Ctrl-C, SIGTERM: see [`remove_temporaries`]).
//! * Anything else (a character device such as `/dev/null` or `/dev/full`, a FIFO, a
//!   socket) and every path under `/dev` or `/proc` is written straight through, never
//!   replaced; `/dev/stdout`, `/dev/stderr` and `/dev/fd/1`, `/dev/fd/2` are the process's
//!   own standard streams.
//!
//! New files get mode 0o666 less the umask (0644 under the usual umask 022), the mode of a
//! file made by `>` in a shell; a replaced file keeps its permission bits, and its owner
//! and group where we may set them (a group that cannot be kept loses its permissions).
//!
//! Symlinks are followed as the kernel follows them on open: at most 40 in a row (a loop
//! is an [`Error::File`], never replaced by a file), and a link in a sticky world-writable
//! folder (`/tmp`) only when it belongs to us or to the folder's owner
//! (`fs.protected_symlinks`; otherwise an [`Error::File`]).
//!
//! Faults, the same for every command: a path that cannot be created (no such folder,
//! permission denied, a folder, a read-only file system) is an [`Error::File`] (exit code 2:
//! bad usage); a write that fails once started (disk full, I/O error) is an
//! [`Error::Write`] (exit code 1). A closed pipe (`goniofit eval … | head`, a FIFO whose
//! reader went away) is not an error: the rest of that output is dropped and the command
//! goes on (its exit code is its own).
//!
//! Before anything is written, every command checks all its files together
//! ([`super::files::FileSet`]): no output is an input or another output, and every output
//! path is usable (the same symlink rules, a name the file system takes).

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
pub(crate) fn remove_temporaries() {
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
pub(crate) enum Sink {
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

/// Decide how `path` is written (see the module docs). A symlink the kernel would not
/// follow (see `resolve_symlinks`) or a loop of symlinks is an [`Error::File`].
pub(crate) fn sink_of(path: &Path) -> Result<Sink> {
    if path.as_os_str() == "-" {
        return Ok(Sink::Stdout);
    }
    let s = path.to_string_lossy();
    match s.as_ref() {
        "/dev/stdout" | "/dev/fd/1" | "/proc/self/fd/1" => return Ok(Sink::Stdout),
        "/dev/stderr" | "/dev/fd/2" | "/proc/self/fd/2" => return Ok(Sink::Stderr),
        _ => {}
    }
    if under_system_folder(path) {
        return Ok(Sink::Through(path.to_path_buf()));
    }
    let target = resolve_symlinks(path)?;
    if under_system_folder(&target) {
        return Ok(Sink::Through(path.to_path_buf()));
    }
    Ok(match std::fs::metadata(&target) {
        Ok(m) if !m.is_file() && !m.is_dir() => Sink::Through(path.to_path_buf()),
        _ => Sink::Replace(target),
    })
}

/// Whether `path` (absolute) lies under `/dev` or `/proc`, whose entries alias devices and
/// open files and must never be replaced.
fn under_system_folder(path: &Path) -> bool {
    let mut c = path.components();
    c.next() == Some(Component::RootDir)
        && matches!(c.next(), Some(Component::Normal(n)) if n == "dev" || n == "proc")
}

/// Symlinks followed in a row before giving up, as the kernel (`ELOOP`).
const MAX_SYMLINKS: usize = 40;

/// `path` with every symlink of its last component followed, as the kernel follows them
/// when it opens a file: at most [`MAX_SYMLINKS`] (more, or a loop, is an [`Error::File`]),
/// and a link in a sticky world-writable folder (such as `/tmp`) only when it belongs to
/// us or to the folder's owner (the `fs.protected_symlinks` rule; otherwise an
/// [`Error::File`]), so that a link planted there by another user cannot make goniofit
/// replace a file that user could not touch. The result may not exist (a dangling link
/// names the file to create).
fn resolve_symlinks(path: &Path) -> Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..=MAX_SYMLINKS {
        let link = match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => m,
            _ => return Ok(p),
        };
        check_protected_link(path, &p, &link)?;
        match std::fs::read_link(&p) {
            Ok(t) if t.is_absolute() => p = t,
            Ok(t) => p = p.parent().map_or_else(|| t.clone(), |d| d.join(&t)),
            Err(_) => return Ok(p),
        }
    }
    Err(Error::File {
        path: path.to_path_buf(),
        message: "too many levels of symbolic links (a loop of links?)".into(),
    })
}

/// Refuse to follow the symlink `link` (met resolving `path`; `meta`: the link's own
/// metadata) where the kernel's `fs.protected_symlinks` rule forbids it: the link lies in
/// a sticky world-writable folder, and neither we nor that folder's owner own it.
fn check_protected_link(path: &Path, link: &Path, meta: &std::fs::Metadata) -> Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let dir = match link.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let Ok(folder) = std::fs::metadata(dir) else {
            return Ok(());
        };
        const STICKY_WORLD_WRITABLE: u32 = 0o1002;
        // SAFETY: geteuid has no preconditions and cannot fail.
        let euid = unsafe { libc::geteuid() };
        if folder.mode() & STICKY_WORLD_WRITABLE == STICKY_WORLD_WRITABLE
            && meta.uid() != euid
            && meta.uid() != folder.uid()
        {
            return Err(Error::File {
                path: path.to_path_buf(),
                message: format!(
                    "not followed: the symlink {} lies in a sticky world-writable folder and belongs to another user (uid {}), as the kernel's protected_symlinks rule refuses; name the file itself",
                    shown(link),
                    meta.uid()
                ),
            });
        }
    }
    #[cfg(not(unix))]
    let _ = (path, link, meta);
    Ok(())
}

/// Whether an I/O error means the path itself is unusable (the user's choice of output,
/// exit 2) rather than a failure while writing (exit 1).
/// A name too long for the file system (`ENAMETOOLONG`) or a loop of symlinks (`ELOOP`) is
/// a path fault too.
fn is_path_fault(e: &std::io::Error) -> bool {
    #[cfg(unix)]
    if matches!(e.raw_os_error(), Some(libc::ENAMETOOLONG | libc::ELOOP)) {
        return true;
    }
    matches!(
        e.kind(),
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
    if !is_path_fault(&e) {
        return Error::Write {
            path: path.to_path_buf(),
            source: e,
        };
    }
    let why = match dir {
        Some(d) if !d.is_dir() => format!("no such directory: {}", shown(d)),
        Some(d) => format!("cannot create a file in directory {}: {e}", shown(d)),
        None => format!("cannot open: {e}"),
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
pub(crate) fn write_atomic(
    path: &Path,
    f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let write_err = |name: &Path| {
        let name = name.to_path_buf();
        move |source| Error::Write { path: name, source }
    };
    match sink_of(path)? {
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
    keep_attributes(&tmp.file, target);
    {
        let mut w = std::io::BufWriter::new(&tmp.file);
        f(&mut w).map_err(write_err)?;
        w.flush().map_err(write_err)?;
    }
    tmp.file.sync_all().map_err(write_err)?;
    tmp.persist(target).map_err(|e| {
        if is_path_fault(&e) {
            open_error(path, Some(&dir), e)
        } else {
            write_err(e)
        }
    })?;
    Ok(())
}

/// Give the new file `tmp` the mode (permission bits) and, where we may, the owner and
/// group of the file `target` it is about to replace (nothing when there is none): a
/// private file stays private. A group that cannot be kept takes the group's permission
/// bits with it, so the new group cannot read what the old one could not.
fn keep_attributes(tmp: &std::fs::File, target: &Path) {
    #[cfg(unix)]
    {
        use std::os::unix::fs::{fchown, MetadataExt, PermissionsExt};
        let Ok(old) = std::fs::metadata(target) else {
            return;
        };
        let mut mode = old.mode() & 0o777;
        if fchown(tmp, Some(old.uid()), Some(old.gid())).is_err()
            && fchown(tmp, None, Some(old.gid())).is_err()
        {
            mode &= !0o070;
        }
        let _ = tmp.set_permissions(std::fs::Permissions::from_mode(mode));
    }
    #[cfg(not(unix))]
    let _ = (tmp, target);
}

/// [`write_atomic`] of bytes already in memory.
pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// Print `text` on standard output; a closed pipe is not an error (see the module docs),
/// any other failure (a full disk behind a redirection) is an [`Error::Write`].
pub(crate) fn print_stdout(text: &str) -> Result<()> {
    write_atomic(Path::new("-"), |w| w.write_all(text.as_bytes()))
}
