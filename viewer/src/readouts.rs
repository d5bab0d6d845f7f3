//! The panel's readouts: time, knee, timings, sizes, the tissue's metrics of the last
//! update, and on request the full tissue audit (every soundness check, as a user's tools
//! would measure it).

use myoslice::Simulation;
use myoslice::tissue::TissueAudit;

use crate::ui::UiState;

/// The tissue audit last asked for, and when: it takes about a second on a whole leg, so it
/// runs when the user asks, not every frame.
#[derive(Debug, Clone, Default)]
pub struct AuditReadout {
    /// Simulated time (s) and tissue update of the audit, and the audit.
    last: Option<(f64, u64, TissueAudit)>,
}

impl AuditReadout {
    /// Audits the tissue of `sim` now (nothing without tissue).
    pub fn run(&mut self, sim: &Simulation) {
        self.last = sim.audit().map(|a| {
            let updates = sim.tissue().map_or(0, |t| t.updates());
            (sim.time(), updates, a)
        });
    }

    /// The audit last taken: simulated time, tissue update, and the audit.
    pub fn last(&self) -> Option<&(f64, u64, TissueAudit)> {
        self.last.as_ref()
    }

    /// The "Tissue audit" section: a button, and the last audit's lines.
    fn show(&mut self, ui: &mut egui::Ui, sim: &Simulation) {
        if sim.tissue().is_none() {
            return;
        }
        egui::CollapsingHeader::new("Tissue audit")
            .default_open(false)
            .show(ui, |ui| {
                if ui
                    .button("Check now")
                    .on_hover_text(
                        "Every soundness check of the tissue, measured as ParaView would \
                         (corner Jacobians) and by winding numbers; about a second",
                    )
                    .clicked()
                {
                    self.run(sim);
                }
                let Some((time, update, a)) = &self.last else {
                    return;
                };
                let moved = sim.tissue().is_some_and(|t| t.updates() != *update);
                ui.label(format!(
                    "at {time:.3} s{}",
                    if moved {
                        " (the tissue has moved since)"
                    } else {
                        ""
                    }
                ));
                egui::Grid::new("audit").num_columns(2).show(ui, |ui| {
                    for l in a.lines() {
                        ui.label(l.check);
                        let colour = if l.holds {
                            ui.visuals().text_color()
                        } else {
                            ui.visuals().warn_fg_color
                        };
                        ui.colored_label(colour, l.found);
                        ui.end_row();
                    }
                });
            });
    }
}

impl UiState {
    pub(crate) fn readouts(&mut self, ui: &mut egui::Ui, sim: &Simulation) {
        let lat = sim.lattice();
        egui::Grid::new("readouts").num_columns(2).show(ui, |ui| {
            ui.label("time");
            ui.label(format!("{:.3} s", sim.time()));
            ui.end_row();
            ui.label("knee angle");
            ui.label(format!(
                "{:.1}°  ({:+.0}°/s)",
                sim.knee_angle().to_degrees(),
                sim.knee_velocity().to_degrees()
            ));
            ui.end_row();
            ui.label("knee torque");
            ui.label(format!("{:+.1} N·m", sim.knee_torque()));
            ui.end_row();
            ui.label("frame / sim");
            ui.label(format!("{:.1} ms / {:.1} ms", self.frame_ms, self.sim_ms));
            ui.end_row();
            // The core's own step timers, since the start: how fast the model runs here
            // and how much of it the tissue takes.
            let t = sim.timers();
            if let Some(f) = t.realtime_factor() {
                ui.label("stepping");
                ui.label(format!(
                    "{f:.2}× real time, tissue {:.0} %",
                    100.0 * t.tissue_wall_s / t.wall_s
                ));
                ui.end_row();
            }
            ui.label("elements");
            ui.label(format!(
                "{} fat hex, {} muscles, {} bones",
                lat.fat.hexes.len(),
                lat.muscles.len(),
                lat.bones.len()
            ));
            ui.end_row();
            if let Some(m) = sim.tissue_metrics() {
                ui.label("tissue");
                ui.label(format!(
                    "min vol {:.2}, max |ΔA| {:.2}, folded (VTK) {}",
                    m.min_volume_ratio, m.max_abs_area_change, m.inverted
                ));
                ui.end_row();
            }
            if let Some(t) = sim.tissue() {
                let g = t.guard_tally();
                ui.label("guard");
                ui.label(format!(
                    "stepped in at {} updates ({} vertices)",
                    g.updates, g.vertices
                ));
                ui.end_row();
            }
            if !sim.warnings().is_empty() {
                ui.label("warnings");
                ui.label(format!(
                    "{} muscles built from the default rule",
                    sim.warnings().len()
                ))
                .on_hover_text(sim.warnings().join("\n"));
                ui.end_row();
            }
        });
        self.audit.show(ui, sim);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myoslice::SimulationConfig;

    #[test]
    fn an_audit_lists_every_check_and_flags_what_fails() {
        let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
        let mut r = AuditReadout::default();
        assert!(r.last().is_none());
        r.run(&sim);
        let (time, update, a) = r.last().unwrap();
        assert_eq!((*time, *update), (0.0, 0));
        let lines = a.lines();
        assert_eq!(lines.len(), 10);
        let folded = &lines[0];
        assert_eq!(folded.found, a.folded_fat.to_string());
        assert_eq!(folded.holds, a.folded_fat == 0);
        // The phantom's gluteus medius and minimus overlap a few millimetres as built.
        let in_muscle = lines
            .iter()
            .find(|l| l.check == "muscle in muscle")
            .unwrap();
        assert!(!in_muscle.holds, "{in_muscle:?}");
        let mut bad = *a;
        bad.skin_crossings = 3;
        let crossings = bad
            .lines()
            .into_iter()
            .find(|l| l.check == "skin crossings");
        assert_eq!(
            crossings.map(|l| (l.found, l.holds)),
            Some(("3".into(), false))
        );
    }

    #[test]
    fn no_tissue_no_audit() {
        let mut cfg = SimulationConfig::default();
        cfg.tissue.enabled = false;
        let sim = Simulation::phantom(cfg).unwrap();
        let mut r = AuditReadout::default();
        r.run(&sim);
        assert!(r.last().is_none());
    }
}
