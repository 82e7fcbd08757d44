//! Every command checks all its outputs against all its inputs and against each other,
//! by the file they are (symlinks, `./` and hard links resolved, standard output as the
//! file it is redirected to), before anything is written: exit 2 and every file as it was.
//! Output paths that cannot be used (a name too long, a loop of symlinks) are exit 2 too,
//! and file names in messages are escaped.

#![cfg(unix)]

use crate::common;

use common::goniofit;
use std::path::{Path, PathBuf};

/// Names in `dir` with their bytes (symlinks as their target's name), sorted.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let p = e.path();
            let meta = std::fs::symlink_metadata(&p).unwrap();
            let bytes = if meta.file_type().is_symlink() {
                std::fs::read_link(&p)
                    .unwrap()
                    .to_string_lossy()
                    .into_owned()
                    .into_bytes()
            } else if meta.is_dir() {
                b"<folder>".to_vec()
            } else {
                std::fs::read(&p).unwrap()
            };
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect();
    v.sort();
    v
}

/// A folder with a measurement `h.csv`, a symlink `link.csv` to it and a hard
/// link `hard.csv` to it.
fn workspace() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    goniofit()
        .current_dir(dir.path())
        .args([
            "synth",
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
            "--noise",
            "0.01",
            "--seed",
            "1",
            "--out",
            "h.csv",
            "--truth",
            "/dev/null",
        ])
        .assert()
        .success();
    std::os::unix::fs::symlink("h.csv", dir.path().join("link.csv")).unwrap();
    std::fs::hard_link(dir.path().join("h.csv"), dir.path().join("hard.csv")).unwrap();
    std::fs::create_dir(dir.path().join("p")).unwrap();
    dir
}

const FIT: &str = "fit --model kbs --wavelength 1 --no-intervals";

/// Run `line` (words split at blanks) in `dir`; expect exit 2 with `message` on standard
/// error, nothing on standard output and no file changed.
fn refused(dir: &Path, line: &str, message: &str) {
    let before = snapshot(dir);
    let out = goniofit()
        .current_dir(dir)
        .args(line.split(' '))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{line}: {err}");
    assert!(err.contains(message), "{line}: {err}");
    assert!(out.stdout.is_empty(), "{line}");
    assert_eq!(snapshot(dir), before, "{line}");
}

#[test]
fn every_output_of_fit_is_checked_against_the_inputs_and_each_other() {
    let dir = workspace();
    let d = dir.path();
    let same = "are the same file";
    for extra in [
        "h.csv --html h.csv",
        "h.csv --summary h.csv",
        "h.csv --summary ./h.csv",
        "./h.csv --residuals h.csv",
        "h.csv --html link.csv",
        "link.csv --summary hard.csv",
        "h.csv --residuals r.csv --html r.csv",
        "h.csv --residuals r.csv --summary ./r.csv",
        "h.csv --plot p --html p/polar.svg",
        "h.csv --plot p --summary p/fit_log.png",
        "--by-group h.csv --summary h.csv",
    ] {
        refused(d, &format!("{FIT} {extra}"), same);
    }
    refused(d, &format!("{FIT} h.csv --plot h.csv"), "not a folder");
    refused(d, &format!("{FIT} h.csv --html p"), "is a folder");
}

#[test]
fn every_other_command_checks_its_outputs() {
    let dir = workspace();
    let d = dir.path();
    let same = "are the same file";
    let kbs = "--model kbs --params sigma=0.3,T=2,scale=1";
    refused(d, &format!("eval {kbs} h.csv -o link.csv"), same);
    refused(d, &format!("eval {kbs} h.csv -o ./hard.csv"), same);
    refused(d, &format!("synth {kbs} --out s.csv --truth ./s.csv"), same);
    refused(
        d,
        &format!("synth {kbs} --layout h.csv --out link.csv"),
        same,
    );
    refused(d, "figures --out h.csv", "not a folder");
    refused(d, "bench work-precision --out h.csv", "not a folder");
    refused(d, "plot h.csv --out h.csv", "not a folder");
    // A picture of `plot` that is the report's own data file, through a link.
    std::os::unix::fs::symlink(d.join("h.csv"), d.join("p/polar.png")).unwrap();
    let report = goniofit()
        .current_dir(d)
        .args(FIT.split(' '))
        .args(["--json", "h.csv"])
        .output()
        .unwrap();
    assert_eq!(report.status.code(), Some(0));
    let report_file = tempfile::NamedTempFile::new().unwrap();
    std::fs::write(report_file.path(), &report.stdout).unwrap();
    let line = format!("plot {} --out p", report_file.path().display());
    refused(d, &line, "the report's input");
}

/// Run `args` in `dir` with standard output appended to `file`; returns the exit code
/// and standard error.
fn with_stdout_to(dir: &Path, args: &str, file: &Path) -> (Option<i32>, String) {
    let out = std::fs::OpenOptions::new().append(true).open(file).unwrap();
    let o = std::process::Command::new(assert_cmd::cargo::cargo_bin("goniofit"))
        .current_dir(dir)
        .args(args.split(' '))
        .stdout(out)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn standard_output_counts_as_the_file_it_goes_to() {
    let dir = workspace();
    let d = dir.path();
    let h = std::fs::read(d.join("h.csv")).unwrap();
    let (code, err) = with_stdout_to(d, &format!("{FIT} h.csv"), &d.join("link.csv"));
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("standard output"), "{err}");
    let (code, err) = with_stdout_to(
        d,
        "eval --model lambert --params scale=1 hard.csv",
        &d.join("h.csv"),
    );
    assert_eq!(code, Some(2), "{err}");
    // The report and --residuals into one file replaced under the report: refused.
    let r = d.join("r.json");
    std::fs::write(&r, "").unwrap();
    let (code, err) = with_stdout_to(d, &format!("{FIT} --json h.csv --residuals r.json"), &r);
    assert_eq!(code, Some(2), "{err}");
    std::fs::write(d.join("p/figure4.svg"), "old").unwrap();
    let (code, err) = with_stdout_to(d, "figures --out p", &d.join("p/figure4.svg"));
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(std::fs::read(d.join("h.csv")).unwrap(), h);
    // Two outputs written through to the one stream are no conflict.
    goniofit()
        .current_dir(d)
        .args(FIT.split(' '))
        .args(["h.csv", "--residuals", "-"])
        .assert()
        .success();
}

#[test]
fn an_unusable_output_name_is_exit_2_before_anything_is_written() {
    let dir = workspace();
    let d = dir.path();
    let long = "a".repeat(300);
    refused(
        d,
        &format!("{FIT} h.csv --summary s.csv --html {long}.html"),
        "too long",
    );
    refused(
        d,
        &format!("render sphere --model lambert --params scale=1 --size 8 --out {long}.png"),
        "too long",
    );
    std::os::unix::fs::symlink("loop.csv", d.join("loop.csv")).unwrap();
    refused(
        d,
        "eval --model lambert --params scale=1 h.csv -o loop.csv",
        "symbolic links",
    );
    let meta = std::fs::symlink_metadata(d.join("loop.csv")).unwrap();
    assert!(meta.file_type().is_symlink());
}

#[test]
fn wrote_lines_escape_control_and_bidi_characters() {
    let dir = workspace();
    let d = dir.path();
    let name = PathBuf::from("x\n\u{202e}y.html");
    let out = goniofit()
        .current_dir(d)
        .args(FIT.split(' '))
        .arg("h.csv")
        .arg("--html")
        .arg(&name)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("wrote x\\n\\u{202e}y.html"), "{err}");
    assert!(!err.contains('\u{202e}'), "{err}");
    assert!(d.join(&name).is_file());
}

#[test]
fn a_replaced_file_keeps_its_mode() {
    use std::os::unix::fs::PermissionsExt;
    let dir = workspace();
    let d = dir.path();
    for mode in [0o600, 0o640, 0o604] {
        let out = d.join(format!("out{mode:o}.csv"));
        std::fs::write(&out, "old").unwrap();
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(mode)).unwrap();
        goniofit()
            .current_dir(d)
            .args(["eval", "--model", "lambert", "--params", "scale=1", "h.csv"])
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
        let m = std::fs::metadata(&out).unwrap();
        assert_eq!(m.permissions().mode() & 0o777, mode);
        assert!(std::fs::read_to_string(&out).unwrap().contains("L_model"));
    }
}

/// `link` made to belong to user `uid` (needs the right to change owners: root).
fn chown_link(link: &Path, uid: u32) -> bool {
    std::os::unix::fs::lchown(link, Some(uid), None).is_ok()
}

#[test]
fn a_symlink_is_followed_only_where_the_kernel_would_follow_it() {
    use std::os::unix::fs::PermissionsExt;
    let dir = workspace();
    let d = dir.path();
    let tmp = d.join("public");
    std::fs::create_dir(&tmp).unwrap();
    std::fs::set_permissions(&tmp, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let secret = d.join("secret");
    std::fs::write(&secret, "private").unwrap();
    std::fs::set_permissions(&secret, std::fs::Permissions::from_mode(0o600)).unwrap();
    let link = tmp.join("link.csv");
    std::os::unix::fs::symlink(&secret, &link).unwrap();
    let nobody = 65534;
    if !chown_link(&link, nobody) {
        eprintln!("skipped: cannot give a symlink to another user here");
        return;
    }
    let eval = "eval --model lambert --params scale=1 h.csv -o public/link.csv";
    refused(d, eval, "protected_symlinks");
    assert_eq!(std::fs::read_to_string(&secret).unwrap(), "private");
    // The folder's owner's link is followed, as the kernel does.
    std::os::unix::fs::lchown(&tmp, Some(nobody), None).unwrap();
    goniofit()
        .current_dir(d)
        .args(eval.split(' '))
        .assert()
        .success();
    let m = std::fs::metadata(&secret).unwrap();
    assert_eq!(m.permissions().mode() & 0o777, 0o600);
    assert!(std::fs::read_to_string(&secret)
        .unwrap()
        .contains("L_model"));
}

#[test]
fn a_replaced_file_keeps_its_owner_where_we_may_set_it() {
    use std::os::unix::fs::MetadataExt;
    let dir = workspace();
    let d = dir.path();
    let out = d.join("theirs.csv");
    std::fs::write(&out, "old").unwrap();
    let nobody = 65534;
    if std::os::unix::fs::chown(&out, Some(nobody), Some(nobody)).is_err() {
        eprintln!("skipped: cannot give a file to another user here");
        return;
    }
    goniofit()
        .current_dir(d)
        .args([
            "eval", "--model", "lambert", "--params", "scale=1", "h.csv", "-o",
        ])
        .arg(&out)
        .assert()
        .success();
    let m = std::fs::metadata(&out).unwrap();
    assert_eq!((m.uid(), m.gid()), (nobody, nobody));
    assert!(std::fs::read_to_string(&out).unwrap().contains("L_model"));
}
