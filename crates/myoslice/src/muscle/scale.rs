//! Factors on a muscle's catalogued parameters, for parameter sweeps and fitting.

use serde::Deserialize;

use crate::error::{Error, Result};

/// Factors on one muscle's Hill parameters as built from the catalogue (a scenario's
/// `[muscle.NAME]` section, Python's sweeps and fits). 1 leaves a parameter as built.
///
/// ```
/// use myoslice::muscle::MuscleScale;
/// let s = MuscleScale { max_force_scale: 1.2, ..MuscleScale::default() };
/// assert!(s.check("semitendinosus").is_ok());
/// let bad = MuscleScale { tendon_slack_length_scale: -1.0, ..s };
/// assert!(bad.check("semitendinosus").is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MuscleScale {
    /// Factor on the maximum isometric force (and with it the chain's stiffness).
    pub max_force_scale: f64,
    /// Factor on the optimal fibre length.
    pub optimal_fibre_length_scale: f64,
    /// Factor on the tendon slack length.
    pub tendon_slack_length_scale: f64,
}

impl Default for MuscleScale {
    fn default() -> Self {
        Self {
            max_force_scale: 1.0,
            optimal_fibre_length_scale: 1.0,
            tendon_slack_length_scale: 1.0,
        }
    }
}

impl MuscleScale {
    /// Smallest and largest factor accepted: beyond them a muscle is no longer the one
    /// the catalogue describes (and its fibre state has no solution).
    pub const RANGE: (f64, f64) = (0.05, 20.0);

    /// Says which factor is not a number within [`Self::RANGE`] (`muscle` names the
    /// muscle or group in the message).
    pub fn check(&self, muscle: &str) -> Result<()> {
        for (name, v) in [
            ("max_force_scale", self.max_force_scale),
            (
                "optimal_fibre_length_scale",
                self.optimal_fibre_length_scale,
            ),
            ("tendon_slack_length_scale", self.tendon_slack_length_scale),
        ] {
            if !(v.is_finite() && (Self::RANGE.0..=Self::RANGE.1).contains(&v)) {
                return Err(Error::InvalidValue {
                    name: format!("muscle.{muscle}.{name}"),
                    value: v.to_string(),
                    expected: format!("a factor from {} to {}", Self::RANGE.0, Self::RANGE.1),
                });
            }
        }
        Ok(())
    }
}
