//! `goniofit design`: the linearised prediction against closed forms and against the
//! scatter of fits of simulated measurements (synth noise, the fit engine, independent of
//! the Fisher information the design computes), the design against a random choice, the
//! honest "no geometry helps", and the command line's outputs and error exits.

use crate::common;

use common::{data, goniofit, GARNET_550};
use goniofit::design::{self, Grid, NoiseModel, Request, Scene};
use goniofit::synth::{self, Noise, NoiseKind};
use goniofit::{
    fit_model, model as by_name, AnglesDeg, Channels, FitConfig, FitInput, Geometry, Model,
    ModelOptions, PerSample, Quantity, ResidualKind, Sample,
};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

/// Simulated measurements per scatter: the relative standard error of a standard
/// deviation from 200 draws is 1/√398 ≈ 5 %, so a 25 % agreement holds at ~5 of it.
const DRAWS: u64 = 200;

/// The measured geometries of the synthetic scenes: in plane, θi 15, 30, 45°, θr from
/// −60 to 60° in 5° steps (75 samples, nothing beyond 60°).
fn scan() -> Vec<AnglesDeg> {
    let mut out = Vec::new();
    for theta_i in [15.0, 30.0, 45.0] {
        for k in -12..=12 {
            let tr = 5.0 * k as f64;
            out.push(AnglesDeg {
                theta_i,
                theta_r: tr.abs(),
                phi_r: if k < 0 { 180.0 } else { 0.0 },
            });
        }
    }
    out
}

fn in_plane() -> Vec<AnglesDeg> {
    Grid {
        theta_max_deg: 85.0,
        step_deg: 2.5,
        in_plane: true,
    }
    .angles()
    .unwrap()
}

fn kbs() -> Box<dyn Model> {
    by_name("kbs", &ModelOptions::default()).unwrap()
}

fn scene<'a>(model: &'a dyn Model, params: &[f64], noise: f64) -> Scene<'a> {
    Scene {
        model,
        params: params.to_vec(),
        wavelength: 1.0,
        quantity: Quantity::Radiance,
        noise: NoiseModel::new(ResidualKind::Relative, noise).unwrap(),
        unit: None,
    }
}

fn request(target: &str, n: usize) -> Request {
    Request {
        existing: scan().iter().map(AnglesDeg::sample).collect(),
        candidates: in_plane(),
        n,
        target: target.into(),
        dynamic_range: design::DYNAMIC_RANGE,
        wavelengths: Vec::new(),
    }
}

/// The fit of one simulated measurement: the scene's model and residual kind from the
/// truth, nothing reduced (the least-squares estimate of every parameter).
fn fit_values(
    model: &dyn Model,
    truth: &[f64],
    geo: &Geometry,
    y: Vec<f64>,
    kind: ResidualKind,
) -> Option<Vec<f64>> {
    let n = y.len();
    let input = FitInput {
        geo: geo.clone(),
        y: y.into(),
        weight: PerSample::One { value: 1.0, len: n },
        channel: Channels::single(n),
        channel_names: vec![String::new()],
    };
    let config = FitConfig {
        model: model.name().into(),
        model_opts: model.options().unwrap_or_default(),
        residual: kind,
        init: model
            .params()
            .iter()
            .zip(truth)
            .map(|(s, v)| (s.name.to_string(), *v))
            .collect(),
        reduce: false,
        ..FitConfig::default()
    };
    let r = fit_model(model, &input, &config).ok()?;
    r.values
        .iter()
        .all(|v| v.is_finite() && *v > 0.0)
        .then_some(r.values)
}

fn sd(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() as f64 - 1.0)).sqrt()
}

/// The standard deviation of ln p̂_j over fits of `DRAWS` measurements at `angles` with
/// relative noise from `goniofit::harness::synth` (L(1 + εz)).
fn realised_log_sd(s: &Scene, angles: &[AnglesDeg], j: usize, seed: u64) -> f64 {
    let samples: Vec<Sample> = angles.iter().map(AnglesDeg::sample).collect();
    let geo = Geometry::new(&samples, &[s.wavelength], s.quantity).unwrap();
    let est: Vec<f64> = (0..DRAWS)
        .filter_map(|k| {
            let noise = Noise {
                kind: NoiseKind::Relative,
                level: s.noise.level,
                seed: seed + k,
            };
            let d = synth::generate(s.model, &s.params, angles, s.wavelength, s.quantity, &noise)
                .unwrap();
            fit_values(s.model, &s.params, &geo, d.value, ResidualKind::Relative)
        })
        .map(|p| p[j].ln())
        .collect();
    assert!(
        est.len() as u64 >= DRAWS - 4,
        "{} of {DRAWS} fits usable",
        est.len()
    );
    sd(&est)
}

fn chosen_angles(d: &design::Design) -> Vec<AnglesDeg> {
    d.chosen
        .iter()
        .map(|c| AnglesDeg {
            theta_i: c[0],
            theta_r: c[1],
            phi_r: c[2],
        })
        .collect()
}

/// Design σ for a KBS scene, then compare the predicted standard error of ln σ after the
/// design with the scatter of fits at the measured + proposed geometries.
fn check_scene(params: [f64; 3], noise: f64, seed: u64) -> design::Design {
    let m = kbs();
    let s = scene(m.as_ref(), &params, noise);
    let d = design::design(&s, &request("sigma", 20)).unwrap();
    let predicted = d.target_after.expect("σ determined after the design");
    let mut angles = scan();
    angles.extend(chosen_angles(&d));
    let realised = realised_log_sd(&s, &angles, 0, seed);
    eprintln!(
        "σ = {}: predicted ±{predicted:.4}, realised ±{realised:.4}",
        params[0]
    );
    assert!(
        (predicted / realised - 1.0).abs() < 0.25,
        "σ = {}: predicted ±{predicted:.4}, realised ±{realised:.4}",
        params[0]
    );
    d
}

#[test]
fn smooth_scene_prediction_matches_simulation() {
    let d = check_scene([0.03, 1.0, 1.0], 0.02, 100);
    assert!(d.target_after < d.target_before);
}

#[test]
fn intermediate_scene_prediction_matches_simulation() {
    let d = check_scene([0.15, 1.0, 1.0], 0.02, 200);
    assert!(d.target_after < d.target_before);
}

/// The rough scene: σ = 3λ, T/σ = 5, 5 % noise. The scan (nothing beyond 60°, g ≥ 60)
/// leaves σ undetermined; grazing samples, where g falls to ~3, determine it.
const ROUGH: [f64; 3] = [3.0, 15.0, 1.0];
const ROUGH_NOISE: f64 = 0.05;

#[test]
fn rough_scene_design_determines_sigma_and_beats_a_random_choice() {
    let d = check_scene(ROUGH, ROUGH_NOISE, 300);
    assert!(d
        .target_before
        .is_none_or(|b| b > design::DETERMINED_RELATIVE_SE));
    assert!(d.after[0].determined, "{:?}", d.after[0]);
    assert!(
        d.sentence.starts_with("σ becomes determined to ±"),
        "{}",
        d.sentence
    );
    // Twenty candidates drawn at random from the same reachable grid.
    let reachable: Vec<AnglesDeg> = in_plane()
        .into_iter()
        .zip(&d.candidates)
        .filter(|(_, c)| c.reachable)
        .map(|(a, _)| a)
        .collect();
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let mut random = scan();
    let mut picked = std::collections::BTreeSet::new();
    while picked.len() < 20 {
        picked.insert(rng.gen_range(0..reachable.len()));
    }
    random.extend(picked.iter().map(|&i| reachable[i]));
    let mut designed = scan();
    designed.extend(chosen_angles(&d));
    let m = kbs();
    let s = scene(m.as_ref(), &ROUGH, ROUGH_NOISE);
    let (sd_design, sd_random) = (
        realised_log_sd(&s, &designed, 0, 400),
        realised_log_sd(&s, &random, 0, 400),
    );
    eprintln!("realised se of ln σ: design {sd_design:.4}, random {sd_random:.4}");
    assert!(
        sd_random >= 2.0 * sd_design,
        "realised se of ln σ: design {sd_design:.4}, random {sd_random:.4}"
    );
}

#[test]
fn lambert_scale_has_the_closed_form_error() {
    // L = s cos θi: with relative noise every sample gives ∂ ln L/∂ ln s = 1, so N samples
    // give se(ln s) = ε/√N; with absolute noise the best are at θi = 0, se = ε/(s√N).
    let m = by_name("lambert", &ModelOptions::default()).unwrap();
    let mut s = scene(m.as_ref(), &[2.0], 0.02);
    let mut r = request("scale", 25);
    r.existing.clear();
    let d = design::design(&s, &r).unwrap();
    assert!((d.target_after.unwrap() - 0.02 / 5.0).abs() < 1e-12);
    assert_eq!(d.target_before, None, "no data: nothing determined");
    s.noise = NoiseModel::new(ResidualKind::Absolute, 0.1).unwrap();
    let d = design::design(&s, &r).unwrap();
    assert!(d.chosen.iter().all(|c| c[0] == 0.0), "{:?}", d.chosen);
    assert!((d.target_after.unwrap() - 0.1 / (2.0 * 5.0)).abs() < 1e-12);
}

#[test]
fn a_surface_rough_everywhere_is_said_so_and_a_longer_wavelength_named() {
    // σ = 20λ: even at 85° g ≈ 470, the rough limit, where only T/σ and the amplitude
    // show; at λ' = 20 (σ = λ') grazing samples determine σ.
    let m = kbs();
    let s = scene(m.as_ref(), &[20.0, 100.0, 1.0], 0.02);
    let mut r = request("sigma", 20);
    let d = design::design(&s, &r).unwrap();
    assert!(!d.after[0].determined);
    assert!(
        d.sentence
            .starts_with("no reachable geometry determines σ at this wavelength"),
        "{}",
        d.sentence
    );
    r.wavelengths = vec![2.0, 20.0];
    let d = design::design(&s, &r).unwrap();
    assert!(
        d.sentence.contains("a measurement at 20 would: ±"),
        "{}",
        d.sentence
    );
    assert!(d.alternatives[1].target_after.unwrap() <= design::DETERMINED_RELATIVE_SE);
}

/// The README's garnet red fit at 550 nm: the design for σ from its report, and the
/// scatter of fits of simulated measurements (log-normal noise of the fit's √ reduced χ²)
/// at the paint's 1439 geometries plus the proposed ones.
#[test]
fn garnet_red_prediction_matches_simulation() {
    let dir = std::env::temp_dir().join(format!("goniofit-design-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let report = dir.join("garnet.json");
    let file = data("cornell/garnet_red.astm");
    let out = goniofit()
        .args(GARNET_550)
        .args(["--quantity", "brdf", "--json"])
        .arg(&file)
        .output()
        .unwrap();
    std::fs::write(&report, &out.stdout).unwrap();
    let json = common::success_stdout(&[
        "design".as_ref(),
        "--from".as_ref(),
        report.as_os_str(),
        "--target".as_ref(),
        "sigma".as_ref(),
        "--in-plane".as_ref(),
        "--json".as_ref(),
    ]);
    let d: serde_json::Value = serde_json::from_str(&json).unwrap();
    let fit: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let truth: Vec<f64> = serde_json::from_value(fit["replay"]["values"].clone()).unwrap();
    let eps = fit["reduced_chi2"].as_f64().unwrap().sqrt();
    assert_eq!(d["noise"]["level"].as_f64().unwrap(), eps);
    let predicted = d["target"]["after"].as_f64().unwrap();
    let opts = goniofit::ReadOptions {
        channel: Some("550nm".into()),
        require_value: true,
        ..Default::default()
    };
    let ds = goniofit::read(&file, &opts).unwrap();
    let mut samples = ds.samples.clone();
    for c in d["chosen"].as_array().unwrap() {
        let a = |k: &str| c[k].as_f64().unwrap();
        samples.push(Sample::from_degrees(a("theta_i"), a("theta_r"), a("phi_r")));
    }
    let geo = Geometry::new(&samples, &[550.0], Quantity::Brdf).unwrap();
    let m = by_name("kbs+lambert", &ModelOptions::default()).unwrap();
    let mut exact = vec![0.0; geo.len()];
    m.eval(&geo, &truth, &mut exact, None);
    let est: Vec<f64> = (0..DRAWS)
        .filter_map(|k| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(500 + k);
            let y = exact
                .iter()
                .map(|f| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    f * (eps * z).exp()
                })
                .collect::<Vec<f64>>();
            fit_values(m.as_ref(), &truth, &geo, y, ResidualKind::Log)
        })
        .map(|p| p[0].ln())
        .collect();
    assert!(est.len() as u64 >= DRAWS - 4);
    let realised = sd(&est);
    eprintln!("garnet σ: predicted ±{predicted:.4}, realised ±{realised:.4}");
    assert!(
        (predicted / realised - 1.0).abs() < 0.25,
        "garnet σ: predicted ±{predicted:.4}, realised ±{realised:.4}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

fn exit_code(args: &[&str]) -> (Option<i32>, String) {
    let out = goniofit().args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

const ROUGH_CLI: [&str; 9] = [
    "design",
    "--model",
    "kbs",
    "--params",
    "sigma=3,T=15,scale=1",
    "--noise",
    "0.05",
    "--residual",
    "relative",
];

#[test]
fn bad_usage_exits_2_with_a_clear_message() {
    let cases: [(&[&str], &str); 5] = [
        (&["--n", "0"], "--n 0"),
        (&["--target", "colour"], "--target 'colour'"),
        (&["--step", "0"], "--step 0"),
        (&["--theta-max", "95"], "--theta-max 95"),
        (&["--dynamic-range", "0.5"], "--dynamic-range 0.5"),
    ];
    for (extra, message) in cases {
        let mut args = ROUGH_CLI.to_vec();
        args.extend_from_slice(extra);
        let (code, err) = exit_code(&args);
        assert_eq!(code, Some(2), "{extra:?}: {err}");
        assert!(err.contains(message), "{extra:?}: {err}");
    }
    let (code, err) = exit_code(&[
        "design",
        "--model",
        "kbs",
        "--params",
        "sigma=3,T=15,scale=1",
    ]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--noise"), "{err}");
    let (code, _) = exit_code(&["design", "--from", "no-such-report.json"]);
    assert_eq!(code, Some(2));
}

#[test]
fn cli_writes_the_geometries_the_picture_and_json() {
    let dir = std::env::temp_dir().join(format!("goniofit-design-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let existing = dir.join("scan.csv");
    let mut csv = String::from("theta_i,theta_r,phi_r\n");
    for a in scan() {
        csv += &format!("{},{},{}\n", a.theta_i, a.theta_r, a.phi_r);
    }
    std::fs::write(&existing, csv).unwrap();
    let (next, pics) = (dir.join("next.csv"), dir.join("pics"));
    let mut args: Vec<&std::ffi::OsStr> = ROUGH_CLI.iter().map(|s| s.as_ref()).collect();
    for a in [
        "--existing".as_ref(),
        existing.as_os_str(),
        "--target".as_ref(),
        "sigma".as_ref(),
    ]
    .into_iter()
    .chain([
        "--in-plane".as_ref(),
        "--n".as_ref(),
        "12".as_ref(),
        "--json".as_ref(),
    ])
    .chain([
        "--out".as_ref(),
        next.as_os_str(),
        "--plot".as_ref(),
        pics.as_os_str(),
    ])
    .chain(["--simulate".as_ref(), "20".as_ref()])
    {
        args.push(a);
    }
    let json: serde_json::Value = serde_json::from_str(&common::success_stdout(&args)).unwrap();
    let rows = std::fs::read_to_string(&next).unwrap();
    let lines: Vec<&str> = rows.lines().collect();
    assert_eq!(lines[0], "theta_i,theta_r,phi_r");
    assert_eq!(lines.len(), 13);
    assert_eq!(json["chosen"].as_array().unwrap().len(), 12);
    assert_eq!(json["measured"]["count"], 75);
    assert_eq!(json["target"]["name"], "sigma");
    assert!(json["before"]["sigma"]["relative"].as_f64().unwrap() > 0.25);
    assert!(json["after"]["T/sigma"]["relative"].as_f64().unwrap() > 0.0);
    assert_eq!(json["simulated"]["draws"], 20);
    assert!(json["target"]["simulated"].as_f64().unwrap() > 0.0);
    assert!(!json.to_string().contains("NaN"));
    let svg = std::fs::read_to_string(pics.join("design.svg")).unwrap();
    assert!(svg.contains("next geometries for σ"));
    assert!(pics.join("design.png").exists());
    std::fs::remove_dir_all(&dir).ok();
}
