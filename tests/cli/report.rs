//! What a fit report states: units, the whole setting in JSON, `plot` from any
//! directory, `--channel` on CSV input, the ASTM file's own quantity, weights transformed
//! with relative/log residuals, the floor's count, `--by-group` on ASTM files, and the
//! smaller help/usage texts.

use crate::common;

use common::{fit_json, goniofit, GARNET_550};
use predicates::prelude::PredicateBooleanExt;
use predicates::str::contains;
use std::path::{Path, PathBuf};

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Run goniofit, expect exit 2 (bad usage or input) and `message` on stderr.
fn usage_error(args: &[&str], message: &str) {
    goniofit()
        .args(args)
        .assert()
        .code(2)
        .stderr(contains(message));
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

const HEMI: &str = "data/synthetic/kbs_hemisphere.csv";
const GARNET: &str = "data/cornell/garnet_red.astm";

#[test]
fn wavelength_units_scale_sigma_and_t_and_are_stated() {
    let bare = fit_json(&["fit", "--wavelength", "1", "--json", HEMI]);
    let nm = fit_json(&["fit", "--wavelength", "633nm", "--json", HEMI]);
    let um = fit_json(&["fit", "--wavelength", "0.633um", "--json", HEMI]);
    // KBS depends on σ/λ and T/λ only: σ in nm is 633 × σ at λ = 1, and 1000 × σ in µm.
    for name in ["sigma", "T"] {
        let s1 = f(&bare["params"][name]["value"]);
        let snm = f(&nm["params"][name]["value"]);
        let sum = f(&um["params"][name]["value"]);
        assert!(
            (snm / (633.0 * s1) - 1.0).abs() < 1e-6,
            "{name}: {snm} vs {s1}"
        );
        assert!(
            (snm / (1000.0 * sum) - 1.0).abs() < 1e-6,
            "{name}: {snm} vs {sum}"
        );
        assert_eq!(nm["params"][name]["unit"], "nm");
        assert_eq!(um["params"][name]["unit"], "µm");
        assert_eq!(bare["params"][name]["unit"], "unit of λ");
    }
    assert_eq!(nm["setting"]["wavelength"]["unit"], "nm");
    assert_eq!(f(&nm["setting"]["wavelength"]["values"][0]), 633.0);
    assert_eq!(nm["setting"]["wavelength"]["source"], "--wavelength");
    // A radiance file states no unit for L: the scale is in the unit of L.
    assert_eq!(nm["params"]["scale"]["unit"], "unit of L");
    // The text report says it too.
    goniofit()
        .args(["fit", "--wavelength", "633nm", HEMI])
        .assert()
        .code(0)
        .stdout(contains(
            "wavelength      = 633 nm (from --wavelength; σ, T in nm)",
        ))
        .stdout(predicates::str::is_match(r"\n    sigma = 1\.58\d+e2 +\+/- [^\n]*nm").unwrap());
    usage_error(&["fit", "--wavelength", "633pm", HEMI], "633nm, 0.633um");
}

#[test]
fn every_command_reads_the_wavelength_with_its_unit() {
    // synth, eval, render and fit share one parser: 633nm, 0.633um, a bare number.
    let dir = tempfile::tempdir().unwrap();
    let csv = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let params = "sigma=150,T=900,scale=1";
    let run = |args: String| goniofit().args(args.split_whitespace()).assert().code(0);
    let synth = |wl: &str, out: &str| {
        run(format!(
            "synth --model kbs --params {params} --layout inplane --wavelength {wl} --out {out}"
        ));
    };
    synth("633nm", &csv("nm.csv"));
    synth("633", &csv("bare.csv"));
    // The same data (σ, T in the unit of λ), and the truth names the unit.
    let nm = std::fs::read_to_string(csv("nm.csv")).unwrap();
    assert_eq!(nm, std::fs::read_to_string(csv("bare.csv")).unwrap());
    assert!(nm.lines().nth(1).unwrap().ends_with(",633.0"), "{nm:.200}");
    let truth = |name: &str| -> serde_json::Value {
        let t = std::fs::read_to_string(dir.path().join(name)).unwrap();
        serde_json::from_str(&t).unwrap()
    };
    assert_eq!(truth("nm.truth.json")["wavelength_unit"], "nm");
    assert_eq!(truth("nm.truth.json")["wavelength"], 633.0);
    assert!(truth("bare.truth.json").get("wavelength_unit").is_none());
    synth("0.633um", &csv("um.csv"));
    assert_eq!(truth("um.truth.json")["wavelength_unit"], "µm");
    // eval: 633nm gives the values of 633.
    let eval = |wl: &str| {
        let args = format!(
            "eval --model kbs --params {params} --wavelength {wl} {}",
            csv("nm.csv")
        );
        common::success_stdout(&args.split_whitespace().collect::<Vec<_>>())
    };
    let e = eval("633nm");
    assert_eq!(e, eval("633"));
    assert!(e.lines().count() > 100);
    // render: accepted, the same picture as the bare number.
    let render = |wl: &str, out: &str| {
        run(format!(
            "render sphere --model kbs --params {params} --size 64 --wavelength {wl} --out {out}"
        ));
        std::fs::read(out).unwrap()
    };
    assert_eq!(render("633nm", &csv("a.png")), render("633", &csv("b.png")));
    // One message for a unit no command knows.
    for (command, wl, file) in [
        ("synth", "633pm", ""),
        ("eval", "633pm", HEMI),
        ("render sphere", "-1nm", ""),
    ] {
        let line = format!("{command} --model kbs --params {params} --wavelength {wl} {file}");
        usage_error(
            &line.split_whitespace().collect::<Vec<_>>(),
            "633nm, 0.633um",
        );
    }
}

#[test]
fn json_carries_the_whole_setting() {
    let v = fit_json(&[&GARNET_550[..], &["--json", GARNET]].concat());
    let st = &v["setting"];
    let path = st["input"]["path"].as_str().unwrap();
    assert!(Path::new(path).is_absolute(), "{path}");
    let bytes = std::fs::read(repo(GARNET)).unwrap();
    assert_eq!(st["input"]["sha256"].as_str().unwrap(), sha256_hex(&bytes));
    assert_eq!(st["input"]["bytes"].as_u64(), Some(bytes.len() as u64));
    assert_eq!(st["wavelength"]["unit"], "nm");
    assert_eq!(st["wavelength"]["source"], "channel name");
    assert_eq!(st["channel"], "550nm");
    assert_eq!(st["quantity"], "brdf");
    assert_eq!(st["quantity_source"], "stated by the file");
    assert_eq!(st["residual"], "log");
    assert_eq!(st["weights"]["source"], "none");
    assert_eq!(st["loss"], "linear");
    assert_eq!(st["absolute_sigma"], false);
    // The floor (1e-6 × max L) and how many values lie below it, counted from the file.
    let ds = goniofit::read(
        &repo(GARNET),
        &goniofit::ReadOptions {
            channel: Some("550nm".into()),
            require_value: true,
            ..Default::default()
        },
    )
    .unwrap();
    let y = ds.value.unwrap();
    let floor = 1e-6 * y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!((f(&st["floor"]["value"]) / floor - 1.0).abs() < 1e-12);
    let below = y.iter().filter(|&&v| v < floor).count();
    assert!(below >= 4, "garnet has exact zeros");
    assert_eq!(st["floor"]["raised"].as_u64(), Some(below as u64));
    // Units: σ, T in nm; scales in sr⁻¹ for a BRDF; π·s_d as a reflectance factor.
    assert_eq!(v["params"]["sigma"]["unit"], "nm");
    assert_eq!(v["params"]["scale_d"]["unit"], "sr⁻¹");
    let rf = &v["derived"]["reflectance_factor"];
    let sd = f(&v["params"]["scale_d"]["value"]);
    assert!((f(&rf["value"]) / (std::f64::consts::PI * sd) - 1.0).abs() < 1e-12);
    assert_eq!(rf["unit"], "1");
}

#[test]
fn astm_files_default_to_the_quantity_their_header_states() {
    let args = GARNET_550;
    let default = fit_json(&[&args[..], &["--json", GARNET]].concat());
    let brdf = fit_json(&[&args[..], &["--quantity", "brdf", "--json", GARNET]].concat());
    let radiance = fit_json(&[&args[..], &["--quantity", "radiance", "--json", GARNET]].concat());
    assert_eq!(default["setting"]["quantity"], "brdf");
    assert_eq!(radiance["setting"]["quantity_source"], "--quantity");
    assert_eq!(f(&default["cost"]), f(&brdf["cost"]));
    assert_ne!(f(&default["cost"]), f(&radiance["cost"]));
}

#[test]
fn relative_residuals_with_sigma_l_transform_the_weights() {
    // σ_L is 1 % of L (the synth noise): the relative residual's uncertainty is 0.01, so
    // with the transformed weights reduced χ² is near 1 (with the weights 1/σ_L² it would be
    // 4.2e10).
    // Log residuals use a floor far below the data here: at the default floor (1e-6 × max L)
    // 358 values of this hemisphere are raised, and their residuals vanish.
    for (residual, floor) in [("relative", "1e-300"), ("log", "1e-300")] {
        let v = fit_json(&[
            "fit",
            "--wavelength",
            "1",
            "--residual",
            residual,
            "--floor",
            floor,
            "--json",
            HEMI,
        ]);
        let chi = f(&v["reduced_chi2"]);
        assert!(
            (0.95..1.08).contains(&chi),
            "{residual}: reduced χ² = {chi}"
        );
        assert_eq!(v["setting"]["floor"]["raised"].as_u64(), Some(0));
        assert_eq!(v["setting"]["weights"]["source"], "sigma_L column");
        assert!(v["setting"]["weights"]["transform"]
            .as_str()
            .unwrap()
            .starts_with("max("));
        // σ, T recovered within 4 standard errors of the truth (0.25, 2.5).
        for (name, truth) in [("sigma", 0.25), ("T", 2.5)] {
            let p = &v["params"][name];
            let (x, se) = (f(&p["value"]), f(&p["stderr"]));
            assert!(
                (x - truth).abs() < 4.0 * se,
                "{residual} {name} = {x} ± {se}"
            );
        }
    }
    goniofit()
        .args(["fit", "--wavelength", "1", "--residual", "relative", HEMI])
        .assert()
        .code(0)
        .stdout(contains(
            "weights         = sigma_L column: max(|L|, floor)²/sigma_L²",
        ));
}

#[test]
fn plot_works_from_any_directory() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("fit.json");
    let out = goniofit()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "fit",
            "--model",
            "kbs",
            "--wavelength",
            "633nm",
            "--json",
            HEMI,
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    std::fs::write(&report, &out.stdout).unwrap();
    // From the report's own directory, where the relative input path does not exist.
    goniofit()
        .current_dir(dir.path())
        .args(["plot", "fit.json", "--out", "pics"])
        .assert()
        .code(0)
        .stderr(contains("wrote"));
    assert!(dir.path().join("pics/polar.png").exists());
}

/// `plot` of a saved report redraws the pictures `fit --plot` wrote, byte for byte: the
/// report's settings rebuild how the file is read (a channel of an ASTM file; a CSV's
/// wavelength with its unit) and the fitted model with its factors.
#[test]
fn plot_of_a_report_redraws_the_pictures_of_its_fit() {
    let dir = tempfile::tempdir().unwrap();
    // The README's garnet fit (its arguments after `fit`), and a CSV with λ's unit.
    let cases = [
        [&GARNET_550[1..], &[GARNET]].concat(),
        vec![
            "--wavelength",
            "633nm",
            "--residual",
            "relative",
            "--fresnel",
            "dielectric",
            HEMI,
        ],
    ];
    for (k, case) in cases.iter().enumerate() {
        let (fitted, redrawn) = (
            dir.path().join(format!("fit{k}")),
            dir.path().join(format!("plot{k}")),
        );
        let out = goniofit()
            .args(["fit", "--no-intervals", "--json", "--plot"])
            .arg(&fitted)
            .args(case)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{case:?}");
        let report = dir.path().join(format!("fit{k}.json"));
        std::fs::write(&report, &out.stdout).unwrap();
        goniofit()
            .arg("plot")
            .arg(&report)
            .arg("--out")
            .arg(&redrawn)
            .assert()
            .code(0);
        let svgs = |d: &Path| {
            let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|x| x == "svg"))
                .map(|p| {
                    (
                        p.file_name().unwrap().to_string_lossy().into_owned(),
                        std::fs::read(&p).unwrap(),
                    )
                })
                .collect();
            files.sort();
            files
        };
        let (a, b) = (svgs(&fitted), svgs(&redrawn));
        assert!(a.len() >= 5, "{case:?}: {} pictures", a.len());
        assert_eq!(a.len(), b.len(), "{case:?}");
        for ((name, x), (other, y)) in a.iter().zip(&b) {
            assert_eq!(name, other);
            assert!(x == y, "{case:?}: {name} differs");
        }
    }
}

#[test]
fn channel_selects_a_wavelength_of_a_csv() {
    let ptfe = "data/nist-ptfe/PTFE.data.csv";
    for channel in ["0.532", "532nm", "0.532um"] {
        let v = fit_json(&[
            "fit",
            "--model",
            "lambert",
            "--channel",
            channel,
            "--json",
            ptfe,
        ]);
        assert_eq!(v["n"].as_u64(), Some(1824), "{channel}");
        assert_eq!(v["setting"]["wavelength"]["unit"], "µm");
        assert_eq!(f(&v["setting"]["wavelength"]["values"][0]), 0.532);
        // Germer's f_r11 is a BRDF.
        assert_eq!(v["setting"]["quantity"], "brdf");
    }
    usage_error(
        &["fit", "--model", "lambert", "--channel", "0.5", ptfe],
        "wavelengths: 0.351µm, 0.532µm, 0.633µm, 1.064µm",
    );
    // --by-group on a CSV without a group column fits each wavelength on its own.
    let v = fit_json(&["fit", "--model", "lambert", "--by-group", "--json", ptfe]);
    assert_eq!(v["datasets"].as_u64(), Some(4));
    // A CSV with neither a group nor a wavelength column cannot select a channel.
    usage_error(
        &["fit", "--wavelength", "1", "--channel", "550nm", HEMI],
        "needs a group column or a wavelength column",
    );
}

#[test]
fn by_group_on_an_astm_file_fits_every_channel() {
    let v = fit_json(&["fit", "--model", "lambert", "--by-group", "--json", GARNET]);
    assert_eq!(v["datasets"].as_u64(), Some(31));
}

#[test]
fn help_and_usage_texts() {
    goniofit()
        .args(["fit", "--help"])
        .assert()
        .code(0)
        .stdout(contains("[default: 1e-10]"))
        .stdout(contains("Examples:"));
    goniofit()
        .args(["bench", "work-precision", "--help"])
        .assert()
        .code(0)
        .stdout(contains(r#"`{"rows": [...]}`"#));
    usage_error(
        &["fit", "--model", "kbz", "--wavelength", "1", HEMI],
        "or auto",
    );
}

#[test]
fn by_group_prints_one_line_per_fit_and_writes_the_summary_csv() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("fits.csv");
    let out = goniofit()
        .args(["fit", "--model", "lambert", "--by-group", "--summary"])
        .arg(&csv)
        .arg(GARNET)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).unwrap();
    let table = text.split("[[Summary]]").nth(1).expect("a summary table");
    // Header + 31 channel lines.
    assert_eq!(table.trim_end().lines().count(), 1 + 1 + 31, "{table}");
    assert!(table.contains("data/cornell/garnet_red.astm [550nm]"));
    let written = std::fs::read_to_string(&csv).unwrap();
    let mut lines = written.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert!(header.starts_with(&["group", "n", "converged", "termination", "cost", "r2"]));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 31);
    // The 550nm row has the cost of the 550nm fit run on its own.
    let one = fit_json(&[
        "fit",
        "--model",
        "lambert",
        "--channel",
        "550nm",
        "--json",
        GARNET,
    ]);
    let row: Vec<&str> = rows
        .iter()
        .find(|r| r.contains("[550nm]"))
        .unwrap()
        .split(',')
        .collect();
    assert_eq!(row[1], "1439");
    assert_eq!(row[3], one["termination"].as_str().unwrap());
    let cost: f64 = row[4].parse().unwrap();
    assert!((cost / f(&one["cost"]) - 1.0).abs() < 1e-9, "{cost}");
}

#[test]
fn long_correlation_matrices_are_summarised() {
    // A joint lambert fit over 31 channels has 31 free scales: the text lists the largest
    // pairs, the JSON keeps the whole matrix.
    let out = goniofit()
        .args(["fit", "--model", "kbs", "--channel", "all", GARNET])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("the 10 largest |ρ|; the full matrix is in --json"),
        "{text}"
    );
    assert!(text
        .lines()
        .filter(|l| !l.contains("note:"))
        .all(|l| l.chars().count() < 200));
    assert!(text.contains("joint fit over 31 channels"), "{text}");
    let v = fit_json(&[
        "fit",
        "--model",
        "kbs",
        "--channel",
        "all",
        "--json",
        GARNET,
    ]);
    let k = v["correlation"]["names"].as_array().unwrap().len();
    assert_eq!(v["correlation"]["matrix"].as_array().unwrap().len(), k);
    assert_eq!(v["correlation"]["largest"].as_array().unwrap().len(), 10);
}

/// An interval from JSON: [lo, hi] with None for an open side.
fn interval(v: &serde_json::Value) -> (Option<f64>, Option<f64>) {
    let a = v
        .as_array()
        .unwrap_or_else(|| panic!("not an interval: {v}"));
    (a[0].as_f64(), a[1].as_f64())
}

#[test]
fn profile_intervals_of_a_linear_model_are_t_times_the_standard_error() {
    // Lambert is linear in its scale: the profile χ² is exactly quadratic, so the interval
    // is ŝ ± t_{(1+P)/2, n−1} · se (lmfit's F test with one parameter).
    let v = fit_json(&[
        "fit",
        "--model",
        "lambert",
        "--channel",
        "0.633",
        "--json",
        "data/nist-ptfe/PTFE.data.csv",
    ]);
    let p = &v["params"]["scale"];
    let (s, se) = (f(&p["value"]), f(&p["stderr"]));
    let dof = (v["n"].as_u64().unwrap() - 1) as f64;
    for (key, prob) in [("interval68", 0.682_689_492_137_086), ("interval95", 0.95)] {
        let t = goniofit::stats::student_t_quantile(0.5 * (1.0 + prob), dof);
        let (lo, hi) = interval(&p[key]);
        let (lo, hi) = (lo.unwrap(), hi.unwrap());
        assert!(
            ((s - lo) / (t * se) - 1.0).abs() < 1e-3,
            "{key}: {lo} vs {s} - {t}·{se}"
        );
        assert!(
            ((hi - s) / (t * se) - 1.0).abs() < 1e-3,
            "{key}: {hi} vs {s} + {t}·{se}"
        );
    }
    // π·s carries the same interval times π.
    let (rlo, _) = interval(&v["derived"]["reflectance_factor"]["interval95"]);
    let (lo, _) = interval(&p["interval95"]);
    assert!((rlo.unwrap() / (std::f64::consts::PI * lo.unwrap()) - 1.0).abs() < 1e-12);
}

#[test]
fn a_flat_profile_gives_a_one_sided_or_open_interval() {
    // A specular lobe fitted to Lambertian data: B goes to its bound 0 and the width w
    // does not matter, so w's profile is flat and B has no upper bound from the data.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("lambert.csv");
    goniofit()
        .args([
            "synth",
            "--model",
            "lambert",
            "--params",
            "scale=1",
            "--layout",
            "inplane",
            "--noise",
            "0.01",
            "--seed",
            "1",
            "--write-sigma",
            "--out",
        ])
        .arg(&csv)
        .assert()
        .code(0);
    let path = csv.to_str().unwrap();
    let v = fit_json(&["fit", "--model", "lambert-specular", "--json", path]);
    assert_eq!(interval(&v["params"]["w"]["interval95"]), (None, None));
    let (lo, hi) = interval(&v["params"]["B"]["interval95"]);
    assert_eq!((lo, hi), (Some(0.0), None));
    // The scale stays bounded on both sides and contains the truth 1 at 95 %.
    let (lo, hi) = interval(&v["params"]["scale"]["interval95"]);
    assert!(lo.unwrap() < 1.0 && 1.0 < hi.unwrap(), "{lo:?} {hi:?}");
    goniofit()
        .args(["fit", "--model", "lambert-specular", path])
        .assert()
        .code(0)
        .stdout(contains("95%: not bounded by the data"));
}

#[test]
fn undetermined_parameters_are_reported_by_their_bounds() {
    let v = fit_json(&[&GARNET_550[..], &["--json", GARNET]].concat());
    for name in ["sigma", "T"] {
        let p = &v["params"][name];
        assert_eq!(p["determined"], false);
        let (lo, hi) = interval(&p["interval95"]);
        let x = f(&p["value"]);
        assert!(
            lo.unwrap() < x && x < hi.unwrap(),
            "{name}: {lo:?} {x} {hi:?}"
        );
        let (lo68, hi68) = interval(&p["interval68"]);
        assert!(lo.unwrap() < lo68.unwrap() && hi68.unwrap() < hi.unwrap());
    }
    // T/σ's interval holds its estimate and is narrower than σ's in relative terms.
    let (lo, hi) = interval(&v["derived"]["T/sigma"]["interval95"]);
    let q = f(&v["derived"]["T/sigma"]["value"]);
    assert!(lo.unwrap() < q && q < hi.unwrap());
}

/// χ² of the garnet fit `args` (without the file) holding `fix` (name=value), the rest
/// fitted from scratch (the fit's own start search), unreduced.
fn chi2_holding(args: &[&str], fix: &str) -> f64 {
    let extra = [
        "--no-reduce",
        "--no-intervals",
        "--fix",
        fix,
        "--json",
        GARNET,
    ];
    f(&fit_json(&[args, &extra[..]].concat())["chi2"])
}

#[test]
fn profile_ends_are_where_a_fit_holding_the_parameter_reaches_the_threshold() {
    // An independent check of the profile search: hold σ (or T) at a reported end and fit
    // the rest from scratch (the fit's own grid search for starting values, not the
    // profile's warm starts). Δχ² there must equal the threshold s²·t²_{(1+P)/2, n−p} to
    // the search's accuracy, CROSS_TOL in √Δχ²; a lower refit would mean the profile
    // missed the minimum, a higher one that the end is off.
    let v = fit_json(&[&GARNET_550[..], &["--json", GARNET]].concat());
    let chi2_min = f(&v["chi2"]);
    let p = v["params"].as_object().unwrap().len();
    let dof = v["n"].as_u64().unwrap() as usize - p;
    for (name, key, prob, side) in [
        ("sigma", "interval95", 0.95, 0),
        ("sigma", "interval95", 0.95, 1),
        ("sigma", "interval68", 0.682_689_492_137_086, 0),
        ("T", "interval95", 0.95, 1),
    ] {
        let (lo, hi) = interval(&v["params"][name][key]);
        let end = [lo, hi][side].unwrap();
        let fix = format!("{name}={end:.17e}");
        let th = goniofit::stats::profile_threshold(prob, chi2_min, dof, false);
        let delta = chi2_holding(&GARNET_550, &fix) - chi2_min;
        assert!(
            ((delta / th).sqrt() - 1.0).abs() < 2.0 * goniofit::stats::CROSS_TOL,
            "{name} {key} end {end}: Δχ² {delta} against the threshold {th}"
        );
    }
}

#[test]
fn a_profile_flat_out_to_the_domain_edge_is_open() {
    // Garnet at 400 nm: Δχ² of σ rises towards large σ but levels off below the 95 %
    // threshold (fits holding σ at 10× and 100× the estimate, from scratch, stay below
    // it), so the data bounds σ from below only; T follows σ along the rough ridge.
    let args = [
        "fit",
        "--model",
        "kbs+lambert",
        "--channel",
        "400nm",
        "--residual",
        "log",
    ];
    let v = fit_json(&[&args[..], &["--json", GARNET]].concat());
    let chi2_min = f(&v["chi2"]);
    let dof = v["n"].as_u64().unwrap() as usize - 4;
    let th = goniofit::stats::profile_threshold(0.95, chi2_min, dof, false);
    for name in ["sigma", "T"] {
        let (lo, hi) = interval(&v["params"][name]["interval95"]);
        assert!(lo.unwrap() < f(&v["params"][name]["value"]) && hi.is_none());
    }
    for factor in [10.0, 100.0] {
        let fix = format!("sigma={}", factor * f(&v["params"]["sigma"]["value"]));
        let delta = chi2_holding(&args, &fix) - chi2_min;
        assert!(delta < th, "σ × {factor}: Δχ² {delta} against {th}");
    }
}

#[test]
fn absolute_sigma_drops_the_residual_scale() {
    let rel = fit_json(&["fit", "--wavelength", "1", "--json", HEMI]);
    let abs = fit_json(&[
        "fit",
        "--wavelength",
        "1",
        "--absolute-sigma",
        "--json",
        HEMI,
    ]);
    assert_eq!(abs["setting"]["absolute_sigma"], true);
    let s = f(&rel["reduced_chi2"]).sqrt();
    let (a, r) = (
        f(&abs["params"]["sigma"]["stderr"]),
        f(&rel["params"]["sigma"]["stderr"]),
    );
    assert!((a * s / r - 1.0).abs() < 1e-9, "{a} {r} {s}");
}

#[test]
fn html_report_is_one_self_contained_page() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("report.html");
    goniofit()
        .args(["fit", "--wavelength", "633nm", "--html"])
        .arg(&page)
        .arg(HEMI)
        .assert()
        .code(0)
        .stderr(contains("pictures inline"));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    for part in [
        "<h2>Reproduce</h2>",
        "<h2>Setting</h2>",
        "<h2>Parameters</h2>",
        "<h2>Derived quantities</h2>",
        "<h2>Identifiability and validity</h2>",
        "<table id=\"validity\">",
        "<td>curvature</td>",
        "<td>shadowing</td>",
        "<h2>Pictures</h2>",
        "95 % interval",
        "--wavelength 633nm",
    ] {
        assert!(html.contains(part), "missing {part}");
    }
    // Every picture inline (six SVGs and the hemispheres of the four busiest of the file's
    // five incidence angles), nothing fetched: no src/href to other files or hosts.
    assert_eq!(html.matches("<svg").count(), 10);
    for attr in ["src=\"", "href=\"", "url("] {
        for (i, _) in html.match_indices(attr) {
            let rest = &html[i + attr.len()..];
            assert!(
                rest.starts_with("data:") || rest.starts_with('#'),
                "external {attr}{}",
                &rest[..40.min(rest.len())]
            );
        }
    }
    // The parameter row of σ carries its unit and both intervals.
    let row = html
        .lines()
        .find(|l| l.starts_with("<tr><td>sigma</td>"))
        .unwrap();
    assert!(
        row.contains("<td>nm</td>") && row.matches('[').count() == 2,
        "{row}"
    );
}

#[test]
fn small_cli_texts_say_what_they_mean() {
    // A Lambert BRDF is a constant: the fit is the mean, R² = 0 exactly (never "−0.0000000").
    let out = goniofit()
        .args([
            "fit",
            "--model",
            "lambert",
            "--channel",
            "550nm",
            "--no-intervals",
            GARNET,
        ])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("R-squared       = 0.0000000\n"), "{text}");
    assert!(!text.contains("-0.0000000"));
    // `render` says what it wrote: size, model, parameters.
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("s.png");
    goniofit()
        .args([
            "render",
            "sphere",
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
            "--out",
        ])
        .arg(&png)
        .assert()
        .code(0)
        .stderr(contains("px").and(contains("model kbs at sigma=0.3,T=2,scale=1")));
}

/// The JSON a fit writes reads back into the library's typed report and is written again
/// value for value: a single fit with intervals and a model comparison, and every fit of a
/// batch report.
#[test]
fn json_reports_read_back_into_the_typed_report() {
    use goniofit::FitReport;
    let round_trip = |v: &serde_json::Value| {
        let report: FitReport = serde_json::from_value(v.clone()).unwrap();
        assert_eq!(&serde_json::to_value(&report).unwrap(), v);
        report
    };
    let auto = fit_json(&[
        "fit",
        "--model",
        "auto",
        "--channel",
        "550nm",
        "--json",
        GARNET,
    ]);
    let report = round_trip(&auto);
    assert!(report.comparison.as_ref().is_some_and(|c| c.len() > 1));
    assert!(report.replay.is_some());
    assert!(report
        .params
        .values()
        .any(|p| p.estimate.interval95.is_some()));
    assert_eq!(report.adequacy.headline, auto["adequacy"]["headline"]);
    let batch = fit_json(&[
        "fit",
        "--model",
        "lambert",
        "--by-group",
        "--json",
        "--no-intervals",
        GARNET,
    ]);
    let fits = batch["fits"].as_array().unwrap();
    assert!(fits.len() > 3);
    for fit in fits {
        round_trip(fit);
    }
}

/// `plot` refuses a file that is not a fit report, saying what it is missing.
#[test]
fn plot_names_what_a_report_lacks() {
    let dir = tempfile::tempdir().unwrap();
    let not_json = dir.path().join("a.json");
    std::fs::write(&not_json, "L,theta_i\n").unwrap();
    usage_error(
        &["plot", not_json.to_str().unwrap(), "--out", "p"],
        "not a goniofit fit report (not JSON)",
    );
    let no_replay = dir.path().join("b.json");
    std::fs::write(&no_replay, r#"{"model": "kbs"}"#).unwrap();
    usage_error(
        &["plot", no_replay.to_str().unwrap(), "--out", "p"],
        "missing field",
    );
}

/// The SHA-256 of `bytes` as lowercase hex, by the sha2 crate.
fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
