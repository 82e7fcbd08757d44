//! Fits with the Fresnel and shadowing factors on the KBS lobe: data synthesised with the
//! factors are recovered within their standard errors, and data without samples at large
//! local incidence angles say that the index is not determined.

mod common;
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

fn fit(file: &str) -> serde_json::Value {
    fit_json(&[
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
        "--json",
        file,
    ])
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
