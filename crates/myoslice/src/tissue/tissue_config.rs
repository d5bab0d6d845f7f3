//! The tissue's options.

use serde::{Deserialize, Serialize};

use crate::error::{Result, check_range};

/// Tissue options (all with documented defaults).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TissueConfig {
    /// Deform muscles and fat at all. Default true.
    pub enabled: bool,
    /// Tissue updates per simulated second (the muscles step at 1 kHz). Default 30.
    pub rate_hz: f64,
    /// Shape-matching iterations per update. Default 6.
    pub iterations: usize,
    /// Shape-matching stiffness k in (0, 1]: fraction of the way to the goal per
    /// iteration. Default 0.6.
    pub stiffness: f64,
    /// Fraction of the last update's own motion carried into the next (inertia; 0 is
    /// quasi-static). Default 0.3.
    pub momentum: f64,
    /// Half-gap (m) kept between the thigh and calf sides of the contact plane behind
    /// the knee. Default 0.001.
    pub contact_gap_m: f64,
    /// No fat element may shrink below half of this share of its rest volume (or half of
    /// its volume in the knee fold, if that is smaller): where relaxation would, the
    /// tissue falls back toward the fold locally (see [`super::Tissue`]). Default 0.05, i.e. a
    /// floor at 2.5 % of rest volume.
    pub min_volume_ratio: f64,
    /// Keep the body surface from passing through itself near the knee (checked exactly,
    /// triangle against triangle, after every update). Default true.
    pub surface_guard: bool,
    /// Push apart muscles whose shapes overlap once they are placed on their chains, each
    /// keeping its volume by bulging where it faces fat. Default false: it roughly
    /// doubles an update's time, and finds only part of the overlap the tissue audit
    /// counts (a muscle's rings, read as outlines, miss some of it).
    pub muscle_contact: bool,
    /// Hold each fat element's volume and keep its corners from folding inside the
    /// relaxation, with the bone passes in the same iterations (see
    /// `tissue::relax`). Default true; false gives the passes run one after another.
    pub fat_constraints: bool,
}

impl Default for TissueConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: 30.0,
            iterations: 6,
            stiffness: 0.6,
            momentum: 0.3,
            contact_gap_m: 0.001,
            min_volume_ratio: 0.05,
            surface_guard: true,
            muscle_contact: false,
            fat_constraints: true,
        }
    }
}

impl TissueConfig {
    /// Checks the options.
    pub fn validate(&self) -> Result<()> {
        check_range("tissue.rate_hz", self.rate_hz, 1.0, 1000.0)?;
        check_range("tissue.iterations", self.iterations as f64, 1.0, 200.0)?;
        check_range("tissue.stiffness", self.stiffness, 1e-3, 1.0)?;
        check_range("tissue.momentum", self.momentum, 0.0, 0.95)?;
        check_range("tissue.contact_gap_m", self.contact_gap_m, 0.0, 0.01)?;
        check_range("tissue.min_volume_ratio", self.min_volume_ratio, 0.0, 0.9)?;
        Ok(())
    }
}
