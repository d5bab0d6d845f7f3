//! How the label names of a segmentation are read: the synonym table (built in, or
//! extended by the user's own names file) and what to do with a name it does not know.
//!
//! A names file (TOML) says what the user's own names stand for, and may add muscles
//! myoslice does not know:
//!
//! ```toml
//! # Name in the segmentation = structure (its canonical name or any synonym).
//! [map]
//! "BFlh" = "biceps_femoris_long"
//! "Label 12" = "fat"
//! "Cartilage" = "background"
//!
//! # A muscle unknown to myoslice: its parameters come from its volume and length.
//! [structure.articularis_genus]
//! kind = "muscle"
//! origin = "femur"
//! insertion = "patella"
//! names = ["AG"]
//! ```
//!
//! A `[map]` entry wins over the built-in synonyms of the same name.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::label_names::{AnatomyNames, Structure, Unmapped};
use crate::label_table::TissueKind;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawNamesFile {
    #[serde(default)]
    map: BTreeMap<String, String>,
    #[serde(default)]
    structure: BTreeMap<String, Structure>,
}

/// How label names are read: by which synonym table, and what becomes of the names it
/// does not know.
///
/// ```
/// use myoslice::label_mapping::LabelMapping;
/// use myoslice::label_names::Unmapped;
/// let text = "[map]\n\"BFlh\" = \"biceps_femoris_long\"\n\"Label 12\" = \"fat\"\n";
/// let m = LabelMapping::new(Unmapped::Error).with_names_str(text, "names.toml")?;
/// let names = m.names()?;
/// assert_eq!(names.lookup("BFlh").map(|s| s.name.as_str()), Some("biceps_femoris_long"));
/// assert_eq!(names.lookup("label-12").map(|s| s.name.as_str()), Some("fat"));
/// # Ok::<(), myoslice::Error>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct LabelMapping {
    unmapped: Unmapped,
    /// The built-in table with the user's names; None: the built-in table as it is.
    names: Option<Arc<AnatomyNames>>,
}

impl From<Unmapped> for LabelMapping {
    fn from(unmapped: Unmapped) -> Self {
        Self::new(unmapped)
    }
}

impl LabelMapping {
    /// The built-in synonym table, unknown names taken as `unmapped` says.
    pub fn new(unmapped: Unmapped) -> Self {
        Self {
            unmapped,
            names: None,
        }
    }

    /// What becomes of a name the table does not know.
    pub fn unmapped(&self) -> Unmapped {
        self.unmapped
    }

    /// The synonym table names are read by.
    pub fn names(&self) -> Result<&AnatomyNames> {
        match &self.names {
            Some(n) => Ok(n),
            None => AnatomyNames::builtin(),
        }
    }

    /// Adds the user's names file (see the module's documentation).
    pub fn with_names_file(self, path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        self.with_names_str(&text, &path.display().to_string())
    }

    /// [`Self::with_names_file`] from the file's text; `origin` names it in errors.
    pub fn with_names_str(self, text: &str, origin: &str) -> Result<Self> {
        let raw: RawNamesFile =
            toml::from_str(text).map_err(|e| Error::parse(origin, e.to_string()))?;
        let mut names = self.names()?.clone();
        let known_bone = |names: &AnatomyNames, b: &str| {
            names
                .lookup(b)
                .is_some_and(|s| s.kind == TissueKind::Bone && s.name == b)
        };
        for (name, mut s) in raw.structure {
            let what = format!("structure.{name}");
            match s.kind {
                TissueKind::Muscle => {}
                TissueKind::Bone => {
                    return Err(Error::parse(
                        origin,
                        format!(
                            "{what}: a bone the skeleton does not know cannot be added; map \
                             its label onto a known bone, \"fat\" or \"background\" in [map]"
                        ),
                    ));
                }
                other => {
                    return Err(Error::parse(
                        origin,
                        format!(
                            "{what}: kind \"{}\" is one of myoslice's own (\"fat\", \
                             \"background\"); map the label onto it in [map] instead",
                            other.as_str()
                        ),
                    ));
                }
            }
            for (key, bone) in [("origin", &s.origin), ("insertion", &s.insertion)] {
                if let Some(b) = bone
                    && !known_bone(&names, b)
                {
                    return Err(Error::parse(
                        origin,
                        format!(
                            "{what}.{key} = \"{b}\": expected a bone by its canonical name \
                             (femur, tibia, fibula, patella, hip_bone, sacrum_coccyx)"
                        ),
                    ));
                }
            }
            s.name = name;
            names.add_structure(s, origin)?;
        }
        // Every target is read against the table before any entry changes it: the
        // entries act together, whatever order their keys sort in ("A" = "b" with
        // "B" = "a" swaps two names).
        let mut aliases = Vec::with_capacity(raw.map.len());
        for (given, target) in &raw.map {
            let Some(i) = names.position(target) else {
                return Err(Error::parse(
                    origin,
                    format!(
                        "map.\"{given}\" = \"{target}\": no structure of that name (`myoslice \
                         labels` lists how names read; a muscle myoslice does not know can be \
                         added as [structure.NAME])"
                    ),
                ));
            };
            aliases.push((given, i));
        }
        for (given, i) in aliases {
            if !names.set_alias(given, i) {
                return Err(Error::parse(
                    origin,
                    format!("map.\"{given}\": the name has no words left to compare"),
                ));
            }
        }
        Ok(Self {
            unmapped: self.unmapped,
            names: Some(Arc::new(names)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_explicit_mapping_wins_over_the_synonym_table() {
        // "Femur" would read as the femur; the user says this label is background.
        let text = "[map]\nFemur = \"background\"\n\"my ST\" = \"semiten\"\n";
        let m = LabelMapping::new(Unmapped::Error)
            .with_names_str(text, "n.toml")
            .unwrap();
        let names = m.names().unwrap();
        assert_eq!(names.lookup("femur").unwrap().name, "background");
        assert_eq!(names.lookup("MY-st").unwrap().name, "semitendinosus");
        // The built-in table itself is untouched.
        let builtin = AnatomyNames::builtin().unwrap();
        assert_eq!(builtin.lookup("femur").unwrap().name, "femur");
    }

    #[test]
    fn map_entries_act_together_whatever_order_they_sort_in() {
        // Two names swapped in the user's segmentation.
        let text = "[map]\n\"Rectus femoris\" = \"vastus_lateralis\"\n\
                    \"Vastus lateralis\" = \"rectus_femoris\"\n\"thigh bone\" = \"femur\"\n\
                    Femur = \"background\"\n";
        let m = LabelMapping::new(Unmapped::Error)
            .with_names_str(text, "n.toml")
            .unwrap();
        let names = m.names().unwrap();
        let read = |n: &str| names.lookup(n).map(|s| s.name.clone());
        assert_eq!(read("rectus femoris").as_deref(), Some("vastus_lateralis"));
        assert_eq!(read("vastus lateralis").as_deref(), Some("rectus_femoris"));
        assert_eq!(read("thigh bone").as_deref(), Some("femur"));
        assert_eq!(read("femur").as_deref(), Some("background"));
        // Attachments follow the structure, not the name: the swap keeps each muscle's.
        let list = [
            (1, "Vastus lateralis".to_string()),
            (2, "Rectus femoris".to_string()),
            (3, "hip".to_string()),
            (4, "patella".to_string()),
            (5, "thigh bone".to_string()),
        ];
        let (table, _) =
            crate::label_names::map_labels(&list, names, Unmapped::Error, "t").unwrap();
        let rf = table.by_name("rectus_femoris").unwrap();
        let vl = table.by_name("vastus_lateralis").unwrap();
        assert_eq!(
            (rf.id, rf.origin.as_deref(), vl.id, vl.origin.as_deref()),
            (1, Some("hip_bone"), 2, Some("femur"))
        );
    }

    #[test]
    fn a_user_muscle_is_added_with_its_attachments() {
        let text = "[structure.articularis_genus]\nkind = \"muscle\"\norigin = \"femur\"\n\
                    insertion = \"patella\"\nnames = [\"AG\"]\n";
        let m = LabelMapping::new(Unmapped::Error)
            .with_names_str(text, "n.toml")
            .unwrap();
        let s = m.names().unwrap().lookup("ag").unwrap();
        assert_eq!(
            (s.name.as_str(), s.kind, s.insertion.as_deref()),
            ("articularis_genus", TissueKind::Muscle, Some("patella"))
        );
    }

    #[test]
    fn a_bad_names_file_is_refused_naming_the_entry() {
        for (text, want) in [
            ("[map]\nX = \"kidney\"\n", "map.\"X\" = \"kidney\""),
            ("[map]\n\"(left)\" = \"fat\"\n", "no words left"),
            (
                "[structure.talus]\nkind = \"bone\"\n",
                "structure.talus: a bone",
            ),
            (
                "[structure.q]\nkind = \"muscle\"\norigin = \"skull\"\n",
                "structure.q.origin = \"skull\"",
            ),
            (
                "[structure.st2]\nkind = \"muscle\"\nnames = [\"semitendinosus\"]\n",
                "a name of 'semitendinosus' too",
            ),
            ("[mapping]\n", "unknown field"),
        ] {
            let e = LabelMapping::new(Unmapped::Error)
                .with_names_str(text, "n.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains(want) && e.contains("n.toml"), "{text}: {e}");
        }
    }
}
