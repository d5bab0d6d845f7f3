//! Which model to load: the phantom, a label volume (NIfTI, NRRD, Slicer segmentation)
//! with what its labels mean, or a scenario.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use myoslice::prelude::*;

/// A model source, as given on the command line or picked in the UI.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum ModelSource {
    /// The built-in phantom.
    #[default]
    Phantom,
    /// A label volume (NIfTI or NRRD) and its label table or a tool's label list; a 3D
    /// Slicer segmentation names its own labels.
    Volume {
        /// Volume path.
        volume: PathBuf,
        /// Label table or label list (None: the segmentation's own names).
        labels: Option<PathBuf>,
        /// The user's names file (TOML).
        names: Option<PathBuf>,
        /// What becomes of label names no structure is known by.
        unmapped: Unmapped,
    },
    /// Files already read (a web page's picked or dropped files): a label volume and,
    /// unless it names its own labels, its label table or label list.
    Files {
        /// The volume's file name (for messages, and its format's ending).
        volume_name: String,
        /// The volume's bytes.
        volume: Arc<[u8]>,
        /// The label file's name and text.
        labels: Option<(String, Arc<str>)>,
        /// What becomes of label names no structure is known by.
        unmapped: Unmapped,
    },
    /// A scenario's text and file name (its model files, if any, are read from where
    /// it names them).
    ScenarioText {
        /// The file name.
        name: String,
        /// The TOML text.
        text: Arc<str>,
    },
}

impl ModelSource {
    /// Builds the simulation.
    pub fn load(&self, config: SimulationConfig) -> Result<Simulation> {
        match self {
            ModelSource::Phantom => Simulation::phantom(config).context("building the phantom"),
            ModelSource::Volume {
                volume,
                labels,
                names,
                unmapped,
            } => {
                for (what, p) in [("volume", Some(volume)), ("label file", labels.as_ref())]
                    .into_iter()
                    .chain([("names file", names.as_ref())])
                {
                    if let Some(p) = p
                        && !p.exists()
                    {
                        bail!("{what} {} does not exist", p.display());
                    }
                }
                let mut mapping = LabelMapping::new(*unmapped);
                if let Some(n) = names {
                    mapping = mapping.with_names_file(n)?;
                }
                Simulation::from_file(
                    volume,
                    labels.as_deref(),
                    mapping,
                    &BuildOptions::default(),
                    config,
                )
                .with_context(|| format!("building the model from {}", volume.display()))
            }
            ModelSource::Files {
                volume_name,
                volume,
                labels,
                unmapped,
            } => {
                let labels = labels.as_ref().map(|(n, t)| (&**t, n.as_str()));
                let (v, t) =
                    myoslice::io::parse_segmentation(volume, volume_name, labels, *unmapped)
                        .with_context(|| format!("reading {volume_name}"))?;
                let lattice = Lattice::build(&v, &t, &BuildOptions::default())
                    .with_context(|| format!("building the model from {volume_name}"))?;
                Simulation::new(
                    lattice,
                    config,
                    &myoslice::muscle::MuscleCatalogue::default(),
                )
                .with_context(|| format!("building the model from {volume_name}"))
            }
            ModelSource::ScenarioText { name, text } => {
                Scenario::from_str_at(text, Path::new(name))
                    .and_then(|sc| sc.build())
                    .with_context(|| format!("building the scenario {name}"))
            }
        }
    }

    /// A short name.
    pub fn describe(&self) -> String {
        match self {
            ModelSource::Phantom => "built-in phantom".into(),
            ModelSource::Volume { volume, .. } => volume.display().to_string(),
            ModelSource::Files { volume_name, .. } => volume_name.clone(),
            ModelSource::ScenarioText { name, .. } => name.clone(),
        }
    }
}

/// Preset motions: excitation per muscle group.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    /// Everything relaxed.
    Relax,
    /// Knee flexion by the hamstrings (the paper's experiment).
    Flexion,
    /// Knee extension by the quadriceps.
    Extension,
    /// Hamstrings and quadriceps together.
    CoContraction,
}

impl Preset {
    /// Parses `relax|flexion|extension|cocontraction`.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "relax" | "rest" => Self::Relax,
            "flexion" => Self::Flexion,
            "extension" => Self::Extension,
            "cocontraction" | "co-contraction" => Self::CoContraction,
            _ => return None,
        })
    }

    /// Sets the excitations of `sim` for this preset.
    pub fn apply(self, sim: &mut Simulation) -> Result<()> {
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
        let names: Vec<String> = sim.muscle_names().iter().map(|s| s.to_string()).collect();
        for n in &names {
            let v = match self {
                Preset::Relax => 0.0,
                Preset::Flexion => f64::from(u8::from(HAMSTRINGS.contains(&n.as_str()))) * 0.6,
                Preset::Extension => f64::from(u8::from(QUADRICEPS.contains(&n.as_str()))) * 0.5,
                Preset::CoContraction => {
                    if HAMSTRINGS.contains(&n.as_str()) || QUADRICEPS.contains(&n.as_str()) {
                        0.4
                    } else {
                        0.0
                    }
                }
            };
            sim.set_excitation(n, v)?;
        }
        Ok(())
    }
}
