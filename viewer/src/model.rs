//! Which model to load: the phantom, a label volume (NIfTI, NRRD, Slicer segmentation)
//! with what its labels mean, or a scenario.

use std::path::PathBuf;

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
        }
    }

    /// A short name.
    pub fn describe(&self) -> String {
        match self {
            ModelSource::Phantom => "built-in phantom".into(),
            ModelSource::Volume { volume, .. } => volume.display().to_string(),
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
