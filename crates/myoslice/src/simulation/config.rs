//! Simulation options, with documented defaults.

use serde::{Deserialize, Serialize};

pub use crate::muscle::TendonModel;

use crate::error::{Error, Result, check_positive, check_range, parse_choice};
use crate::tissue::TissueConfig;

/// Which muscle model drives the chains.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MuscleModel {
    /// Hill-type muscle-tendon units (De Groote 2016) setting the contraction force from
    /// activation, fibre length and velocity (beyond the paper).
    Hill,
    /// The paper's spring chain: a contraction force proportional to excitation on damped
    /// springs of fixed rest length (Eq. 1).
    Spring,
}

impl MuscleModel {
    /// Every model, in the order fronts list them.
    pub const ALL: [Self; 2] = [Self::Hill, Self::Spring];

    /// The name used in scenarios, the CLI and Python (`"hill"`, `"spring"`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Hill => "hill",
            Self::Spring => "spring",
        }
    }
}

impl std::str::FromStr for MuscleModel {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        parse_choice("muscle_model", s, &Self::ALL, |m| m.name())
    }
}

/// Options of a [`super::Simulation`]. Every field has a documented default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulationConfig {
    /// Body mass (kg) scaling Dempster's segment masses. Default 60.
    pub body_mass_kg: f64,
    /// Body height (m) scaling Dempster's segment lengths. Default 1.65.
    pub height_m: f64,
    /// Muscle model. Default Hill.
    pub muscle_model: MuscleModel,
    /// Tendons of the Hill units. Default rigid.
    pub tendon: TendonModel,
    /// Knee flexion limits (degrees). Default [0, 140].
    pub knee_limits_deg: [f64; 2],
    /// Viscous knee damping (N m s/rad). Default 0.3.
    pub knee_damping: f64,
    /// Gravity (m/s², body frame). Default [0, 0, -9.81].
    pub gravity: [f64; 3],
    /// Knee angle at the start (degrees). Default 0 (the rest pose of the slices).
    pub initial_knee_deg: f64,
    /// Largest internal step (s): `step(dt)` splits longer steps. Default 0.001 (1 kHz).
    pub max_step_s: f64,
    /// Target spacing of chain mass points along a muscle belly (m). Default 0.04.
    pub chain_spacing_m: f64,
    /// Half-angle of the cones keeping chain points near the bone (degrees). Default 15.
    pub cone_half_angle_deg: f64,
    /// Chain spring constant relative to the muscle: k_i = this × F_max / L_i. Default 0.5.
    pub chain_stiffness: f64,
    /// Tether of an unloaded chain (beyond the paper, [`crate::muscle::Tether`]): N/m
    /// pulling each cone-anchored chain point toward its rest place on its bone (per point:
    /// the whole pull grows as `chain_spacing_m` shrinks). 0 leaves the paper's chain.
    /// Default 600.
    pub chain_tether: f64,
    /// Muscle force (N) from which the tether is off; it fades linearly up to it (0 turns
    /// the tether off). The same for every muscle: 1.5 % of the vastus medialis' F_max,
    /// a quarter of the weakest catalogued muscles' (82 N). Default 20.
    pub chain_tether_release_n: f64,
    /// Whether muscles press on one another: each chain point keeps its rest distance
    /// from its neighbours' centre lines (see [`crate::muscle::ChainContact`]). Default on.
    pub chain_contact: bool,
    /// Tissue deformation options.
    pub tissue: TissueConfig,
}

impl Default for SimulationConfig {
    fn default() -> Self {
        Self {
            body_mass_kg: 60.0,
            height_m: 1.65,
            muscle_model: MuscleModel::Hill,
            tendon: TendonModel::Rigid,
            knee_limits_deg: [0.0, 140.0],
            knee_damping: 0.3,
            gravity: [0.0, 0.0, -9.81],
            initial_knee_deg: 0.0,
            max_step_s: 1e-3,
            chain_spacing_m: 0.04,
            cone_half_angle_deg: 15.0,
            chain_stiffness: 0.5,
            chain_tether: 600.0,
            chain_tether_release_n: 20.0,
            chain_contact: true,
            tissue: TissueConfig::default(),
        }
    }
}

impl SimulationConfig {
    /// Checks every option, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        check_positive("body_mass_kg", self.body_mass_kg)?;
        check_range("height_m", self.height_m, 0.5, 2.5)?;
        let [lo, hi] = self.knee_limits_deg;
        check_range("knee_limits_deg[0]", lo, -20.0, 180.0)?;
        check_range("knee_limits_deg[1]", hi, -20.0, 180.0)?;
        if hi <= lo {
            return Err(Error::invalid(
                "knee_limits_deg",
                format!("[{lo}, {hi}]"),
                "expected [extension, flexion] with extension < flexion",
            ));
        }
        check_range("knee_damping", self.knee_damping, 0.0, 1e3)?;
        for (i, g) in self.gravity.iter().enumerate() {
            check_range(&format!("gravity[{i}]"), *g, -100.0, 100.0)?;
        }
        check_range("initial_knee_deg", self.initial_knee_deg, lo, hi)?;
        check_range("max_step_s", self.max_step_s, 1e-5, 0.01)?;
        check_range("chain_spacing_m", self.chain_spacing_m, 0.005, 0.5)?;
        check_range("cone_half_angle_deg", self.cone_half_angle_deg, 1.0, 89.0)?;
        check_range("chain_stiffness", self.chain_stiffness, 0.0, 100.0)?;
        check_range("chain_tether", self.chain_tether, 0.0, 1e5)?;
        check_range(
            "chain_tether_release_n",
            self.chain_tether_release_n,
            0.0,
            1e5,
        )?;
        self.tissue.validate()?;
        Ok(())
    }
}
