//! The pictures of a finished fit: the picture input built from the fit's problem (fitted
//! values, standardized residuals, per-channel parameters), titled with the status line
//! its report gives. Used by `fit --plot`/`--html`, `goniofit plot` and Python's
//! `FitResult.figures()`.

use crate::error::Result;
use crate::fit::driver::{self, FitConfig, FitInput};
use std::path::{Path, PathBuf};

/// A fit to draw: its layout, parameter values, fitted values when the fit has them (else
/// they are evaluated here), and its number of free parameters (the standardised
/// residuals' degrees of freedom are the samples less these).
pub(super) type FitToDraw<'a> = (
    &'a crate::fit::problem::ParamLayout,
    &'a [f64],
    Option<&'a [f64]>,
    usize,
);

/// Draw the pictures of a fit (see [`FitToDraw`]) into `dir` as PNG and SVG (see
/// [`with_plot_input`] for what `status` and `unit` are); returns the files written.
pub(crate) fn plot_fit(
    dir: &Path,
    config: &FitConfig,
    input: &FitInput,
    fit: FitToDraw,
    status: (&str, &[String]),
    unit: Option<&str>,
) -> Result<Vec<PathBuf>> {
    with_plot_input(config, input, fit, status, unit, |p| {
        crate::plot::fit::write_fit_plots(dir, p)
    })
}

/// Call `draw` with the picture input of a fit at parameter values `fit.1` (layout
/// `fit.0`; `fit.2` its fitted values when the fit has them, else they are evaluated
/// here), with `status.0` (the report's status line) under the titles, the parameters of
/// `status.1` (not determined by the data) named in the title without a value, and λ in
/// `unit`. A joint fit draws every channel with its own parameters (the polar and contour
/// maps: the busiest θi's channel, named in their titles).
pub(crate) fn with_plot_input<T>(
    config: &FitConfig,
    input: &FitInput,
    (layout, values, fitted, n_free): FitToDraw,
    status: (&str, &[String]),
    unit: Option<&str>,
    draw: impl FnOnce(&crate::plot::fit::FitPlotInput) -> Result<T>,
) -> Result<T> {
    use crate::fit::problem::FitProblem;
    let model = crate::model::by_name(&config.model, &config.model_opts)?;
    let floor = driver::residual_floor(config, &input.y);
    let problem = FitProblem::new(
        model.as_ref(),
        layout.clone(),
        input,
        config.residual,
        floor,
    )?
    .with_loss(config.loss);
    let fitted = match fitted.filter(|f| f.len() == input.y.len()) {
        Some(f) => f.to_vec(),
        None => problem.model_values(values, false).0,
    };
    let residuals = problem.raw_residuals(&fitted);
    let std_residuals = driver::standardized_residuals(
        &problem,
        &residuals,
        n_free,
        config.weights_are_uncertainties,
    );
    let n_channels = layout.index.len().max(1);
    let params: Vec<Vec<f64>> = (0..n_channels)
        .map(|c| layout.model_params(values, c))
        .collect();
    let joint = n_channels > 1;
    let plot_input = crate::plot::fit::FitPlotInput {
        title: plot_title(model.as_ref(), layout, &params[0], status.1),
        subtitle: match factors_words(&config.model_opts) {
            Some(words) => format!("{words}; {}", status.0),
            None => status.0.to_string(),
        },
        model: model.as_ref(),
        params: &params[0],
        geo: &input.geo,
        measured: &input.y,
        fitted: &fitted,
        std_residuals: &std_residuals,
        wavelength_unit: unit,
        channels: crate::plot::fit::Channels {
            of_sample: match input.channel.as_slice() {
                Some(c) if joint => c,
                _ => &[],
            },
            params: if joint { &params } else { &[] },
            names: &layout.channel_names,
        },
    };
    draw(&plot_input)
}

/// The factors on the KBS lobe in words ("KBS lobe × dielectric Fresnel factor × Smith
/// shadowing"), none for the paper's model.
fn factors_words(opts: &crate::model::ModelOptions) -> Option<String> {
    use crate::model::{fresnel::Fresnel, shadowing::Shadowing};
    if !opts.has_factors() {
        return None;
    }
    let mut words = String::from("KBS lobe");
    if opts.fresnel != Fresnel::None {
        words += &format!(" × {} Fresnel factor", opts.fresnel.name());
    }
    if opts.shadowing != Shadowing::None {
        let name = opts.shadowing.name().replace("smith", "Smith");
        words += &format!(" × {name} shadowing");
    }
    Some(words)
}

/// "kbs: sigma=… T=… scale=…"; for a joint fit only the shared parameters, and which are
/// per channel. A parameter in `undetermined` gets no value: "(σ, T not determined)".
fn plot_title(
    model: &dyn crate::model::Model,
    layout: &crate::fit::problem::ParamLayout,
    params: &[f64],
    undetermined: &[String],
) -> String {
    let n_channels = layout.index.len();
    let per_channel = |j: usize| {
        n_channels > 1
            && layout
                .params
                .iter()
                .any(|p| p.spec == j && p.channel.is_some())
    };
    let mut title = format!("{}:", model.name());
    let mut own = Vec::new();
    let mut loose = Vec::new();
    for (j, (spec, v)) in model.params().iter().zip(params).enumerate() {
        if per_channel(j) {
            own.push(spec.name.to_string());
        } else if undetermined.iter().any(|u| u == spec.name) {
            loose.push(spec.name.replace("sigma", "σ"));
        } else {
            title += &format!(" {}={}", spec.name, crate::plot::fmt_num(*v));
        }
    }
    if !loose.is_empty() {
        title += &format!(" ({} not determined)", loose.join(", "));
    }
    if !own.is_empty() {
        title += &format!(
            " (joint fit of {n_channels} channels; {} per channel)",
            own.join(", ")
        );
    }
    title
}

/// The pictures of a dataset's fit `o` in memory as (name, SVG document), titled with
/// `status` (the report's status line and the parameters the data does not determine:
/// `FitReport::status_line` and `FitReport::undetermined` of the report); none when the
/// fit was stopped before its fitted values were evaluated. `unit`: the unit of λ.
pub fn svg_of_outcome(
    config: &FitConfig,
    o: &crate::fit::dataset::Outcome,
    status: (&str, &[String]),
    unit: Option<&str>,
) -> Result<Vec<(String, String)>> {
    of_outcome(config, o, status, unit, crate::plot::fit::svg_pictures)
}

/// The key picture of `o` alone (see [`svg_of_outcome`]): measured and fitted values on a
/// log scale (`fit_log`), as an SVG document; None when the fitted values were not
/// evaluated.
pub fn key_svg_of_outcome(
    config: &FitConfig,
    o: &crate::fit::dataset::Outcome,
    status: (&str, &[String]),
    unit: Option<&str>,
) -> Result<Option<String>> {
    let svg = of_outcome(config, o, status, unit, |input| {
        super::check(input)?;
        let chart = super::fit_chart(input, true)?;
        Ok(vec![(String::new(), crate::plot::svg_string(&chart)?)])
    })?;
    Ok(svg.into_iter().next().map(|(_, svg)| svg))
}

/// As [`svg_of_outcome`], each picture as the bytes of a PNG file.
pub fn png_of_outcome(
    config: &FitConfig,
    o: &crate::fit::dataset::Outcome,
    status: (&str, &[String]),
    unit: Option<&str>,
) -> Result<Vec<(String, Vec<u8>)>> {
    of_outcome(config, o, status, unit, crate::plot::fit::png_pictures)
}

/// The pictures of `o` drawn by `draw` (see [`svg_of_outcome`]).
fn of_outcome<T>(
    config: &FitConfig,
    o: &crate::fit::dataset::Outcome,
    status: (&str, &[String]),
    unit: Option<&str>,
    draw: impl FnOnce(&crate::plot::fit::FitPlotInput) -> Result<Vec<(String, T)>>,
) -> Result<Vec<(String, T)>> {
    if !o.result.fitted_computed {
        return Ok(Vec::new());
    }
    with_plot_input(
        config,
        &o.input,
        (
            &o.result.layout,
            &o.result.values,
            Some(&o.result.fitted),
            o.result.n_free,
        ),
        status,
        unit,
        draw,
    )
}
