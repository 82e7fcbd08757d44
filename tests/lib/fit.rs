//! The fit layer on synthetic data with known truth: recovery within the reported
//! uncertainties, identifiability verdicts in the smooth, intermediate and rough regimes,
//! joint multi-channel fits, and the report formats.

use crate::fit::driver::{fit, FitConfig, FitInput, FitResult, Verdict};
use crate::geometry::{Geometry, Quantity};
use crate::harness::synth::{generate, Layout, Noise, NoiseKind};
use crate::model::{by_name, ModelOptions};
use std::sync::atomic::Ordering::SeqCst;

/// Synthetic data for `model` at `params` on `layout`, with relative noise: one channel of
/// [`joint_synthetic`].
fn synthetic(
    model: &str,
    params: &[f64],
    layout: Layout,
    noise: f64,
    seed: u64,
    lambda: f64,
) -> FitInput {
    joint_synthetic(
        model,
        &[params.to_vec()],
        &[lambda],
        &[""],
        layout,
        noise,
        seed,
    )
}

/// Several channels of synthetic data in one input (unit weights): channel c, named
/// `names[c]`, at wavelength `lambdas[c]` with model parameters `params[c]` and relative
/// noise `noise` (seed `seed0 + c`), on the same angles.
fn joint_synthetic(
    model: &str,
    params: &[Vec<f64>],
    lambdas: &[f64],
    names: &[&str],
    layout: Layout,
    noise: f64,
    seed0: u64,
) -> FitInput {
    let m = by_name(model, &ModelOptions::default()).unwrap();
    let angles = layout.angles();
    let mut samples = Vec::new();
    let (mut y, mut lambda, mut channel) = (Vec::new(), Vec::new(), Vec::new());
    for (c, (p, &lam)) in params.iter().zip(lambdas).enumerate() {
        let noise = Noise {
            kind: NoiseKind::Relative,
            level: noise,
            seed: seed0 + c as u64,
        };
        let d = generate(m.as_ref(), p, &angles, lam, Quantity::Radiance, &noise).unwrap();
        lambda.extend(std::iter::repeat_n(lam, d.len()));
        channel.extend(std::iter::repeat_n(c, d.len()));
        samples.extend(d.samples);
        y.extend(d.value);
    }
    let geo = Geometry::new(&samples, &lambda, Quantity::Radiance).unwrap();
    let n = geo.len();
    FitInput {
        geo,
        y: y.into(),
        weight: vec![1.0; n].into(),
        channel: channel.into(),
        channel_names: names.iter().map(|s| s.to_string()).collect(),
    }
}

fn config(model: &str) -> FitConfig {
    FitConfig {
        model: model.into(),
        residual: crate::fit::problem::ResidualKind::Relative,
        ..FitConfig::default()
    }
}

fn param<'a>(r: &'a FitResult, name: &str) -> &'a crate::fit::driver::ParamResult {
    r.params.iter().find(|p| p.name == name).unwrap()
}

fn derived<'a>(r: &'a FitResult, name: &str) -> &'a crate::fit::driver::Derived {
    r.derived.iter().find(|p| p.name == name).unwrap()
}

/// |estimate − truth| within k standard errors (and the standard error is stated).
fn within(value: f64, stderr: Option<f64>, truth: f64, k: f64) -> bool {
    let se = stderr.expect("a determined quantity has a standard error");
    (value - truth).abs() <= k * se
}

#[test]
fn intermediate_regime_recovers_all_parameters_within_uncertainty() {
    // g = (2π·0.25·c)² spans ≈ 0.2 .. 9.9: every parameter is determined.
    let truth = [0.25, 2.5, 1.0];
    let input = synthetic("kbs", &truth, Layout::hemisphere(), 0.01, 7, 1.0);
    // Relative residuals on every sample, however small (the default floor is 1e-6 × max).
    let mut cfg = config("kbs");
    cfg.floor = Some(f64::MIN_POSITIVE);
    let r = fit(&input, &cfg).unwrap();
    assert!(r.converged(), "termination {:?}", r.termination);
    assert_eq!(r.verdict, Verdict::Full);
    for (name, t) in ["sigma", "T", "scale"].iter().zip(truth) {
        let p = param(&r, name);
        assert!(p.determined, "{name} should be determined");
        assert!(
            within(p.value, p.stderr, t, 4.0),
            "{name}: {} ± {:?} vs truth {t}",
            p.value,
            p.stderr
        );
        // 1 % noise on 3240 samples pins each parameter to well under 1 %.
        assert!(
            (p.value / t - 1.0).abs() < 0.01,
            "{name}: {} vs {t}",
            p.value
        );
    }
    // Reduced chi-square of relative residuals ≈ noise variance.
    assert!(
        (r.reduced_chi2 / 1e-4 - 1.0).abs() < 0.1,
        "reduced chi2 {}",
        r.reduced_chi2
    );
}

/// With the default floor (relative residuals below 1e-6 × max L are not resolved, as on
/// a real instrument) the σ-dependence of the far tails is invisible.
#[test]
fn rough_regime_reports_only_ratio_and_amplitude() {
    // σ = 60λ: g from ≈ 2e3 to 1e5; the lobe depends on T/σ only, up to O(1/g) terms far
    // below the noise.
    let truth = [60.0, 300.0, 1.0];
    let layout = Layout::hemisphere().with_grid(4, 12, 24).unwrap();
    let input = synthetic("kbs", &truth, layout, 0.01, 3, 1.0);
    let r = fit(&input, &config("kbs")).unwrap();
    assert!(r.converged(), "termination {:?}", r.termination);
    assert_eq!(r.verdict, Verdict::Rough, "notes: {:?}", r.notes);
    assert!(!param(&r, "sigma").determined);
    assert!(!param(&r, "T").determined);
    assert!(!param(&r, "scale").determined);
    let ratio = derived(&r, "T/sigma");
    assert!(ratio.determined);
    assert!(
        within(ratio.value, ratio.stderr, 5.0, 4.0),
        "T/σ {} ± {:?}",
        ratio.value,
        ratio.stderr
    );
    let amp = derived(&r, "amplitude");
    // amplitude s·(T/σ)² = 25 at the truth.
    assert!(
        (amp.value / 25.0 - 1.0).abs() < 0.02,
        "amplitude {}",
        amp.value
    );
}

#[test]
fn smooth_regime_reports_t_and_amplitude() {
    // σ = 3e-4 λ: g ≤ (2π·3e-4·2)² ≈ 1.4e-5, far below what 1 % noise can resolve.
    let truth = [3e-4, 1.5, 2.0];
    let layout = Layout::hemisphere().with_grid(4, 12, 24).unwrap();
    let input = synthetic("kbs", &truth, layout, 0.01, 5, 1.0);
    let r = fit(&input, &config("kbs")).unwrap();
    assert!(r.converged(), "termination {:?}", r.termination);
    assert_eq!(r.verdict, Verdict::Smooth, "notes: {:?}", r.notes);
    assert!(!param(&r, "sigma").determined);
    assert!(!param(&r, "scale").determined);
    let t = param(&r, "T");
    assert!(t.determined);
    assert!(
        within(t.value, t.stderr, 1.5, 4.0),
        "T {} ± {:?}",
        t.value,
        t.stderr
    );
    let amp = derived(&r, "amplitude");
    // s·σ² = 2 · (3e-4)² = 1.8e-7.
    assert!(
        within(amp.value, amp.stderr, 1.8e-7, 4.0),
        "amplitude {} ± {:?}",
        amp.value,
        amp.stderr
    );
}

#[test]
fn joint_fit_shares_sigma_and_t_across_channels() {
    // Three wavelengths, per-channel scales; σ and T shared.
    let truth = [0.25, 2.5];
    let scales = [1.0, 0.7, 0.4];
    let lambdas = [0.8, 1.0, 1.25];
    let input = joint_synthetic(
        "kbs",
        &scales.map(|s| vec![truth[0], truth[1], s]),
        &lambdas,
        &["800nm", "1000nm", "1250nm"],
        Layout::hemisphere().with_grid(4, 12, 24).unwrap(),
        0.01,
        100,
    );
    let r = fit(&input, &config("kbs")).unwrap();
    assert!(r.converged());
    assert_eq!(r.params.len(), 5, "sigma, T and three scales");
    for (name, t) in [
        ("sigma", 0.25),
        ("T", 2.5),
        ("scale[800nm]", 1.0),
        ("scale[1000nm]", 0.7),
        ("scale[1250nm]", 0.4),
    ] {
        let p = param(&r, name);
        assert!(p.determined, "{name}");
        assert!(
            within(p.value, p.stderr, t, 4.0),
            "{name}: {} ± {:?} vs {t}",
            p.value,
            p.stderr
        );
    }
}

#[test]
fn lambert_specular_recovers_lobe() {
    let truth = [0.2, 1.5, 0.12];
    let input = synthetic("lambert-specular", &truth, Layout::inplane(), 0.01, 9, 1.0);
    let r = fit(&input, &config("lambert-specular")).unwrap();
    assert!(r.converged());
    for (name, t) in ["scale", "B", "w"].iter().zip(truth) {
        let p = param(&r, name);
        assert!(
            within(p.value, p.stderr, t, 4.0),
            "{name}: {} ± {:?} vs {t}",
            p.value,
            p.stderr
        );
    }
}

#[test]
fn fixed_parameters_stay_fixed_and_too_few_samples_is_an_error() {
    let input = synthetic("kbs", &[0.25, 2.5, 1.0], Layout::inplane(), 0.01, 1, 1.0);
    let mut cfg = config("kbs");
    cfg.fix = vec![("T".into(), 2.5)];
    let r = fit(&input, &cfg).unwrap();
    assert_eq!(param(&r, "T").value, 2.5);
    assert!(param(&r, "T").fixed);
    assert_eq!(r.n_free, 2);

    let few = input.subset(&[0, 1, 2]);
    let err = fit(&few, &config("kbs")).unwrap_err();
    assert!(
        err.to_string()
            .contains("more samples than free parameters"),
        "{err}"
    );
    let mut zero = input.clone();
    zero.y.iter_mut().for_each(|v| *v = 0.0);
    assert!(fit(&zero, &config("kbs"))
        .unwrap_err()
        .to_string()
        .contains("zero"));
    let mut bad = config("kbs");
    bad.fix = vec![("roughness".into(), 1.0)];
    assert!(fit(&input, &bad)
        .unwrap_err()
        .to_string()
        .contains("roughness"));
}

#[test]
fn problem_jacobian_matches_central_differences() {
    // The solver's Jacobian (√w ∂r/∂f ∂f/∂p dp/dx, assembled per block) against central
    // differences of its residuals: every residual kind, two channels with per-channel
    // scales, unequal weights, and one parameter held fixed.
    use crate::fit::problem::{FitProblem, ParamLayout, ResidualKind};
    use goniofit_lm::{finite_difference_jacobian, LeastSquaresProblem};
    let model = by_name("kbs+lambert", &ModelOptions::default()).unwrap();
    let mut input = joint_synthetic(
        "kbs+lambert",
        &[vec![0.3, 2.0, 1.0, 0.05], vec![0.3, 2.0, 0.6, 0.05]],
        &[0.8, 1.2],
        &["a", "b"],
        Layout::hemisphere().with_grid(3, 6, 8).unwrap(),
        0.05,
        7,
    );
    let n = input.geo.len();
    input.weight = (0..n).map(|i| 0.5 + (i % 3) as f64).collect();
    for kind in [
        ResidualKind::Absolute,
        ResidualKind::Relative,
        ResidualKind::Log,
    ] {
        let mut layout = ParamLayout::new(model.as_ref(), &input.channel_names);
        let fixed = layout.find("scale_d[b]")[0];
        layout.params[fixed].fixed = Some(0.04);
        let problem = FitProblem::new(model.as_ref(), layout.clone(), &input, kind, 1e-9).unwrap();
        // Off the data's parameters, so residuals are not small.
        let x = layout.to_x(&[0.27, 2.3, 0.9, 0.04, 0.7, 0.04]);
        let (r, jac) = problem.residuals_and_jacobian(&x);
        assert_eq!(
            jac.ncols(),
            5,
            "{kind:?}: the fixed scale_d[b] has no column"
        );
        assert_eq!(r, problem.residuals(&x));
        let fd = finite_difference_jacobian(|z| problem.residuals(z), &x, None);
        for j in 0..jac.ncols() {
            let scale = jac.column(j).amax().max(1e-300);
            for i in 0..n {
                let err = (jac[(i, j)] - fd[(i, j)]).abs() / scale;
                assert!(
                    err < 1e-6,
                    "{kind:?} column {j} row {i}: {} vs {}",
                    jac[(i, j)],
                    fd[(i, j)]
                );
            }
        }
    }
}

#[test]
fn an_overflowing_fit_is_never_reported_converged() {
    // The library takes any finite values (the CLI refuses these at input, naming the
    // line): one L = 1e200 makes the cost ½Σr² overflow; the result must not say converged.
    let mut input = synthetic("lambert", &[0.7], Layout::inplane(), 0.0, 1, 1.0);
    input.y[5] = 1e200;
    let mut c = config("lambert");
    c.residual = crate::fit::problem::ResidualKind::Absolute;
    let r = fit(&input, &c).unwrap();
    assert!(!r.cost.is_finite() || !r.is_finite());
    assert!(!r.converged());
    assert!(
        r.notes
            .iter()
            .any(|n| n.starts_with("not a usable optimum")),
        "{:?}",
        r.notes
    );
    // With a finite outlier instead (sample 5 given sample 4's value) the fit converges,
    // every number finite.
    input.y[5] = input.y[4];
    let r = fit(&input, &c).unwrap();
    assert!(r.converged() && r.is_finite());
}

#[test]
fn an_evaluation_stopped_before_it_starts_gives_no_number() {
    // A stop requested before an evaluation: every block is skipped, so no residual and no
    // Jacobian entry is a number (the solver rejects such a point), and a whole fit stopped
    // before its first evaluation on the data ends with Error::Stopped instead of a report.
    // Without the request the same evaluation is finite everywhere.
    with_stoppable_kbs(|input, problem, x, flag, stop| {
        assert!(input.geo.len() > 2 * 1024, "several evaluation blocks");
        let open = problem.evaluate(x, Some(stop));
        assert!(open.residuals.iter().all(|v| v.is_finite()));
        assert!(open.jacobian.iter().all(|v| v.is_finite()));
        flag.store(true, SeqCst);
        let cut = problem.evaluate(x, Some(stop));
        assert!(cut.residuals.iter().all(|v| v.is_nan()));
        assert!(cut.jacobian.iter().all(|v| v.is_nan()));
        let mut config = config("kbs");
        config.lm.stop = Some(stop.clone());
        match fit(input, &config) {
            Err(crate::error::Error::Stopped(m)) => assert!(m.contains("nothing fitted"), "{m}"),
            other => panic!("expected Error::Stopped, got {:?}", other.map(|r| r.cost)),
        }
    });
}

/// A KBS problem on 4,800 synthetic samples (σ = 0.3, T = 2, scale = 1; several evaluation
/// blocks), the truth's solver variables x, and a stop request of a flag not yet set,
/// handed to `check`.
fn with_stoppable_kbs(
    check: impl FnOnce(
        &FitInput,
        &crate::fit::problem::FitProblem,
        &nalgebra::DVector<f64>,
        &std::sync::atomic::AtomicBool,
        &goniofit_lm::Stop,
    ),
) {
    use crate::fit::problem::{FitProblem, ParamLayout, ResidualKind};
    let input = synthetic(
        "kbs",
        &[0.3, 2.0, 1.0],
        Layout::hemisphere().with_grid(4, 30, 40).unwrap(),
        0.01,
        3,
        1.0,
    );
    let model = by_name("kbs", &ModelOptions::default()).unwrap();
    let layout = ParamLayout::new(model.as_ref(), &input.channel_names);
    let x = layout.to_x(&[0.3, 2.0, 1.0]);
    let problem =
        FitProblem::new(model.as_ref(), layout, &input, ResidualKind::Absolute, 1e-9).unwrap();
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let stop = goniofit_lm::Stop::new(None, Some(flag.clone()));
    check(&input, &problem, &x, &flag, &stop);
}

#[test]
fn a_jacobian_not_cached_is_not_evaluated_after_a_stop() {
    // The end of a stopped fit asks for the Jacobian at its best point: handed over from
    // the cache when the last evaluation was there, otherwise not evaluated once the stop
    // is requested (every entry NaN; the fit then reports its point with the uncertainties
    // "not computed"). Without the request it is evaluated, equal to the cached one.
    with_stoppable_kbs(|input, problem, x, flag, stop| {
        flag.store(true, SeqCst);
        let skipped = problem.jacobian_until(x, Some(stop));
        assert_eq!(skipped.shape(), (input.geo.len(), 3));
        assert!(skipped.iter().all(|v| v.is_nan()));
        flag.store(false, SeqCst);
        let evaluated = problem.jacobian_until(x, Some(stop));
        assert!(evaluated.iter().all(|v| v.is_finite()));
        // Cached by a residual evaluation at x: handed over even after the request (once).
        let _ = problem.residuals_until(x, None);
        flag.store(true, SeqCst);
        assert_eq!(problem.jacobian_until(x, Some(stop)), evaluated);
        assert!(problem
            .jacobian_until(x, Some(stop))
            .iter()
            .all(|v| v.is_nan()));
    });
}

/// Under a robust loss the pictures standardize the residuals as the report does (by the
/// robust objective), not by χ².
#[test]
fn pictures_standardize_residuals_as_the_report_does_under_a_robust_loss() {
    use crate::fit::problem::loss::{Loss, LossKind};
    let input = synthetic("lambert", &[0.3], Layout::hemisphere(), 0.05, 5, 1.0);
    let config = FitConfig {
        model: "lambert".into(),
        loss: Loss::new(LossKind::Cauchy, 0.002).unwrap(),
        ..FitConfig::default()
    };
    let r = fit(&input, &config).unwrap();
    let drawn = crate::plot::fit::with_plot_input(
        &config,
        &input,
        (&r.layout, &r.values, Some(&r.fitted), r.n_free),
        ("", &[]),
        None,
        |p| Ok(p.std_residuals.to_vec()),
    )
    .unwrap();
    assert_eq!(drawn, r.std_residuals);
    // The robust objective's s is not χ²'s here: the check above tells them apart.
    let n = r.residuals.len() as f64;
    let chi2: f64 = r.residuals.iter().map(|e| e * e).sum();
    let by_chi2 = r.residuals[0] / (chi2 / (n - 1.0)).sqrt();
    assert!((by_chi2 / r.std_residuals[0] - 1.0).abs() > 0.01);
}
