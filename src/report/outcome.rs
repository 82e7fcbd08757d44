//! The reports of one dataset's [`Outcome`]: the chosen fit's report, with the model
//! comparison when several candidates ran (`auto`), and in JSON the `replay` block that
//! `goniofit plot` redraws from. The CLI and the Python package both print these.

use super::{json, text, RunInfo};
use crate::fit::dataset::Outcome;
use crate::fit::driver::FitResult;
use crate::settings::{Front, Settings};

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
        } else if r.termination == goniofit_lm::Termination::Degenerate {
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
/// (`replay`) and, for several candidates, the `comparison`. `settings` are the fit's
/// settings, which `goniofit plot` rebuilds the fit from.
pub fn report(o: &Outcome, info: &RunInfo, settings: &Settings) -> json::FitReport {
    let mut report = json::FitReport::of(&o.result, info);
    report.replay = Some(replay(&o.result, settings));
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

/// What `goniofit plot` needs to redraw fit `r` ([`json::Replay`]), `settings` being the
/// fit's settings.
pub(crate) fn replay(r: &FitResult, settings: &Settings) -> json::Replay {
    json::Replay {
        settings: settings.clone(),
        model: r.model.clone(),
        factors: r.factors.trim().to_string(),
        names: r.layout.params.iter().map(|p| p.name.clone()).collect(),
        values: r.values.clone(),
        n_free: r.n_free,
    }
}

/// The whole setting of one dataset's fit for the report: the `settings` as `front` gave
/// them, the input `file` (default for arrays), the floor and how many values it raised,
/// the weights as transformed for the residual, the distinct wavelengths of the samples,
/// where the quantity and λ came from, and the units.
pub fn setting(
    ds: &crate::io::Dataset,
    input: &crate::fit::driver::FitInput,
    (settings, front): (&Settings, Front),
    file: super::setting::InputInfo,
) -> super::Setting {
    use crate::fit::problem::loss::LossKind;
    use crate::fit::problem::weights::{floor_raised, residual_weights};
    use crate::fit::problem::ResidualKind;
    let residual = settings.residual;
    let floor = crate::fit::dataset::floor_for(settings.floor, &input.y);
    let (_, weights) = residual_weights(
        ds.weight.as_deref().filter(|_| ds.sigma_l.is_none()),
        ds.sigma_l.as_deref(),
        &input.y,
        residual,
        floor,
    );
    let wavelength_source = match (settings.wavelength, &ds.wavelength) {
        (Some(_), _) => front.source("wavelength"),
        (None, Some(_)) => ds.wavelength_origin.unwrap_or("wavelength column").into(),
        (None, None) => "none".to_string(),
    };
    let mut values: Vec<f64> = Vec::new();
    if wavelength_source != "none" {
        for l in input.geo.wavelength.iter() {
            if !values.contains(&l) {
                values.push(l);
            }
        }
    }
    let unit = settings.wavelength_unit(ds);
    let (quantity, quantity_source) = settings.quantity_for(ds, front);
    let linear = settings.loss == LossKind::Linear;
    super::Setting {
        input: file,
        wavelength: super::setting::WavelengthInfo {
            values,
            unit: unit.clone(),
            source: wavelength_source,
        },
        channel: settings.channel.clone(),
        quantity,
        quantity_source,
        residual,
        floor: super::setting::FloorInfo {
            value: floor,
            raised: floor_raised(&input.y, residual, floor),
            used: residual != ResidualKind::Absolute,
        },
        weights,
        loss: settings.loss.name().into(),
        f_scale: (!linear).then_some(settings.f_scale),
        absolute_sigma: settings.absolute_sigma,
        units: super::Units {
            length: unit,
            quantity,
            radiance: None,
        },
    }
}
