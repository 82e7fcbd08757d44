//! Isotropic RGB BRDFs of the EPFL Realistic Graphics Lab database (`.bsdf`, Dupuy & Jakob
//! 2018, "An Adaptive Parameterization for Efficient Material Acquisition and Rendering").
//!
//! The file is a "tensor_file" ([`tensor`]) with the fields `theta_i` (incidence
//! elevations, rad), `phi_i` (length 1 for an isotropic file), `ndf` and `sigma` (the
//! microfacet normal distribution D and the projected area σ, as bilinear tables over
//! (u_θ, u_φ)), `vndf` (the visible-normal distribution per θi: the warp, [`warp`]) and
//! `rgb` (per θi and channel, values on a regular grid of the warp's *input* square).
//!
//! Coordinates: a facet normal ωm at elevation θm and azimuth φm (relative to the
//! incidence azimuth) is u = (√(2θm/π), (φm + π)/2π). A grid point s of the rgb table maps
//! through the VNDF warp at θi to u, hence ωm, and the outgoing direction is ωi reflected
//! about ωm. The stored number there is not a BRDF: the reference loader's `eval` returns
//! `rgb(s) · D(u) / (4 σ(θi))`, which is f_r · cos θo; goniofit divides by cos θo.
//!
//! [`RglBrdf::samples`] gives the measured points: for every stored θi with cos θi > 10⁻⁶
//! (the 90° incidence is grazing: the loader gives 0 there) and every grid point whose
//! outgoing direction is above the horizon, (θi, θr, φr) in goniofit's convention (ωi at
//! azimuth 0, φr = φo − π so that the mirror direction is φr = 0) and f_r per channel.
//! Negative values (the reconstruction's out-of-gamut ringing) are kept as measured; the
//! loader clips them to 0 for rendering. [`RglBrdf::eval`] is the loader's interpolation
//! at any pair of directions.
//!
//! Channels are `r`, `g`, `b` (sRGB); their nominal wavelengths are [`NOMINAL_NM`], used
//! when no `--wavelength` is given. Anisotropic (`phi_i` longer than 1), spectral
//! (`spectra` instead of `rgb`) and malformed files are refused with the field, its byte
//! offset and what was expected.

pub(crate) mod tensor;
pub(crate) mod warp;

use super::{shown, Dataset, ReadOptions};
use crate::error::{Error, Result};
use crate::geometry::{wrap_phi, Quantity, Sample};
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;
use tensor::{dtype_name, Field, TensorFile, FLOAT32};
use warp::Warp;

/// The channel names, in the file's order.
pub(crate) const CHANNELS: [&str; 3] = ["r", "g", "b"];

/// Nominal wavelengths (nm) of the r, g, b channels: the dominant wavelengths of the sRGB
/// primaries, rounded to the nanometre.
pub(crate) const NOMINAL_NM: [f64; 3] = [612.0, 549.0, 465.0];

/// How the report names a wavelength taken from [`NOMINAL_NM`].
pub(crate) const NOMINAL_ORIGIN: &str = "nominal wavelength of the sRGB channel";

/// Incidences with cos θi at or below this are not sampled (grazing).
const GRAZING_COS: f64 = 1e-6;

/// An isotropic RGL BRDF, ready to sample and evaluate.
#[derive(Debug, Clone)]
pub(crate) struct RglBrdf {
    /// Incidence elevations of the tables (rad, ascending).
    pub theta_i: Vec<f32>,
    ndf: Warp,
    sigma: Warp,
    vndf: Warp,
    rgb: [Warp; 3],
    /// Grid size of the rgb tables (columns, rows).
    grid: (usize, usize),
}

/// One measured point: geometry, the grid point it comes from and f_r per channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RglSample {
    /// Index of θi in the file's `theta_i`, row and column of the rgb grid.
    pub index: (usize, usize, usize),
    /// Angles in goniofit's convention (rad).
    pub sample: Sample,
    /// Outgoing direction (unit vector; ωi = (sin θi, 0, cos θi)).
    pub wo: [f64; 3],
    /// f_r (1/sr) per channel r, g, b.
    pub brdf: [f64; 3],
}

/// π in f32, as the loader's constants.
const PI32: f32 = std::f32::consts::PI;

/// θm → u_θ of the loader's parameterisation.
fn theta2u(theta: f32) -> f32 {
    (theta * (2.0 / PI32)).sqrt()
}
/// φ → u_φ of the loader's parameterisation.
fn phi2u(phi: f32) -> f32 {
    (phi + PI32) / (2.0 * PI32)
}
/// Elevation of a unit vector, robust near the normal (as the loader computes it: the
/// chord in f32, its arcsine in f64, rounded to f32).
fn elevation(d: [f32; 3]) -> f32 {
    let half_chord = 0.5 * (d[0] * d[0] + d[1] * d[1] + (d[2] - 1.0) * (d[2] - 1.0)).sqrt();
    (2.0 * f64::from(half_chord.min(1.0)).asin()) as f32
}
/// The loader's dot product (summed from 0 in order).
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A located error about field `f`.
fn field_err(path: &Path, f: &Field, message: String) -> Error {
    Error::file(
        path,
        format!(
            "field '{}' (entry at byte {}, data at byte {}): {message}",
            f.name, f.header_at, f.offset
        ),
    )
}

/// A float32 field of `ndim` dimensions, every value finite.
fn float_field<'t>(
    path: &Path,
    tf: &'t TensorFile,
    name: &str,
    ndim: usize,
) -> Result<(&'t Field, Vec<f32>)> {
    let f = tf.field(name).map_err(|m| Error::file(path, m))?;
    if f.dtype != FLOAT32 || f.shape.len() != ndim {
        return Err(field_err(
            path,
            f,
            format!(
                "expected float32 with {ndim} dimension(s), found {} with shape {:?}",
                dtype_name(f.dtype),
                f.shape
            ),
        ));
    }
    let values = tf.f32_values(f);
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(field_err(
            path,
            f,
            format!(
                "value {k} (byte {}) is {}, expected a finite number",
                f.offset + 4 * k,
                values[k]
            ),
        ));
    }
    Ok((f, values))
}

/// Refuse a spectral or anisotropic file, naming why.
fn check_kind(path: &Path, tf: &TensorFile) -> Result<()> {
    if tf.field("rgb").is_err() {
        if let Ok(f) = tf.field("spectra") {
            return Err(field_err(
                path,
                f,
                "a spectral file (fields 'wavelengths', 'spectra'): goniofit reads the RGB files (names ending in _rgb.bsdf)".into(),
            ));
        }
    }
    Ok(())
}

impl RglBrdf {
    /// Parse an RGL `.bsdf` file's bytes (`path` names it in messages).
    pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<RglBrdf> {
        let tf = TensorFile::parse(bytes).map_err(|m| Error::file(path, m))?;
        check_kind(path, &tf)?;
        let (f_ti, theta_i) = float_field(path, &tf, "theta_i", 1)?;
        let (f_pi, phi_i) = float_field(path, &tf, "phi_i", 1)?;
        if phi_i.len() != 1 {
            return Err(field_err(
                path,
                f_pi,
                format!("expected length 1 (an isotropic file), found {}: anisotropic files are not read", phi_i.len()),
            ));
        }
        let ascending = theta_i.windows(2).all(|w| w[0] < w[1]);
        if theta_i.is_empty()
            || !ascending
            || theta_i[0] < 0.0
            || *theta_i.last().unwrap() as f64 > FRAC_PI_2 + 1e-6
        {
            return Err(field_err(
                path,
                f_ti,
                format!("expected ascending angles within [0, π/2], found {theta_i:?}"),
            ));
        }
        let nt = theta_i.len();
        let table = |name: &str| -> Result<Warp> {
            let (f, v) = float_field(path, &tf, name, 2)?;
            let (ny, nx) = (f.shape[0], f.shape[1]);
            grid_ok(path, f, nx, ny)?;
            Ok(Warp::plain(nx, ny, vec![0.0], &v))
        };
        let ndf = table("ndf")?;
        let sigma = table("sigma")?;
        let (f_v, v) = float_field(path, &tf, "vndf", 4)?;
        expect_shape(path, f_v, &[1, nt], &f_v.shape[..2])?;
        let (vny, vnx) = (f_v.shape[2], f_v.shape[3]);
        grid_ok(path, f_v, vnx, vny)?;
        let vndf =
            Warp::sampling(vnx, vny, theta_i.clone(), &v).map_err(|m| field_err(path, f_v, m))?;
        let (f_rgb, rgb_values) = float_field(path, &tf, "rgb", 5)?;
        expect_shape(path, f_rgb, &[1, nt, 3], &f_rgb.shape[..3])?;
        let (ny, nx) = (f_rgb.shape[3], f_rgb.shape[4]);
        grid_ok(path, f_rgb, nx, ny)?;
        let channel = |c: usize| {
            let mut d = Vec::with_capacity(nt * nx * ny);
            for t in 0..nt {
                let start = (t * 3 + c) * nx * ny;
                d.extend_from_slice(&rgb_values[start..start + nx * ny]);
            }
            Warp::plain(nx, ny, theta_i.clone(), &d)
        };
        let rgb = [channel(0), channel(1), channel(2)];
        Ok(RglBrdf {
            theta_i,
            ndf,
            sigma,
            vndf,
            rgb,
            grid: (nx, ny),
        })
    }

    /// f_r (1/sr) per channel at incident direction `wi` (towards the light) and outgoing
    /// `wo`, unit vectors in the local frame (z = normal), by the reference loader's
    /// interpolation (in f32, as the loader); 0 when either is at or below the horizon.
    #[cfg(test)]
    pub(crate) fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> [f64; 3] {
        let f = self.eval_cos(wi, wo);
        if wi[2] <= 0.0 || wo[2] <= 0.0 {
            return [0.0; 3];
        }
        f.map(|v| v / wo[2])
    }

    /// f_r · cos θo per channel, as the reference loader's `eval` (without its clipping of
    /// negative values to 0); 0 when either direction is at or below the horizon.
    #[cfg(test)]
    pub(crate) fn eval_cos(&self, wi: [f64; 3], wo: [f64; 3]) -> [f64; 3] {
        self.eval_cos32(wi.map(|v| v as f32), wo.map(|v| v as f32))
            .map(f64::from)
    }

    /// [`RglBrdf::eval_cos`] in the loader's f32 arithmetic.
    fn eval_cos32(&self, wi: [f32; 3], wo: [f32; 3]) -> [f32; 3] {
        if wi[2] <= 0.0 || wo[2] <= 0.0 {
            return [0.0; 3];
        }
        let h = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let n = dot(h, h).sqrt();
        let wm = [h[0] / n, h[1] / n, h[2] / n];
        let theta_i = elevation(wi);
        let phi_i = wi[1].atan2(wi[0]);
        let theta_m = elevation(wm);
        let phi_m = wm[1].atan2(wm[0]);
        let u_wi = [theta2u(theta_i), phi2u(phi_i)];
        let mut u_wm = [theta2u(theta_m), phi2u(phi_m - phi_i)];
        u_wm[1] -= u_wm[1].floor();
        let s = self.vndf.invert(u_wm, theta_i);
        let ndf = self.ndf.eval(u_wm, 0.0);
        let sigma4 = 4.0 * self.sigma.eval(u_wi, 0.0);
        [0, 1, 2].map(|c| self.rgb[c].eval(s, theta_i) * ndf / sigma4)
    }

    /// The outgoing direction the loader's sampling maps grid point (`col`, `row`) of the
    /// rgb table to at incidence `wi` (elevation `theta_i`), in f32 as the loader.
    fn grid_direction(&self, wi: [f32; 3], theta_i: f32, col: usize, row: usize) -> [f32; 3] {
        let (nx, ny) = self.grid;
        let u = [col as f32 / (nx - 1) as f32, row as f32 / (ny - 1) as f32];
        let u_wm = self.vndf.sample(u, theta_i);
        let phi_m = (2.0 * u_wm[1] - 1.0) * PI32;
        let theta_m = u_wm[0] * u_wm[0] * (PI32 / 2.0);
        let wm = [
            phi_m.cos() * theta_m.sin(),
            phi_m.sin() * theta_m.sin(),
            theta_m.cos(),
        ];
        let d = dot(wm, wi);
        [0, 1, 2].map(|k| wm[k] * 2.0 * d - wi[k])
    }

    /// The measured points (see the module docs), in the order θi, grid row, grid column.
    pub(crate) fn samples(&self) -> Vec<RglSample> {
        let (nx, ny) = self.grid;
        let mut out = Vec::new();
        for (t, &theta_i) in self.theta_i.iter().enumerate() {
            let wi = [theta_i.sin(), 0.0, theta_i.cos()];
            if wi[2] as f64 <= GRAZING_COS {
                continue;
            }
            for row in 0..ny {
                for col in 0..nx {
                    let wo = self.grid_direction(wi, theta_i, col, row);
                    if wo[2] <= 0.0 {
                        continue;
                    }
                    let f = self.eval_cos32(wi, wo);
                    if !f.iter().chain(&wo).all(|v| v.is_finite()) {
                        continue; // a damaged table's warp, not a measured point
                    }
                    let wo = wo.map(f64::from);
                    let sample = Sample {
                        theta_i: theta_i as f64,
                        theta_r: wo[0].hypot(wo[1]).atan2(wo[2]),
                        phi_r: wrap_phi(wo[1].atan2(wo[0]) - PI),
                    };
                    let brdf = f.map(|v| v as f64 / wo[2]);
                    out.push(RglSample {
                        index: (t, row, col),
                        sample,
                        wo,
                        brdf,
                    });
                }
            }
        }
        out
    }
}

/// A grid of at least 2 × 2 (the interpolation needs a cell).
fn grid_ok(path: &Path, f: &Field, nx: usize, ny: usize) -> Result<()> {
    if nx < 2 || ny < 2 {
        return Err(field_err(
            path,
            f,
            format!("expected a grid of at least 2 × 2, found {ny} × {nx}"),
        ));
    }
    Ok(())
}

/// The leading dimensions `got` of field `f` equal `want`.
fn expect_shape(path: &Path, f: &Field, want: &[usize], got: &[usize]) -> Result<()> {
    if want != got {
        return Err(field_err(
            path,
            f,
            format!(
                "expected leading dimensions {want:?} (phi_i, theta_i{}), found shape {:?}",
                if want.len() == 3 { ", 3 channels" } else { "" },
                f.shape
            ),
        ));
    }
    Ok(())
}

/// Read an RGL file as a dataset: the measured points of the channel(s) `opts.channel`
/// selects (`r`, `g`, `b` or `all`; required), f_r in 1/sr (quantity BRDF), each channel's
/// nominal wavelength in nm. `lines` holds each point's 1-based number among the file's
/// points (θi, row, column order); the pass-through columns are the angles in degrees,
/// the channel and BRDF.
pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Dataset> {
    let brdf = RglBrdf::parse(path, bytes)?;
    let selected = select_channels(path, opts.channel.as_deref())?;
    let points = brdf.samples();
    if points.is_empty() {
        return Err(Error::file(
            path,
            "no measured point above the horizon".into(),
        ));
    }
    let n = points.len() * selected.len();
    let mut ds = Dataset {
        path: path.to_path_buf(),
        headers: ["theta_i", "theta_r", "phi_r", "channel", "BRDF"]
            .map(String::from)
            .to_vec(),
        rows: Vec::with_capacity(n),
        lines: Vec::with_capacity(n),
        samples: Vec::with_capacity(n),
        value: Some(Vec::with_capacity(n)),
        weight: None,
        sigma_l: None,
        wavelength: Some(Vec::with_capacity(n)),
        wavelength_unit: Some("nm".into()),
        wavelength_origin: Some(NOMINAL_ORIGIN),
        channel: Some(Vec::with_capacity(n)),
        quantity: Some(Quantity::Brdf),
    };
    for &c in &selected {
        for (k, p) in points.iter().enumerate() {
            let s = p.sample;
            ds.rows.push(vec![
                super::format_value(s.theta_i.to_degrees()),
                super::format_value(s.theta_r.to_degrees()),
                super::format_value(s.phi_r.to_degrees()),
                CHANNELS[c].to_string(),
                super::format_value(p.brdf[c]),
            ]);
            ds.lines.push(k + 1);
            ds.samples.push(s);
            ds.value.as_mut().unwrap().push(p.brdf[c]);
            ds.wavelength.as_mut().unwrap().push(NOMINAL_NM[c]);
            ds.channel.as_mut().unwrap().push(CHANNELS[c].to_string());
        }
    }
    Ok(ds)
}

/// The channel indices `--channel` selects; none given is an error listing them.
pub(crate) fn select_channels(path: &Path, channel: Option<&str>) -> Result<Vec<usize>> {
    let list = "r, g, b";
    match channel.map(str::trim) {
        Some(c) if c.eq_ignore_ascii_case("all") => Ok(vec![0, 1, 2]),
        Some(c) => CHANNELS
            .iter()
            .position(|n| n.eq_ignore_ascii_case(c))
            .map(|k| vec![k])
            .ok_or_else(|| Error::Usage(format!("{}: no channel '{c}' (channels: {list}; or 'all')", shown(path)))),
        None => Err(Error::Usage(format!(
            "{}: 3 channels; choose one with --channel NAME or all with --channel all (channels: {list})",
            shown(path)
        ))),
    }
}
