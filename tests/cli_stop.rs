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

#[test]
fn timeout_ends_a_joint_fit_with_its_report_and_exit_3() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let t0 = Instant::now();
    let out = goniofit()
        .args(joint_fit_args())
        .args(["--timeout", "1", "--json"])
        .output()
        .expect("run goniofit");
    let wall = t0.elapsed().as_secs_f64();
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON report");
    assert_eq!(v["termination"], "timeout");
    assert_eq!(v["converged"], false);
    let cost = v["cost"].as_f64().expect("a finite cost");
    assert!(cost.is_finite() && cost > 0.0);
    // The uninterrupted fit takes 4–5 s unloaded and 20 s on a loaded machine (before
    // this change `--timeout 1` took 4.5 s: the reduced refit ignored it). The bound leaves
    // room for a CI machine shared with other jobs (1.5 s is the goal unloaded).
    assert!(wall < 10.0, "took {wall:.2} s with --timeout 1");
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
