//! The picture commands: `figures` writes the paper's figures, `render sphere` one sphere,
//! each as a valid PNG or SVG.

use crate::common::{assert_svg, png_size};
use assert_cmd::Command;

#[test]
fn figures_command_writes_all_eight_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("figs");
    Command::cargo_bin("goniofit")
        .unwrap()
        .args(["figures", "--out"])
        .arg(&out)
        .assert()
        .success();
    for k in 4..=7 {
        let png = std::fs::read(out.join(format!("figure{k}.png"))).unwrap();
        let (w, h) = png_size(&png);
        assert!(w >= 600 && h >= 500, "figure{k}: {w}×{h}");
        let svg = std::fs::read_to_string(out.join(format!("figure{k}.svg"))).unwrap();
        assert_svg(&svg);
    }
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 8);
}

#[test]
fn render_sphere_command_writes_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    for (name, extra) in [("s.png", vec![]), ("s.svg", vec!["--negative", "--marks"])] {
        let path = dir.path().join(name);
        Command::cargo_bin("goniofit")
            .unwrap()
            .args([
                "render",
                "sphere",
                "--model",
                "kbs-rough",
                "--params",
                "sigma=1,T=5,scale=1",
                "--light-deg",
                "45",
                "--size",
                "64",
                "--out",
            ])
            .arg(&path)
            .args(extra)
            .assert()
            .success()
            .stderr(predicates::str::contains(format!(
                "wrote {} (64×64 px",
                path.display()
            )));
        let bytes = std::fs::read(&path).unwrap();
        if name.ends_with(".png") {
            assert_eq!(png_size(&bytes), (64, 64));
        } else {
            let text = String::from_utf8(bytes).unwrap();
            assert!(text.starts_with("<svg") && text.contains("data:image/png;base64,"));
        }
    }
    // Bad input: unknown extension, bad parameters -> exit 2.
    Command::cargo_bin("goniofit")
        .unwrap()
        .args([
            "render", "sphere", "--model", "lambert", "--params", "scale=1", "--out",
        ])
        .arg(dir.path().join("s.jpg"))
        .assert()
        .code(2);
    Command::cargo_bin("goniofit")
        .unwrap()
        .args([
            "render", "sphere", "--model", "kbs", "--params", "sigma=1", "--out",
        ])
        .arg(dir.path().join("s.png"))
        .assert()
        .code(2);
}
