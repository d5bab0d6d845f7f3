//! The simulation configuration from the constructors' keyword arguments.

use myoslice::prelude::*;
use pyo3::prelude::*;

use crate::errors::{Kind, OrPy, py_err};

/// The keyword arguments `Simulation.phantom` and `Simulation.from_nifti` share.
pub(crate) struct ConfigArgs<'a> {
    pub(crate) body_mass_kg: f64,
    pub(crate) height_m: f64,
    pub(crate) muscle_model: &'a str,
    pub(crate) tendon: &'a str,
    pub(crate) tissue: bool,
    pub(crate) tissue_rate_hz: f64,
    /// None: the core's default. Signed, so that a negative count gets the same
    /// `InvalidInputError` as zero rather than an `OverflowError`.
    pub(crate) tissue_iterations: Option<i64>,
    pub(crate) initial_knee_deg: f64,
    pub(crate) max_step_s: f64,
    /// None: the core's default.
    pub(crate) chain_tether: Option<f64>,
    /// None: the core's default.
    pub(crate) chain_tether_release_n: Option<f64>,
    /// None: the core's default.
    pub(crate) chain_contact: Option<bool>,
    /// None: the core's default.
    pub(crate) muscle_contact: Option<bool>,
    /// None: the core's default.
    pub(crate) fat_constraints: Option<bool>,
}

impl ConfigArgs<'_> {
    /// The configuration, checked (a bad value raises `ValueError` naming it).
    pub(crate) fn config(self, py: Python<'_>) -> PyResult<SimulationConfig> {
        let model: MuscleModel = self.muscle_model.parse().or_py(py)?;
        let tendon: TendonModel = self.tendon.parse().or_py(py)?;
        let d = SimulationConfig::default();
        let mut c = SimulationConfig {
            body_mass_kg: self.body_mass_kg,
            tendon,
            height_m: self.height_m,
            muscle_model: model,
            initial_knee_deg: self.initial_knee_deg,
            max_step_s: self.max_step_s,
            chain_tether: self.chain_tether.unwrap_or(d.chain_tether),
            chain_tether_release_n: self
                .chain_tether_release_n
                .unwrap_or(d.chain_tether_release_n),
            chain_contact: self.chain_contact.unwrap_or(d.chain_contact),
            ..d
        };
        c.tissue.enabled = self.tissue;
        c.tissue.rate_hz = self.tissue_rate_hz;
        if let Some(on) = self.muscle_contact {
            c.tissue.muscle_contact = on;
        }
        if let Some(on) = self.fat_constraints {
            c.tissue.fat_constraints = on;
        }
        if let Some(n) = self.tissue_iterations {
            c.tissue.iterations = usize::try_from(n).map_err(|_| {
                py_err(
                    py,
                    Kind::Invalid,
                    format!("tissue_iterations = {n}: expected at least one iteration"),
                )
            })?;
        }
        c.validate().or_py(py)?;
        Ok(c)
    }
}
