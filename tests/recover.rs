//! A seeded small recovery run: coverage of the reported uncertainties in a sensible band,
//! and small recovery errors in the quantities the fits say the data determines.

use goniofit::recover::{self, RecoverConfig, Regime};

#[test]
fn seeded_recovery_is_calibrated_and_accurate() {
    let config = RecoverConfig {
        scenes: 16,
        seed: 11,
        ..RecoverConfig::default()
    };
    let report = recover::run(&config, &|_| {});
    assert_eq!(report.scenes, 16);
    assert_eq!(report.errors, 0, "{}", report.table());
    assert!(report.converged >= 15, "{}", report.table());
    // Every regime is represented and scored.
    for regime in Regime::ALL {
        let r = report
            .regimes
            .iter()
            .find(|r| r.regime == regime)
            .unwrap_or_else(|| panic!("no {regime:?} scenes"));
        assert!(!r.quantities.is_empty());
    }
    // ±2 se should hold ~95 % of truths: with ~60 correlated checks, accept 0.8..=1.
    assert!(
        report.n_with_stderr >= 40,
        "only {} scored truths",
        report.n_with_stderr
    );
    assert!(
        (0.8..=1.0).contains(&report.coverage),
        "coverage {}\n{}",
        report.coverage,
        report.table()
    );
    // 1 % noise on hundreds of samples: determined quantities within a few percent
    // (median well below 1 %). Quantities scored in fewer than 3 scenes have no meaningful
    // median (seed 11 scene 13 is a fit that ran off to σ ~ 1e53 and was called rough: see
    // the lead's note on issue #6).
    for r in &report.regimes {
        for q in r.quantities.iter().filter(|q| q.n >= 3) {
            assert!(
                q.median_rel_error < 0.01,
                "{:?} {}: median error {}",
                r.regime,
                q.name,
                q.median_rel_error
            );
        }
    }
    // Fits that determine everything are accurate to a few percent.
    for res in &report.results {
        if res.verdict == Some(goniofit::fit::driver::Verdict::Full) {
            for c in &res.checks {
                assert!(
                    c.rel_error < 0.05,
                    "scene {} {}: {} vs {}",
                    res.scene.id,
                    c.name,
                    c.value,
                    c.truth
                );
            }
        }
    }
    // Same seed, same scenes.
    let again = recover::draw_scenes(16, 11, 0.01);
    for (a, b) in again.iter().zip(&report.results) {
        assert_eq!(a.sigma, b.scene.sigma);
        assert_eq!(a.noise.seed, b.scene.noise.seed);
    }
}

#[test]
fn scoring_follows_the_verdict() {
    let scenes = recover::draw_scenes(4, 11, 0.01);
    for s in &scenes {
        let r = recover::run_scene(s, &RecoverConfig::default());
        let names: Vec<&str> = r.checks.iter().map(|c| c.name.as_str()).collect();
        match r.verdict.unwrap() {
            goniofit::fit::driver::Verdict::Full => {
                assert_eq!(names, ["sigma", "T", "scale", "T/sigma"])
            }
            goniofit::fit::driver::Verdict::Rough => assert_eq!(names, ["T/sigma", "amplitude"]),
            goniofit::fit::driver::Verdict::Smooth => assert_eq!(names, ["T", "amplitude"]),
            goniofit::fit::driver::Verdict::Partial => {}
        }
        for c in &r.checks {
            assert!(c.value.is_finite() && c.truth > 0.0);
        }
    }
}
