//! Scenario files: an experiment as a TOML file that can be kept and shared.
//!
//! ```toml
//! [model]
//! source = "phantom"          # or "nifti": volume = "..." (NIfTI or NRRD) with labels =
//!                             # "..." (label table or a tool's label list; not for a
//!                             # Slicer .seg.nrrd), optional names = "..." (your names, TOML)
//!                             # and unmapped = "error" | "fat" | "ignore"; paths relative
//!                             # to this file
//! slice_step = 5              # keep every k-th slice (default 5)
//! rays = 48                   # rays per polygon (default 48)
//!
//! [body]
//! mass_kg = 60.0              # default 60
//! height_m = 1.65             # default 1.65
//!
//! [simulation]
//! muscle_model = "hill"       # or "spring" (the paper's), default hill
//! tendon = "rigid"            # or "compliant" (Hill units), default rigid
//! duration_s = 1.0            # required
//! step_s = 0.001              # default 0.001
//! initial_knee_deg = 0.0      # default 0
//! chain_tether = 600.0        # N/m pulling relaxed chains to rest, 0 = off (default 600)
//! chain_tether_release_n = 20.0  # muscle force (N) where the tether lets go (default 20)
//! chain_contact = true        # muscles' chains keep off one another (default true)
//! excitation_scale = 1.0      # factor on every [excitation] value (capped at 1), default 1
//!
//! [tissue]                    # every TissueConfig field, all optional
//! rate_hz = 30.0
//! muscle_contact = false      # push overlapping muscle shapes apart (default false: slow)
//! fat_constraints = true      # fat holds its volume and unfolds inside its iterations
//!
//! [excitation]                # per muscle or group: [[time s, value], ...]
//! hamstrings = [[0.0, 0.0], [0.2, 0.6]]
//!
//! [muscle.hamstrings]         # per muscle or group, factors on the catalogue's values
//! max_force_scale = 1.0       # all default 1, each 0.05 to 20
//! optimal_fibre_length_scale = 1.0
//! tendon_slack_length_scale = 1.0
//!
//! [output]
//! frames = 30                 # output frames over the run (default 25)
//! vtu = true                  # ParaView series (default true)
//! glb = true                  # animated glTF for Blender (default true)
//! audit = false               # every tissue check after each update, audit.csv (slow)
//! ```
//!
//! Groups: `flexors`, `extensors`, `hamstrings`, `quadriceps`, `all`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::lattice::BuildOptions;
use crate::muscle::{MuscleGroup, MuscleScale};
use crate::simulation::{MuscleModel, Schedule, Simulation, SimulationConfig, TendonModel};
use crate::slices::SliceReduction;
use crate::tissue::TissueConfig;

/// Where the model comes from.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSection {
    /// `phantom` or `nifti`.
    #[serde(default = "default_source")]
    pub source: String,
    /// Label volume, NIfTI or NRRD (for `nifti`), relative to the scenario file.
    pub volume: Option<PathBuf>,
    /// Label table or a tool's label list (for `nifti`; none for a 3D Slicer
    /// segmentation, which names its labels).
    pub labels: Option<PathBuf>,
    /// The user's names file (TOML, see [`crate::label_mapping`]).
    pub names: Option<PathBuf>,
    /// What becomes of a label name no structure is known by: `error` (default), `fat`
    /// or `ignore`.
    pub unmapped: Option<String>,
    /// Keep every k-th slice.
    #[serde(default = "default_step")]
    pub slice_step: usize,
    /// Rays per polygon.
    #[serde(default = "default_rays")]
    pub rays: usize,
}

fn default_source() -> String {
    "phantom".into()
}
fn default_step() -> usize {
    5
}
fn default_rays() -> usize {
    48
}

impl Default for ModelSection {
    fn default() -> Self {
        Self {
            source: default_source(),
            volume: None,
            labels: None,
            names: None,
            unmapped: None,
            slice_step: 5,
            rays: 48,
        }
    }
}

/// Body size.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BodySection {
    /// Body mass (kg).
    pub mass_kg: f64,
    /// Body height (m).
    pub height_m: f64,
}

impl Default for BodySection {
    fn default() -> Self {
        Self {
            mass_kg: 60.0,
            height_m: 1.65,
        }
    }
}

/// Run settings.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSection {
    /// Muscle model.
    #[serde(default = "default_model")]
    pub muscle_model: MuscleModel,
    /// Tendons of the Hill units.
    #[serde(default)]
    pub tendon: TendonModel,
    /// Simulated time (s).
    pub duration_s: f64,
    /// Step (s).
    #[serde(default = "default_dt")]
    pub step_s: f64,
    /// Knee angle at the start (deg).
    #[serde(default)]
    pub initial_knee_deg: f64,
    /// The chains' tether (N/m; [`SimulationConfig::chain_tether`]); its default when
    /// absent.
    #[serde(default)]
    pub chain_tether: Option<f64>,
    /// Muscle force (N) at which the tether lets go
    /// ([`SimulationConfig::chain_tether_release_n`]); its default when absent.
    #[serde(default)]
    pub chain_tether_release_n: Option<f64>,
    /// Whether muscles' chains press on one another
    /// ([`SimulationConfig::chain_contact`]); its default when absent.
    #[serde(default)]
    pub chain_contact: Option<bool>,
    /// Factor on every excitation schedule's values (capped at 1); 1 when absent.
    #[serde(default = "one")]
    pub excitation_scale: f64,
}

fn default_model() -> MuscleModel {
    MuscleModel::Hill
}
fn one() -> f64 {
    1.0
}
fn default_dt() -> f64 {
    1e-3
}

/// What to write.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSection {
    /// Frames written over the run (besides the first).
    pub frames: usize,
    /// Write VTU frames and a PVD series.
    pub vtu: bool,
    /// Write an animated GLB.
    pub glb: bool,
    /// Audit the tissue after every update into `audit.csv` (slow: about a second an
    /// update).
    pub audit: bool,
}

impl Default for OutputSection {
    fn default() -> Self {
        Self {
            frames: 25,
            vtu: true,
            glb: true,
            audit: false,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    #[serde(default)]
    model: ModelSection,
    #[serde(default)]
    body: BodySection,
    simulation: SimulationSection,
    #[serde(default)]
    tissue: TissueConfig,
    #[serde(default)]
    excitation: BTreeMap<String, Vec<(f64, f64)>>,
    #[serde(default)]
    muscle: BTreeMap<String, MuscleScale>,
    #[serde(default)]
    output: OutputSection,
}

/// A parsed scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// File it came from (for relative paths and messages).
    pub path: PathBuf,
    /// Model.
    pub model: ModelSection,
    /// Body.
    pub body: BodySection,
    /// Run.
    pub simulation: SimulationSection,
    /// Tissue options.
    pub tissue: TissueConfig,
    /// Excitation schedules by muscle or group name (already scaled by
    /// `simulation.excitation_scale`).
    pub excitation: BTreeMap<String, Schedule>,
    /// Factors on the catalogued parameters by muscle or group name.
    pub muscle: BTreeMap<String, MuscleScale>,
    /// Outputs.
    pub output: OutputSection,
    text: String,
}

impl Scenario {
    /// Reads and checks a scenario file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_str_at(&text, path)
    }

    /// Parses scenario text; `path` locates relative files and names errors.
    pub fn from_str_at(text: &str, path: &Path) -> Result<Self> {
        let err = |reason: String| Error::Parse {
            path: path.into(),
            reason,
        };
        let raw: RawScenario = toml::from_str(text).map_err(|e| err(e.to_string()))?;
        let line_of = |key: &str| {
            text.lines()
                .position(|l| l.trim_start().starts_with(key))
                .map_or(String::new(), |n| format!(" (line {})", n + 1))
        };
        let s = &raw.simulation;
        if !(s.duration_s.is_finite() && s.duration_s > 0.0) {
            return Err(err(format!(
                "simulation.duration_s = {}{}: expected a duration > 0 s",
                s.duration_s,
                line_of("duration_s")
            )));
        }
        if !(s.step_s.is_finite() && s.step_s > 0.0 && s.step_s <= 0.01) {
            return Err(err(format!(
                "simulation.step_s = {}{}: expected 0 < step <= 0.01 s",
                s.step_s,
                line_of("step_s")
            )));
        }
        if !(s.excitation_scale.is_finite() && (0.0..=10.0).contains(&s.excitation_scale)) {
            return Err(err(format!(
                "simulation.excitation_scale = {}{}: expected 0 to 10",
                s.excitation_scale,
                line_of("excitation_scale")
            )));
        }
        for (name, scale) in &raw.muscle {
            scale
                .check(name)
                .map_err(|e| err(format!("{e}{}", line_of(&format!("[muscle.{name}]")))))?;
        }
        for (key, value) in [
            ("chain_tether", s.chain_tether),
            ("chain_tether_release_n", s.chain_tether_release_n),
        ] {
            if let Some(v) = value
                && !(v.is_finite() && (0.0..=1e5).contains(&v))
            {
                return Err(err(format!(
                    "simulation.{key} = {v}{}: expected 0 to 100000",
                    line_of(&format!("{key} "))
                )));
            }
        }
        match raw.model.source.as_str() {
            "phantom" => {
                for (k, given) in [
                    ("names", raw.model.names.is_some()),
                    ("unmapped", raw.model.unmapped.is_some()),
                    ("volume", raw.model.volume.is_some()),
                    ("labels", raw.model.labels.is_some()),
                ] {
                    if given {
                        return Err(err(format!(
                            "model.{k}{}: only for model.source = \"nifti\" (the phantom has \
                             its own labels)",
                            line_of(k)
                        )));
                    }
                }
            }
            "nifti" => {
                let Some(volume) = &raw.model.volume else {
                    return Err(err(
                        "model.volume is required when model.source = \"nifti\"".into(),
                    ));
                };
                for (k, p) in [
                    ("volume", Some(volume)),
                    ("labels", raw.model.labels.as_ref()),
                ]
                .into_iter()
                .chain([("names", raw.model.names.as_ref())])
                {
                    let Some(p) = p else { continue };
                    let full = resolve(path, p);
                    if !full.exists() {
                        return Err(err(format!(
                            "model.{k} = {}{}: file not found ({})",
                            p.display(),
                            line_of(k),
                            full.display()
                        )));
                    }
                }
                if let Some(u) = &raw.model.unmapped
                    && crate::label_names::Unmapped::parse(u).is_none()
                {
                    return Err(err(format!(
                        "model.unmapped = \"{u}\"{}: expected \"error\", \"fat\" or \"ignore\"",
                        line_of("unmapped")
                    )));
                }
            }
            other => {
                return Err(err(format!(
                    "model.source = \"{other}\"{}: expected \"phantom\" or \"nifti\"",
                    line_of("source")
                )));
            }
        }
        if raw.output.frames > 100_000 {
            return Err(err(format!(
                "output.frames = {}{}: expected at most 100000",
                raw.output.frames,
                line_of("frames")
            )));
        }
        let mut excitation = BTreeMap::new();
        let gain = raw.simulation.excitation_scale;
        for (name, pts) in raw.excitation {
            // Checked as written, then scaled: a bad value is named as the user wrote it.
            Schedule::new(pts.clone())
                .map_err(|e| err(format!("excitation.{name}{}: {e}", line_of(&name))))?;
            let pts = pts
                .into_iter()
                .map(|(t, v)| (t, (v * gain).min(1.0)))
                .collect();
            let sched = Schedule::new(pts)
                .map_err(|e| err(format!("excitation.{name}{}: {e}", line_of(&name))))?;
            excitation.insert(name, sched);
        }
        Ok(Self {
            path: path.into(),
            model: raw.model,
            body: raw.body,
            simulation: raw.simulation,
            tissue: raw.tissue,
            excitation,
            muscle: raw.muscle,
            output: raw.output,
            text: text.to_string(),
        })
    }

    /// The simulation configuration it describes.
    pub fn config(&self) -> SimulationConfig {
        let d = SimulationConfig::default();
        let s = &self.simulation;
        SimulationConfig {
            body_mass_kg: self.body.mass_kg,
            height_m: self.body.height_m,
            muscle_model: s.muscle_model,
            tendon: s.tendon,
            initial_knee_deg: s.initial_knee_deg,
            max_step_s: s.step_s,
            chain_tether: s.chain_tether.unwrap_or(d.chain_tether),
            chain_tether_release_n: s.chain_tether_release_n.unwrap_or(d.chain_tether_release_n),
            chain_contact: s.chain_contact.unwrap_or(d.chain_contact),
            tissue: self.tissue.clone(),
            ..d
        }
    }

    /// The lattice options it describes.
    pub fn build_options(&self) -> BuildOptions {
        BuildOptions {
            reduction: SliceReduction {
                slice_step: self.model.slice_step,
                pixel_mm: None,
            },
            rays: self.model.rays,
            ..BuildOptions::default()
        }
    }

    /// Builds the simulation with its schedules applied.
    pub fn build(&self) -> Result<Simulation> {
        self.check()?;
        self.build_on(self.lattice()?)
    }

    /// Checks the simulation settings it describes (as [`Self::build`] does first, before
    /// the slow part).
    pub fn check(&self) -> Result<()> {
        self.checked_config().map(|_| ())
    }

    fn checked_config(&self) -> Result<SimulationConfig> {
        let config = self.config();
        config.validate().map_err(|e| Error::Parse {
            path: self.path.clone(),
            reason: e.to_string(),
        })?;
        Ok(config)
    }

    /// The lattice of its model (the slow part of [`Self::build`]): the phantom's, or the
    /// label volume's read with its labels and names.
    pub fn lattice(&self) -> Result<crate::lattice::Lattice> {
        let (volume, table) = match self.model.source.as_str() {
            "nifti" => {
                let v = resolve(
                    &self.path,
                    self.model.volume.as_deref().unwrap_or(Path::new("")),
                );
                let l = self.model.labels.as_deref().map(|l| resolve(&self.path, l));
                let unmapped = self
                    .model
                    .unmapped
                    .as_deref()
                    .and_then(crate::label_names::Unmapped::parse)
                    .unwrap_or_default();
                let mut mapping = crate::label_mapping::LabelMapping::new(unmapped);
                if let Some(n) = &self.model.names {
                    mapping = mapping.with_names_file(resolve(&self.path, n))?;
                }
                crate::io::read_input(v, l.as_deref(), mapping)?
            }
            _ => crate::phantom::Phantom::default().generate()?,
        };
        crate::lattice::Lattice::build(&volume, &table, &self.build_options())
    }

    /// What [`Self::lattice`] depends on, as text: two scenarios with the same key build
    /// the same lattice (their other sections may differ), so a lattice built for one
    /// serves the other (sweeps build each model once per process).
    pub fn lattice_key(&self) -> String {
        let m = &self.model;
        // Each file read by its full path, size and modification time: an edited file
        // is a new model (a volume's detached data file or PNG slices too).
        let stamp = |full: PathBuf| {
            let full = std::fs::canonicalize(&full).unwrap_or(full);
            let meta = std::fs::metadata(&full).ok();
            (
                full,
                meta.as_ref().map(std::fs::Metadata::len),
                meta.and_then(|m| m.modified().ok()),
            )
        };
        let file = |p: &Option<PathBuf>| p.as_ref().map(|p| stamp(resolve(&self.path, p)));
        let volume: Option<Vec<_>> = m.volume.as_ref().map(|p| {
            crate::io::input_files(resolve(&self.path, p))
                .into_iter()
                .map(stamp)
                .collect()
        });
        format!(
            "{}|{:?}|{:?}|{:?}|{:?}|{:?}",
            m.source,
            volume,
            file(&m.labels),
            file(&m.names),
            m.unmapped,
            self.build_options()
        )
    }

    /// Builds the simulation on a lattice of its model ([`Self::lattice`], perhaps kept
    /// from an earlier build with the same [`Self::lattice_key`]), with its schedules and
    /// muscle factors applied.
    pub fn build_on(&self, lattice: crate::lattice::Lattice) -> Result<Simulation> {
        let mut sim = self.simulation_on(lattice)?;
        self.apply_schedules(&mut sim)?;
        Ok(sim)
    }

    /// The simulation its settings make on `lattice`, before [`Self::apply_schedules`]:
    /// it depends only on the lattice and [`Self::config`], so one built for a scenario
    /// serves (cloned) every scenario with the same lattice key and configuration.
    pub fn simulation_on(&self, lattice: crate::lattice::Lattice) -> Result<Simulation> {
        let config = self.checked_config()?;
        Simulation::new(lattice, config, &crate::muscle::MuscleCatalogue::default())
    }

    /// Applies the excitation schedules and the muscles' parameter factors to a
    /// simulation (checking every name).
    ///
    /// The broader name first, the narrower after it, whatever their order in the file:
    /// `all`, then `flexors` and `extensors`, then `hamstrings` and `quadriceps`, then
    /// single muscles, so that `[muscle.semitendinosus]` overrides `[muscle.hamstrings]`
    /// for that muscle.
    pub fn apply_schedules(&self, sim: &mut Simulation) -> Result<()> {
        for (name, sched) in by_breadth(&self.excitation) {
            for m in self.members(sim, "excitation", name)? {
                sim.set_schedule(&m, sched.clone())?;
            }
        }
        for (name, scale) in by_breadth(&self.muscle) {
            for m in self.members(sim, "muscle", name)? {
                sim.scale_muscle(&m, scale)?;
            }
        }
        Ok(())
    }

    /// The muscles `name` (a muscle or group) stands for, in the error naming section and
    /// line when none.
    fn members(&self, sim: &Simulation, section: &str, name: &str) -> Result<Vec<String>> {
        let targets = group_members(sim, name);
        if !targets.is_empty() {
            return Ok(targets);
        }
        let known: Vec<&str> = sim.muscle_names();
        let e = Error::unknown_name(
            "muscle or group",
            name,
            known.into_iter().chain(GROUPS.iter().copied()),
        );
        let line = self
            .text
            .lines()
            .position(|l| l.contains(name))
            .map_or(String::new(), |n| format!(" (line {})", n + 1));
        Err(Error::Parse {
            path: self.path.clone(),
            reason: format!("{section}.{name}{line}: {e}"),
        })
    }
}

/// Entries from the broadest group to single muscles (name order within a rank).
fn by_breadth<T>(entries: &BTreeMap<String, T>) -> Vec<(&str, &T)> {
    let rank = |n: &str| match n {
        "all" => 0,
        "flexors" | "extensors" => 1,
        "hamstrings" | "quadriceps" => 2,
        _ => 3,
    };
    let mut v: Vec<(&str, &T)> = entries.iter().map(|(k, t)| (k.as_str(), t)).collect();
    v.sort_by_key(|(k, _)| rank(k));
    v
}

/// Group names scenarios accept.
pub const GROUPS: [&str; 5] = ["flexors", "extensors", "hamstrings", "quadriceps", "all"];

/// Muscles a name stands for: itself, or the members of a group.
pub fn group_members(sim: &Simulation, name: &str) -> Vec<String> {
    const HAMSTRINGS: [&str; 4] = [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
    ];
    const QUADRICEPS: [&str; 4] = [
        "rectus_femoris",
        "vastus_lateralis",
        "vastus_medialis",
        "vastus_intermedius",
    ];
    let all = sim.muscles();
    let pick = |f: &dyn Fn(&crate::muscle::MuscleUnit) -> bool| {
        all.iter()
            .filter(|m| f(m))
            .map(|m| m.name.clone())
            .collect()
    };
    match name {
        "flexors" => pick(&|m| m.group == MuscleGroup::Flexor),
        "extensors" => pick(&|m| m.group == MuscleGroup::Extensor),
        "hamstrings" => pick(&|m| HAMSTRINGS.contains(&m.name.as_str())),
        "quadriceps" => pick(&|m| QUADRICEPS.contains(&m.name.as_str())),
        "all" => pick(&|_| true),
        n => pick(&|m| m.name == n),
    }
}

fn resolve(scenario: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        scenario.parent().unwrap_or(Path::new(".")).join(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(t: &str) -> Result<Scenario> {
        Scenario::from_str_at(t, Path::new("test.toml"))
    }

    /// The message of the error `t` gives.
    fn parse_err(t: &str) -> String {
        parse(t).unwrap_err().to_string()
    }

    #[test]
    fn a_minimal_scenario_parses_with_defaults() {
        let s = parse(
            "[simulation]\nduration_s = 0.5\n[excitation]\nhamstrings = [[0.0, 0.0], [0.1, 0.5]]\n",
        )
        .unwrap();
        assert_eq!(s.model.source, "phantom");
        assert_eq!(s.simulation.step_s, 1e-3);
        assert_eq!(s.output.frames, 25);
        assert!((s.excitation["hamstrings"].value(0.05) - 0.25).abs() < 1e-12);
    }

    #[test]
    fn bad_scenarios_name_the_problem() {
        let e = parse_err("[simulation]\nduration_s = 0.5\nbogus = 1\n");
        assert!(e.contains("bogus") && e.contains("line 3"), "{e}");
        let e = parse_err("[simulation]\nduration_s = \"long\"\n");
        assert!(e.contains("duration_s"), "{e}");
        let e = parse_err("[simulation]\nduration_s = -1\n");
        assert!(e.contains("duration_s") && e.contains("line 2"), "{e}");
        let e = parse_err(
            "[model]\nsource = \"nifti\"\nvolume = \"nope.nii\"\nlabels = \"nope.json\"\n[simulation]\nduration_s = 1\n",
        );
        assert!(e.contains("model.volume") && e.contains("not found"), "{e}");
        let e = parse_err(
            "[model]\nsource = \"phantom\"\nnames = \"n.toml\"\n[simulation]\nduration_s = 1\n",
        );
        assert!(
            e.contains("model.names (line 3)") && e.contains("only for"),
            "{e}"
        );
        let e = parse_err("[model]\nsource = \"nifti\"\n[simulation]\nduration_s = 1\n");
        assert!(e.contains("model.volume is required"), "{e}");
        let e = parse_err("[simulation]\nduration_s = 1\n[excitation]\nx = [[0.0, 2.0]]\n");
        assert!(e.contains("excitation.x"), "{e}");
        let e = parse_err(
            "[simulation]\nduration_s = 1\nchain_tether = 600\nchain_tether_release_n = -5\n",
        );
        assert!(
            e.contains("simulation.chain_tether_release_n = -5") && e.contains("line 4"),
            "{e}"
        );
        let e = parse_err("[simulation]\nduration_s = 1\nchain_tether = nan\n");
        assert!(
            e.contains("simulation.chain_tether = NaN") && e.contains("line 3"),
            "{e}"
        );
    }

    #[test]
    fn excitation_scale_multiplies_every_schedule_and_caps_at_one() {
        let s = parse(
            "[simulation]\nduration_s = 1\nexcitation_scale = 1.5\n[excitation]\nhamstrings = [[0.0, 0.4], [0.2, 0.8]]\n",
        )
        .unwrap();
        assert_eq!(
            s.excitation["hamstrings"].points(),
            &[(0.0, 0.4 * 1.5), (0.2, 1.0)]
        );
        let e = parse_err("[simulation]\nduration_s = 1\nexcitation_scale = -1\n");
        assert!(
            e.contains("excitation_scale = -1") && e.contains("line 3"),
            "{e}"
        );
    }

    #[test]
    fn muscle_factors_are_read_per_name_and_checked() {
        let s = parse("[simulation]\nduration_s = 1\n[muscle.hamstrings]\nmax_force_scale = 1.5\n")
            .unwrap();
        let f = s.muscle["hamstrings"];
        assert_eq!(
            (
                f.max_force_scale,
                f.optimal_fibre_length_scale,
                f.tendon_slack_length_scale
            ),
            (1.5, 1.0, 1.0)
        );
        let e =
            parse_err("[simulation]\nduration_s = 1\n[muscle.hamstrings]\nmax_force_scale = 0\n");
        assert!(
            e.contains("muscle.hamstrings.max_force_scale") && e.contains("line 3"),
            "{e}"
        );
        let e = parse_err("[simulation]\nduration_s = 1\n[muscle.hamstrings]\nforce = 2\n");
        assert!(e.contains("force"), "{e}");
    }

    #[test]
    fn the_chains_tether_is_read_from_the_simulation_section_or_left_at_its_default() {
        let d = SimulationConfig::default();
        let s = parse("[simulation]\nduration_s = 1\n").unwrap().config();
        assert_eq!(
            (s.chain_tether, s.chain_tether_release_n),
            (d.chain_tether, d.chain_tether_release_n)
        );
        let s = parse(
            "[simulation]\nduration_s = 1\nchain_tether = 0\nchain_tether_release_n = 35.5\n",
        )
        .unwrap()
        .config();
        assert_eq!((s.chain_tether, s.chain_tether_release_n), (0.0, 35.5));
    }
}
