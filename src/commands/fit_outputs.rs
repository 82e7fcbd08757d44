//! The files `goniofit fit` writes besides the report: `--residuals`, `--html` and the
//! `--plot` pictures, for one fit (one page, one folder of pictures) and for a batch (one
//! page with every fit, one folder per fit).

use super::fit_args::Command;
use crate::fit::dataset::Outcome;
use crate::fit::driver::{FitConfig, FitResult};
use crate::io::{self, Dataset};
use crate::plot::fit::{plot_fit, svg_of_outcome};
use crate::report::json::FitReport;
use crate::report::{self, RunInfo};
use std::path::{Path, PathBuf};

/// The outputs of a single fit: `--residuals`, `--html`, `--plot`.
/// A fit whose stop request cut the evaluation of its fitted values (see
/// [`FitResult::fitted_computed`]) writes neither the residuals file nor pictures, and
/// says so.
pub(crate) fn write_single_outputs(c: &Command, o: &Outcome, info: &RunInfo) -> anyhow::Result<()> {
    let args = &c.args;
    if !o.result.fitted_computed {
        if args.residuals.is_some() || args.plot.is_some() {
            eprintln!("goniofit: no residuals file and no pictures written: the fit was stopped before its fitted values were evaluated");
        }
    } else if let Some(path) = &args.residuals {
        write_residuals(path, &o.dataset, &o.result)?;
    }
    if let Some(path) = &args.html {
        let pictures = svg_pictures(c, o, info)?;
        let text = report::outcome::to_text(o, info);
        let comparison = report::outcome::comparison(o);
        let page = report::html::page(&o.result, info, &text, &comparison, &pictures);
        io::write_bytes(path, page.as_bytes())?;
        eprintln!(
            "goniofit: wrote {} (one page, {} pictures inline)",
            io::shown(path),
            pictures.len()
        );
    }
    if let Some(dir) = args.plot.as_ref().filter(|_| o.result.fitted_computed) {
        let written = draw_pictures(c, dir, o, info)?;
        eprintln!(
            "goniofit: wrote {} pictures to {}",
            written.len(),
            io::shown(dir)
        );
    }
    Ok(())
}

/// The outputs of a batch of fits: `--html` as one page (summary table, overview, one
/// section per fit), `--plot` as one folder per fit ([`fit_folder`]). Fits whose fitted
/// values were not evaluated get no pictures.
pub(crate) fn write_batch_outputs(
    c: &Command,
    outcomes: &[Outcome],
    infos: &[RunInfo],
    skipped: &[String],
) -> anyhow::Result<()> {
    let args = &c.args;
    if let Some(dir) = &args.plot {
        let mut count = 0;
        for (k, (o, info)) in outcomes.iter().zip(infos).enumerate() {
            if o.result.fitted_computed {
                let sub = dir.join(fit_folder(k, outcomes.len(), &o.label));
                count += draw_pictures(c, &sub, o, info)?.len();
            }
        }
        eprintln!(
            "goniofit: wrote {count} pictures to {} (one folder per fit)",
            io::shown(dir)
        );
    }
    let Some(path) = &args.html else {
        return Ok(());
    };
    let rows: Vec<report::summary::Row> = outcomes
        .iter()
        .zip(infos)
        .map(|(o, i)| report::summary::row(&o.label, &o.result, &i.setting.units))
        .collect();
    let mut sections = Vec::with_capacity(outcomes.len());
    for (o, info) in outcomes.iter().zip(infos) {
        sections.push(report::batch_html::FitSection {
            result: &o.result,
            info,
            text: report::outcome::to_text(o, info),
            comparison: report::outcome::comparison(o),
            pictures: svg_pictures(c, o, info)?,
        });
    }
    let (overview_x, overview) = overview(outcomes, infos)?;
    let command = infos.first().map_or(String::new(), |i| i.command.clone());
    let page = report::batch_html::batch_page(&report::batch_html::Batch {
        command: &command,
        rows: &rows,
        sections,
        overview,
        overview_x,
        not_fitted: skipped,
    });
    io::write_bytes(path, page.as_bytes())?;
    eprintln!(
        "goniofit: wrote {} (one page, {} fits)",
        io::shown(path),
        outcomes.len()
    );
    Ok(())
}

/// The folder of fit `k` (0-based) of `n` in a batch's `--plot` folder: its number
/// (zero-padded, so folders sort in the summary's order) and its label with every
/// character but letters, digits, `.`, `-` and `_` made `_` (the file's folders left out).
pub(crate) fn fit_folder(k: usize, n: usize, label: &str) -> String {
    let width = n.to_string().len();
    // "data/cornell/garnet_red.astm [550nm]" → "garnet_red.astm [550nm]".
    let (file, group) = match label.find(" [") {
        Some(i) => (&label[..i], &label[i..]),
        None => (label, ""),
    };
    let base = Path::new(file)
        .file_name()
        .map_or(file.to_string(), |f| f.to_string_lossy().into_owned());
    let mut name: String = format!("{base}{group}")
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    while name.contains("__") {
        name = name.replace("__", "_");
    }
    format!("{:0width$}_{}", k + 1, name.trim_matches('_'))
}

/// The small-multiples overview of a batch: T/σ and each free model parameter against the
/// wavelength (when every fit has one wavelength and they differ) or against the fit's
/// row in the summary table, for the fits that converged; returns what x is and the charts
/// as (title, SVG).
fn overview(
    outcomes: &[Outcome],
    infos: &[RunInfo],
) -> anyhow::Result<(String, Vec<(String, String)>)> {
    use crate::plot::overview::{overview_charts, Quantity};
    let wl: Vec<Option<f64>> = infos
        .iter()
        .map(|i| match i.setting.wavelength.values.as_slice() {
            [w] => Some(*w),
            _ => None,
        })
        .collect();
    let by_wavelength = wl.iter().all(Option::is_some)
        && wl.windows(2).any(|w| w[0] != w[1])
        && infos
            .windows(2)
            .all(|w| w[0].setting.units == w[1].setting.units);
    let (x_desc, xs): (String, Vec<f64>) = if by_wavelength {
        let unit = infos[0].setting.units.length_name();
        (
            format!("wavelength ({unit})"),
            wl.iter().map(|w| w.unwrap_or(f64::NAN)).collect(),
        )
    } else {
        (
            "the fit's row (#) in the summary table".into(),
            (1..=outcomes.len()).map(|k| k as f64).collect(),
        )
    };
    let mut quantities: Vec<Quantity> = Vec::new();
    let mut add = |name: &str, unit: String, x: f64, v: f64, det: bool| match quantities
        .iter_mut()
        .find(|q| q.name == name)
    {
        Some(q) => q.points.push((x, v, det)),
        None => quantities.push(Quantity {
            name: name.to_string(),
            unit,
            points: vec![(x, v, det)],
        }),
    };
    // A fit that did not converge has no usable values (a degenerate one's can be far off
    // any scale): it is left out, as the page's caption says.
    for ((o, info), &x) in outcomes.iter().zip(infos).zip(&xs) {
        let r = &o.result;
        if !r.converged() {
            continue;
        }
        if let Some(d) = r.derived.iter().find(|d| d.name == "T/sigma") {
            add("T/σ", String::new(), x, d.value, d.determined);
        }
        for p in r.params.iter().filter(|p| !p.fixed) {
            let unit = info.setting.units.of_param(&p.name);
            add(
                &p.name.replace("sigma", "σ"),
                unit,
                x,
                p.value,
                p.determined,
            );
        }
    }
    let mut out = Vec::new();
    for chart in overview_charts(&x_desc, &quantities) {
        out.push((chart.title.clone(), crate::plot::svg_string(&chart)?));
    }
    Ok((x_desc, out))
}

/// The pictures of one outcome in memory as (name, SVG), none when its fitted values were
/// not evaluated.
fn svg_pictures(c: &Command, o: &Outcome, info: &RunInfo) -> anyhow::Result<Vec<(String, String)>> {
    let config = outcome_config(c, o);
    let report = FitReport::of(&o.result, info);
    let (line, undetermined) = (report.status_line(), report.undetermined());
    let unit = c.settings.wavelength_unit(&o.dataset);
    Ok(svg_of_outcome(
        &config,
        o,
        (&line, &undetermined),
        unit.as_deref(),
    )?)
}

/// The fit configuration of an outcome's chosen model, with its factors (an `auto`
/// choice's are not among the settings).
fn outcome_config(c: &Command, o: &Outcome) -> FitConfig {
    let uncertainties = o.dataset.sigma_l.is_some();
    c.settings.fit_config(&o.result.full_model(), uncertainties)
}

/// Draw the pictures of one outcome into `dir` (PNG and SVG; see [`plot_fit`]), with the
/// status line of its report; returns the files written.
fn draw_pictures(
    c: &Command,
    dir: &Path,
    o: &Outcome,
    info: &RunInfo,
) -> anyhow::Result<Vec<PathBuf>> {
    let config = outcome_config(c, o);
    let report = FitReport::of(&o.result, info);
    Ok(plot_fit(
        dir,
        &config,
        &o.input,
        (
            &o.result.layout,
            &o.result.values,
            Some(&o.result.fitted),
            o.result.n_free,
        ),
        (&report.status_line(), &report.undetermined()),
        c.settings.wavelength_unit(&o.dataset).as_deref(),
    )?)
}

/// Write the input rows with L_fit, residual, std_residual and mode (atomically).
fn write_residuals(path: &Path, ds: &Dataset, r: &FitResult) -> anyhow::Result<()> {
    let mut headers = ds.headers.clone();
    headers.extend(["L_fit", "residual", "std_residual", "mode"].map(String::from));
    let rows: Vec<Vec<String>> = ds
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut row = row.clone();
            row.push(format!("{:e}", r.fitted[i]));
            row.push(format!("{:e}", r.residuals[i]));
            row.push(format!("{:e}", r.std_residuals[i]));
            row.push(r.sample_modes[i].name().to_string());
            row
        })
        .collect();
    io::write_csv(path, &headers, &rows)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_batch_fit_folder_is_numbered_and_named_by_file_and_group() {
        assert_eq!(
            fit_folder(4, 31, "data/cornell/garnet_red.astm [550nm]"),
            "05_garnet_red.astm_550nm"
        );
        assert_eq!(fit_folder(0, 9, "a b/c.csv"), "1_c.csv");
        assert_eq!(fit_folder(60, 61, "x.csv [7]"), "61_x.csv_7");
    }
}
