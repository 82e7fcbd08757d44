//! What a fit runs on, made from [`Settings`]: how a file is read, the fit's configuration,
//! the quantity and the unit of λ of a dataset. The values are those
//! [`Settings::check`] accepts.

use super::{Front, Settings};
use crate::fit::dataset::DatasetFit;
use crate::fit::driver::FitConfig;
use crate::fit::problem::loss::Loss;
use crate::geometry::Quantity;
use crate::io::{Dataset, ReadOptions};
use crate::model::ModelOptions;
use goniofit_lm::LmConfig;

impl Settings {
    /// How a file is read for the fit: its angle conventions, column names, channel
    /// (every channel for `by_group`) and MERL subsampling; the measured value required.
    pub fn read_options(&self) -> crate::error::Result<ReadOptions> {
        let channel = match (&self.channel, self.by_group) {
            (None, true) => Some("all".to_string()),
            (c, _) => c.clone(),
        };
        Ok(ReadOptions {
            radians: self.radians,
            signed_theta_r: self.signed_theta_r,
            columns: crate::io::csv::parse_columns(self.columns.as_deref().unwrap_or(""))?,
            require_value: true,
            channel,
            subsample: self.subsample,
        })
    }

    /// The model options: evaluation mode, tolerance, patch and the lobe's factors.
    pub fn model_options(&self) -> ModelOptions {
        ModelOptions {
            mode: self.mode,
            tol: self.tol,
            patch: self.patch,
            fresnel: self.fresnel,
            shadowing: self.shadowing,
        }
    }

    /// The configuration of a fit of `model`: a name, optionally followed by factor options
    /// as reports write them (`kbs+lambert --fresnel dielectric`), which then replace these
    /// settings' factors. `uncertainties`: the weights come from stated uncertainties. The
    /// solver shows no progress and has no stop request of its own.
    pub fn fit_config(&self, model: &str, uncertainties: bool) -> FitConfig {
        let (model, model_opts) = self.model_options().with_factors_of(model);
        let lm = LmConfig {
            max_iters: self.max_iter,
            timeout: super::timeout(Front::Json, self.timeout).ok().flatten(),
            progress: false,
            ..FitConfig::default().lm
        };
        FitConfig {
            model,
            model_opts,
            residual: self.residual,
            loss: Loss {
                kind: self.loss,
                f_scale: self.f_scale,
            },
            floor: self.floor,
            init: self.init.clone(),
            fix: self.fix.clone(),
            lm,
            weights_are_uncertainties: uncertainties,
            reduce: self.reduce,
        }
    }

    /// The measured quantity of a dataset's fit and where it came from: these settings
    /// (named as `front` spells the option), what the file states, or radiance by default.
    pub fn quantity_for(&self, ds: &Dataset, front: Front) -> (Quantity, String) {
        match (self.quantity, ds.quantity) {
            (Some(q), _) => (q, front.source("quantity")),
            (None, Some(q)) => (q, "stated by the file".into()),
            (None, None) => (Quantity::Radiance, "default".into()),
        }
    }

    /// The fit of dataset `ds` with these settings (its quantity the file's when the
    /// settings name none); `single`: the only dataset of the call (its profile intervals
    /// computed unless `intervals` says otherwise).
    pub fn dataset_fit(&self, ds: &Dataset, single: bool) -> DatasetFit {
        DatasetFit {
            model: self.model.clone(),
            quantity: self.quantity_for(ds, Front::Json).0,
            wavelength: self.wavelength,
            config: self.fit_config(&self.model, false),
            absolute_sigma: self.absolute_sigma,
            intervals: self.intervals.unwrap_or(single),
        }
    }

    /// The unit of λ (and of σ, T) of a dataset's fit: `wavelength_unit` with a
    /// `wavelength`, else the data's unit, else `wavelength_unit` as stated.
    pub fn wavelength_unit(&self, ds: &Dataset) -> Option<String> {
        match (self.wavelength, &ds.wavelength) {
            (None, Some(_)) => ds
                .wavelength_unit
                .clone()
                .or_else(|| self.wavelength_unit.clone()),
            _ => self.wavelength_unit.clone(),
        }
    }
}
