//! `goniofit synth` end to end: exact values, reproducible noise, noise statistics,
//! layouts, the truth file and the error exits.

use assert_cmd::Command;
use goniofit::synth::{self, Layout, Noise, NoiseKind, Truth};
use goniofit::{model as by_name, EvalMode, ModelOptions};
use goniofit::{Geometry, Quantity, Sample};
use predicates::str::contains;
use std::path::{Path, PathBuf};

const KBS: [&str; 4] = ["--model", "kbs", "--params", "sigma=0.3,T=2,scale=1"];

/// `goniofit synth` writes a wavelength column for the KBS models.
const WITH_WAVELENGTH: goniofit::synth::CsvOptions = goniofit::synth::CsvOptions {
    sigma: false,
    wavelength: true,
    signed_theta_r: false,
};

fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

/// Run `goniofit synth KBS... args --out dir/name`, expecting success; the CSV path.
fn synth(dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    let out = dir.join(name);
    goniofit()
        .arg("synth")
        .args(KBS)
        .args(args)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    out
}

/// A parsed synth CSV: the header and the rows as numbers.
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    fn read(path: &Path) -> Table {
        let mut rdr = csv::Reader::from_path(path).unwrap();
        let header = rdr.headers().unwrap().iter().map(String::from).collect();
        let rows = rdr
            .records()
            .map(|r| r.unwrap().iter().map(|f| f.parse().unwrap()).collect())
            .collect();
        Table { header, rows }
    }

    fn col(&self, name: &str) -> Vec<f64> {
        let j = self.header.iter().position(|h| h == name).unwrap();
        self.rows.iter().map(|r| r[j]).collect()
    }

    /// Samples as a reader following docs/conventions.md would build them (signed θr < 0 → |θr| at
    /// φr = 180°).
    fn samples(&self) -> Vec<Sample> {
        self.rows
            .iter()
            .map(|r| {
                if r[1] < 0.0 {
                    Sample::from_degrees(r[0], -r[1], 180.0)
                } else {
                    Sample::from_degrees(r[0], r[1], r[2])
                }
            })
            .collect()
    }
}

fn model_values(
    model: &str,
    params: &[f64],
    opts: &ModelOptions,
    t: &Table,
    q: Quantity,
) -> Vec<f64> {
    let m = by_name(model, opts).unwrap();
    let geo = Geometry::new(&t.samples(), &[1.0], q).unwrap();
    let mut out = vec![0.0; geo.len()];
    m.eval(&geo, params, &mut out, None);
    out
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn zero_noise_is_the_model_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let opts = ModelOptions::default();
    for (name, args) in [
        ("hemi.csv", vec!["--layout", "hemisphere"]),
        ("graz.csv", vec!["--layout", "grazing", "--grid", "10x9x12"]),
        ("inpl.csv", vec!["--layout", "inplane", "--signed-theta-r"]),
        ("inpl2.csv", vec!["--layout", "inplane", "--step", "0.7"]),
    ] {
        let path = synth(dir.path(), name, &args);
        let t = Table::read(&path);
        let want = model_values("kbs", &[0.3, 2.0, 1.0], &opts, &t, Quantity::Radiance);
        assert_eq!(bits(&t.col("L")), bits(&want), "{name}");
        assert!(want.iter().all(|v| v.is_finite() && *v >= 0.0));
    }
    // Options reach the model: BRDF, the series mode and a patch.
    let path = synth(
        dir.path(),
        "brdf.csv",
        &[
            "--layout",
            "inplane",
            "--quantity",
            "brdf",
            "--mode",
            "series",
            "--patch",
            "50,60",
        ],
    );
    let t = Table::read(&path);
    let opts = ModelOptions {
        mode: EvalMode::Series,
        patch: Some((50.0, 60.0)),
        ..ModelOptions::default()
    };
    let want = model_values("kbs", &[0.3, 2.0, 1.0], &opts, &t, Quantity::Brdf);
    assert_eq!(bits(&t.col("L")), bits(&want));
    let rad = model_values("kbs", &[0.3, 2.0, 1.0], &opts, &t, Quantity::Radiance);
    let ti = t.col("theta_i");
    for i in 0..rad.len() {
        let r = want[i] * ti[i].to_radians().cos() / rad[i];
        assert!((r - 1.0).abs() < 1e-14, "BRDF = L / cos θi");
    }
}

#[test]
fn same_seed_same_file_other_seed_other_file() {
    let dir = tempfile::tempdir().unwrap();
    let args = |seed: &'static str| {
        vec![
            "--layout",
            "inplane",
            "--noise",
            "0.05",
            "--noise-kind",
            "poisson",
            "--seed",
            seed,
            "--write-sigma",
        ]
    };
    let a = std::fs::read(synth(dir.path(), "a.csv", &args("42"))).unwrap();
    let b = std::fs::read(synth(dir.path(), "b.csv", &args("42"))).unwrap();
    let c = std::fs::read(synth(dir.path(), "c.csv", &args("43"))).unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
    // Only the noisy column differs between seeds: angles and sigma_L are the same.
    let (tb, tc) = (
        Table::read(&dir.path().join("b.csv")),
        Table::read(&dir.path().join("c.csv")),
    );
    for col in ["theta_i", "theta_r", "phi_r", "sigma_L"] {
        assert_eq!(tb.col(col), tc.col(col));
    }
    let differ = tb
        .col("L")
        .iter()
        .zip(tc.col("L"))
        .filter(|(x, y)| *x != y)
        .count();
    assert!(differ > tb.rows.len() * 9 / 10);
}

fn mean_sd(r: &[f64]) -> (f64, f64) {
    let n = r.len() as f64;
    let mean = r.iter().sum::<f64>() / n;
    let var = r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

#[test]
fn noise_statistics_match_the_level() {
    let dir = tempfile::tempdir().unwrap();
    let grid = ["--layout", "hemisphere", "--grid", "10x30x60"]; // 18 000 samples
    let exact = Table::read(&synth(dir.path(), "exact.csv", &grid)).col("L");
    let n = exact.len() as f64;
    assert_eq!(exact.len(), 18_000);
    let eps = 0.02;
    let run = |kind: &str| {
        let mut a = grid.to_vec();
        a.extend([
            "--noise",
            "0.02",
            "--seed",
            "5",
            "--write-sigma",
            "--noise-kind",
            kind,
        ]);
        Table::read(&synth(dir.path(), &format!("{kind}.csv"), &a))
    };

    // Relative: value/exact − 1 has mean 0 and sd ε.
    let t = run("relative");
    let r: Vec<f64> = t
        .col("L")
        .iter()
        .zip(&exact)
        .map(|(v, l)| v / l - 1.0)
        .collect();
    let (mean, sd) = mean_sd(&r);
    assert!(mean.abs() < 4.0 * eps / n.sqrt(), "mean {mean}");
    assert!((sd / eps - 1.0).abs() < 0.03, "sd {sd} vs {eps}");
    let sig = t.col("sigma_L");
    for (s, l) in sig.iter().zip(&exact) {
        assert!((s - eps * l).abs() <= 1e-15 * l);
    }

    // Absolute: constant σ = ε·max L, and standardised residuals are N(0, 1).
    let peak = exact.iter().cloned().fold(0.0, f64::max);
    let t = run("absolute");
    let sig = t.col("sigma_L");
    assert!(sig.iter().all(|s| (s - eps * peak).abs() < 1e-15 * peak));
    let z: Vec<f64> = t
        .col("L")
        .iter()
        .zip(&exact)
        .zip(&sig)
        .map(|((v, l), s)| (v - l) / s)
        .collect();
    let (mean, sd) = mean_sd(&z);
    assert!(
        mean.abs() < 4.0 / n.sqrt() && (sd - 1.0).abs() < 0.03,
        "{mean} {sd}"
    );

    // Poisson-like: variance ∝ L.
    let t = run("poisson");
    let sig = t.col("sigma_L");
    for (s, l) in sig.iter().zip(&exact) {
        assert!((s * s - eps * eps * l * peak).abs() <= 1e-12 * eps * eps * l * peak);
    }
    let z: Vec<f64> = t
        .col("L")
        .iter()
        .zip(&exact)
        .zip(&sig)
        .filter(|(_, s)| **s > 0.0)
        .map(|((v, l), s)| (v - l) / s)
        .collect();
    let (mean, sd) = mean_sd(&z);
    assert!(
        mean.abs() < 4.0 / n.sqrt() && (sd - 1.0).abs() < 0.03,
        "{mean} {sd}"
    );
}

#[test]
fn layout_facts() {
    let dir = tempfile::tempdir().unwrap();
    // Hemisphere: counts and ranges.
    let t = Table::read(&synth(
        dir.path(),
        "h.csv",
        &["--layout", "hemisphere", "--grid", "4x6x8"],
    ));
    assert_eq!(t.rows.len(), 4 * 6 * 8);
    let uniq = |v: Vec<f64>| {
        let mut v = v;
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    assert_eq!(uniq(t.col("theta_i")), vec![11.25, 33.75, 56.25, 78.75]);
    assert_eq!(
        uniq(t.col("theta_r")),
        vec![7.5, 22.5, 37.5, 52.5, 67.5, 82.5]
    );
    assert_eq!(
        uniq(t.col("phi_r")),
        vec![-180.0, -135.0, -90.0, -45.0, 0.0, 45.0, 90.0, 135.0]
    );
    // Default hemisphere: ~3k samples, θr ∈ (0, 90), φr ∈ [−180, 180).
    let t = Table::read(&synth(dir.path(), "h2.csv", &[]));
    assert_eq!(t.rows.len(), 3240);
    assert!(t.col("theta_r").iter().all(|x| *x > 0.0 && *x < 90.0));
    assert!(t.col("phi_r").iter().all(|x| *x >= -180.0 && *x < 180.0));
    assert!(t.col("theta_i").iter().all(|x| *x >= 0.0 && *x < 90.0));

    // Grazing: θi from 70 to 89.
    let t = Table::read(&synth(dir.path(), "g.csv", &["--layout", "grazing"]));
    let ti = uniq(t.col("theta_i"));
    assert_eq!(ti, vec![70.0, 74.75, 79.5, 84.25, 89.0]);
    assert!(t.col("L").iter().all(|v| v.is_finite()));

    // In-plane: θr < 0 is |θr| at φr = 180, or signed at φr = 0 with --signed-theta-r.
    let t = Table::read(&synth(
        dir.path(),
        "i.csv",
        &["--layout", "inplane", "--theta-i", "30"],
    ));
    assert_eq!(t.rows.len(), 171);
    assert_eq!(t.rows[0][..3], [30.0, 85.0, 180.0]);
    assert_eq!(t.rows[85][..3], [30.0, 0.0, 0.0]);
    assert_eq!(t.rows[170][..3], [30.0, 85.0, 0.0]);
    let s = Table::read(&synth(
        dir.path(),
        "s.csv",
        &["--layout", "inplane", "--theta-i", "30", "--signed-theta-r"],
    ));
    assert_eq!(s.rows[0][..3], [30.0, -85.0, 0.0]);
    assert!(s.col("phi_r").iter().all(|p| *p == 0.0));
    let tr = s.col("theta_r");
    assert!(tr.windows(2).all(|w| w[1] - w[0] == 1.0));
    assert_eq!(
        bits(&s.col("L")),
        bits(&t.col("L")),
        "same data, other spelling"
    );

    // --samples keeps N rows spread over all θi.
    let t = Table::read(&synth(dir.path(), "n.csv", &["--samples", "100"]));
    assert_eq!(t.rows.len(), 100);
    assert_eq!(uniq(t.col("theta_i")).len(), 5);

    // A layout file, with a signed θr and extra columns; a wavelength column on request.
    let angles = dir.path().join("angles.csv");
    std::fs::write(
        &angles,
        "# my scan\nphi_r,theta_i,theta_r,note\n0,45,-30,a\n90,10,20,b\n",
    )
    .unwrap();
    let t = Table::read(&synth(
        dir.path(),
        "f.csv",
        &[
            "--layout",
            angles.to_str().unwrap(),
            "--write-wavelength",
            "--wavelength",
            "0.5",
        ],
    ));
    assert_eq!(t.header, ["theta_i", "theta_r", "phi_r", "L", "wavelength"]);
    assert_eq!(t.rows[0][..3], [45.0, 30.0, 180.0]);
    assert_eq!(t.rows[1][..3], [10.0, 20.0, 90.0]);
    assert_eq!(t.col("wavelength"), vec![0.5, 0.5]);
}

#[test]
fn truth_file_round_trips_and_names_every_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let out = synth(
        dir.path(),
        "data.csv",
        &[
            "--layout",
            "inplane",
            "--noise",
            "0.01",
            "--noise-kind",
            "absolute",
            "--seed",
            "9",
            "--wavelength",
            "0.633",
        ],
    );
    let truth_path = dir.path().join("data.truth.json");
    assert_eq!(synth::truth_path(&out), truth_path);
    let truth = Truth::read(&truth_path).unwrap();
    assert_eq!(truth.model, "kbs");
    let names: Vec<&str> = truth.params.keys().map(String::as_str).collect();
    assert_eq!(names, ["T", "scale", "sigma"]);
    let m = by_name(&truth.model, &ModelOptions::default()).unwrap();
    assert_eq!(truth.param_vector(m.as_ref()).unwrap(), vec![0.3, 2.0, 1.0]);
    assert_eq!(truth.wavelength, 0.633);
    assert_eq!(
        truth.noise,
        Noise {
            kind: NoiseKind::Absolute,
            level: 0.01,
            seed: 9
        }
    );
    assert_eq!(truth.n, 855);
    assert_eq!(truth.quantity, Quantity::Radiance);
    assert_eq!(truth.mode, "auto");
    assert_eq!(truth.data, "data.csv");
    assert!(truth.layout.starts_with("inplane"));
    // Serialise and parse again: the same value.
    let again: Truth = serde_json::from_str(&serde_json::to_string(&truth).unwrap()).unwrap();
    assert_eq!(again, truth);

    // The truth regenerates the file through the library.
    let layout = Layout::parse(&truth.layout).unwrap();
    assert_eq!(layout, Layout::inplane());
    let data = synth::generate(
        m.as_ref(),
        &truth.param_vector(m.as_ref()).unwrap(),
        &layout.angles(),
        truth.wavelength,
        truth.quantity,
        &truth.noise,
    )
    .unwrap();
    let mut bytes = Vec::new();
    data.write_csv(&mut bytes, &WITH_WAVELENGTH).unwrap();
    assert_eq!(bytes, std::fs::read(&out).unwrap());
    let again = truth.regenerate().unwrap();
    assert_eq!(bits(&again.value), bits(&data.value));
    assert_eq!(truth.model_options().unwrap(), ModelOptions::default());

    // A subsampled grid with options regenerates too.
    let out2 = synth(
        dir.path(),
        "sub.csv",
        &[
            "--grid",
            "3x7x11",
            "--samples",
            "50",
            "--mode",
            "series",
            "--patch",
            "40,30",
            "--quantity",
            "brdf",
            "--noise",
            "0.1",
            "--seed",
            "4",
        ],
    );
    let t2 = Truth::read(&synth::truth_path(&out2)).unwrap();
    assert_eq!(t2.layout, "hemisphere 3x7x11");
    assert_eq!(t2.subsample, Some(50));
    assert_eq!(t2.mode, "series");
    assert_eq!(t2.patch, Some((40.0, 30.0)));
    let d2 = t2.regenerate().unwrap();
    let mut bytes = Vec::new();
    d2.write_csv(&mut bytes, &WITH_WAVELENGTH).unwrap();
    assert_eq!(bytes, std::fs::read(&out2).unwrap());

    // --truth puts it elsewhere; a truth missing a parameter is refused by name.
    let other = dir.path().join("t.json");
    goniofit()
        .arg("synth")
        .args(KBS)
        .arg("--truth")
        .arg(&other)
        .assert()
        .success()
        .stdout(contains("theta_i,theta_r,phi_r,L"));
    let mut t = Truth::read(&other).unwrap();
    assert_eq!(t.data, "-");
    t.params.remove("sigma");
    let err = t.param_vector(m.as_ref()).unwrap_err().to_string();
    assert!(err.contains("sigma"), "{err}");
}

#[test]
fn other_models_and_stdout() {
    let out = goniofit()
        .args([
            "synth",
            "--model",
            "lambert-specular",
            "--params",
            "scale=2,B=0.5,w=0.1",
            "--layout",
            "inplane",
            "--theta-i",
            "45",
        ])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "theta_i,theta_r,phi_r,L");
    assert_eq!(lines.len(), 172);
}

fn fails(args: &[&str], message: &str) {
    goniofit()
        .arg("synth")
        .args(args)
        .assert()
        .code(2)
        .stderr(contains(message));
}

#[test]
fn bad_input_exits_2_with_a_clear_message() {
    fails(
        &["--model", "kbx", "--params", "sigma=1"],
        "unknown model 'kbx'",
    );
    fails(
        &["--model", "kbs", "--params", "sigma=0.3,T=2,scale=1,q=3"],
        "parameter q: model kbs has no such parameter",
    );
    fails(
        &["--model", "kbs", "--params", "sigma=0.3,T=2"],
        "parameter scale: missing",
    );
    fails(
        &["--model", "kbs", "--params", "sigma=-1,T=2,scale=1"],
        "parameter sigma",
    );
    fails(
        &[&KBS[..], &["--grid", "5x18"]].concat(),
        "grid '5x18': expected three counts",
    );
    fails(
        &[&KBS[..], &["--grid", "0x18x36"]].concat(),
        "every count must be at least 1",
    );
    fails(
        &[&KBS[..], &["--layout", "inplane", "--grid", "5x5x5"]].concat(),
        "--grid applies",
    );
    fails(
        &[&KBS[..], &["--theta-i", "30"]].concat(),
        "apply to the inplane layout",
    );
    fails(
        &[&KBS[..], &["--layout", "inplane", "--theta-i", "95"]].concat(),
        "outside [0°, 90°)",
    );
    fails(
        &[&KBS[..], &["--layout", "nope.csv"]].concat(),
        "layout 'nope.csv': neither inplane, hemisphere, grazing nor an existing CSV file",
    );
    fails(
        &[&KBS[..], &["--noise", "-0.1"]].concat(),
        "noise level -0.1",
    );
    fails(
        &[&KBS[..], &["--samples", "99999"]].concat(),
        "--samples 99999",
    );
    fails(
        &[&KBS[..], &["--wavelength", "0"]].concat(),
        "'0' is not a positive length",
    );
    fails(&[&KBS[..], &["--tol", "2"]].concat(), "--tol 2");
    fails(&[&KBS[..], &["--patch", "1"]].concat(), "--patch '1'");
    fails(&[&KBS[..], &["--noise-kind", "pink"]].concat(), "pink");

    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("angles.csv");
    std::fs::write(&f, "theta_i,theta_r,phi_r\n10,20,30\n10,abc,30\n").unwrap();
    fails(
        &[&KBS[..], &["--layout", f.to_str().unwrap()]].concat(),
        ":3: column theta_r: 'abc' is not a number",
    );
    std::fs::write(&f, "theta_i,theta_r,phi_r\n95,20,30\n").unwrap();
    fails(
        &[&KBS[..], &["--layout", f.to_str().unwrap()]].concat(),
        ":2: column theta_i,theta_r,phi_r: theta_i = 95",
    );
    std::fs::write(&f, "theta_i,phi_r\n10,30\n").unwrap();
    fails(
        &[&KBS[..], &["--layout", f.to_str().unwrap()]].concat(),
        "no column 'theta_r'",
    );
    std::fs::write(&f, "theta_i,theta_r,phi_r\n").unwrap();
    fails(
        &[&KBS[..], &["--layout", f.to_str().unwrap()]].concat(),
        "no data rows",
    );
    let missing_dir = dir.path().join("no/such/dir/out.csv");
    fails(
        &[&KBS[..], &["--out", missing_dir.to_str().unwrap()]].concat(),
        "no/such/dir",
    );
}
