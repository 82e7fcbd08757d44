//! Stops that always stop: `--timeout` and SIGINT end a whole fit (start search, first
//! solve, reduced refit, every channel) with the report of the best point so far,
//! `converged: false`, termination `timeout`/`interrupted`, exit 3. The two tests take
//! turns (a lock), so that each measures its own fit.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const GARNET: &str = "data/cornell/garnet_red.astm";

/// One heavy fit at a time in this binary.
static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn goniofit() -> Command {
    Command::new(env!("CARGO_BIN_EXE_goniofit"))
}

fn joint_fit_args() -> Vec<&'static str> {
    vec![
        "fit",
        "--model",
        "kbs+lambert",
        "--quantity",
        "brdf",
        "--channel",
        "all",
        "--residual",
        "log",
        GARNET,
    ]
}

/// Run `goniofit ARGS --json`, expect the report of a fit its time limit stopped (exit 3,
/// termination "timeout", not converged): (wall seconds, report).
fn timed_out_fit(args: &[std::ffi::OsString]) -> (f64, serde_json::Value) {
    let t0 = Instant::now();
    let out = goniofit()
        .args(args)
        .arg("--json")
        .output()
        .expect("run goniofit");
    let wall = t0.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON report");
    assert_eq!(v["termination"], "timeout");
    assert_eq!(v["converged"], false);
    (wall, v)
}

#[test]
fn timeout_ends_a_joint_fit_with_its_report_and_exit_3() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    // Every bundled paint: garnet_red's start search (28 channels' amplitudes at each grid
    // point) once hung in an SVD that never converged, and it ignored the time limit.
    for paint in ["garnet_red", "acryl_blue", "cayman", "krylon_blue"] {
        let file = format!("data/cornell/{paint}.astm");
        let mut args: Vec<std::ffi::OsString> = joint_fit_args().iter().map(|a| a.into()).collect();
        *args.last_mut().unwrap() = file.into();
        args.extend(["--timeout".into(), "1".into()]);
        let (wall, v) = timed_out_fit(&args);
        let cost = v["cost"].as_f64().expect("a finite cost");
        assert!(cost.is_finite() && cost > 0.0, "{paint}: cost {cost}");
        // The report says why it stopped: in the start search, or in the solver.
        let notes = v["notes"].to_string();
        assert!(
            notes.contains("time limit") || notes.contains("search for starting values"),
            "{paint}: {notes}"
        );
        // The uninterrupted fit takes 4–5 s unloaded and 20 s on a loaded machine; before
        // the start search checked the stop request `--timeout 1` took 8–11 s (and hung on
        // garnet_red). A sanity bound only, for a CI machine shared with other jobs (the
        // goal unloaded is 1.5 s; the README gives measured times).
        assert!(wall < 20.0, "{paint}: took {wall:.2} s with --timeout 1");
    }
}

#[cfg(unix)]
#[test]
fn sigint_during_a_fit_prints_the_report_and_exits_3() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let child = goniofit()
        .args(joint_fit_args())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start goniofit");
    std::thread::sleep(Duration::from_millis(800));
    let t0 = Instant::now();
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(status.success());
    let out = child.wait_with_output().expect("wait for goniofit");
    let after = t0.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("termination     = interrupted"), "{text}");
    assert!(text.contains("[[Variables]]"), "{text}");
    assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    // Same allowance for a loaded machine as above.
    assert!(after < 10.0, "took {after:.2} s after SIGINT");
}

/// A scratch folder of this test binary (under the target folder).
fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch folder");
    d
}

#[test]
fn timeout_bounds_a_slow_series_fit_with_its_intervals() {
    // 18,000 rough samples (g ≈ 2.6e4) in forced series mode: one evaluation costs ~0.5 s
    // of CPU. Before the profile intervals shared the command's stop request each of their
    // refits got a fresh time limit, and `--timeout 2` took 336 s.
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("slow_series");
    let csv = dir.join("rough.csv");
    let made = goniofit()
        .args([
            "synth",
            "--model",
            "kbs",
            "--params",
            "sigma=20,T=100,scale=1",
        ])
        .args(["--grid", "10x30x60", "--noise", "0.01", "--out"])
        .arg(&csv)
        .output()
        .expect("run synth");
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let args = [
        "fit",
        "--model",
        "kbs",
        "--mode",
        "series",
        "--timeout",
        "2",
    ];
    let mut args: Vec<std::ffi::OsString> = args.iter().map(|a| a.into()).collect();
    args.push(csv.into());
    let (wall, v) = timed_out_fit(&args);
    let notes = v["notes"].to_string();
    assert!(notes.contains("no profile intervals"), "{notes}");
    // 2 s of limit plus the first evaluation and the final Jacobian (never cut): ~3 s on an
    // idle 2-core machine; the bound leaves room for a loaded one.
    assert!(wall < 20.0, "took {wall:.2} s with --timeout 2");
}

#[cfg(unix)]
#[test]
fn sigint_while_eval_writes_leaves_no_temporary() {
    // eval of 1.5M rows writes ~65 MB through a hidden temporary; SIGINT while it is being
    // written must remove it and leave no output (exit 130: the command had no report).
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("eval_sigint");
    let csv = dir.join("angles.csv");
    {
        use std::io::Write;
        let mut w = std::io::BufWriter::new(std::fs::File::create(&csv).unwrap());
        writeln!(w, "theta_i,theta_r,phi_r").unwrap();
        for k in 0..1_500_000u64 {
            let (a, b, c) = (k % 80, (k / 80) % 80, (k / 6400) % 360);
            writeln!(w, "{a}.5,{b}.25,{c}.125").unwrap();
        }
    }
    let target = dir.join("out.csv");
    let mut child = goniofit()
        .args([
            "eval",
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
        ])
        .args(["--wavelength", "1", "-o"])
        .arg(&target)
        .arg(&csv)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start goniofit");
    let temporary = || {
        std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .any(|e| e.file_name().to_string_lossy().starts_with(".goniofit-"))
    };
    let t0 = Instant::now();
    while !temporary() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "eval ended before its temporary was seen"
        );
        assert!(
            t0.elapsed() < Duration::from_secs(300),
            "no temporary after 300 s"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(status.success());
    let status = child.wait().expect("wait for goniofit");
    assert_eq!(status.code(), Some(130));
    assert!(!temporary(), "a temporary was left behind");
    assert!(!target.exists(), "a partial output was left behind");
}
