//! ALTA text data files (the BRDF library of Belcour et al., `data_io` "vertical segment"
//! files).
//!
//! A file is a header of `#` lines, then one sample per line:
//!
//! ```text
//! #DIM 3 1                          inputs, outputs per row
//! #PARAM_IN RUSIN_TH_TD_PD          the input parametrization (angles in radians)
//! #PARAM_OUT INV_STERADIAN          what the outputs are
//! #VS 2                             optional, one per output: its uncertainty columns
//! 0.1 0.2 0.3  0.52  0.50 0.54      inputs, outputs, then each output's VS columns
//! ```
//!
//! Inputs read ([`Input`]): `SPHERICAL_TL_PL_TV_PV` (θl, φl, θv, φv), `ISOTROPIC_TV_TL_DPHI`
//! (θv, θl, Δφ = φl − φv), `ISOTROPIC_TL_TV_PROJ_DPHI` (θl, θv cos Δφ, θv sin Δφ with the
//! light at azimuth 0), `RUSIN_TH_TD_PD` and `RUSIN_TH_PH_TD_PD` (Rusinkiewicz half and
//! difference angles; the difference vector is the view direction in the half vector's
//! frame, as ALTA's `half_to_cartesian`), and `CARTESIAN` (view x, y, z, then light x, y,
//! z). L is the light (goniofit's source, θi), V the view (θr); goniofit's azimuth is
//! φr = φv − φl − π, so that the mirror direction is φr = 0. An isotropic reading: the
//! azimuth of the half vector (φh) and a common rotation about the normal do not matter.
//!
//! Outputs: `INV_STERADIAN` (a BRDF, 1/sr) and `INV_STERADIAN_COSINE_FACTOR` (the BRDF times
//! the cosine of the output direction, ALTA's definition; goniofit divides by cos θv). One
//! output is one channel; three outputs are the channels `r`, `g`, `b` at the nominal
//! wavelengths of the RGL reader; other counts are channels `y1`, `y2`, … without a
//! wavelength.
//!
//! `#VS 2` gives each value's lower and upper bound: half their distance is read as the
//! value's standard uncertainty `sigma_L`; `#VS 1` gives a relative half-width dt (the value
//! lies in v(1 ± dt)): `sigma_L` = |v| dt. Without VS columns there is no `sigma_L`.
//!
//! Rows whose light or view direction is not above the horizon (z ≤ 1e-9; for
//! cosine-weighted values cos θv ≤ 1e-6) are not samples goniofit can fit and are skipped.
//! Everything else that is not as described is an [`Error::Input`] naming the line.

use super::{Dataset, ReadOptions};
use crate::error::{Error, Result};
use crate::geometry::{wrap_phi, Sample};
use std::f64::consts::PI;
use std::path::Path;

/// The input parametrizations goniofit reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Input {
    /// θl, φl, θv, φv.
    SphericalTlPlTvPv,
    /// θv, θl, Δφ = φl − φv.
    IsotropicTvTlDphi,
    /// θl, θv cos Δφ, θv sin Δφ (light at azimuth 0, Δφ the view's azimuth).
    IsotropicTlTvProjDphi,
    /// θh, θd, φd.
    RusinThTdPd,
    /// θh, φh, θd, φd.
    RusinThPhTdPd,
    /// Vx, Vy, Vz, Lx, Ly, Lz.
    Cartesian,
}

impl Input {
    /// The parametrization named `name` (ALTA's spelling).
    fn parse(name: &str) -> Option<Input> {
        Some(match name {
            "SPHERICAL_TL_PL_TV_PV" => Input::SphericalTlPlTvPv,
            "ISOTROPIC_TV_TL_DPHI" => Input::IsotropicTvTlDphi,
            "ISOTROPIC_TL_TV_PROJ_DPHI" => Input::IsotropicTlTvProjDphi,
            "RUSIN_TH_TD_PD" => Input::RusinThTdPd,
            "RUSIN_TH_PH_TD_PD" => Input::RusinThPhTdPd,
            "CARTESIAN" => Input::Cartesian,
            _ => return None,
        })
    }

    /// Input values per row.
    fn dimension(self) -> usize {
        match self {
            Input::IsotropicTvTlDphi | Input::IsotropicTlTvProjDphi | Input::RusinThTdPd => 3,
            Input::SphericalTlPlTvPv | Input::RusinThPhTdPd => 4,
            Input::Cartesian => 6,
        }
    }

    /// The view and light unit vectors of one row's inputs `x` (radians), or None when a
    /// CARTESIAN vector has no length.
    pub(crate) fn directions(self, x: &[f64]) -> Option<([f64; 3], [f64; 3])> {
        let sph = |t: f64, p: f64| [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
        Some(match self {
            Input::SphericalTlPlTvPv => (sph(x[2], x[3]), sph(x[0], x[1])),
            Input::IsotropicTvTlDphi => (sph(x[0], 0.0), sph(x[1], x[2])),
            Input::IsotropicTlTvProjDphi => {
                let t = x[1].hypot(x[2]);
                (sph(t, x[2].atan2(x[1])), sph(x[0], 0.0))
            }
            Input::RusinThTdPd => super::merl::directions(x[0], x[1], x[2]),
            Input::RusinThPhTdPd => super::merl::directions(x[0], x[2], x[3]),
            Input::Cartesian => (unit(&x[..3])?, unit(&x[3..6])?),
        })
    }
}

/// `v` scaled to length 1, or None for a zero or non-finite length.
fn unit(v: &[f64]) -> Option<[f64; 3]> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n.is_finite() && n > 0.0).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// The header: dimensions, parametrizations and VS column counts.
#[derive(Debug, Clone)]
struct Header {
    inputs: usize,
    outputs: usize,
    input: Option<Input>,
    cosine_weighted: bool,
    vs: Vec<usize>,
}

/// Whether a file's start is an ALTA data file: its first non-blank line is `#DIM`.
pub(crate) fn is_alta(head: &[u8]) -> bool {
    let head = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    head.split(|&b| b == b'\n')
        .map(|l| l.trim_ascii())
        .find(|l| !l.is_empty())
        .is_some_and(|l| {
            l.strip_prefix(b"#")
                .is_some_and(|r| r.trim_ascii_start().starts_with(b"DIM"))
        })
}

/// Parse ALTA data `text` (see the module docs) into a dataset of the channels
/// `opts.channel` selects (one output: no choice needed).
pub(crate) fn parse(path: &Path, text: &str, opts: &ReadOptions) -> Result<Dataset> {
    let mut header: Option<Header> = None;
    let mut pending: Vec<(usize, &str)> = Vec::new();
    let mut rows: Vec<(usize, Vec<f64>)> = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let t = raw.trim();
        if let Some(rest) = t.strip_prefix('#') {
            pending.push((line, rest.trim()));
            continue;
        }
        if t.is_empty() {
            continue;
        }
        let h = match &header {
            Some(h) => h,
            None => header.insert(read_header(path, &pending, line)?),
        };
        rows.push((line, read_row(path, line, t, h)?));
    }
    let h = match header {
        Some(h) => h,
        None => read_header(path, &pending, text.lines().count().max(1))?,
    };
    if rows.is_empty() {
        return Err(Error::file(
            path,
            "no data rows after the ALTA header".into(),
        ));
    }
    build(path, &h, &rows, opts)
}

/// The header from the `#` lines before the first data row (`first_row`).
fn read_header(path: &Path, lines: &[(usize, &str)], first_row: usize) -> Result<Header> {
    let mut h = Header {
        inputs: 0,
        outputs: 0,
        input: None,
        cosine_weighted: false,
        vs: Vec::new(),
    };
    let mut dim_seen = false;
    let mut out_seen = false;
    for &(line, text) in lines {
        let mut words = text.split_whitespace();
        let key = words.next().unwrap_or("");
        let arg = words.next().unwrap_or("");
        match key {
            "DIM" => {
                let n = |s: &str| s.parse::<usize>().ok().filter(|&v| (1..=64).contains(&v));
                let (Some(i), Some(o)) = (n(arg), words.next().and_then(n)) else {
                    return Err(Error::input(
                        path,
                        line,
                        "#DIM",
                        format!("'{text}': expected '#DIM inputs outputs' (whole numbers 1 to 64)"),
                    ));
                };
                (h.inputs, h.outputs, dim_seen) = (i, o, true);
            }
            "PARAM_IN" => {
                h.input = Some(Input::parse(arg).ok_or_else(|| {
                    Error::input(path, line, "#PARAM_IN", format!("'{arg}' is not read by goniofit (it reads SPHERICAL_TL_PL_TV_PV, ISOTROPIC_TV_TL_DPHI, ISOTROPIC_TL_TV_PROJ_DPHI, RUSIN_TH_TD_PD, RUSIN_TH_PH_TD_PD, CARTESIAN)"))
                })?);
            }
            "PARAM_OUT" => {
                h.cosine_weighted = match arg {
                    "INV_STERADIAN" => false,
                    "INV_STERADIAN_COSINE_FACTOR" => true,
                    _ => return Err(Error::input(path, line, "#PARAM_OUT", format!("'{arg}' is not read by goniofit (it reads INV_STERADIAN and INV_STERADIAN_COSINE_FACTOR)"))),
                };
                out_seen = true;
            }
            "VS" => match arg.parse::<usize>() {
                Ok(v @ 0..=2) => h.vs.push(v),
                _ => {
                    return Err(Error::input(
                        path,
                        line,
                        "#VS",
                        format!("'{arg}': expected 0, 1 or 2"),
                    ))
                }
            },
            _ => {}
        }
    }
    check_header(path, &h, dim_seen, out_seen, first_row)?;
    h.vs.resize(h.outputs, 0);
    Ok(h)
}

/// The header's parts agree with each other and with what goniofit needs.
fn check_header(path: &Path, h: &Header, dim: bool, out: bool, line: usize) -> Result<()> {
    let missing = |what: &str| {
        Error::input(
            path,
            line,
            what,
            format!("the ALTA header has no {what} line before the first data row"),
        )
    };
    if !dim {
        return Err(missing("#DIM"));
    }
    if !out {
        return Err(missing("#PARAM_OUT"));
    }
    let input = h.input.ok_or_else(|| missing("#PARAM_IN"))?;
    if input.dimension() != h.inputs {
        return Err(Error::input(
            path,
            line,
            "#DIM",
            format!(
                "{} inputs per row, but {input:?} has {}",
                h.inputs,
                input.dimension()
            ),
        ));
    }
    if h.vs.len() > h.outputs {
        return Err(Error::input(
            path,
            line,
            "#VS",
            format!("{} #VS lines for {} outputs", h.vs.len(), h.outputs),
        ));
    }
    Ok(())
}

/// One data row's numbers: inputs, outputs and VS columns, all finite.
fn read_row(path: &Path, line: usize, text: &str, h: &Header) -> Result<Vec<f64>> {
    let want = h.inputs + h.outputs + h.vs.iter().sum::<usize>();
    let mut v = Vec::with_capacity(want);
    for (k, word) in text.split_whitespace().enumerate() {
        let column = format!("column {}", k + 1);
        let x: f64 = word
            .parse()
            .map_err(|_| Error::input(path, line, &column, format!("'{word}' is not a number")))?;
        if !x.is_finite() {
            return Err(Error::input(
                path,
                line,
                &column,
                format!("'{word}' is not finite"),
            ));
        }
        v.push(x);
    }
    if v.len() != want {
        return Err(Error::input(
            path,
            line,
            "row",
            format!(
                "{} numbers; the header asks for {want} ({} inputs, {} outputs, {} VS columns)",
                v.len(),
                h.inputs,
                h.outputs,
                want - h.inputs - h.outputs
            ),
        ));
    }
    Ok(v)
}

/// The channel names of `outputs` values per row.
fn channel_names(outputs: usize) -> Vec<String> {
    if outputs == 3 {
        super::rgl::CHANNELS.iter().map(|s| s.to_string()).collect()
    } else {
        (1..=outputs).map(|k| format!("y{k}")).collect()
    }
}

/// The output indices `--channel` selects: any when there is one output.
fn select(path: &Path, outputs: usize, channel: Option<&str>) -> Result<Vec<usize>> {
    let names = channel_names(outputs);
    match channel.map(str::trim) {
        _ if outputs == 1 => Ok(vec![0]),
        Some(c) if c.eq_ignore_ascii_case("all") => Ok((0..outputs).collect()),
        Some(c) => names
            .iter()
            .position(|n| n.eq_ignore_ascii_case(c))
            .map(|k| vec![k])
            .ok_or_else(|| {
                Error::Usage(format!(
                    "{}: no channel '{c}' (channels: {}; or 'all')",
                    super::shown(path),
                    names.join(", ")
                ))
            }),
        None => Err(Error::Usage(format!(
            "{}: {outputs} channels; choose one with --channel NAME or all with --channel all (channels: {})",
            super::shown(path),
            names.join(", ")
        ))),
    }
}

/// The dataset of the selected outputs of `rows`.
fn build(
    path: &Path,
    h: &Header,
    rows: &[(usize, Vec<f64>)],
    opts: &ReadOptions,
) -> Result<Dataset> {
    let selected = select(path, h.outputs, opts.channel.as_deref())?;
    let names = channel_names(h.outputs);
    let with_sigma = selected.iter().all(|&c| h.vs[c] > 0);
    let mut ds = super::empty_brdf(path, selected.len() > 1, with_sigma, h.outputs == 3);
    for &c in &selected {
        let vs_at = h.inputs + h.outputs + h.vs[..c].iter().sum::<usize>();
        for (line, v) in rows {
            let input = h.input.expect("checked header");
            let Some((view, light)) = input.directions(&v[..h.inputs]) else {
                return Err(Error::input(
                    path,
                    *line,
                    "row",
                    "a CARTESIAN direction of length 0".into(),
                ));
            };
            if light[2] <= 1e-9 || view[2] <= 1e-9 || (h.cosine_weighted && view[2] <= 1e-6) {
                continue;
            }
            let scale = if h.cosine_weighted {
                1.0 / view[2]
            } else {
                1.0
            };
            let value = v[h.inputs + c] * scale;
            if !value.is_finite() {
                let m = format!("output {}: {value} after dividing by cos θv", c + 1);
                return Err(Error::input(path, *line, "row", m));
            }
            ds.samples.push(sample(view, light));
            ds.lines.push(*line);
            ds.value.as_mut().unwrap().push(value);
            if let Some(s) = ds.sigma_l.as_mut() {
                let cols = &v[vs_at..];
                let sigma = uncertainty(path, *line, (h.vs[c], c), cols, value, scale)?;
                s.push(sigma);
                ds.weight.as_mut().unwrap().push(sigma.powi(-2));
            }
            if let Some(w) = ds.wavelength.as_mut() {
                w.push(super::rgl::NOMINAL_NM[c]);
            }
            if let Some(ch) = ds.channel.as_mut() {
                ch.push(names[c].clone());
            }
        }
    }
    if ds.samples.is_empty() {
        return Err(Error::file(
            path,
            "no row has both directions above the horizon".into(),
        ));
    }
    Ok(ds)
}

/// The standard uncertainty of output `c`'s `value` (already divided by cos θv, `scale` the
/// factor) from its VS columns `cols` (`vs` of them): positive, with a finite weight 1/σ².
fn uncertainty(
    path: &Path,
    line: usize,
    (vs, c): (usize, usize),
    cols: &[f64],
    value: f64,
    scale: f64,
) -> Result<f64> {
    let sigma = match vs {
        2 => 0.5 * (cols[1] - cols[0]) * scale,
        _ => value.abs() * cols[0],
    };
    if sigma > 0.0 && sigma.is_finite() && sigma.powi(-2).is_finite() {
        return Ok(sigma);
    }
    let m = format!(
        "output {}: an uncertainty of {sigma} (the VS columns must give a positive width whose inverse square is finite)",
        c + 1
    );
    Err(Error::input(path, line, "#VS", m))
}

/// goniofit's angles of a view and a light direction (unit vectors above the horizon).
fn sample(view: [f64; 3], light: [f64; 3]) -> Sample {
    let polar = |d: [f64; 3]| d[0].hypot(d[1]).atan2(d[2]);
    Sample {
        theta_i: polar(light),
        theta_r: polar(view),
        phi_r: wrap_phi(view[1].atan2(view[0]) - light[1].atan2(light[0]) - PI),
    }
}
