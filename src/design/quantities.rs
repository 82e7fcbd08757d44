//! The quantities a design reports and may target: the model's parameters and the derived
//! quantities of the KBS models, each a monomial Π p_k^{c_k} of positive parameters, i.e.
//! the linear combination cᵀx of the design variables x = ln p.

use crate::model::Model;
use nalgebra::DVector;

/// A reported quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct QuantityDef {
    /// `sigma`, `T`, …, or a derived name (`T/sigma`, `beckmann_alpha`, …).
    pub name: String,
    /// The model's unit for a parameter; empty for a derived quantity.
    pub unit: String,
    /// Its value at the scene's parameters.
    pub value: f64,
    /// c: the quantity is cᵀx (x = ln p for a positive parameter, p otherwise), up to a
    /// constant factor.
    pub coef: DVector<f64>,
    /// Whether the design variable is ln of the quantity (its standard error is relative).
    pub log: bool,
    /// Whether it is derived from the parameters (not one of the model's own).
    pub derived: bool,
    /// Its meaning in one line (the parameter's doc, or the derived quantity's formula).
    pub doc: String,
}

/// The parameters of `model` at `params`, then, for models with σ and T, T/σ, Beckmann's
/// α = 2σ/T, the rough-regime amplitude s·(T/σ)², the smooth-regime amplitude s·σ², and
/// with a Lambertian term its reflectance factor π·s_d.
pub(crate) fn quantities(model: &dyn Model, params: &[f64]) -> Vec<QuantityDef> {
    let specs = model.params();
    let q = specs.len();
    let mut out: Vec<QuantityDef> = specs
        .iter()
        .enumerate()
        .map(|(j, s)| QuantityDef {
            name: s.name.to_string(),
            unit: s.unit.to_string(),
            value: params[j],
            coef: DVector::from_fn(q, |k, _| if k == j { 1.0 } else { 0.0 }),
            log: s.positive,
            derived: false,
            doc: s.doc.to_string(),
        })
        .collect();
    let find = |name: &str| specs.iter().position(|s| s.name == name && s.positive);
    let mut derived = |name: &str, factor: f64, terms: &[(usize, f64)], doc: &str| {
        let mut coef = DVector::zeros(q);
        let mut value = factor;
        for &(k, c) in terms {
            coef[k] += c;
            value *= params[k].powf(c);
        }
        out.push(QuantityDef {
            name: name.into(),
            unit: String::new(),
            value,
            coef,
            log: true,
            derived: true,
            doc: doc.into(),
        });
    };
    if let (Some(s), Some(t)) = (find("sigma"), find("T")) {
        derived(
            "T/sigma",
            1.0,
            &[(t, 1.0), (s, -1.0)],
            "correlation length over rms height",
        );
        derived(
            "beckmann_alpha",
            2.0,
            &[(s, 1.0), (t, -1.0)],
            "Beckmann's α = 2σ/T",
        );
        if let Some(a) = find("scale") {
            let rough = [(a, 1.0), (t, 2.0), (s, -2.0)];
            derived(
                "amplitude_rough",
                1.0,
                &rough,
                "s·(T/σ)², the rough-regime lobe amplitude",
            );
            let smooth = [(a, 1.0), (s, 2.0)];
            derived(
                "amplitude_smooth",
                1.0,
                &smooth,
                "s·σ², the smooth-regime lobe amplitude",
            );
        }
    }
    if let Some(d) = find("scale_d") {
        derived(
            "reflectance_factor",
            std::f64::consts::PI,
            &[(d, 1.0)],
            "π·s_d",
        );
    }
    out
}
