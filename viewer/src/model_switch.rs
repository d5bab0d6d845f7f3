//! The panel's model switches: the muscle model and the Hill units' tendons, changed on
//! the running simulation (the core carries the state over, see
//! `Simulation::set_muscle_model` and `Simulation::set_tendon_model`).

use myoslice::simulation::{MuscleModel, Simulation, TendonModel};

/// Draws the two switches and applies a change to `sim` at once.
pub fn show(ui: &mut egui::Ui, sim: &mut Simulation) {
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
