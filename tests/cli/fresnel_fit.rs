//! Fits with the Fresnel and shadowing factors on the KBS lobe: data synthesised with the
//! factors are recovered within their standard errors, and data without samples at large
//! local incidence angles say that the index is not determined.

use crate::common;
use common::{fit_json, success_stdout};

/// Synthesise kbs+lambert data with a dielectric Fresnel factor (n = 1.5) and Smith
/// shadowing (T/σ = 8) on `layout`, 1 % relative noise, into `dir`; returns the file.
fn synth(dir: &std::path::Path, layout: &str, seed: u64) -> String {
    let out = dir.join(format!("scene{seed}.csv"));
    let out = out.to_str().unwrap().to_string();
    success_stdout(&[
        "synth",
        "--model",
        "kbs+lambert",
        "--params",
        "sigma=0.5,T=4,scale=1,scale_d=0.05,n=1.5",
        "--fresnel",
        "dielectric",
        "--shadowing",
        "smith",
        "--layout",
        layout,
        "--noise",
        "0.01",
        "--seed",
        &seed.to_string(),
        "--out",
        &out,
    ]);
    out
}

/// The physically based lobe on relative residuals (append the selection and the file).
const EXTENDED_RELATIVE: [&str; 9] = [
    "fit",
    "--model",
    "kbs+lambert",
    "--fresnel",
    "dielectric",
    "--shadowing",
    "smith",
    "--residual",
    "relative",
];

fn fit(file: &str) -> serde_json::Value {
    fit_json(&[&EXTENDED_RELATIVE[..], &["--no-intervals", "--json", file]].concat())
}

#[test]
fn synthetic_scenes_recover_n_and_the_slope_ratio() {
    let dir = tempfile::tempdir().unwrap();
    for seed in 1..=5 {
        let v = fit(&synth(dir.path(), "hemisphere", seed));
        assert_eq!(v["factors"], "--fresnel dielectric --shadowing smith");
        for (value, se, truth, what) in [
            (&v["params"]["n"], &v["params"]["n"]["stderr"], 1.5, "n"),
            (
                &v["derived"]["T/sigma"],
                &v["derived"]["T/sigma"]["stderr"],
                8.0,
                "T/σ",
            ),
        ] {
            assert_eq!(value["determined"], true, "seed {seed}: {what} {value}");
            let (x, se) = (value["value"].as_f64().unwrap(), se.as_f64().unwrap());
            assert!(
                se > 0.0 && se < 0.01 * truth,
                "seed {seed}: {what} s.e. {se}"
            );
            assert!(
                (x - truth).abs() < 3.0 * se,
                "seed {seed}: {what} = {x} ± {se}"
            );
        }
    }
}

#[test]
fn without_large_local_angles_n_is_not_determined() {
    let dir = tempfile::tempdir().unwrap();
    let file = synth(dir.path(), "inplane theta_i=10,20 max=30 step=1", 7);
    let v = fit(&file);
    assert_eq!(v["params"]["n"]["determined"], false);
    let notes = v["notes"].to_string();
    assert!(
        notes.contains("n is not determined: no sample beyond θ_loc = 60°"),
        "{notes}"
    );
}

#[test]
fn factors_are_named_in_the_report_and_shadowing_in_validity() {
    let dir = tempfile::tempdir().unwrap();
    let file = synth(dir.path(), "hemisphere", 11);
    let text = success_stdout(&[
        "fit",
        "--model",
        "kbs+lambert",
        "--fresnel",
        "dielectric",
        "--shadowing",
        "smith",
        "--residual",
        "relative",
        "--no-intervals",
        &file,
    ]);
    assert!(text.contains("model           = kbs+lambert --fresnel dielectric --shadowing smith"));
    assert!(
        text.contains("shadowing       = modelled: Smith's"),
        "{text}"
    );
}

/// `--model auto` fits the extended candidate (kbs+lambert with the dielectric factor and
/// Smith shadowing) beside the four plain models; on data made with those factors BIC
/// chooses it and recovers n; its cost is no higher than the same model fitted on its own
/// (auto also starts it from the plain kbs+lambert optimum and keeps the lower cost); the
/// report's replay names the factors, so `goniofit plot` redraws the chosen model (with
/// the index among its parameters, which the plain model would refuse).
#[test]
fn auto_chooses_the_extended_lobe_on_data_made_with_it_and_plot_redraws_it() {
    let dir = tempfile::tempdir().unwrap();
    let file = synth(dir.path(), "hemisphere", 3);
    let auto = fit_json(&[
        "fit",
        "--model",
        "auto",
        "--residual",
        "relative",
        "--no-intervals",
        "--json",
        &file,
    ]);
    let names: Vec<&str> = auto["comparison"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["model"].as_str().unwrap())
        .collect();
    assert_eq!(names, goniofit::AUTO_CANDIDATES);
    assert_eq!(auto["model"], "kbs+lambert");
    assert_eq!(auto["factors"], "--fresnel dielectric --shadowing smith");
    assert_eq!(auto["replay"]["factors"], auto["factors"]);
    let chosen = &auto["comparison"][4];
    assert_eq!(chosen["chosen"], true);
    // The plain kbs+lambert misses the grazing rise and the shadowed wings: far worse BIC.
    assert!(auto["comparison"][3]["delta_bic"].as_f64().unwrap() > 100.0);
    let n = &auto["params"]["n"];
    let (x, se) = (n["value"].as_f64().unwrap(), n["stderr"].as_f64().unwrap());
    assert!((x - 1.5).abs() < 3.0 * se, "n = {x} ± {se}");
    let own = fit(&file);
    let (c_auto, c_own) = (
        auto["cost"].as_f64().unwrap(),
        own["cost"].as_f64().unwrap(),
    );
    assert!(
        c_auto <= c_own * (1.0 + 1e-9),
        "auto {c_auto} vs alone {c_own}"
    );
    let report = dir.path().join("auto.json");
    std::fs::write(&report, auto.to_string()).unwrap();
    let pics = dir.path().join("pics");
    common::success_stdout(&[
        std::ffi::OsStr::new("plot"),
        report.as_os_str(),
        "--out".as_ref(),
        pics.as_os_str(),
    ]);
}

/// A near-mirror surface (g ≈ 1e-3) of a high index, on a hemisphere of five incidence
/// angles: the fit finds the index (n = 2.45 within 3 s.e.), not the plain lobe's valley
/// that an index below 1 would open (total internal reflection makes the factor a constant
/// there, a second scale; χ²/(n − p) ≈ 55 at that valley against ≈ 1 here).
#[test]
fn a_near_mirror_of_high_index_finds_its_index() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mirror.csv");
    let out = out.to_str().unwrap();
    success_stdout(&[
        "synth",
        "--model",
        "kbs",
        "--fresnel",
        "dielectric",
        "--shadowing",
        "smith",
        "--params",
        "sigma=0.009465,T=2.503,scale=0.978,n=2.451",
        "--layout",
        "hemisphere 5x18x24",
        "--noise",
        "0.01",
        "--noise-kind",
        "relative",
        "--seed",
        "12829661802753887198",
        "--write-sigma",
        "--out",
        out,
    ]);
    let v = fit_json(&[
        "fit",
        "--model",
        "kbs",
        "--fresnel",
        "dielectric",
        "--shadowing",
        "smith",
        "--no-intervals",
        "--json",
        out,
    ]);
    let n = &v["params"]["n"];
    let (x, se) = (n["value"].as_f64().unwrap(), n["stderr"].as_f64().unwrap());
    assert!((x - 2.451).abs() < 3.0 * se && se < 0.01, "n = {x} ± {se}");
    let chi2 = v["reduced_chi2"].as_f64().unwrap();
    assert!(chi2 < 1.5, "χ²/(n − p) = {chi2}");
}

/// The dielectric and Schlick index lies above 1: a start or value at or below it is
/// refused, naming the domain; the conductor's n may lie below 1.
#[test]
fn a_dielectric_index_at_or_below_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let file = synth(dir.path(), "inplane theta_i=10,20 max=30 step=5", 2);
    for (fresnel, params) in [
        ("dielectric", "sigma=0.5,T=4,scale=1,scale_d=0.05,n=0.8"),
        ("schlick", "sigma=0.5,T=4,scale=1,scale_d=0.05,n=1"),
    ] {
        let out = common::goniofit()
            .args(["eval", "--model", "kbs+lambert", "--fresnel", fresnel])
            .args(["--params", params, &file])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{fresnel}: {err}");
        assert!(err.contains("outside its domain (> 1)"), "{fresnel}: {err}");
    }
    success_stdout(&[
        "eval",
        "--model",
        "kbs+lambert",
        "--fresnel",
        "conductor",
        "--params",
        "sigma=0.5,T=4,scale=1,scale_d=0.05,n=0.05,kappa=4",
        &file,
    ]);
}

/// A fit with factors ends no higher than the same fit started from the plain model's
/// optimum (Cornell acryl_blue at 420 nm: its own start search alone ends in a smooth
/// valley at n → 1 with ½Σr² = 1370, the rough valley beside the plain optimum is 1306).
#[test]
fn a_fit_with_factors_is_no_worse_than_from_the_plain_optimum() {
    let file = common::data("cornell/acryl_blue.astm");
    let file = file.to_str().unwrap();
    let base = [
        &common::PAINT_BRDF_LOG[..],
        &["--channel", "420nm", "--no-intervals", "--json"],
    ]
    .concat();
    let factors = ["--fresnel", "dielectric", "--shadowing", "smith"];
    let plain = fit_json(&[&base[..], &[file]].concat());
    let init: Vec<String> = ["sigma", "T", "scale", "scale_d"]
        .iter()
        .map(|k| format!("{k}={}", plain["params"][k]["value"]))
        .collect();
    let init = init.join(",");
    let seeded = fit_json(&[&base[..], &factors, &["--init", &init, file]].concat());
    let own = fit_json(&[&base[..], &factors, &[file]].concat());
    let (c_own, c_seeded) = (
        own["cost"].as_f64().unwrap(),
        seeded["cost"].as_f64().unwrap(),
    );
    assert!(
        c_own <= c_seeded * (1.0 + 1e-9),
        "{c_own} vs {c_seeded} from the plain optimum"
    );
    assert!(c_own < 1310.0, "{c_own}");
}

/// A fit whose index runs to n → ∞ (Cornell garnet red at 650 nm, relative residuals: the
/// best lobe has no Fresnel rise) ends `degenerate` at that edge and says so, with n not
/// determined and the lobe's σ, T and scale determined.
#[test]
fn an_index_run_to_infinity_is_the_edge_n_to_infinity() {
    let file = common::data("cornell/garnet_red.astm");
    let tail = [
        "--channel",
        "650nm",
        "--no-intervals",
        file.to_str().unwrap(),
    ];
    let (_, v) = common::run_json(&[&EXTENDED_RELATIVE[..], &tail].concat());
    assert_eq!(v["termination"], "degenerate", "{v}");
    let notes = v["notes"].to_string();
    assert!(notes.contains("ran to n → ∞"), "{notes}");
    assert!(v["params"]["n"]["value"].as_f64().unwrap() >= 1e17);
    assert_eq!(v["params"]["n"]["determined"], false);
    for k in ["sigma", "T", "scale"] {
        assert_eq!(
            v["params"][k]["determined"], true,
            "{k}: {}",
            v["params"][k]
        );
    }
}
