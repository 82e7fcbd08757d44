//! SIGINT and SIGTERM at 20 seeded random moments to each command (fit, fit --by-group,
//! eval, convert, synth, render, figures, recover, plot). Each run must end promptly, with
//! the exit code the README gives a stop (`fit`: 3, the code of the fit it finished, or 130
//! before its run started or after it ended; the other commands: 130; any command: 0 when
//! it finished first, or death by the signal itself when it came before the handler was
//! installed), every output either absent or complete, and no hidden temporary
//! (`.goniofit-*.tmp`) left behind.

use std::collections::BTreeMap;
use std::io::Read;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Signals per command.
const MOMENTS: usize = 20;

fn goniofit() -> Command {
    Command::new(env!("CARGO_BIN_EXE_goniofit"))
}

/// Longest a run may take after its signal.
const AFTER_SIGNAL: Duration = Duration::from_secs(20);

/// One command under test: its arguments (run in a fresh folder; inputs by absolute
/// path), whether it is a fit (exit 3 on a stop), and the outputs that must be absent or
/// complete.
struct Case {
    name: &'static str,
    args: Vec<String>,
    fit: bool,
}

/// The inputs, made once in `dir`: h.csv (KBS σ = 0.3 λ, T = 2 λ, 1 % noise), g.csv (the
/// same rows in two groups) and fit.json (a report of h.csv's fit, for `plot`).
fn inputs(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let h = dir.join("h.csv");
    let out = goniofit()
        .args([
            "synth",
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
        ])
        .args(["--noise", "0.01", "--seed", "1", "--out"])
        .arg(&h)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&h).unwrap();
    let mut grouped = String::new();
    for (i, line) in text.lines().enumerate() {
        let group = if i == 0 {
            "group"
        } else if i % 2 == 0 {
            "a"
        } else {
            "b"
        };
        grouped.push_str(&format!("{line},{group}\n"));
    }
    let g = dir.join("g.csv");
    std::fs::write(&g, grouped).unwrap();
    let report = goniofit()
        .args(["fit", "--model", "kbs", "--wavelength", "1", "--json"])
        .arg(&h)
        .output()
        .unwrap();
    assert_eq!(report.status.code(), Some(0));
    let json = dir.join("fit.json");
    std::fs::write(&json, &report.stdout).unwrap();
    (h, g, json)
}

fn cases(h: &Path, g: &Path, json: &Path) -> Vec<Case> {
    let p = |p: &Path| p.to_string_lossy().to_string();
    let v = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<String>>();
    let kbs = ["--model", "kbs", "--params", "sigma=0.3,T=2,scale=1"];
    let with = |mut a: Vec<String>, more: &[String]| {
        a.extend_from_slice(more);
        a
    };
    vec![
        Case {
            name: "fit",
            args: with(
                v(&[
                    "fit",
                    "--model",
                    "kbs",
                    "--wavelength",
                    "1",
                    "--residuals",
                    "r.csv",
                    "--json",
                ]),
                &[p(h)],
            ),
            fit: true,
        },
        Case {
            name: "fit --by-group",
            args: with(
                v(&[
                    "fit",
                    "--model",
                    "kbs",
                    "--wavelength",
                    "1",
                    "--by-group",
                    "--summary",
                    "s.csv",
                ]),
                &[p(g)],
            ),
            fit: true,
        },
        Case {
            name: "eval",
            args: with(
                v(&[&["eval"][..], &kbs[..], &["--wavelength", "1"][..]].concat()),
                &[p(h)],
            ),
            fit: false,
        },
        Case {
            name: "convert",
            args: with(
                v(&["convert", "--channel", "all", "--out", "c.csv"]),
                &[p(g)],
            ),
            fit: false,
        },
        Case {
            name: "synth",
            args: v(&[
                &["synth"][..],
                &kbs[..],
                &["--noise", "0.01", "--seed", "1", "--out", "s.csv"][..],
            ]
            .concat()),
            fit: false,
        },
        Case {
            name: "render",
            args: v(&[
                &["render", "sphere"][..],
                &kbs[..],
                &["--size", "128", "--out", "p.png"][..],
            ]
            .concat()),
            fit: false,
        },
        Case {
            name: "figures",
            args: v(&["figures", "--out", "figs"]),
            fit: false,
        },
        Case {
            name: "recover",
            args: v(&["recover", "--scenes", "8", "--seed", "11", "--json"]),
            fit: false,
        },
        Case {
            name: "plot",
            args: with(v(&["plot", "--out", "pl"]), &[p(json)]),
            fit: false,
        },
    ]
}

/// Every file under `dir` (relative path → bytes).
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let path = e.path();
            if path.is_dir() {
                todo.push(path);
            } else {
                let rel = path.strip_prefix(dir).unwrap().to_path_buf();
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

/// Uniform numbers in [0, 1) from a seeded xorshift generator.
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A complete fit output, as `reference` (the output of a fit left to finish) is: the
/// residuals CSV, a header and one row per sample, each with the header's field count; or
/// the summary, the header and one row per group fitted (a stopped batch lists only those).
fn complete_fit_output(name: &Path, bytes: &[u8], reference: &[u8]) -> bool {
    let text = String::from_utf8_lossy(bytes);
    let lines: Vec<&str> = text.lines().collect();
    let want: Vec<String> = String::from_utf8_lossy(reference)
        .lines()
        .map(String::from)
        .collect();
    let whole =
        text.ends_with('\n') && lines.first().map(|h| h.to_string()) == want.first().cloned();
    if name.to_string_lossy() == "r.csv" {
        let fields = want[0].split(',').count();
        whole && lines.len() == want.len() && lines.iter().all(|l| l.split(',').count() == fields)
    } else {
        whole && lines.len() <= want.len()
    }
}

/// Run `case` once in `dir` with `signal` ("INT"/"TERM") after `delay`: the failure, if it
/// failed. `reference`: the outputs of a run left to finish.
/// Read `pipe` to its end on a thread of its own; the bytes when joined.
fn drain<R: Read + Send + 'static>(pipe: Option<R>) -> std::thread::JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        if let Some(mut pipe) = pipe {
            let _ = pipe.read_to_end(&mut bytes);
        }
        bytes
    })
}

fn one_run(
    case: &Case,
    dir: &Path,
    signal: &str,
    delay: Duration,
    reference: &BTreeMap<PathBuf, Vec<u8>>,
) -> Option<String> {
    std::fs::create_dir_all(dir).unwrap();
    let what = format!("{} SIG{signal} at {:.3} s", case.name, delay.as_secs_f64());
    let signo = if signal == "INT" {
        libc::SIGINT
    } else {
        libc::SIGTERM
    };
    let mut child = goniofit()
        .args(&case.args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The pipes are read while the command runs, so that a command writing more than a
    // pipe holds never waits on this test.
    let (stdout, stderr) = (drain(child.stdout.take()), drain(child.stderr.take()));
    std::thread::sleep(delay);
    if child.try_wait().unwrap().is_none() {
        // SAFETY: kill(2) on the child's pid; the child is not reaped before try_wait
        // above or wait below, so the pid is still the child's.
        unsafe { libc::kill(child.id() as libc::pid_t, signo) };
    }
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > AFTER_SIGNAL {
            let _ = child.kill();
            return Some(format!(
                "{what}: still running {AFTER_SIGNAL:?} after the signal"
            ));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let out = Output {
        status: child.wait().unwrap(),
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
    };
    let err = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code();
    let killed = out.status.signal() == Some(signo);
    let ok_code = match code {
        Some(0) => true,
        Some(3) => case.fit,
        // A fit's stop request exists from the start of its run to its end: a signal
        // during the process's start-up (argument parsing) ends it as any other command,
        // with nothing written, and so does one in the moment between the end of the run
        // (every output written: checked complete below) and the process's exit.
        Some(130) => !case.fit || out.stdout.is_empty() || files(dir).len() == reference.len(),
        _ => killed,
    };
    if !ok_code {
        return Some(format!("{what}: exit {:?}: {err}", out.status));
    }
    let written = files(dir);
    if let Some(tmp) = written
        .keys()
        .find(|p| p.to_string_lossy().contains(".goniofit-"))
    {
        return Some(format!("{what}: left {}", tmp.display()));
    }
    for (name, bytes) in &written {
        let complete = match reference.get(name) {
            Some(r) if case.fit => complete_fit_output(name, bytes, r),
            Some(r) => r == bytes,
            None => false,
        };
        if !complete {
            return Some(format!("{what}: {} is not complete", name.display()));
        }
    }
    // A run that finished (exit 0) wrote every output; its standard output is whole.
    if code == Some(0) {
        if !case.fit && written.len() != reference.len() {
            return Some(format!(
                "{what}: exit 0 with {} of {} outputs",
                written.len(),
                reference.len()
            ));
        }
        if case.name == "recover"
            && serde_json::from_slice::<serde_json::Value>(&out.stdout).is_err()
        {
            return Some(format!("{what}: exit 0 without its JSON"));
        }
    }
    if case.fit
        && !out.stdout.is_empty()
        && case.name == "fit"
        && serde_json::from_slice::<serde_json::Value>(&out.stdout).is_err()
    {
        return Some(format!("{what}: a report that is not whole JSON"));
    }
    let _ = std::fs::remove_dir_all(dir);
    None
}

#[test]
fn a_signal_at_any_moment_ends_every_command_cleanly() {
    // Its runs, two at a time, would load the machine under the timed stops of `stops`.
    let _turn = crate::TURN.lock().unwrap_or_else(|e| e.into_inner());
    let base = std::env::temp_dir().join(format!("goniofit-signal-moments-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let (h, g, json) = inputs(&base);
    let cases = cases(&h, &g, &json);
    let mut next = uniform(0x9e37_79b9_7f4a_7c15);
    // Each command's outputs and wall time when left to finish; then its 20 runs with a
    // signal somewhere in [0, 1.2 × that time], SIGINT and SIGTERM in turn.
    let mut runs = Vec::new();
    let mut references = Vec::new();
    for (c, case) in cases.iter().enumerate() {
        let dir = base.join(format!("ref{c}"));
        std::fs::create_dir_all(&dir).unwrap();
        let t0 = Instant::now();
        let out = goniofit()
            .args(&case.args)
            .current_dir(&dir)
            .output()
            .unwrap();
        let wall = t0.elapsed();
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}: {}",
            case.name,
            String::from_utf8_lossy(&out.stderr)
        );
        references.push(files(&dir));
        for k in 0..MOMENTS {
            let signal = if k % 2 == 0 { "INT" } else { "TERM" };
            let delay = wall.mul_f64(1.2 * next());
            runs.push((c, k, signal, delay));
        }
    }
    let failures = std::sync::Mutex::new(Vec::new());
    let cursor = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = cursor.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some(&(c, k, signal, delay)) = runs.get(i) else {
                    break;
                };
                let dir = base.join(format!("run{c}-{k}"));
                if let Some(f) = one_run(&cases[c], &dir, signal, delay, &references[c]) {
                    failures.lock().unwrap().push(f);
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    if failures.is_empty() {
        let _ = std::fs::remove_dir_all(&base);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn recover_ends_on_a_signal_with_130_and_no_summary() {
    // 600 scenes take minutes: SIGINT, SIGTERM or SIGHUP after 0.8 s ends the run within
    // the fits' next steps, with exit 130 (README), nothing on standard output (no summary
    // counting the scenes being fitted as errors) and the count of scenes fitted.
    for (signal, signo) in [
        ("INT", libc::SIGINT),
        ("TERM", libc::SIGTERM),
        ("HUP", libc::SIGHUP),
    ] {
        let mut child = goniofit()
            .args(["recover", "--scenes", "600", "--seed", "11", "--json"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(800));
        // SAFETY: kill(2) on the child's pid, not yet reaped.
        unsafe { libc::kill(child.id() as libc::pid_t, signo) };
        let t0 = Instant::now();
        while child.try_wait().unwrap().is_none() {
            assert!(t0.elapsed() < AFTER_SIGNAL, "SIG{signal}: still running");
            std::thread::sleep(Duration::from_millis(5));
        }
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "SIG{signal}: {err}");
        assert!(out.stdout.is_empty(), "SIG{signal}: a summary was printed");
        assert!(
            err.contains("of 600 scenes were fitted: no summary"),
            "SIG{signal}: {err}"
        );
    }
}
