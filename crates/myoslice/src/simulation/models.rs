//! Switching the muscle and tendon models of a running simulation.

use super::{MuscleModel, Simulation, TendonModel};
use crate::error::Result;
use crate::muscle::MuscleScale;

impl Simulation {
    /// The muscle model driving the chains now.
    pub fn muscle_model(&self) -> MuscleModel {
        self.config.muscle_model
    }

    /// The default tendon model: the one [`Self::set_tendon_model`] last gave every
    /// muscle (or the configuration's). A muscle may have its own (the catalogue's
    /// `tendon`, or [`Self::set_muscle_tendon`]); its readout says which.
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
    /// velocity); to rigid, the fibre takes the whole path again. Every muscle takes it,
    /// those with a tendon of their own too; a muscle whose tendon does not change keeps
    /// its fibre state.
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
        self.config.tendon = tendon;
        for i in 0..self.muscles.len() {
            self.switch_tendon(i, tendon);
        }
    }

    /// Gives one muscle its own tendon model mid-run (the others keep theirs and their
    /// fibre states); its fibre starts as [`Self::set_tendon_model`] starts them.
    ///
    /// ```no_run
    /// use myoslice::prelude::*;
    /// let mut sim = Simulation::phantom(SimulationConfig::default())?;
    /// sim.set_muscle_tendon("gastrocnemius_medial", TendonModel::Compliant)?;
    /// assert_eq!(sim.muscle("gastrocnemius_medial")?.tendon, TendonModel::Compliant);
    /// assert_eq!(sim.muscle("semitendinosus")?.tendon, TendonModel::Rigid);
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn set_muscle_tendon(&mut self, name: &str, tendon: TendonModel) -> Result<()> {
        let i = self.muscle_index(name)?;
        self.switch_tendon(i, tendon);
        Ok(())
    }

    fn switch_tendon(&mut self, i: usize, tendon: TendonModel) {
        if self.muscles[i].tendon != tendon {
            self.muscles[i].tendon = tendon;
            self.start_fibre(i);
        }
    }

    /// Multiplies one muscle's Hill parameters by `scale` (maximum force, optimal fibre
    /// length, tendon slack length), from the values it was built with: calling it twice
    /// does not compound. The fibre restarts as [`Self::set_tendon_model`] starts it.
    ///
    /// ```no_run
    /// use myoslice::muscle::MuscleScale;
    /// use myoslice::prelude::*;
    /// let mut sim = Simulation::phantom(SimulationConfig::default())?;
    /// let stronger = MuscleScale { max_force_scale: 1.5, ..MuscleScale::default() };
    /// sim.scale_muscle("semitendinosus", &stronger)?;
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn scale_muscle(&mut self, name: &str, scale: &MuscleScale) -> Result<()> {
        let i = self.muscle_index(name)?;
        scale.check(name)?;
        let m = &mut self.muscles[i];
        let built = m.built_hill;
        m.hill.max_isometric_force = built.max_isometric_force * scale.max_force_scale;
        m.hill.optimal_fibre_length = built.optimal_fibre_length * scale.optimal_fibre_length_scale;
        m.hill.tendon_slack_length = built.tendon_slack_length * scale.tendon_slack_length_scale;
        self.start_fibre(i);
        Ok(())
    }

    /// Every fibre in the state the current models give it at the current path (see
    /// [`Self::start_fibre`]).
    pub(super) fn start_fibres(&mut self) {
        for i in 0..self.muscles.len() {
            self.start_fibre(i);
        }
    }

    /// Muscle `i`'s fibre in the state the current models give it at the current path:
    /// static equilibrium for a compliant Hill unit, the rigid-tendon kinematics otherwise.
    fn start_fibre(&mut self, i: usize) {
        let hill = self.config.muscle_model == MuscleModel::Hill;
        let m = &mut self.muscles[i];
        m.fibre = if hill && m.tendon == TendonModel::Compliant {
            m.hill
                .compliant_tendon_step(m.activation, m.path_length, m.fibre.length, None)
        } else {
            m.hill
                .rigid_tendon_kinematics(m.path_length, m.path_velocity)
        };
    }
}
