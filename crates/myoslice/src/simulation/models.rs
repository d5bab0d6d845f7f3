//! Switching the muscle and tendon models of a running simulation.

use super::{MuscleModel, Simulation, TendonModel};

impl Simulation {
    /// The muscle model driving the chains now.
    pub fn muscle_model(&self) -> MuscleModel {
        self.config.muscle_model
    }

    /// The Hill units' tendon model now.
    pub fn tendon_model(&self) -> TendonModel {
        self.config.tendon
    }

    /// Switches the muscle model mid-run (the viewer's and Python's model switch). The
    /// pose, the chains and the activations carry over; each fibre starts from the new
    /// model's state at the current path (see [`Self::set_tendon_model`]).
    ///
    /// ```no_run
    /// use myoslice::prelude::*;
    /// let mut sim = Simulation::phantom(SimulationConfig::default())?;
    /// sim.set_excitation("semitendinosus", 1.0)?;
    /// sim.step(0.2)?;
    /// sim.set_muscle_model(MuscleModel::Spring); // the paper's Eq. 1 from here on
    /// sim.step(0.2)?;
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn set_muscle_model(&mut self, model: MuscleModel) {
        if model != self.config.muscle_model {
            self.config.muscle_model = model;
            self.start_fibres();
        }
    }

    /// Switches the Hill units' tendons mid-run. To compliant, every fibre starts in
    /// static equilibrium with its tendon at the current path length and activation (a
    /// step from the rigid fibre length would read the tendon's stretch as a fibre
    /// velocity); to rigid, the fibre takes the whole path again.
    ///
    /// ```no_run
    /// use myoslice::prelude::*;
    /// let mut sim = Simulation::phantom(SimulationConfig::default())?;
    /// sim.set_tendon_model(TendonModel::Compliant);
    /// sim.set_excitation("semitendinosus", 1.0)?;
    /// sim.step(0.2)?;
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn set_tendon_model(&mut self, tendon: TendonModel) {
        if tendon != self.config.tendon {
            self.config.tendon = tendon;
            self.start_fibres();
        }
    }

    /// Every fibre in the state the current models give it at the current path: static
    /// equilibrium for compliant Hill units, the rigid-tendon kinematics otherwise.
    pub(super) fn start_fibres(&mut self) {
        let compliant = self.config.tendon == TendonModel::Compliant
            && self.config.muscle_model == MuscleModel::Hill;
        for m in &mut self.muscles {
            m.fibre = if compliant {
                m.hill
                    .compliant_tendon_step(m.activation, m.path_length, m.fibre.length, None)
            } else {
                m.hill
                    .rigid_tendon_kinematics(m.path_length, m.path_velocity)
            };
        }
    }
}
