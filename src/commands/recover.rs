//! `goniofit recover`: synthetic recovery across regimes, with coverage of the reported
//! uncertainties.

use crate::harness::recover::{self, RecoverConfig};
use clap::Args;
use goniofit_lm::Stop;
use std::io::IsTerminal as _;
use std::time::Duration;

#[derive(Debug, Args)]
#[command(after_help = "\
Each scene draws σ, T, scale log-uniformly in one regime (smooth: σ/λ 0.003–0.015; \
intermediate: σ/λ 0.08–0.4; rough: σ/λ 4–10; grazing: intermediate roughness on the grazing \
layout, θi 70–89°), on a sparse or dense layout, adds seeded noise (relative or \
Poisson-like), and fits KBS from the default starting values, weighting by 1/σ_L². Only the \
quantities the fit reports as determined are scored: σ, T, scale (verdict full); T/σ and the \
amplitude s·(T/σ)² (rough); T and the amplitude s·σ² (smooth). Coverage is the fraction of \
truths inside ±2 reported standard errors (≈ 0.95 when calibrated).

Example:
  goniofit recover --scenes 30 --seed 11 --json > recover.json")]
pub(crate) struct RecoverArgs {
    /// Number of scenes (regimes in turn: smooth, intermediate, rough, grazing).
    #[arg(long, default_value_t = 30)]
    pub scenes: usize,
    /// Seed of the scene and noise draws (same seed, same scenes and data).
    #[arg(long, default_value_t = 11)]
    pub seed: u64,
    /// Noise level ε of every scene.
    #[arg(long, default_value_t = 0.01)]
    pub noise: f64,
    /// Wall-clock limit of each fit's solver, seconds.
    #[arg(long, default_value_t = 60.0)]
    pub timeout: f64,
    /// Fit only these scene ids (comma-separated, each below --scenes): the scenes are
    /// drawn as in the whole run, so a scene keeps its truth, layout and noise.
    #[arg(long, value_delimiter = ',', value_name = "ID,...")]
    pub only: Option<Vec<usize>>,
    /// Print one JSON object (summary per regime and every scene) instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Fresnel and shadowing factors on every scene's lobe (truth and fit): n drawn from
    /// 1.3 to 2.5 (κ from 0.5 to 5), and every twelfth scene on in-plane scans up to 40°,
    /// where n must come out not determined.
    #[command(flatten)]
    pub factors: super::args::FactorArgs,
}

/// Run `goniofit recover`.
pub(crate) fn run(args: RecoverArgs) -> anyhow::Result<u8> {
    crate::settings::scenes(crate::settings::Front::Cli, args.scenes)?;
    if !(args.noise.is_finite() && args.noise > 0.0) {
        return Err(crate::error::Error::Usage(format!(
            "--noise {} must be positive (coverage needs noise)",
            args.noise
        ))
        .into());
    }
    let fit_timeout = crate::settings::timeout(crate::settings::Front::Cli, Some(args.timeout))?;
    if let Some(bad) = args.only.iter().flatten().find(|&&id| id >= args.scenes) {
        return Err(crate::error::Error::Usage(format!(
            "--only {bad}: scene ids run from 0 to {} (--scenes {})",
            args.scenes - 1,
            args.scenes
        ))
        .into());
    }
    let config = RecoverConfig {
        scenes: args.scenes,
        seed: args.seed,
        noise: args.noise,
        fit_timeout,
        only: args.only.clone(),
        fresnel: args.factors.fresnel.into(),
        shadowing: args.factors.shadowing.into(),
    };
    let fitted = args.only.as_ref().map_or(args.scenes, Vec::len);
    let bar = progress_bar(fitted as u64, "fitting scenes");
    // One stop request for the whole run: a signal ends it (exit 130, nothing printed)
    // instead of being taken by the scenes being fitted as their own time limit.
    let stop = Stop::new(None, None);
    let report = recover::run(&config, &stop, &|_r| bar.inc(1));
    bar.finish_and_clear();
    let report = match report {
        Err(e @ crate::error::Error::Stopped(_)) => {
            eprintln!("goniofit: stopped: {e}");
            return Ok(SIGNALLED);
        }
        r => r?,
    };
    if args.json {
        crate::io::print_stdout(&format!("{}\n", serde_json::to_string_pretty(&report)?))?;
    } else {
        crate::io::print_stdout(&report.table())?;
    }
    Ok(0)
}

/// The exit code of a run ended by a signal (as an unhandled SIGINT's; docs/guide.md).
const SIGNALLED: u8 = 130;

/// A progress bar on stderr, hidden when stderr is not a terminal.
pub(crate) fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(bar_style(
        "{spinner} {msg} [{bar:30}] {pos}/{len} {elapsed} (eta {eta})",
    ));
    bar.set_message(what.to_string());
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// A bar style from an indicatif template (the default bar if the template is invalid).
pub(crate) fn bar_style(template: &str) -> indicatif::ProgressStyle {
    indicatif::ProgressStyle::with_template(template)
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> ")
}
