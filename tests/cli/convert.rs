//! `goniofit convert` end to end: the samples `fit` fits, written as a CSV that reads back
//! to the same dataset; bad input exits 2 with a located message before anything is
//! written; `fit --model auto` runs on an RGL file.

use assert_cmd::Command;
use goniofit::{read as read_dataset, ReadOptions};
use predicates::prelude::*;
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(p)
}

fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

fn opts(channel: Option<&str>) -> ReadOptions {
    ReadOptions {
        channel: channel.map(String::from),
        require_value: true,
        ..Default::default()
    }
}

/// Every format's converted table reads back as the same samples, values and channels.
#[test]
fn converted_tables_read_back_as_the_same_dataset() {
    let dir = tempfile::tempdir().unwrap();
    for (file, channel) in [
        ("rgl-epfl/paper_white_rgb.bsdf", Some("all")),
        ("cornell/garnet_red.astm", Some("550nm")),
        ("synthetic/kbs_inplane.csv", None),
    ] {
        let out = dir.path().join("samples.csv");
        let mut cmd = goniofit();
        cmd.arg("convert");
        if let Some(c) = channel {
            cmd.args(["--channel", c]);
        }
        cmd.arg("--out")
            .arg(&out)
            .arg(data(file))
            .assert()
            .success();
        let orig = read_dataset(&data(file), &opts(channel)).unwrap();
        let back = read_dataset(&out, &opts(channel.map(|_| "all"))).unwrap();
        assert_eq!(back.len(), orig.len(), "{file}");
        assert_eq!(back.quantity, orig.quantity, "{file}");
        assert_eq!(back.value, orig.value, "{file}");
        assert_eq!(back.wavelength, orig.wavelength, "{file}");
        if orig.channel.is_some() {
            assert_eq!(back.channel, orig.channel, "{file}");
        }
        for (a, b) in back.samples.iter().zip(&orig.samples) {
            for (x, y) in [
                (a.theta_i, b.theta_i),
                (a.theta_r, b.theta_r),
                (a.phi_r, b.phi_r),
            ] {
                assert!((x - y).abs() < 1e-12, "{file}: {a:?} vs {b:?}");
            }
        }
    }
}

/// A multi-channel file without `--channel`, and a damaged RGL file, exit 2 with the
/// reason (the channels; the byte offset) and write nothing.
#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("samples.csv");
    goniofit()
        .args(["convert", "--out"])
        .arg(&out)
        .arg(data("rgl-epfl/paper_white_rgb.bsdf"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("channels: r, g, b"));
    let bytes = std::fs::read(data("rgl-epfl/paper_white_rgb.bsdf")).unwrap();
    let cut = dir.path().join("cut.bsdf");
    std::fs::write(&cut, &bytes[..5000]).unwrap();
    goniofit()
        .args(["convert", "--channel", "r", "--out"])
        .arg(&out)
        .arg(&cut)
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("byte")
                .and(predicate::str::contains("beyond the end of the file")),
        );
    assert!(!out.exists());
}

/// `fit --model auto` on an RGL channel chooses and reports a model (exit 0).
#[test]
fn fit_auto_runs_on_an_rgl_channel() {
    goniofit()
        .args(["fit", "--model", "auto", "--channel", "g"])
        .arg(data("rgl-epfl/vch_golden_yellow_rgb.bsdf"))
        .assert()
        .success()
        .stdout(
            predicate::str::contains("<- chosen")
                .and(predicate::str::contains("channel         = g")),
        );
}
