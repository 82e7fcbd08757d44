//! The reports of one dataset's [`Outcome`]: the chosen fit's report, with the model
//! comparison when several candidates ran (`auto`), and in JSON the `replay` block that
//! `goniofit plot` redraws from. The CLI and the Python package both print these.

use super::{json, text, RunInfo};
use crate::fit::dataset::Outcome;
use crate::fit::driver::FitResult;

/// One candidate of a model comparison (`--model auto`), as every report shows it.
pub struct Candidate<'a> {
    /// The candidate's fit, as a summary (the per-sample vectors of candidates are moved out).
    pub result: &'a FitResult,
    /// Its BIC minus the chosen fit's.
    pub delta_bic: f64,
    /// Whether it is the reported fit: the converged candidate of least BIC (of least BIC
    /// overall when none converged).
    pub chosen: bool,
    /// A usable fit within ΔBIC < 2 of the chosen one (`fit::dataset::BIC_TIE`).
    pub tie: bool,
}

impl Candidate<'_> {
    /// What became of the fit: `converged`, `degenerate (not usable)` or `not converged
    /// (TERMINATION; not usable)`.
    pub fn state(&self) -> String {
        let r = self.result;
        if r.converged() {
            "converged".into()
        } else if r.termination == crate::lm::Termination::Degenerate {
            "degenerate (not usable)".into()
        } else {
            format!(
                "not converged ({}; not usable)",
                json::termination_name(r.termination)
            )
        }
    }

    /// Its part in the choice: `chosen`, `tie` or empty.
    pub fn role(&self) -> &'static str {
        match (self.chosen, self.tie) {
            (true, _) => "chosen",
            (false, true) => "tie",
            _ => "",
        }
    }
}

/// The outcome's candidates with their ΔBIC to the chosen fit and the ties
/// (`crate::fit::dataset::tied_with`); empty when only one model was fitted.
pub fn comparison(o: &Outcome) -> Vec<Candidate<'_>> {
    if o.candidates.len() < 2 {
        return Vec::new();
    }
    let best = o
        .candidates
        .iter()
        .position(|r| r.full_model() == o.result.full_model())
        .unwrap_or(0);
    let tied: Vec<String> = crate::fit::dataset::tied_with(&o.candidates, best)
        .iter()
        .map(|(r, _)| r.full_model())
        .collect();
    o.candidates
        .iter()
        .enumerate()
        .map(|(i, r)| Candidate {
            result: r,
            delta_bic: r.bic - o.candidates[best].bic,
            chosen: i == best,
            tie: tied.contains(&r.full_model()),
        })
        .collect()
}

/// The outcome's report: [`json::FitReport::of`] the chosen fit, with its `replay` block
/// and, for several candidates, the `comparison`. `args` are the fit's
/// command-line arguments (without the program name) that `goniofit plot` parses again.
pub fn report(o: &Outcome, info: &RunInfo, args: &[String]) -> json::FitReport {
    let mut report = json::FitReport::of(&o.result, info);
    report.replay = Some(replay(&o.result, args));
    let rows = comparison(o);
    if !rows.is_empty() {
        report.comparison = Some(rows.iter().map(comparison_row).collect());
    }
    report
}

/// A candidate as the report's comparison lists it.
fn comparison_row(c: &Candidate) -> json::ComparisonRow {
    let r = c.result;
    json::ComparisonRow {
        model: r.full_model(),
        bic: json::num(r.bic),
        aic: json::num(r.aic),
        cost: json::num(r.cost),
        converged: r.converged(),
        termination: json::termination_name(r.termination),
        delta_bic: json::num(c.delta_bic),
        chosen: c.chosen,
        tie: c.tie,
    }
}

/// The outcome's report as text: the model comparison (the lowest BIC among the usable
/// fits wins; ΔBIC < 2 is a tie) when several candidates ran, each candidate marked with
/// what became of its fit, then `text::render` of the chosen fit.
pub fn to_text(o: &Outcome, info: &RunInfo) -> String {
    let mut s = String::new();
    let rows = comparison(o);
    if !rows.is_empty() {
        s += "[[Model comparison]] (lowest BIC among the usable fits wins; ΔBIC < 2 is a tie)\n";
        let width = rows
            .iter()
            .map(|c| c.result.full_model().chars().count())
            .fold(17, usize::max);
        for c in &rows {
            let r = c.result;
            let role = match c.role() {
                "" => String::new(),
                role => format!("  <- {role}"),
            };
            s += &format!(
                "    {:<width$} BIC = {:>14.4}  AIC = {:>14.4}  cost = {:.6e}  ΔBIC = {:>10.2}  {}{role}\n",
                r.full_model(),
                r.bic,
                r.aic,
                r.cost,
                c.delta_bic,
                c.state(),
            );
        }
    }
    s + &text::render(&o.result, info)
}

/// What `goniofit plot` needs to redraw fit `r` ([`json::Replay`]), `args` being the
/// fit's command-line arguments.
pub(crate) fn replay(r: &FitResult, args: &[String]) -> json::Replay {
    json::Replay {
        args: args.to_vec(),
        model: r.model.clone(),
        factors: r.factors.trim().to_string(),
        names: r.layout.params.iter().map(|p| p.name.clone()).collect(),
        values: r.values.clone(),
        n_free: r.n_free,
    }
}

/// Where a fit's setting came from, beside the dataset and the fit input: what the caller
/// (the CLI's arguments, the Python keywords) decided.
#[derive(Debug, Clone, Default)]
pub struct SettingSource {
    /// The input file (absolute path, checksum), or empty for arrays.
    pub file: super::setting::InputInfo,
    /// `--channel` as given.
    pub channel: Option<String>,
    /// The quantity fitted and where it came from (`--quantity`, `stated by the file`,
    /// `default`).
    pub quantity: crate::geometry::Quantity,
    /// Where the quantity came from (`--quantity`, `stated by the file`, `default`).
    pub quantity_source: String,
    /// The residual kind asked for: absolute, relative or log.
    pub residual: crate::fit::problem::ResidualKind,
    /// The floor asked for (None: 1e-6 × max |L|).
    pub floor: Option<f64>,
    /// The unit of λ and where λ came from (`--wavelength`, `channel name`, `wavelength
    /// column`, `none`).
    pub wavelength_unit: Option<String>,
    /// Where λ came from (`--wavelength`, `channel name`, `wavelength column`, `none`).
    pub wavelength_source: String,
    /// The robust loss (`linear` = plain least squares; scipy's names) and its scale C
    /// (None for linear).
    pub loss: String,
    /// The loss scale C (`--f-scale`), in the unit of the weighted residual; None for linear.
    pub f_scale: Option<f64>,
    /// Whether standard errors come from the stated uncertainties as they are (scipy's
    /// `absolute_sigma=True`) instead of being rescaled by the residual scatter.
    pub absolute_sigma: bool,
}

/// The whole setting of one dataset's fit for the report: the caller's `source`, the
/// floor and how many values it raised, the weights as transformed for the residual, the
/// distinct wavelengths of the samples, and the units.
pub fn setting(
    ds: &crate::io::Dataset,
    input: &crate::fit::driver::FitInput,
    source: &SettingSource,
) -> super::Setting {
    use crate::fit::problem::weights::{floor_raised, residual_weights};
    use crate::fit::problem::ResidualKind;
    let residual = source.residual;
    let floor = crate::fit::dataset::floor_for(source.floor, &input.y);
    let (_, weights) = residual_weights(
        ds.weight.as_deref().filter(|_| ds.sigma_l.is_none()),
        ds.sigma_l.as_deref(),
        &input.y,
        residual,
        floor,
    );
    let mut values: Vec<f64> = Vec::new();
    if source.wavelength_source != "none" {
        for l in input.geo.wavelength.iter() {
            if !values.contains(&l) {
                values.push(l);
            }
        }
    }
    let unit = source.wavelength_unit.clone();
    super::Setting {
        input: source.file.clone(),
        wavelength: super::setting::WavelengthInfo {
            values,
            unit: unit.clone(),
            source: source.wavelength_source.clone(),
        },
        channel: source.channel.clone(),
        quantity: source.quantity,
        quantity_source: source.quantity_source.clone(),
        residual,
        floor: super::setting::FloorInfo {
            value: floor,
            raised: floor_raised(&input.y, residual, floor),
            used: residual != ResidualKind::Absolute,
        },
        weights,
        loss: source.loss.clone(),
        f_scale: source.f_scale,
        absolute_sigma: source.absolute_sigma,
        units: super::Units {
            length: unit,
            quantity: source.quantity,
            radiance: None,
        },
    }
}
