//! Where a simulation's wall-clock time goes: cumulative timers of its `step` calls.

use std::time::Duration;

use crate::tissue::TissuePhases;

/// Wall-clock time spent inside [`Simulation::step`](crate::Simulation::step) since the
/// simulation was built (a clone starts with its original's) or the timers were reset,
/// split into the tissue updates (phase by phase) and the rest (muscles and skeleton).
///
/// They measure the machine, not the model: they are never part of a checkpoint, and
/// `set_state` leaves them alone. Reading them from Python next to a timer of the call
/// gives exactly what the binding adds.
///
/// ```
/// use myoslice::StepTimers;
/// let t = StepTimers::default();
/// assert_eq!(t.calls, 0);
/// assert_eq!(t.realtime_factor(), None);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepTimers {
    /// `step` calls that ran, failed ones included (not those refused for their `dt`).
    pub calls: u64,
    /// Muscle and skeleton steps taken (of at most `max_step_s` each), failed calls' included.
    pub steps: u64,
    /// Tissue updates run within the calls.
    pub tissue_updates: u64,
    /// Simulated time the successful calls advanced (s).
    pub simulated_s: f64,
    /// Wall-clock time inside the calls (s).
    pub wall_s: f64,
    /// Of `wall_s`, the part spent updating the tissue (s). The muscles and the skeleton
    /// step on beside each update's validity guard (see
    /// [`Simulation::step`](crate::Simulation::step)), so their steps can run within it
    /// (on another thread, or on the guard's own while it waits for its parallel work),
    /// and so can the placing of the next update's muscle shapes once they are done.
    pub tissue_wall_s: f64,
    /// Each phase of the updates: part of `tissue_wall_s` (the rest is the backup a call
    /// takes before its first update and the check that everything stayed finite), but
    /// for muscle shapes placed beside the last update's guard, which count in
    /// `muscle_shapes_s` only.
    pub tissue_phases: TissuePhases,
}

impl StepTimers {
    /// Wall-clock time of the calls outside tissue updates (s): the muscles and the
    /// skeleton, less their steps that ran beside an update's guard.
    pub fn muscles_wall_s(&self) -> f64 {
        (self.wall_s - self.tissue_wall_s).max(0.0)
    }

    /// Simulated seconds per wall-clock second; None before any time was measured.
    pub fn realtime_factor(&self) -> Option<f64> {
        (self.wall_s > 0.0).then(|| self.simulated_s / self.wall_s)
    }

    /// Records one call.
    pub(crate) fn add_call(&mut self, wall: Duration, steps: u64, simulated_s: f64) {
        self.calls += 1;
        self.steps += steps;
        self.simulated_s += simulated_s;
        self.wall_s += wall.as_secs_f64();
    }

    /// Records one tissue update within a call, and its phases.
    pub(crate) fn add_tissue(&mut self, wall: Duration, phases: &TissuePhases) {
        self.tissue_updates += 1;
        self.tissue_wall_s += wall.as_secs_f64();
        self.tissue_phases.add(phases);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn muscle_time_is_what_the_tissue_leaves() {
        let mut t = StepTimers::default();
        t.add_call(Duration::from_millis(30), 30, 0.03);
        let phases = TissuePhases {
            guard_s: 0.004,
            ..Default::default()
        };
        t.add_tissue(Duration::from_millis(10), &phases);
        assert_eq!(t.tissue_phases, phases);
        assert_eq!((t.calls, t.steps, t.tissue_updates), (1, 30, 1));
        assert!((t.muscles_wall_s() - 0.02).abs() < 1e-12);
        assert!((t.realtime_factor().unwrap_or(0.0) - 1.0).abs() < 1e-9);
    }
}
