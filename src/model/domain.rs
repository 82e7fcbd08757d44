//! Where a model can be evaluated, and where its accuracy is stated.
//!
//! [`evaluate_checked`] is the model's value at every sample or a usage error (exit code 2)
//! that names the first sample and the parameters at which the value is not a finite
//! number: parameters so large or small that the model overflows double precision
//! (`sigma=1e300,T=1e300`; `B=1e308,w=1e-300`; a wavelength of 1e-300). Commands that
//! print model values (`eval`, `synth`, `render`) use it, so that no NaN or ±inf is ever
//! printed with exit code 0.
//!
//! [`accuracy_warnings`] lists the parameters outside the range where the KBS sum's
//! accuracy is stated (docs/guide.md, "Accuracy of the KBS sum"): T/λ ∈ [1e-3, 1e5],
//! g ∈ [1e-12, 1e6], a ∈ [0, 1e8]. Values there are still finite, but their accuracy is not
//! checked against the reference; the commands print these as warnings on standard error.

use super::Model;
use crate::error::{Error, Result};
use crate::geometry::Geometry;

/// The documented accuracy range of the KBS sum: T/λ.
pub(crate) const T_OVER_LAMBDA: (f64, f64) = (1e-3, 1e5);
/// The documented accuracy range of the KBS sum: g = (2πσ/λ)² (cos θi + cos θr)².
pub(crate) const G_RANGE: (f64, f64) = (1e-12, 1e6);
/// The documented accuracy range of the KBS sum: upper end of a = v_xy² T²/4.
pub(crate) const A_MAX: f64 = 1e8;

/// A number for messages: plain where that is short (`0.3`, `2`, `550`), scientific
/// otherwise (`1e300`, `2.5e-7`); always the shortest form that reads back exactly.
pub(crate) fn short_number(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-4..1e6).contains(&a) || !v.is_finite() {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `name = value, …` of a parameter vector, for messages.
pub(crate) fn describe_params(model: &dyn Model, params: &[f64]) -> String {
    model
        .params()
        .iter()
        .zip(params)
        .map(|(s, v)| format!("{} = {}", s.name, short_number(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The model's values (the measured quantity of `geo`) at `params`, each finite; otherwise
/// an [`Error::Usage`] naming the first sample whose value is not finite, its angles and
/// wavelength, and the parameters. `params` must have the model's length (checked).
pub(crate) fn evaluate_checked(
    model: &dyn Model,
    params: &[f64],
    geo: &Geometry,
) -> Result<Vec<f64>> {
    super::check_param_count(model, params)?;
    for (spec, v) in model.params().iter().zip(params) {
        super::check_param_value(spec, *v)?;
    }
    let mut out = vec![0.0; geo.len()];
    model.eval(geo, params, &mut out, None);
    check_finite(model, params, geo, &out, "")?;
    Ok(out)
}

/// Ok when every entry of `values` (one per sample of `geo`: the model's values, or with
/// `what` = "'s derivative by NAME" a column of its Jacobian) is finite; otherwise the
/// [`Error::Usage`] of `evaluate_checked` for the first sample that is not.
pub fn check_finite(
    model: &dyn Model,
    params: &[f64],
    geo: &Geometry,
    values: &[f64],
    what: &str,
) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => {
            Err(Error::Usage(format!(
                "model {}{what} is not a finite number ({}) at theta_i = {}°, theta_r = {}°, phi_r = {}°, wavelength {} for {}: \
                 these parameters lie outside the range the model can be evaluated in (double precision overflows)",
                model.name(),
                if values[i].is_nan() {
                    "undefined"
                } else {
                    "it overflows"
                },
                crate::error::fmt_num(geo.theta_i[i].to_degrees()),
                crate::error::fmt_num(geo.theta_r[i].to_degrees()),
                crate::error::fmt_num(geo.phi_r[i].to_degrees()),
                short_number(geo.wavelength[i]),
                describe_params(model, params),
            )))
        }
    }
}

/// Warnings for parameters outside the documented accuracy range of the KBS sum (empty for
/// the other models and inside the range). Each names the quantity, its range over the
/// samples and the documented range.
pub(crate) fn accuracy_warnings(model: &dyn Model, params: &[f64], geo: &Geometry) -> Vec<String> {
    let idx = |name: &str| model.params().iter().position(|s| s.name == name);
    let (Some(js), Some(jt)) = (idx("sigma"), idx("T")) else {
        return Vec::new();
    };
    let (Some(&sigma), Some(&corr)) = (params.get(js), params.get(jt)) else {
        return Vec::new();
    };
    let range = |f: &dyn Fn(usize) -> f64| {
        (0..geo.len()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
            let v = f(i);
            (lo.min(v), hi.max(v))
        })
    };
    let t_l = range(&|i| corr / geo.wavelength[i]);
    let g = range(&|i| geo.g(i, sigma));
    let a = range(&|i| geo.a(i, corr));
    let mut out = Vec::new();
    let span = |(lo, hi): (f64, f64)| {
        if lo == hi {
            format!("{lo:.3e}")
        } else {
            format!("{lo:.3e} .. {hi:.3e}")
        }
    };
    if t_l.0 < T_OVER_LAMBDA.0 || t_l.1 > T_OVER_LAMBDA.1 {
        out.push(format!(
            "T/wavelength = {} is outside [{:e}, {:e}], where the accuracy of the KBS sum is stated",
            span(t_l),
            T_OVER_LAMBDA.0,
            T_OVER_LAMBDA.1
        ));
    }
    if g.0 < G_RANGE.0 || g.1 > G_RANGE.1 {
        out.push(format!(
            "g = (2π sigma/wavelength)²(cos θi + cos θr)² = {} is outside [{:e}, {:e}], where the accuracy of the KBS sum is stated",
            span(g),
            G_RANGE.0,
            G_RANGE.1
        ));
    }
    if a.1 > A_MAX {
        out.push(format!(
            "a = v_xy² T²/4 reaches {:.3e}, beyond {A_MAX:e}, where the accuracy of the KBS sum is stated",
            a.1
        ));
    }
    out
}
