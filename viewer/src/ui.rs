//! The control panel: playback, excitation sliders by group, presets, layers and colour
//! maps, a live plot, readouts and error dialogs. State is plain data, testable without a
//! window.

use std::collections::VecDeque;

use myoslice::Simulation;
use myoslice::label_names::Unmapped;
use myoslice::muscle::MuscleGroup;

use crate::camera::CameraPreset;
use crate::colormap::{self, ColorMode};
use crate::model::{ModelSource, Preset};
use crate::scene::SceneOptions;

/// Samples kept for the live plot.
pub const HISTORY: usize = 600;

/// Time series for the live plot.
#[derive(Debug, Clone, Default)]
pub struct History {
    /// Time (s).
    pub t: VecDeque<f64>,
    /// Knee angle (deg).
    pub angle: VecDeque<f64>,
    /// Force (N) of each plotted muscle, in the order of `UiState::plotted`.
    pub forces: Vec<VecDeque<f64>>,
}

impl History {
    /// Appends a sample, dropping the oldest beyond [`HISTORY`].
    pub fn push(&mut self, t: f64, angle_deg: f64, forces: &[f64]) {
        if self.forces.len() != forces.len() {
            self.forces = vec![VecDeque::new(); forces.len()];
            self.t.clear();
            self.angle.clear();
        }
        self.t.push_back(t);
        self.angle.push_back(angle_deg);
        for (q, f) in self.forces.iter_mut().zip(forces) {
            q.push_back(*f);
        }
        while self.t.len() > HISTORY {
            self.t.pop_front();
            self.angle.pop_front();
            for q in &mut self.forces {
                q.pop_front();
            }
        }
    }

    /// Drops everything.
    pub fn clear(&mut self) {
        *self = Self::default();
    }
}

/// What the user asked for this frame, for the app to carry out.
#[derive(Debug, Clone, PartialEq)]
pub enum UiAction {
    /// Rebuild the simulation from its source.
    Reset,
    /// Advance one step of 10 ms while paused.
    Step,
    /// Apply a preset motion.
    Preset(Preset),
    /// Load another model.
    Load(ModelSource),
    /// Move the camera to a preset view.
    Camera(CameraPreset),
}

/// Everything the panel shows and edits.
#[derive(Debug, Clone)]
pub struct UiState {
    /// Simulation running.
    pub playing: bool,
    /// Simulated seconds per real second.
    pub speed: f64,
    /// Body-surface colours.
    pub color_mode: ColorMode,
    /// Layer visibility: bone, muscle, skin.
    pub visible: [bool; 3],
    /// Layer opacity.
    pub opacity: [f32; 3],
    /// Highlighted muscle.
    pub selected: Option<usize>,
    /// Muscle under the cursor in the 3D view.
    pub hovered: Option<usize>,
    /// Muscles in the force plot.
    pub plotted: Vec<usize>,
    /// Live plot data.
    pub history: History,
    /// An error to show in a dialog.
    pub error: Option<String>,
    /// Last frame time (ms) and simulation time per frame (ms).
    pub frame_ms: f32,
    /// Scale of the surface colours in the last frame (log2 area ratio, or metres).
    pub color_range: f32,
    /// Wall time of the last simulation advance (ms).
    pub sim_ms: f32,
    /// Path fields of the "open model" form.
    pub open_volume: String,
    /// Label table path of the form.
    pub open_labels: String,
    /// The user's names file (TOML) of the form.
    pub open_names: String,
    /// What the form takes unknown label names as.
    pub open_unmapped: Unmapped,
    /// The model shown.
    pub source: ModelSource,
    /// Where the panel was drawn last (points): a finger put down there is the panel's.
    pub panel_rect: Option<egui::Rect>,
    /// The tissue audit last asked for.
    pub audit: crate::readouts::AuditReadout,
}

impl Default for UiState {
    fn default() -> Self {
        Self {
            playing: true,
            speed: 0.5,
            color_mode: ColorMode::Area,
            visible: [true, true, true],
            opacity: [1.0, 1.0, 0.45],
            selected: None,
            hovered: None,
            plotted: Vec::new(),
            history: History::default(),
            error: None,
            frame_ms: 0.0,
            color_range: 1.0,
            sim_ms: 0.0,
            open_volume: String::new(),
            open_labels: String::new(),
            open_names: String::new(),
            open_unmapped: Unmapped::Error,
            source: ModelSource::Phantom,
            panel_rect: None,
            audit: Default::default(),
        }
    }
}

impl UiState {
    /// Chooses the default plotted muscles: the largest flexor and extensor.
    pub fn default_plot(&mut self, sim: &Simulation) {
        let pick = |g: MuscleGroup| {
            sim.muscles()
                .iter()
                .enumerate()
                .filter(|(_, m)| m.group == g && m.crosses_knee)
                .max_by(|a, b| {
                    a.1.hill
                        .max_isometric_force
                        .total_cmp(&b.1.hill.max_isometric_force)
                })
                .map(|(i, _)| i)
        };
        self.plotted = [pick(MuscleGroup::Flexor), pick(MuscleGroup::Extensor)]
            .into_iter()
            .flatten()
            .collect();
        self.history.clear();
    }

    /// What the 3D view draws, from the panel's settings.
    pub fn scene_options(&self) -> SceneOptions {
        SceneOptions {
            color_mode: self.color_mode,
            visible: self.visible,
            opacity: self.opacity,
            selected_muscle: self.selected,
            hovered_muscle: self.hovered,
            ..SceneOptions::default()
        }
    }

    /// A click in the 3D view on `picked` (None: empty space): selects that muscle, or
    /// clears the selection when it was already selected or nothing was hit.
    pub fn click(&mut self, picked: Option<usize>) {
        self.selected = if picked == self.selected {
            None
        } else {
            picked
        };
    }

    /// The tooltip of the muscle under the cursor: name, force and knee moment arm.
    pub fn hover_text(&self, sim: &Simulation) -> Option<String> {
        let m = sim.muscles().get(self.hovered?)?;
        let mut text = format!("{}\n{:.0} N", m.name.replace('_', " "), m.force);
        if m.crosses_knee {
            text += &format!(", moment arm {:+.1} cm", m.moment_arm * 100.0);
        }
        text += if self.selected == self.hovered {
            "\nclick to clear"
        } else {
            "\nclick to select"
        };
        Some(text)
    }

    /// Records the simulation's state for the plot.
    pub fn record(&mut self, sim: &Simulation) {
        let forces: Vec<f64> = self
            .plotted
            .iter()
            .map(|&i| sim.muscles()[i].force)
            .collect();
        self.history
            .push(sim.time(), sim.knee_angle().to_degrees(), &forces);
    }

    /// Draws the panel; returns the actions to carry out.
    pub fn show(&mut self, ui: &mut egui::Ui, sim: &mut Simulation) -> Vec<UiAction> {
        let mut actions = Vec::new();
        let panel = egui::Panel::left("controls")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading("myoslice");
                    ui.label(self.source.describe());
                    self.readouts(ui, sim);
                    ui.separator();
                    self.playback(ui, &mut actions);
                    ui.separator();
                    self.muscles(ui, sim, &mut actions);
                    ui.separator();
                    self.display(ui, &mut actions);
                    ui.separator();
                    self.plot(ui, sim);
                    ui.separator();
                    self.open_form(ui, &mut actions);
                });
            });
        self.panel_rect = Some(panel.response.rect);
        let ctx = ui.ctx().clone();
        if let (Some(text), Some(pos)) =
            (self.hover_text(sim), ctx.input(|i| i.pointer.hover_pos()))
        {
            egui::Area::new(egui::Id::unique("hovered muscle"))
                .order(egui::Order::Tooltip)
                .interactable(false)
                .fixed_pos(pos + egui::vec2(16.0, 16.0))
                .show(&ctx, |ui| {
                    egui::Frame::popup(ui.style()).show(ui, |ui| ui.label(text));
                });
        }
        let mut close = false;
        if let Some(msg) = &self.error {
            egui::Window::new("Error")
                .collapsible(false)
                .resizable(false)
                .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
                .show(&ctx, |ui| {
                    ui.label(msg.as_str());
                    if ui.button("OK").clicked() {
                        close = true;
                    }
                });
        }
        if close {
            self.error = None;
        }
        actions
    }

    fn playback(&mut self, ui: &mut egui::Ui, actions: &mut Vec<UiAction>) {
        ui.horizontal(|ui| {
            if ui
                .button(if self.playing { "Pause" } else { "Play" })
                .clicked()
            {
                self.playing = !self.playing;
            }
            if ui.button("Step").clicked() {
                actions.push(UiAction::Step);
            }
            if ui.button("Reset").clicked() {
                actions.push(UiAction::Reset);
            }
        });
        ui.add(
            egui::Slider::new(&mut self.speed, 0.05..=2.0)
                .logarithmic(true)
                .text("speed (× real time)"),
        );
        ui.horizontal_wrapped(|ui| {
            for (p, name) in [
                (Preset::Flexion, "Knee flexion"),
                (Preset::Extension, "Extension"),
                (Preset::CoContraction, "Co-contraction"),
                (Preset::Relax, "Relax"),
            ] {
                if ui.button(name).clicked() {
                    actions.push(UiAction::Preset(p));
                }
            }
        });
    }

    fn muscles(&mut self, ui: &mut egui::Ui, sim: &mut Simulation, _actions: &mut Vec<UiAction>) {
        crate::model_switch::show(ui, sim, self.selected);
        ui.label("Excitation");
        for (group, title) in [
            (MuscleGroup::Flexor, "Flexors"),
            (MuscleGroup::Extensor, "Extensors"),
            (MuscleGroup::Other, "Others"),
        ] {
            egui::CollapsingHeader::new(title)
                .default_open(group != MuscleGroup::Other)
                .show(ui, |ui| {
                    let names: Vec<(usize, String, f64, f64)> = sim
                        .muscles()
                        .iter()
                        .enumerate()
                        .filter(|(_, m)| m.group == group)
                        .map(|(i, m)| (i, m.name.clone(), m.excitation, m.force))
                        .collect();
                    for (i, name, mut e, f) in names {
                        ui.horizontal(|ui| {
                            let sel = self.selected == Some(i);
                            if ui.selectable_label(sel, &name).clicked() {
                                self.selected = if sel { None } else { Some(i) };
                            }
                            if ui
                                .add(egui::Slider::new(&mut e, 0.0..=1.0).show_value(true))
                                .changed()
                            {
                                let _ = sim.set_excitation(&name, e);
                            }
                            ui.label(format!("{f:.0} N"));
                        });
                    }
                });
        }
    }

    fn display(&mut self, ui: &mut egui::Ui, actions: &mut Vec<UiAction>) {
        ui.label("Display");
        egui::ComboBox::from_label("surface colour")
            .selected_text(match self.color_mode {
                ColorMode::Area => "area change",
                ColorMode::Degree => "deformation degree",
                ColorMode::None => "none",
            })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut self.color_mode, ColorMode::Area, "area change");
                ui.selectable_value(
                    &mut self.color_mode,
                    ColorMode::Degree,
                    "deformation degree",
                );
                ui.selectable_value(&mut self.color_mode, ColorMode::None, "none");
            });
        for (i, name) in ["bone", "muscle", "skin"].iter().enumerate() {
            ui.horizontal(|ui| {
                ui.checkbox(&mut self.visible[i], *name);
                ui.add(egui::Slider::new(&mut self.opacity[i], 0.05..=1.0).text("opacity"));
            });
        }
        ui.horizontal_wrapped(|ui| {
            ui.label("camera:");
            for (p, name) in CameraPreset::ALL {
                if ui.button(name).clicked() {
                    actions.push(UiAction::Camera(p));
                }
            }
        });
        self.legend(ui);
    }

    /// The colour bar of the surface colours, with its scale.
    fn legend(&self, ui: &mut egui::Ui) {
        let r = self.color_range.max(1e-6);
        let color_at = |t: f32| -> [f32; 3] {
            match self.color_mode {
                // t in [0, 1] spans area ratios 2^-r .. 2^r.
                ColorMode::Area => colormap::area_color((r * (2.0 * t - 1.0)).exp2() - 1.0, r),
                ColorMode::Degree => colormap::degree_color(t * r, r),
                ColorMode::None => colormap::SKIN,
            }
        };
        let (labels, caption) = match self.color_mode {
            ColorMode::Area => (
                [
                    format!("{:+.0} %", 100.0 * ((-r).exp2() - 1.0)),
                    "no change".to_string(),
                    format!("{:+.0} %", 100.0 * (r.exp2() - 1.0)),
                ],
                "body-surface area change: red shrank, blue grew",
            ),
            ColorMode::Degree => (
                [
                    "0 mm".to_string(),
                    format!("{:.1} mm", 500.0 * r),
                    format!("{:.1} mm", 1000.0 * r),
                ],
                "deformation degree (paper Eq. 5)",
            ),
            ColorMode::None => return,
        };
        let width = ui.available_width().min(280.0);
        let (rect, _) = ui.allocate_exact_size(egui::vec2(width, 14.0), egui::Sense::hover());
        let mut mesh = egui::Mesh::default();
        const STEPS: u32 = 32;
        for k in 0..=STEPS {
            let t = k as f32 / STEPS as f32;
            let c = color_at(t);
            let c = egui::Color32::from(egui::Rgba::from_rgb(c[0], c[1], c[2]));
            let x = rect.left() + t * rect.width();
            mesh.colored_vertex(egui::pos2(x, rect.top()), c);
            mesh.colored_vertex(egui::pos2(x, rect.bottom()), c);
            if k > 0 {
                let i = 2 * k;
                mesh.add_triangle(i - 2, i - 1, i);
                mesh.add_triangle(i - 1, i + 1, i);
            }
        }
        ui.painter().add(egui::Shape::mesh(mesh));
        ui.horizontal(|ui| {
            ui.set_width(width);
            ui.label(egui::RichText::new(&labels[0]).small());
            ui.add_space((width - 150.0).max(0.0) / 2.0);
            ui.label(egui::RichText::new(&labels[1]).small());
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                ui.label(egui::RichText::new(&labels[2]).small());
            });
        });
        ui.label(egui::RichText::new(caption).small());
    }

    fn plot(&mut self, ui: &mut egui::Ui, sim: &Simulation) {
        ui.label("Knee angle (°) and muscle forces (N / 20)");
        let t: Vec<f64> = self.history.t.iter().copied().collect();
        let angle: egui_plot::PlotPoints = t
            .iter()
            .zip(&self.history.angle)
            .map(|(t, a)| [*t, *a])
            .collect();
        let forces: Vec<(String, egui_plot::PlotPoints)> = self
            .plotted
            .iter()
            .zip(&self.history.forces)
            .map(|(&i, q)| {
                let pts: egui_plot::PlotPoints =
                    t.iter().zip(q).map(|(t, f)| [*t, *f / 20.0]).collect();
                (sim.muscles()[i].name.clone(), pts)
            })
            .collect();
        egui_plot::Plot::new("history")
            .height(170.0)
            .legend(egui_plot::Legend::default())
            .show(ui, |p| {
                p.line(egui_plot::Line::new("knee angle", angle));
                for (name, pts) in forces {
                    p.line(egui_plot::Line::new(name, pts));
                }
            });
    }

    /// What becomes of label names no structure is known by, for the next load.
    fn unknown_names(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.label("unknown names");
            for (rule, text) in [
                (Unmapped::Error, "refuse"),
                (Unmapped::Fat, "fat"),
                (Unmapped::Ignore, "background"),
            ] {
                ui.radio_value(&mut self.open_unmapped, rule, text);
            }
        });
    }

    /// In a page, files come from the page's Open button or a drop (no paths to type).
    #[cfg(target_arch = "wasm32")]
    fn open_form(&mut self, ui: &mut egui::Ui, actions: &mut Vec<UiAction>) {
        egui::CollapsingHeader::new("Open model")
            .default_open(false)
            .show(ui, |ui| {
                ui.label(
                    "Drop a label volume (NIfTI, NRRD, a Slicer .seg.nrrd) with its label \
                     table or label list on the page, or a scenario (.toml); or use the \
                     page's Open button.",
                );
                self.unknown_names(ui);
                if ui.button("Phantom").clicked() {
                    actions.push(UiAction::Load(ModelSource::Phantom));
                }
            });
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn open_form(&mut self, ui: &mut egui::Ui, actions: &mut Vec<UiAction>) {
        egui::CollapsingHeader::new("Open model")
            .default_open(false)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.label("volume");
                    ui.text_edit_singleline(&mut self.open_volume);
                });
                ui.horizontal(|ui| {
                    ui.label("labels");
                    ui.text_edit_singleline(&mut self.open_labels);
                });
                ui.horizontal(|ui| {
                    ui.label("names");
                    ui.text_edit_singleline(&mut self.open_names);
                });
                self.unknown_names(ui);
                ui.horizontal(|ui| {
                    if ui.button("Load volume").clicked() {
                        let path = |s: &str| (!s.trim().is_empty()).then(|| s.trim().into());
                        actions.push(UiAction::Load(ModelSource::Volume {
                            volume: self.open_volume.trim().into(),
                            labels: path(&self.open_labels),
                            names: path(&self.open_names),
                            unmapped: self.open_unmapped,
                        }));
                    }
                    if ui.button("Phantom").clicked() {
                        actions.push(UiAction::Load(ModelSource::Phantom));
                    }
                });
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myoslice::SimulationConfig;

    #[test]
    fn the_ui_has_glyphs_for_every_character_of_its_labels() {
        // egui ships no font unless asked (`default_fonts`): every label would be boxes.
        let ctx = egui::Context::default();
        let mut out = ctx.run_ui(egui::RawInput::default(), |_| {});
        out.textures_delta.clear();
        // Every character the interface's sources write, comments included (a superset).
        let text: String = [
            include_str!("ui.rs"),
            include_str!("app.rs"),
            include_str!("readouts.rs"),
        ]
        .concat();
        let mut chars: Vec<char> = text.chars().filter(|c| !c.is_control()).collect();
        chars.sort_unstable();
        chars.dedup();
        let font = egui::FontId::proportional(14.0);
        let missing: String = chars
            .into_iter()
            .filter(|c| !ctx.fonts_mut(|f| f.has_glyph(&font, *c)))
            .collect();
        assert!(missing.is_empty(), "no glyph for {missing:?}");
    }

    #[test]
    fn clicking_a_muscle_selects_it_and_clicking_it_again_or_on_nothing_clears() {
        let mut ui = UiState::default();
        ui.click(Some(3));
        assert_eq!(ui.selected, Some(3));
        ui.click(Some(5));
        assert_eq!(ui.selected, Some(5));
        ui.click(Some(5));
        assert_eq!(ui.selected, None);
        ui.click(Some(2));
        ui.click(None);
        assert_eq!(ui.selected, None);
    }

    #[test]
    fn the_hover_tooltip_names_the_muscle_with_its_force_and_moment_arm() {
        let mut config = SimulationConfig::default();
        config.tissue.enabled = false;
        let sim = Simulation::phantom(config).expect("phantom");
        let mut ui = UiState::default();
        assert_eq!(ui.hover_text(&sim), None);
        let st = sim.muscle_index("semitendinosus").expect("semitendinosus");
        ui.hovered = Some(st);
        let text = ui.hover_text(&sim).expect("a tooltip");
        assert!(text.starts_with("semitendinosus\n"), "{text}");
        assert!(
            text.contains("moment arm +"),
            "a flexor's arm is positive: {text}"
        );
        // A stale index (after loading a smaller model) shows nothing rather than panicking.
        ui.hovered = Some(sim.muscles().len());
        assert_eq!(ui.hover_text(&sim), None);
    }

    #[test]
    fn history_keeps_a_bounded_window_and_resets_on_new_muscles() {
        let mut h = History::default();
        for k in 0..HISTORY + 50 {
            h.push(k as f64, 1.0, &[2.0, 3.0]);
        }
        assert_eq!(h.t.len(), HISTORY);
        assert_eq!(h.t[0], 50.0);
        assert_eq!(h.forces.len(), 2);
        h.push(0.0, 0.0, &[1.0]);
        assert_eq!((h.t.len(), h.forces.len()), (1, 1));
    }

    #[test]
    fn default_state_plays_and_colours_by_area() {
        let s = UiState::default();
        assert!(s.playing && s.color_mode == ColorMode::Area && s.visible.iter().all(|v| *v));
    }
}
