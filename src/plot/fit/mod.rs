//! The pictures of a finished fit: measured vs fitted (linear and log), standardized
//! residuals over θr and φr, the fitted lobe as a polar plot, the fitted model as a
//! contour map over (θr, φr) with the sample positions, and the measured, fitted and
//! residual values on the projected hemisphere ([`super::hemisphere`]). [`fit_pictures`]
//! lists them, [`svg_pictures`] renders them in memory, [`write_fit_plots`] to files.
//!
//! In-plane views use the signed view angle: θr for |φr| ≤ 90° (the forward side), −θr for
//! |φr| > 90° (toward the source). A sample is in the plane of incidence when its φr is
//! within 1° of 0° or 180°; an incidence angle with no such sample shows its samples
//! nearest to the plane instead, with the fitted values at those samples as rings (no
//! curve: they are not along one line).

mod charts;
pub(crate) mod input;
mod of_fit;
mod polar;

pub(crate) use charts::{fit_chart, residual_chart};
use input::{busiest, check, eval_group, plane_curve_samples, wavelength_text};
pub(crate) use input::{checked_groups, group_label, quantity_desc};
pub(crate) use input::{plane_samples, signed_theta_r_deg, Channels, FitPlotInput, Group};
pub(crate) use of_fit::plot_fit;
#[cfg(test)]
pub(crate) use of_fit::with_plot_input;
pub use of_fit::{key_svg_of_outcome, png_of_outcome, svg_of_outcome};
pub(crate) use polar::{polar_plot, PolarPlot};

use super::contour::{linspace, Grid};
use super::figures::{ContourPlot, LEVELS};
use super::hemisphere::{hemisphere_plots, HemispherePlot, MAX_HEMISPHERES};
use super::xy::XyPlot;
use super::{fmt_num, write_png_svg, DrawError, Picture};
use crate::error::{Error, Result};
use crate::geometry::Sample;
use plotters::coord::Shift;
use plotters::prelude::*;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// The fitted model over (θr, φr) at the θi with the most samples, with that θi's sample
/// positions marked.
pub(crate) fn contour_plot(input: &FitPlotInput) -> Result<ContourPlot> {
    let gs = checked_groups(input)?;
    let geo = input.geo;
    let g = busiest(&gs);
    let xs = linspace(0.0, 90.0, 91);
    let ys = linspace(-180.0, 180.0, 181);
    let mut samples = Vec::with_capacity(xs.len() * ys.len());
    for &phi in &ys {
        for &tr in &xs {
            samples.push(Sample::from_degrees(g.theta_i.to_degrees(), tr, phi));
        }
    }
    let z = eval_group(input, g, &samples)?;
    let grid = Grid { xs, ys, z };
    let (_, hi) = grid.range();
    let hi = if hi.is_finite() { hi } else { 0.0 };
    let marks: Vec<(f64, f64)> = g
        .idx
        .iter()
        .map(|&k| (geo.theta_r[k].to_degrees(), geo.phi_r[k].to_degrees()))
        .collect();
    Ok(ContourPlot {
        title: format!(
            "{} — fitted model over (θr, φr), θi = {}°{}",
            input.title,
            fmt_num(g.theta_i.to_degrees()),
            input.channel_note(g.channel)
        ),
        subtitle: input.subtitle.clone(),
        x_desc: "θr, view angle from the surface normal (degrees)".into(),
        y_desc: "φr, azimuth from the plane of incidence (degrees)".into(),
        z_desc: format!("fitted {}", quantity_desc(geo.quantity)),
        size: (1000, 700),
        grid,
        levels: LEVELS.iter().map(|l| l * hi).collect(),
        levels_label: "contours at 0.05, 0.1, 0.2, …, 0.9 × max".into(),
        marks: vec![(
            format!(
                "samples at θi = {}° ({})",
                fmt_num(g.theta_i.to_degrees()),
                g.idx.len()
            ),
            marks,
            RGBColor(40, 110, 255),
        )],
    })
}

/// The names of the pictures [`fit_pictures`] draws (without an extension; files get
/// `.png` and `.svg`), in order: the six drawn for every fit, then up to
/// [`MAX_HEMISPHERES`] hemisphere pictures (`hemisphere_1` … in the order of θi).
pub(crate) const PICTURES: [&str; 6 + MAX_HEMISPHERES] = [
    "fit_linear",
    "fit_log",
    "residuals_theta",
    "residuals_phi",
    "polar",
    "contour",
    "hemisphere_1",
    "hemisphere_2",
    "hemisphere_3",
    "hemisphere_4",
];

/// One picture of a fit, of any kind.
pub(crate) enum FitPicture {
    /// An x–y chart: measured vs fitted over signed θr (linear or log y), or the
    /// standardized residuals over θr or φr.
    Xy(XyPlot),
    /// The fitted lobe in the plane of incidence, in polar form, at the θi with the most
    /// samples.
    Polar(PolarPlot),
    /// The fitted model's contours over (θr, φr) at that θi, the samples' positions marked.
    Contour(ContourPlot),
    /// Measured, fitted and residual discs on the projected hemisphere at one θi.
    Hemisphere(HemispherePlot),
}

impl Picture for FitPicture {
    fn size(&self) -> (u32, u32) {
        match self {
            FitPicture::Xy(p) => p.size(),
            FitPicture::Polar(p) => p.size(),
            FitPicture::Contour(p) => p.size(),
            FitPicture::Hemisphere(p) => p.size(),
        }
    }

    fn draw<DB: super::stroke::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        match self {
            FitPicture::Xy(p) => p.draw(root),
            FitPicture::Polar(p) => p.draw(root),
            FitPicture::Contour(p) => p.draw(root),
            FitPicture::Hemisphere(p) => p.draw(root),
        }
    }
}

/// The pictures of a fit, named as in [`PICTURES`]: fit_linear, fit_log (measured vs
/// fitted over signed θr for each θi: in-plane samples with the model's curve, or the
/// fitted values at the samples nearest the plane), residuals_theta and residuals_phi
/// (standardized residuals over θr and φr), polar (the fitted lobe in the plane of
/// incidence at the θi with most samples), contour (the fitted model over (θr, φr) at that
/// θi, sample positions marked), and hemisphere_k (measured, fitted and residuals on the
/// projected hemisphere, for up to [`MAX_HEMISPHERES`] incidence angles: those with the
/// most samples).
pub(crate) fn fit_pictures(input: &FitPlotInput) -> Result<Vec<(String, FitPicture)>> {
    check(input)?;
    let mut out = vec![
        (PICTURES[0], FitPicture::Xy(fit_chart(input, false)?)),
        (PICTURES[1], FitPicture::Xy(fit_chart(input, true)?)),
        (PICTURES[2], FitPicture::Xy(residual_chart(input, false)?)),
        (PICTURES[3], FitPicture::Xy(residual_chart(input, true)?)),
        (PICTURES[4], FitPicture::Polar(polar_plot(input)?)),
        (PICTURES[5], FitPicture::Contour(contour_plot(input)?)),
    ];
    for (k, h) in hemisphere_plots(input)?.into_iter().enumerate() {
        out.push((PICTURES[6 + k], FitPicture::Hemisphere(h)));
    }
    Ok(out
        .into_iter()
        .map(|(name, p)| (name.to_string(), p))
        .collect())
}

/// The pictures of [`fit_pictures`] rendered in memory as SVG documents: (name, SVG).
pub(crate) fn svg_pictures(input: &FitPlotInput) -> Result<Vec<(String, String)>> {
    fit_pictures(input)?
        .into_iter()
        .map(|(name, p)| Ok((name, super::svg_string(&p)?)))
        .collect()
}

/// The pictures of [`fit_pictures`] rendered in memory as PNG files' bytes: (name, PNG),
/// rendered side by side on the thread pool.
pub(crate) fn png_pictures(input: &FitPlotInput) -> Result<Vec<(String, Vec<u8>)>> {
    fit_pictures(input)?
        .into_par_iter()
        .map(|(name, p)| Ok((name, super::png_bytes(&p)?)))
        .collect()
}

/// Write the pictures of [`fit_pictures`] into `dir` (created if needed), each as PNG and
/// SVG, rendered side by side on the thread pool. Returns the written paths, in the order
/// of [`PICTURES`].
pub(crate) fn write_fit_plots(dir: &Path, input: &FitPlotInput) -> Result<Vec<PathBuf>> {
    let pictures = fit_pictures(input)?;
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let written: Vec<Vec<PathBuf>> = pictures
        .par_iter()
        .map(|(name, p)| write_png_svg(p, dir, name))
        .collect::<Result<_>>()?;
    Ok(written.into_iter().flatten().collect())
}
