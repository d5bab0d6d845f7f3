//! The panel's model switches: the muscle model, the Hill units' tendons and the selected
//! muscle's own tendon, changed on the running simulation (the core carries the state
//! over, see `Simulation::set_muscle_model`, `set_tendon_model` and `set_muscle_tendon`).

use myoslice::simulation::{MuscleModel, Simulation, TendonModel};

/// Draws the two switches, and with a muscle `selected` a third for its own tendon
/// (`Simulation::set_muscle_tendon`), and applies a change to `sim` at once.
pub fn show(ui: &mut egui::Ui, sim: &mut Simulation, selected: Option<usize>) {
    egui::Grid::new("models").num_columns(2).show(ui, |ui| {
        ui.label("muscle model");
        let mut model = sim.muscle_model();
        choice(
            ui,
            "muscle model",
            &mut model,
            &MuscleModel::ALL,
            |m| match m {
                MuscleModel::Hill => "Hill (De Groote)",
                MuscleModel::Spring => "spring chain (paper)",
            },
        );
        sim.set_muscle_model(model);
        ui.end_row();
        ui.label("tendons");
        let mut tendon = sim.tendon_model();
        ui.add_enabled_ui(model == MuscleModel::Hill, |ui| {
            choice(
                ui,
                "tendons",
                &mut tendon,
                &TendonModel::ALL,
                TendonModel::name,
            );
        });
        // Only when chosen: every muscle takes it, those with a tendon of their own too.
        if tendon != sim.tendon_model() {
            sim.set_tendon_model(tendon);
        }
        ui.end_row();
        if let Some(m) = selected.and_then(|i| sim.muscles().get(i)) {
            let (name, mut own) = (m.name.clone(), m.tendon);
            ui.label(format!("{name}'s tendon"));
            ui.add_enabled_ui(model == MuscleModel::Hill, |ui| {
                choice(
                    ui,
                    "own tendon",
                    &mut own,
                    &TendonModel::ALL,
                    TendonModel::name,
                );
            });
            if own != m.tendon {
                // The name comes from the simulation itself: it cannot be unknown.
                let _ = sim.set_muscle_tendon(&name, own);
            }
            ui.end_row();
        }
    });
}

fn choice<T: Copy + PartialEq>(
    ui: &mut egui::Ui,
    id: &str,
    value: &mut T,
    all: &[T],
    label: fn(T) -> &'static str,
) {
    egui::ComboBox::from_id_salt(id)
        .selected_text(label(*value))
        .show_ui(ui, |ui| {
            for &c in all {
                ui.selectable_value(value, c, label(c));
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use myoslice::SimulationConfig;

    #[test]
    fn drawing_the_switches_changes_no_muscle_s_own_tendon() {
        // The global switch once set every muscle's tendon each frame: a muscle's own
        // tendon must outlive frames where nothing was chosen, selected or not.
        let mut config = SimulationConfig::default();
        config.tissue.enabled = false;
        let mut sim = Simulation::phantom(config).expect("phantom");
        sim.set_muscle_tendon("semitendinosus", TendonModel::Compliant)
            .expect("a muscle of the phantom");
        let st = sim.muscle_index("semitendinosus").expect("a muscle");
        let ctx = egui::Context::default();
        for selected in [None, Some(st), Some(0)] {
            let mut out = ctx.run_ui(egui::RawInput::default(), |ui| show(ui, &mut sim, selected));
            out.textures_delta.clear();
            assert_eq!(sim.muscles()[st].tendon, TendonModel::Compliant);
            assert_eq!(sim.tendon_model(), TendonModel::Rigid);
            assert!(
                sim.muscles()
                    .iter()
                    .enumerate()
                    .all(|(i, m)| i == st || m.tendon == TendonModel::Rigid)
            );
        }
    }
}
