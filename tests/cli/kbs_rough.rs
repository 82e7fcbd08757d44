//! `kbs-rough` (the paper's rough approximation, eq. 43) is fitted in its own parameters by
//! construction: it depends on σ and T only through T/σ, so σ is held and the fit
//! determines T/σ and the amplitude s·(T/σ)²; σ never runs toward 0 (to 1e-127, where the
//! fit would stop with "Jacobian is not finite").

use crate::common;

use common::{data, fit_json};

fn truth() -> (f64, f64) {
    let text = std::fs::read_to_string(data("synthetic/kbs_rough.truth.json")).unwrap();
    let t: serde_json::Value = serde_json::from_str(&text).unwrap();
    let p = &t["params"];
    let (sigma, corr, scale) = (
        p["sigma"].as_f64().unwrap(),
        p["T"].as_f64().unwrap(),
        p["scale"].as_f64().unwrap(),
    );
    (corr / sigma, scale * (corr / sigma).powi(2))
}

fn rough_fit(extra: &[&str]) -> serde_json::Value {
    let path = data("synthetic/kbs_rough.csv");
    let mut args = vec!["fit", "--model", "kbs-rough", "--wavelength", "1", "--json"];
    args.extend_from_slice(extra);
    args.push(path.to_str().unwrap());
    fit_json(&args)
}

#[test]
fn kbs_rough_recovers_t_over_sigma_within_2_percent_and_says_what_it_cannot_tell() {
    let (ratio, amplitude) = truth();
    assert_eq!(ratio, 5.0);
    let j = rough_fit(&["--no-intervals"]);
    assert_eq!(j["converged"], true, "{j}");
    assert_eq!(j["verdict"], "rough");
    let d = &j["derived"];
    let got = d["T/sigma"]["value"].as_f64().unwrap();
    assert!((got / ratio - 1.0).abs() < 0.02, "T/σ = {got}");
    assert_eq!(d["T/sigma"]["determined"], true);
    let se = d["T/sigma"]["stderr"].as_f64().unwrap();
    assert!((got - ratio).abs() < 4.0 * se, "T/σ = {got} ± {se}");
    let amp = d["amplitude"]["value"].as_f64().unwrap();
    assert!(
        (amp / amplitude - 1.0).abs() < 0.02,
        "amplitude {amp} vs {amplitude}"
    );
    // σ and T separately: not determined, no error bar, and the note says why.
    for name in ["sigma", "T"] {
        assert_eq!(j["params"][name]["determined"], false, "{name}");
        assert!(j["params"][name]["stderr"].is_null(), "{name}");
    }
    let notes = j["notes"].to_string();
    assert!(notes.contains("only through T/σ"), "{notes}");
    assert!(notes.contains("not σ and T separately"), "{notes}");
}

#[test]
fn the_held_sigma_does_not_change_what_kbs_rough_determines() {
    // Held at --init's σ = 3 instead of λ: the same T/σ and amplitude, T scaled with σ.
    let a = rough_fit(&["--no-intervals"]);
    let b = rough_fit(&["--no-intervals", "--init", "sigma=3,T=15,scale=1"]);
    assert_eq!(b["converged"], true);
    let v = |j: &serde_json::Value, k: &str| j["derived"][k]["value"].as_f64().unwrap();
    for k in ["T/sigma", "amplitude"] {
        assert!(
            (v(&a, k) / v(&b, k) - 1.0).abs() < 1e-6,
            "{k}: {} vs {}",
            v(&a, k),
            v(&b, k)
        );
    }
    let s = |j: &serde_json::Value| j["params"]["sigma"]["value"].as_f64().unwrap();
    assert_eq!(s(&a), 1.0);
    assert_eq!(s(&b), 3.0);
}
