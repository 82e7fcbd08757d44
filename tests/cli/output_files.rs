//! Output files end to end, for every command that writes one: special files are written
//! through (never replaced), symlinked files are replaced at their target, the same file in
//! and out is refused (exit 2), a failed write leaves no partial file and no temporary
//! (exit 1, the same for every command), a closed pipe is quiet, and every file has the
//! mode of a file made the ordinary way.

#![cfg(unix)]

use assert_cmd::Command;
use predicates::prelude::*;
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(p)
}

fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

fn bin() -> PathBuf {
    assert_cmd::cargo::cargo_bin("goniofit")
}

/// Names in `dir`, sorted (hidden temporaries included).
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const EVAL: [&str; 5] = ["eval", "--model", "lambert", "--params", "scale=1"];

/// The eval table of `angles_inplane.csv`, as printed on stdout.
fn eval_table() -> Vec<u8> {
    goniofit()
        .args(EVAL)
        .arg(data("angles_inplane.csv"))
        .assert()
        .success()
        .get_output()
        .stdout
        .clone()
}

/// `eval … angles_inplane.csv -o OUT`, which must succeed.
fn eval_to(out: &Path) {
    goniofit()
        .args(EVAL)
        .arg(data("angles_inplane.csv"))
        .arg("-o")
        .arg(out)
        .assert()
        .success();
}

/// The `.goniofit-*.tmp` names in `dir`.
fn temporaries(dir: &Path) -> Vec<std::ffi::OsString> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| {
            let n = n.to_string_lossy();
            n.starts_with(".goniofit-") && n.ends_with(".tmp")
        })
        .collect()
}

/// `-o /dev/stdout` writes through the device: the table reaches stdout, and `/dev/stdout`
/// stays the link or device it was (a write through a temporary and a rename, as a regular file
/// gets, would replace it by a file when run as root, or fail otherwise), with no
/// temporary left in /dev.
#[test]
fn dev_stdout_prints_the_table() {
    let what = || {
        let meta = std::fs::symlink_metadata("/dev/stdout").unwrap();
        (meta.file_type(), std::fs::read_link("/dev/stdout").ok())
    };
    let before = what();
    let out = goniofit()
        .args(EVAL)
        .arg(data("angles_inplane.csv"))
        .args(["-o", "/dev/stdout"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    assert_eq!(out, eval_table());
    assert!(!before.0.is_file(), "{before:?}");
    assert_eq!(what(), before);
    assert_eq!(
        temporaries(Path::new("/dev")),
        Vec::<std::ffi::OsString>::new()
    );
}

#[test]
fn a_symlink_keeps_being_a_link_and_its_target_is_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("target.csv");
    std::fs::write(&target, "old\n").unwrap();
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink("target.csv", &link).unwrap();
    eval_to(&link);
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read(&target).unwrap(), eval_table());
    assert_eq!(names(dir.path()), ["link.csv", "target.csv"]);

    // A dangling link names the file to create.
    let dangling = dir.path().join("dangling.csv");
    std::os::unix::fs::symlink("made.csv", &dangling).unwrap();
    eval_to(&dangling);
    assert_eq!(
        std::fs::read(dir.path().join("made.csv")).unwrap(),
        eval_table()
    );
}

/// `mkfifo path` (the test needs the tool).
fn mkfifo(path: &Path) {
    let ok = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap();
    assert!(ok.success());
}

#[test]
fn a_fifo_is_written_through_not_replaced() {
    use std::io::Read;
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.csv");
    mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut s = Vec::new();
            std::fs::File::open(&fifo)
                .unwrap()
                .read_to_end(&mut s)
                .unwrap();
            s
        })
    };
    eval_to(&fifo);
    assert_eq!(reader.join().unwrap(), eval_table());
    let ft = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(ft.is_fifo(), "the FIFO was replaced: {ft:?}");
    assert_eq!(names(dir.path()), ["pipe.csv"]);
}

/// A link in a temporary folder to `/dev/full` (every write fails with ENOSPC, "disk
/// full"). Through a link, so that even a regression replaces only the link.
fn full_disk(dir: &Path) -> PathBuf {
    let p = dir.join("full.csv");
    std::os::unix::fs::symlink("/dev/full", &p).unwrap();
    p
}

#[test]
fn a_full_disk_is_exit_1_for_every_command() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let full = full_disk(dir.path());
    let runs: Vec<Vec<std::ffi::OsString>> = vec![
        EVAL.iter()
            .map(Into::into)
            .chain([
                data("angles_inplane.csv").into(),
                "-o".into(),
                full.clone().into(),
            ])
            .collect(),
        [
            "synth", "--model", "lambert", "--params", "scale=1", "--truth",
        ]
        .iter()
        .map(Into::into)
        .chain([full.clone().into()])
        .collect(),
        ["fit", "--model", "lambert", "--residuals"]
            .iter()
            .map(Into::into)
            .chain([
                full.clone().into(),
                data("synthetic/lambert_specular.csv").into(),
            ])
            .collect(),
    ];
    for args in runs {
        goniofit()
            .args(&args)
            .assert()
            .code(1)
            .stderr(predicate::str::contains("No space left on device"));
    }
    // Standard output on a full disk: the same code for eval, synth and fit.
    for args in [
        [&EVAL[..], &[data("angles_inplane.csv").to_str().unwrap()]].concat(),
        vec!["synth", "--model", "lambert", "--params", "scale=1"],
        vec![
            "fit",
            "--model",
            "lambert",
            data("synthetic/lambert_specular.csv").to_str().unwrap(),
        ],
    ] {
        let out = std::process::Command::new(bin())
            .args(&args)
            .stdout(std::fs::File::create(&full).unwrap())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("No space left on device"));
    }
    let ft = std::fs::metadata("/dev/full").unwrap().file_type();
    assert!(ft.is_char_device());
    assert_eq!(names(dir.path()), ["full.csv"]);
}

/// Run goniofit with a file-size limit of `kib` KiB (writes beyond it fail with EFBIG, as
/// on a full disk; SIGXFSZ is ignored so that the write returns the error).
fn limited(kib: u32, args: &[&std::ffi::OsStr]) -> std::process::Output {
    std::process::Command::new("bash")
        .arg("-c")
        .arg(format!("trap '' XFSZ; ulimit -f {kib}; exec \"$0\" \"$@\""))
        .arg(bin())
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn a_failed_write_leaves_the_old_file_and_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // eval -o of ~2 MB, with 64 KiB allowed: the old file stays, nothing else appears.
    let out = d.join("table.csv");
    std::fs::write(&out, "old\n").unwrap();
    let ptfe = data("nist-ptfe/PTFE.data.csv");
    let mut args: Vec<&std::ffi::OsStr> = EVAL.iter().map(|s| s.as_ref()).collect();
    args.extend([ptfe.as_os_str(), "-o".as_ref(), out.as_os_str()]);
    let r = limited(64, &args);
    assert_eq!(r.status.code(), Some(1), "{r:?}");
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("table.csv: writing failed: File too large"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old\n");
    assert_eq!(names(d), ["table.csv"]);

    // render: a PNG of 2048² px does not fit in 16 KiB: no file, a clean message.
    let png = d.join("sphere.png");
    let r = limited(
        16,
        &[
            "render", "sphere", "--model", "lambert", "--params", "scale=1", "--size", "2048",
            "--out",
        ]
        .iter()
        .map(|s| s.as_ref())
        .chain([png.as_os_str()])
        .collect::<Vec<_>>(),
    );
    assert_eq!(r.status.code(), Some(1), "{r:?}");
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("sphere.png: writing failed: File too large"),
        "{err}"
    );
    assert!(!err.contains("Error {") && !err.contains("Os {"), "{err}");
    assert_eq!(names(d), ["table.csv"]);

    // fit --plot: the pictures that did not fit leave nothing, not a 0-byte or cut PNG.
    let plots = d.join("plots");
    let r = limited(
        24,
        &["fit", "--model", "lambert", "--plot"]
            .iter()
            .map(|s| s.as_ref())
            .chain([
                plots.as_os_str(),
                data("synthetic/lambert_specular.csv").as_os_str(),
            ])
            .collect::<Vec<_>>(),
    );
    assert_eq!(r.status.code(), Some(1), "{r:?}");
    for name in names(&plots) {
        assert!(!name.starts_with('.'), "temporary left: {name}");
        let bytes = std::fs::read(plots.join(&name)).unwrap();
        if name.ends_with(".png") {
            // A whole PNG ends with its IEND chunk.
            assert!(
                bytes.ends_with(&[0x49, 0x45, 0x4E, 0x44, 0xAE, 0x42, 0x60, 0x82]),
                "{name}"
            );
        } else {
            assert!(
                String::from_utf8(bytes)
                    .unwrap()
                    .trim_end()
                    .ends_with("</svg>"),
                "{name}"
            );
        }
    }
}

#[test]
fn the_same_file_in_and_out_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let x = d.join("x.csv");
    std::fs::copy(data("synthetic/lambert_specular.csv"), &x).unwrap();
    let original = std::fs::read(&x).unwrap();
    let link = d.join("alias.csv");
    std::os::unix::fs::symlink(&x, &link).unwrap();
    let s = d.join("s.csv");
    // Command lines as text (the temporary folder's path has no blanks).
    let (x, link, s) = (x.display(), link.display(), s.display());
    let lambert = "--model lambert --params scale=1";
    let cases = [
        (format!("eval {lambert} {x} -o {x}"), "input"),
        (format!("eval {lambert} {x} -o {link}"), "input"),
        (format!("fit --model lambert {x} --residuals {x}"), "input"),
        (format!("synth {lambert} --layout {x} --out {x}"), "input"),
        (
            format!("synth {lambert} --out {s} --truth {s}"),
            "other output",
        ),
    ];
    for (line, what) in cases {
        let args: Vec<&str> = line.split(' ').collect();
        goniofit().args(&args).assert().code(2).stdout("").stderr(
            predicate::str::contains("are the same file").and(predicate::str::contains(format!(
                "would destroy the {what}"
            ))),
        );
        assert_eq!(std::fs::read(d.join("x.csv")).unwrap(), original, "{line}");
    }
    assert_eq!(names(d), ["alias.csv", "x.csv"]);
}

#[test]
fn every_output_has_the_ordinary_mode() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plain = d.join("plain");
    std::fs::write(&plain, "x").unwrap();
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    let want = mode(&plain);
    let s = d.join("s.csv");
    goniofit()
        .args([
            "synth", "--model", "lambert", "--params", "scale=1", "--out",
        ])
        .arg(&s)
        .assert()
        .success();
    let e = d.join("e.csv");
    goniofit()
        .args(EVAL)
        .arg(&s)
        .arg("-o")
        .arg(&e)
        .assert()
        .success();
    let r = d.join("r.csv");
    let plots = d.join("plots");
    goniofit()
        .args(["fit", "--model", "lambert", "--residuals"])
        .arg(&r)
        .arg("--plot")
        .arg(&plots)
        .arg(data("synthetic/lambert_specular.csv"))
        .assert()
        .success();
    let png = d.join("sphere.png");
    goniofit()
        .args([
            "render", "sphere", "--model", "lambert", "--params", "scale=1", "--size", "16",
            "--out",
        ])
        .arg(&png)
        .assert()
        .success();
    let mut files = vec![s.clone(), d.join("s.truth.json"), e, r, png];
    files.extend(names(&plots).iter().map(|n| plots.join(n)));
    assert!(files.len() >= 15);
    for f in files {
        assert_eq!(mode(&f), want, "{}", f.display());
    }
}

#[test]
fn a_closed_pipe_is_quiet_for_every_command() {
    use std::process::Stdio;
    for args in [
        vec!["synth", "--model", "lambert", "--params", "scale=1"],
        vec!["fit", "--model", "lambert", "--json"],
        vec!["fit", "--model", "lambert"],
    ] {
        let mut cmd = std::process::Command::new(bin());
        cmd.args(&args);
        if args[0] == "fit" {
            cmd.arg(data("synthetic/lambert_specular.csv"));
        }
        // The reader is gone before anything is written: every write meets EPIPE.
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        assert!(
            !err.contains("error") && !err.contains("panic"),
            "{args:?}: {err}"
        );
    }
}
