//! Which model to load: the phantom, a label volume (NIfTI, NRRD, Slicer segmentation)
//! with what its labels mean, or a scenario.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, anyhow, bail};
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

    /// The model of files already read (a web page's picked or dropped files, with their
    /// names): a scenario, or a volume with its label file, told apart by content as the
    /// command line does ([`myoslice::io::InputKind::sniff_head`]).
    pub fn from_files(files: Vec<(String, Vec<u8>)>, unmapped: Unmapped) -> Result<Self> {
        use myoslice::io::InputKind;
        if files.is_empty() {
            return Err(anyhow!("no file given"));
        }
        let mut volumes = Vec::new();
        let mut others = Vec::new();
        for (name, bytes) in files {
            if name.to_ascii_lowercase().ends_with(".nhdr") {
                return Err(anyhow!(
                    "{name}: a detached NRRD header's data file cannot be read in a page; save \
                     the volume as one .nrrd (or NIfTI) file"
                ));
            }
            match InputKind::sniff_head(&bytes, Path::new(&name)) {
                Ok(InputKind::Volume) => volumes.push((name, bytes)),
                Ok(InputKind::Scenario) => others.push((name, bytes, true)),
                Ok(InputKind::PngStack { .. }) => {
                    return Err(anyhow!(
                        "{name}: a PNG stack's manifest: its slices are a folder, which a page \
                         cannot read; open the stack as one NIfTI or NRRD volume instead"
                    ));
                }
                // Not a volume, scenario or manifest: a label file (its reader says more).
                Err(_) => others.push((name, bytes, false)),
            }
        }
        let text = |name: &str, bytes: Vec<u8>| {
            String::from_utf8(bytes).map_err(|_| anyhow!("{name} is not UTF-8 text"))
        };
        match (volumes.len(), others.len()) {
            (0, 1) if others[0].2 => {
                let (name, bytes, _) = others.remove(0);
                let text = text(&name, bytes)?;
                Ok(ModelSource::ScenarioText {
                    name,
                    text: text.into(),
                })
            }
            (1, n) if n <= 1 => {
                let (volume_name, volume) = volumes.remove(0);
                let labels = match others.pop() {
                    Some((name, bytes, _)) => {
                        let t = text(&name, bytes)?;
                        Some((name, t.into()))
                    }
                    None => None,
                };
                Ok(ModelSource::Files {
                    volume_name,
                    volume: volume.into(),
                    labels,
                    unmapped,
                })
            }
            (0, _) => Err(anyhow!(
                "none of the files is a label volume (NIfTI .nii/.nii.gz, NRRD .nrrd, a Slicer \
                 segmentation .seg.nrrd) or a scenario"
            )),
            (1, o) => Err(anyhow!(
                "give one label volume with at most one label file (got {o} other files)"
            )),
            _ => Err(anyhow!(
                "give one label volume with at most one label file; these read as volumes \
                 (binary, or not UTF-8 text): {}",
                volumes
                    .iter()
                    .map(|v| v.0.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn file(name: &str, bytes: &[u8]) -> (String, Vec<u8>) {
        (name.to_string(), bytes.to_vec())
    }

    /// A NIfTI-1 header's start (its size, 348) and a gzip stream's magic.
    const NII: &[u8] = &[0x5c, 0x01, 0x00, 0x00, 0, 0, 0, 0];
    const GZ: &[u8] = &[0x1f, 0x8b, 0x08, 0x00];

    #[test]
    fn dropped_files_are_told_apart_by_content_in_any_order() {
        let labels = file("labels.json", br#"{"labels": {}}"#);
        for files in [
            vec![file("leg.nii.gz", GZ), labels.clone()],
            vec![labels.clone(), file("leg.nii.gz", GZ)],
            // A volume whatever its name, a label list over 4 KiB whose cut falls inside
            // a character.
            vec![
                file("scan", NII),
                file("labels.txt", &"é".repeat(3000).into_bytes()),
            ],
        ] {
            match ModelSource::from_files(files, Unmapped::Fat).expect("a volume and labels") {
                ModelSource::Files {
                    volume_name,
                    labels: Some((label_name, _)),
                    unmapped: Unmapped::Fat,
                    ..
                } => {
                    assert!(volume_name == "leg.nii.gz" || volume_name == "scan");
                    assert!(label_name.starts_with("labels"));
                }
                other => panic!("{other:?}"),
            }
        }
        let scenario = file("knee.toml", b"[model]\nphantom = true\n");
        assert!(matches!(
            ModelSource::from_files(vec![scenario], Unmapped::Error),
            Ok(ModelSource::ScenarioText { .. })
        ));
        // A Slicer segmentation names its own labels: alone is enough.
        let seg = file("leg.seg.nrrd", b"NRRD0004\ntype: uint8\n");
        assert!(matches!(
            ModelSource::from_files(vec![seg], Unmapped::Error),
            Ok(ModelSource::Files { labels: None, .. })
        ));
    }

    #[test]
    fn files_a_page_cannot_open_say_why() {
        let err = |files: Vec<(String, Vec<u8>)>| {
            format!(
                "{:#}",
                ModelSource::from_files(files, Unmapped::Error).expect_err("refused")
            )
        };
        assert!(err(vec![]).contains("no file"));
        assert!(err(vec![file("leg.nhdr", b"NRRD0004\n")]).contains("detached"));
        assert!(err(vec![file("a.nii", NII), file("b.nii", NII)]).contains("a.nii, b.nii"));
        assert!(
            err(vec![file("labels.txt", b"0 0 0 0 1 1 1 \"Clear Label\"\n")])
                .contains("none of the files is a label volume")
        );
        // A label list saved in Latin-1 reads as binary: the message names both files.
        let latin1 = err(vec![
            file("leg.nii", NII),
            file("l.txt", &[0x41, 0xe9, 0x41]),
        ]);
        assert!(latin1.contains("leg.nii, l.txt"), "{latin1}");
        let three = err(vec![
            file("leg.nii", NII),
            file("a.json", b"{}"),
            file("b.json", b"{}"),
        ]);
        assert!(three.contains("2 other files"), "{three}");
    }
}
