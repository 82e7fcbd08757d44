//! Every parameter of every model, set to a hostile value (NaN, ±∞, −1, 0, 1e-300, 1e300,
//! 1e19), through `eval --params`, `fit --init` and `fit --fix`: each run ends within
//! 10 s, without a panic (exit 101), with exit 0, 2 or 3, and prints no NaN or infinity
//! among its results. Among them the runs at the far end of the series: a correlation length of
//! 1e17 λ, where the KBS sum's peak index passes 2⁵³, and a fit held at T = 1e20.

use goniofit::ModelOptions;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The hostile values, as typed on the command line.
const VALUES: [&str; 8] = ["nan", "inf", "-inf", "-1", "0", "1e-300", "1e300", "1e19"];

fn goniofit() -> Command {
    Command::new(env!("CARGO_BIN_EXE_goniofit"))
}

/// Longest a run may take.
const LIMIT: Duration = Duration::from_secs(10);

/// A usable value of each parameter (by name), for the parameters not under test.
fn usable(name: &str) -> f64 {
    match name {
        "sigma" => 0.3,
        "T" => 2.0,
        _ => 0.5,
    }
}

/// `h.csv` (KBS σ = 0.3 λ, T = 2 λ, 1 % noise) thinned to every 40th of its 3240 rows, in
/// `dir`: small enough that a fit takes a fraction of a second.
fn small_file(dir: &Path) -> PathBuf {
    let full = dir.join("h.csv");
    let out = goniofit()
        .args([
            "synth",
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
        ])
        .args(["--noise", "0.01", "--seed", "1", "--out"])
        .arg(&full)
        .output()
        .expect("run synth");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&full).unwrap();
    let mut lines = text.lines();
    let mut small = format!("{}\n", lines.next().unwrap());
    for line in lines.step_by(40) {
        small.push_str(line);
        small.push('\n');
    }
    let path = dir.join("small.csv");
    std::fs::write(&path, small).unwrap();
    path
}

/// Run `cmd` with a limit of [`LIMIT`] (killed past it): its output and whether it ended
/// in time.
fn run_limited(cmd: &mut Command) -> (Output, bool) {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn goniofit");
    let t0 = Instant::now();
    let in_time = loop {
        if child.try_wait().expect("wait").is_some() {
            break true;
        }
        if t0.elapsed() > LIMIT {
            let _ = child.kill();
            break false;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    (child.wait_with_output().expect("collect output"), in_time)
}

/// The first word of `text` that spells a non-finite number (NaN, inf, infinity, any case
/// and sign).
pub fn non_finite_word(text: &str) -> Option<&str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.'))
        .find(|w| matches!(w.to_ascii_lowercase().as_str(), "nan" | "inf" | "infinity"))
}

/// The failure of one run, if it failed: over time, a panic, an exit code other than 0, 2
/// or 3, or a non-finite number in its results (standard output).
fn failure(what: &str, out: &Output, in_time: bool) -> Option<String> {
    let err = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let code = out.status.code();
    if !in_time {
        return Some(format!("{what}: still running after {LIMIT:?}"));
    }
    if !matches!(code, Some(0 | 2 | 3)) {
        return Some(format!("{what}: exit {code:?}: {err}"));
    }
    non_finite_word(&stdout).map(|w| format!("{what}: prints {w:?} (exit {code:?})"))
}

/// Every (model, parameter, value) case as the argument lists of its three runs.
fn cases(file: &Path) -> Vec<(String, Vec<String>)> {
    let file = file.to_string_lossy().to_string();
    let mut out = Vec::new();
    for name in goniofit::MODEL_NAMES {
        let m = goniofit::model(name, &ModelOptions::default()).unwrap();
        let specs = m.params();
        for (k, spec) in specs.iter().enumerate() {
            for v in VALUES {
                let params: Vec<String> = specs
                    .iter()
                    .enumerate()
                    .map(|(j, s)| match j == k {
                        true => format!("{}={v}", s.name),
                        false => format!("{}={}", s.name, usable(s.name)),
                    })
                    .collect();
                let common = ["--model", name, "--wavelength", "1"].map(String::from);
                let mut eval = vec!["eval".to_string(), "--params".into(), params.join(",")];
                eval.extend(common.clone());
                eval.push(file.clone());
                out.push((format!("eval {name} {}={v}", spec.name), eval));
                for how in ["--init", "--fix"] {
                    let mut fit = vec!["fit".to_string(), how.into(), format!("{}={v}", spec.name)];
                    fit.extend(common.clone());
                    fit.extend(["--json".into(), file.clone()]);
                    out.push((format!("fit {how} {name} {}={v}", spec.name), fit));
                }
            }
        }
    }
    out
}

#[test]
fn every_parameter_of_every_model_at_hostile_values_ends_cleanly() {
    let dir = std::env::temp_dir().join(format!("goniofit-hostile-params-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = small_file(&dir);
    let cases = cases(&file);
    assert!(cases.len() >= 6 * 8 * 3, "{} cases", cases.len());
    // Two runs at a time (a 2-core CI).
    let next = std::sync::atomic::AtomicUsize::new(0);
    let failures = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some((what, args)) = cases.get(i) else {
                    break;
                };
                let (out, in_time) = run_limited(goniofit().args(args).current_dir(&dir));
                if let Some(f) = failure(what, &out, in_time) {
                    failures.lock().unwrap().push(f);
                }
            });
        }
    });
    let _ = std::fs::remove_dir_all(&dir);
    let failures = failures.into_inner().unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_huge_correlation_length_evaluates_to_the_flat_limit_at_once() {
    // One sample off the specular direction: at T = 1e16 … 1e300 λ the radiance there is
    // 0 (Q < e^{-999 999}, the flat-surface limit), printed as 0 without delay; at the
    // specular direction itself (v_xy = 0, a = 0) it grows as T².
    let dir = std::env::temp_dir().join(format!("goniofit-flat-limit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a.csv");
    std::fs::write(
        &file,
        "theta_i,theta_r,phi_r,L\n9,2.5,-180,0.87\n30,30,0,1\n",
    )
    .unwrap();
    for t in ["1e16", "1e17", "1e19", "1e100", "1e300"] {
        let (out, in_time) = run_limited(
            goniofit()
                .args(["eval", "--model", "kbs", "--wavelength", "1", "--params"])
                .arg(format!("sigma=0.3,T={t},scale=1"))
                .arg(&file),
        );
        assert!(in_time, "T={t}: still running after {LIMIT:?}");
        let text = String::from_utf8_lossy(&out.stdout);
        let code = out.status.code();
        let rows: Vec<&str> = text.lines().skip(1).collect();
        if t == "1e300" {
            // (T/λ)² overflows at the specular sample: refused, exit 2.
            assert_eq!(code, Some(2), "T={t}: {text}");
            continue;
        }
        assert_eq!(
            code,
            Some(0),
            "T={t}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let value = |row: &str| row.rsplit(',').next().unwrap().parse::<f64>().unwrap();
        assert_eq!(value(rows[0]), 0.0, "T={t}: {text}");
        let specular = value(rows[1]);
        assert!(specular.is_finite() && specular > 0.0, "T={t}: {text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
