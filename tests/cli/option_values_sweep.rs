//! Every numeric option of every command, over values a hostile or careless caller may
//! give (NaN, ±∞, −1, 0, 1e-300, 1e300, 1e19): the command either runs or refuses the
//! value with exit 2; it never panics (exit 101) or fails internally (exit 1), never prints
//! NaN or inf of its own, and never runs for more than 10 s.

#![cfg(unix)]

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const VALUES: [&str; 8] = ["nan", "inf", "-inf", "-1", "0", "1e-300", "1e300", "1e19"];

/// The longest any one run may take.
const LIMIT: Duration = Duration::from_secs(10);

/// The words a command must not print unless they echo the value given.
fn non_finite_words(text: &str) -> Vec<&str> {
    text.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| matches!(*w, "NaN" | "nan" | "inf" | "Inf" | "infinity" | "Infinity"))
        .collect()
}

/// [`non_finite_words`] of `text` but for those echoing the value given (`v`, written
/// `value`), as typed or as Rust prints the number, in a refusal.
fn unechoed_non_finite_words(text: &str, v: &str, value: &str) -> Vec<String> {
    let mut shown = text.to_string();
    let parsed: Option<f64> = v.parse().ok();
    for echo in [value.to_string(), v.to_string()]
        .into_iter()
        .chain(parsed.map(|x| format!("{x}")))
        .chain(parsed.map(|x| format!("{x:e}")))
    {
        shown = shown.replace(&echo, "<value>");
    }
    non_finite_words(&shown)
        .into_iter()
        .map(String::from)
        .collect()
}

/// Run goniofit with `args` in `dir`, killed after [`LIMIT`]; returns the exit code
/// (None when killed), standard output and standard error.
fn run(dir: &Path, args: &[String]) -> (Option<i32>, String, String, Duration) {
    let out_file = dir.join(".stdout");
    let err_file = dir.join(".stderr");
    let t0 = Instant::now();
    let mut child = Command::new(assert_cmd::cargo::cargo_bin("goniofit"))
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_file).unwrap())
        .stderr(std::fs::File::create(&err_file).unwrap())
        .spawn()
        .unwrap();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if t0.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let read = |p: &PathBuf| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
    (code, read(&out_file), read(&err_file), t0.elapsed())
}

/// `base` with `option=value` (the option's value written by `form`), for every value;
/// each run must end as the module docs say.
fn sweep(dir: &Path, base: &str, option: &str, form: Form) -> Vec<String> {
    let mut failures = Vec::new();
    for v in VALUES {
        let mut args: Vec<String> = base.split(' ').map(String::from).collect();
        let value = form(v);
        args.push(format!("{option}={value}"));
        let (code, out, err, took) = run(dir, &args);
        let line = args.join(" ");
        let words = unechoed_non_finite_words(&format!("{out}\n{err}"), v, &value);
        if !matches!(code, Some(0 | 2 | 3)) || !words.is_empty() || took > LIMIT {
            failures.push(format!(
                "{line}: exit {code:?} in {took:.1?}, printed {words:?}\n{}",
                err.lines().take(3).collect::<Vec<_>>().join("\n")
            ));
        }
    }
    failures
}

/// How an option's value is written from the swept number.
type Form<'a> = &'a dyn Fn(&str) -> String;

fn plain(v: &str) -> String {
    v.to_string()
}

fn pair(v: &str) -> String {
    format!("{v},{v}")
}

/// A folder with a small measurement `s.csv` (144 samples) and its JSON fit report.
fn workspace() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    common::goniofit()
        .current_dir(dir.path())
        .args(
            "synth --model kbs --params sigma=0.3,T=2,scale=1 --noise 0.01 --seed 1 --grid 3x6x8 --out s.csv"
                .split(' '),
        )
        .assert()
        .success();
    dir
}

/// The numeric options of `fit` (and of a fit replayed by `plot`), with how each value is
/// written and the options it needs beside it.
const FIT_OPTIONS: [(&str, &str, bool); 8] = [
    ("--wavelength", "", false),
    ("--f-scale", "--loss soft_l1", false),
    ("--floor", "--residual log", false),
    ("--tol", "", false),
    ("--max-iter", "", false),
    ("--timeout", "", false),
    ("--threads", "", false),
    ("--patch", "", true),
];

fn check(failures: Vec<String>) {
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn fit_options() {
    let dir = workspace();
    let mut failures = Vec::new();
    for by_group in ["", "--by-group "] {
        for (option, with, is_pair) in FIT_OPTIONS {
            let base = format!("fit --model kbs --no-intervals {by_group}{with} s.csv");
            let base = base.replace("  ", " ");
            let form: Form = if is_pair { &pair } else { &plain };
            failures.extend(sweep(dir.path(), &base, option, form));
        }
    }
    check(failures);
}

#[test]
fn plot_replays_of_fit_options() {
    let dir = workspace();
    let d = dir.path();
    let report = common::goniofit()
        .current_dir(d)
        .args("fit --model kbs --no-intervals --json s.csv".split(' '))
        .output()
        .unwrap();
    let json: serde_json::Value = serde_json::from_slice(&report.stdout).unwrap();
    let mut failures = Vec::new();
    for (option, _, is_pair) in FIT_OPTIONS {
        // The setting's key, and the value as JSON text (`nan`, `inf`: not JSON).
        let key = option.trim_start_matches("--").replace('-', "_");
        for v in VALUES {
            let value = if is_pair {
                format!("[{v}, {v}]")
            } else {
                v.to_string()
            };
            let mut j = json.clone();
            j["replay"]["settings"][&key] = "\u{1}".into();
            let text = serde_json::to_string(&j).unwrap();
            let text = text.replace("\"\\u0001\"", &value);
            std::fs::write(d.join("r.json"), text).unwrap();
            let (code, out, err, took) = run(d, &["plot".into(), "r.json".into()]);
            let words = unechoed_non_finite_words(&format!("{out}\n{err}"), v, &value);
            if !matches!(code, Some(0 | 2)) || !words.is_empty() || took > LIMIT {
                failures.push(format!(
                    "plot of a fit with {key}: {value}: exit {code:?}, printed {words:?}: {err}"
                ));
            }
        }
    }
    check(failures);
}

#[test]
fn eval_synth_render_recover_bench_options() {
    let dir = workspace();
    let d = dir.path();
    let kbs = "--model kbs --params sigma=0.3,T=2,scale=1";
    let eval = format!("eval {kbs} --wavelength 1 s.csv");
    let synth = format!("synth {kbs} --grid 2x4x4");
    let inplane = format!("synth {kbs} --layout inplane --theta-i 30 --step 5");
    let render = "render sphere --model lambert --params scale=1 --size 8 --out r.png";
    let recover = "recover --scenes 1";
    let cases: Vec<(&str, &str, Form)> = vec![
        (&eval, "--wavelength", &plain),
        (&eval, "--tol", &plain),
        (&eval, "--patch", &pair),
        (&synth, "--wavelength", &plain),
        (&synth, "--noise", &plain),
        (&synth, "--seed", &plain),
        (&synth, "--tol", &plain),
        (&synth, "--patch", &pair),
        (&synth, "--samples", &plain),
        (&synth, "--grid", &|v| format!("{v}x2x2")),
        (&inplane, "--step", &plain),
        (&inplane, "--theta-r-max", &plain),
        (&inplane, "--theta-i", &plain),
        (render, "--light-deg", &plain),
        (render, "--size", &plain),
        (render, "--wavelength", &plain),
        (recover, "--seed", &plain),
        (recover, "--noise", &plain),
        (recover, "--timeout", &plain),
        ("recover", "--scenes", &plain),
        (recover, "--only", &plain),
        ("bench work-precision --out wp", "--repeats", &plain),
    ];
    let mut failures = Vec::new();
    for (base, option, form) in cases {
        failures.extend(sweep(d, base, option, form));
    }
    check(failures);
}

#[test]
fn a_count_beyond_what_memory_holds_is_refused() {
    let dir = workspace();
    let args: Vec<String> = "recover --scenes 1000000000 --only 0"
        .split(' ')
        .map(String::from)
        .collect();
    let (code, _, err, _) = run(dir.path(), &args);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--scenes 1000000000"), "{err}");
}

#[test]
fn a_thread_count_beyond_the_machine_is_capped_with_a_note() {
    let dir = workspace();
    for n in ["100000", "18446744073709551615"] {
        let args: Vec<String> = format!("fit --model kbs --no-intervals --threads {n} s.csv")
            .split(' ')
            .map(String::from)
            .collect();
        let (code, _, err, took) = run(dir.path(), &args);
        assert_eq!(code, Some(0), "--threads {n}: {err}");
        assert!(err.contains("threads"), "--threads {n}: {err}");
        assert!(took < LIMIT);
    }
}
