//! The `goniofit fit` command line equivalent to [`Settings`] (the report's `command` of a
//! fit the Python package ran).

use super::Settings;
use crate::fit::problem::loss::LossKind;
use crate::model::fresnel::Fresnel;
use crate::model::shadowing::Shadowing;

impl Settings {
    /// The `goniofit fit` options that ask for these settings, without the files: the
    /// model, quantity (when given), residual, evaluation mode, tolerance and iteration
    /// limit always, every other option when it differs from its default.
    pub fn command_args(&self) -> Vec<String> {
        let mut a: Vec<String> = vec!["fit".into()];
        let mut flag = |name: &str, value: Option<String>| {
            a.push(format!("--{name}"));
            a.extend(value);
        };
        flag("model", Some(self.model.clone()));
        if let Some(q) = self.quantity {
            flag("quantity", Some(name_of(&q)));
        }
        flag("residual", Some(name_of(&self.residual)));
        flag("mode", Some(name_of(&self.mode)));
        flag("tol", Some(format!("{:e}", self.tol)));
        flag("max-iter", Some(self.max_iter.to_string()));
        if self.loss != LossKind::Linear {
            flag("loss", Some(self.loss.name().into()));
            flag("f-scale", Some(self.f_scale.to_string()));
        }
        if let Some(l) = self.wavelength {
            let unit = self.wavelength_unit.as_deref().unwrap_or_default();
            flag("wavelength", Some(format!("{l}{unit}")));
        }
        for (name, pairs) in [("init", &self.init), ("fix", &self.fix)] {
            if !pairs.is_empty() {
                flag(name, Some(assignments(pairs)));
            }
        }
        if let Some((x, y)) = self.patch {
            flag("patch", Some(format!("{x},{y}")));
        }
        if self.fresnel != Fresnel::None {
            flag("fresnel", Some(self.fresnel.name().into()));
        }
        if self.shadowing != Shadowing::None {
            flag("shadowing", Some(self.shadowing.name().into()));
        }
        let values = [
            ("floor", self.floor.map(|f| f.to_string())),
            ("timeout", self.timeout.map(|t| t.to_string())),
            ("channel", self.channel.clone()),
            ("columns", self.columns.clone()),
            (
                "subsample",
                (self.subsample != 1).then(|| self.subsample.to_string()),
            ),
            ("threads", self.threads.map(|n| n.to_string())),
        ];
        for (name, value) in values {
            if value.is_some() {
                flag(name, value);
            }
        }
        let switches = [
            ("radians", self.radians),
            ("signed-theta-r", self.signed_theta_r),
            ("no-reduce", !self.reduce),
            ("absolute-sigma", self.absolute_sigma),
            ("no-intervals", self.intervals == Some(false)),
            ("by-group", self.by_group),
            ("warm-start", self.warm_start),
        ];
        for (name, on) in switches {
            if on {
                flag(name, None);
            }
        }
        a
    }

    /// `goniofit` followed by [`Self::command_args`], joined by spaces.
    pub fn command_line(&self) -> String {
        format!("goniofit {}", self.command_args().join(" "))
    }
}

/// `name=value,...`.
fn assignments(pairs: &[(String, f64)]) -> String {
    pairs
        .iter()
        .map(|(k, x)| format!("{k}={x}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// A choice's name as JSON spells it (`brdf`, `log`, `series`).
fn name_of<T: serde::Serialize>(choice: &T) -> String {
    match serde_json::to_value(choice) {
        Ok(serde_json::Value::String(name)) => name,
        _ => String::new(),
    }
}
