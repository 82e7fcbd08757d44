//! Settings in JSON and the command line equivalent to them.

use super::*;

/// Every option at a value other than its default.
fn all_set() -> Settings {
    Settings {
        model: "kbs+lambert".into(),
        wavelength: Some(0.633),
        wavelength_unit: Some("µm".into()),
        quantity: Some(Quantity::Brdf),
        channel: Some("550nm".into()),
        by_group: true,
        radians: true,
        signed_theta_r: true,
        columns: Some("theta_i=ti,L=brdf".into()),
        subsample: 4,
        residual: ResidualKind::Log,
        loss: LossKind::SoftL1,
        f_scale: 0.03,
        floor: Some(1e-4),
        init: vec![("sigma".into(), 0.3), ("T".into(), 2.0)],
        fix: vec![("scale_d[550nm]".into(), 0.1)],
        mode: EvalMode::Series,
        tol: 1e-8,
        patch: Some((10.0, 20.0)),
        fresnel: Fresnel::Conductor,
        shadowing: Shadowing::SmithCorrelated,
        max_iter: 50,
        timeout: Some(60.0),
        reduce: false,
        absolute_sigma: true,
        intervals: Some(false),
        warm_start: true,
        threads: Some(2),
    }
}

#[test]
fn every_option_survives_json() {
    let s = all_set();
    let text = serde_json::to_string_pretty(&s).unwrap();
    let back: Settings = serde_json::from_str(&text).unwrap();
    assert_eq!(back, s);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let defaults = serde_json::to_value(Settings::default()).unwrap();
    for (key, value) in v.as_object().unwrap() {
        assert_ne!(&defaults[key], value, "{key} is at its default");
    }
    assert_eq!(v["init"], serde_json::json!({"sigma": 0.3, "T": 2.0}));
    assert_eq!(v["patch"], serde_json::json!([10.0, 20.0]));
    assert_eq!(v["shadowing"], "smith-correlated");
    assert_eq!(v["loss"], "soft_l1");
    assert_eq!(v["mode"], "series");
    s.check(Front::Cli).unwrap();
}

#[test]
fn keys_left_out_take_their_defaults_and_unknown_keys_are_refused() {
    let s: Settings = serde_json::from_str(r#"{"model": "lambert"}"#).unwrap();
    assert_eq!(
        s,
        Settings {
            model: "lambert".into(),
            ..Settings::default()
        }
    );
    let e = serde_json::from_str::<Settings>(r#"{"modle": "kbs"}"#).unwrap_err();
    assert!(e.to_string().contains("unknown field `modle`"), "{e}");
}

#[test]
fn values_are_refused_with_the_option_named_as_the_front_end_spells_it() {
    let bad = Settings {
        f_scale: 0.0,
        ..Settings::default()
    };
    let e = |front| bad.check(front).unwrap_err().to_string();
    assert!(
        e(Front::Cli).starts_with("--f-scale 0: "),
        "{}",
        e(Front::Cli)
    );
    assert!(e(Front::Python).starts_with("f_scale 0: "));
    let subsample = Settings {
        subsample: 0,
        ..Settings::default()
    };
    assert!(subsample.check(Front::Json).is_err());
    let init = Settings {
        init: vec![("sigma".into(), f64::NAN)],
        ..Settings::default()
    };
    assert!(init.check(Front::Python).is_err());
}

#[test]
fn the_command_line_asks_for_the_same_settings() {
    let line = all_set().command_line();
    assert!(line.starts_with(
        "goniofit fit --model kbs+lambert --quantity brdf --residual log --mode series --tol 1e-8 --max-iter 50 --loss soft_l1 --f-scale 0.03 --wavelength 0.633µm --init sigma=0.3,T=2 --fix scale_d[550nm]=0.1 --patch 10,20 --fresnel conductor --shadowing smith-correlated"
    ), "{line}");
    for flag in [
        "--floor 0.0001",
        "--timeout 60",
        "--channel 550nm",
        "--columns theta_i=ti,L=brdf",
        "--subsample 4",
        "--threads 2",
        "--radians",
        "--signed-theta-r",
        "--no-reduce",
        "--absolute-sigma",
        "--no-intervals",
        "--by-group",
        "--warm-start",
    ] {
        assert!(line.contains(flag), "{flag} in {line}");
    }
    assert_eq!(
        Settings::default().command_line(),
        "goniofit fit --model kbs --residual absolute --mode auto --tol 1e-10 --max-iter 500"
    );
}
