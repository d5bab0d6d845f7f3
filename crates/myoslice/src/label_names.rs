//! What a segmentation's label names mean: each name a tool or a person gave a label
//! ("M. semitendinosus (left)", "BFlh", "semiten_l", "Subcutaneous fat") is mapped onto a
//! structure myoslice knows, by the synonym table in `assets/anatomy_names.toml`, after
//! normalising away case, punctuation, side words and filler words (see [`normalise`]).

use std::collections::BTreeMap;
use std::sync::OnceLock;

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::label_table::{Label, LabelTable, TissueKind};

/// The built-in synonym table.
const BUILTIN: &str = include_str!("../../../assets/anatomy_names.toml");

/// Words a name may carry that say nothing of which structure it is: sides and fillers.
const IGNORED_WORDS: [&str; 16] = [
    "left", "right", "l", "r", "lt", "rt", "sinister", "sinistra", "dexter", "dextra", "m", "mm",
    "musculus", "muscle", "muscles", "os",
];

/// "bone" is a filler too ("femur bone" reads as "femur", "hip bone" as "hip").
const BONE_WORD: &str = "bone";

/// The key a name is compared by: lower case; camelCase split; anything not a letter
/// or digit a separator; side words (left, right, l, r, lt, rt, sinister, dexter...) and
/// fillers (m, mm, musculus, muscle, muscles, os, bone) dropped; the rest joined with
/// no space.
///
/// ```
/// use myoslice::label_names::normalise;
/// assert_eq!(normalise("M. Semi-Tendinosus (left)"), "semitendinosus");
/// assert_eq!(normalise("semiten_l"), "semiten");
/// assert_eq!(normalise("BicepsFemorisLong"), "bicepsfemorislong");
/// assert_eq!(normalise("Hip bone, right"), "hip");
/// ```
pub fn normalise(name: &str) -> String {
    let mut spaced = String::with_capacity(name.len() + 8);
    let mut prev_lower = false;
    for c in name.chars() {
        if c.is_alphanumeric() {
            if c.is_uppercase() && prev_lower {
                spaced.push(' ');
            }
            prev_lower = c.is_lowercase() || c.is_ascii_digit();
            spaced.extend(c.to_lowercase());
        } else {
            spaced.push(' ');
            prev_lower = false;
        }
    }
    spaced
        .split_whitespace()
        .filter(|w| !IGNORED_WORDS.contains(w) && *w != BONE_WORD)
        .collect()
}

/// A structure myoslice knows, as the synonym table describes it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Structure {
    /// Canonical name (that of the muscle catalogue and the skeleton).
    #[serde(skip)]
    pub name: String,
    /// What it is.
    pub kind: TissueKind,
    /// Bone a muscle starts on (canonical name).
    #[serde(default)]
    pub origin: Option<String>,
    /// Bone a muscle ends on (canonical name).
    #[serde(default)]
    pub insertion: Option<String>,
    /// Other names it goes by.
    #[serde(default)]
    pub names: Vec<String>,
}

#[derive(Deserialize)]
struct RawNames {
    structure: BTreeMap<String, Structure>,
}

/// The synonym table: every name (normalised) of every structure.
#[derive(Debug, Clone)]
pub struct AnatomyNames {
    structures: Vec<Structure>,
    /// Normalised name → structure index.
    index: BTreeMap<String, usize>,
}

impl AnatomyNames {
    /// The table shipped in `assets/anatomy_names.toml`.
    pub fn builtin() -> Result<&'static Self> {
        static TABLE: OnceLock<std::result::Result<AnatomyNames, String>> = OnceLock::new();
        TABLE
            .get_or_init(|| {
                Self::from_toml_str(BUILTIN, "assets/anatomy_names.toml").map_err(|e| e.to_string())
            })
            .as_ref()
            .map_err(|e| Error::Build(e.clone()))
    }

    /// Parses a synonym table (`[structure.NAME]` with `kind`, `origin`, `insertion` and
    /// `names`); a name that normalises like another structure's is an error.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        let raw: RawNames =
            toml::from_str(text).map_err(|e| Error::parse(origin, e.to_string()))?;
        let mut table = Self {
            structures: Vec::with_capacity(raw.structure.len()),
            index: BTreeMap::new(),
        };
        for (name, mut s) in raw.structure {
            s.name = name;
            table.add_structure(s, origin)?;
        }
        Ok(table)
    }

    /// Adds a structure under its canonical name and its synonyms; a name that
    /// normalises like another structure's is an error.
    pub(crate) fn add_structure(&mut self, s: Structure, origin: &str) -> Result<usize> {
        let i = self.structures.len();
        let mut keys = Vec::with_capacity(s.names.len() + 1);
        for n in std::iter::once(&s.name).chain(&s.names) {
            let key = normalise(n);
            if key.is_empty() {
                return Err(Error::parse(
                    origin,
                    format!("'{}': the name '{n}' has no words left to compare", s.name),
                ));
            }
            if let Some(&j) = self.index.get(&key) {
                let other = &self.structures[j];
                return Err(Error::parse(
                    origin,
                    format!(
                        "'{n}' of '{}' reads as '{key}', a name of '{}' too",
                        s.name, other.name
                    ),
                ));
            }
            keys.push(key);
        }
        for key in keys {
            self.index.insert(key, i);
        }
        self.structures.push(s);
        Ok(i)
    }

    /// Makes `name` read as structure `i`, whatever it read as before (an explicit
    /// mapping wins over the synonym table). False when the name has no words to compare.
    pub(crate) fn set_alias(&mut self, name: &str, i: usize) -> bool {
        let key = normalise(name);
        if key.is_empty() || i >= self.structures.len() {
            return false;
        }
        self.index.insert(key, i);
        true
    }

    /// Index of the structure a name stands for.
    pub(crate) fn position(&self, name: &str) -> Option<usize> {
        self.index.get(&normalise(name)).copied()
    }

    /// The structure a label name stands for, if the table knows it.
    pub fn lookup(&self, name: &str) -> Option<&Structure> {
        self.index
            .get(&normalise(name))
            .map(|&i| &self.structures[i])
    }

    /// The structure of this canonical name (whatever names the table maps onto others).
    pub fn structure(&self, canonical: &str) -> Option<&Structure> {
        self.structures.iter().find(|s| s.name == canonical)
    }

    /// Every structure, by canonical name.
    pub fn structures(&self) -> &[Structure] {
        &self.structures
    }
}

/// What to do with a label whose name the table does not know.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Unmapped {
    /// Refuse the table, naming every such label (the default: a muscle read as fat
    /// would silently vanish from the simulation).
    #[default]
    Error,
    /// Count it as fat (soft tissue that moves with the rest).
    Fat,
    /// Count it as background (outside the body).
    Ignore,
}

impl Unmapped {
    /// The rule by its name: `error`, `fat` or `ignore` (as the CLI, the viewer, Python
    /// and scenarios spell it).
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "error" => Self::Error,
            "fat" => Self::Fat,
            "ignore" => Self::Ignore,
            _ => return None,
        })
    }
}

/// How one label was read.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedLabel {
    /// Label value in the volume.
    pub id: u16,
    /// The name the file gave it.
    pub source: String,
    /// The structure it was mapped to (None: unmapped, taken as `kind`).
    pub structure: Option<String>,
    /// Its kind in the table built.
    pub kind: TissueKind,
    /// The name it has in the table built.
    pub name: String,
}

/// Builds a label table from `(value, name)` pairs (an ITK-SNAP or Slicer label list):
/// each name mapped by `names`, the others as `unmapped` says. Returns the table and how
/// each label was read. Two labels mapped onto one bone or muscle are an error; several
/// onto fat or background keep their own names (`fat`, `fat_7`, ...). A muscle's
/// origin and insertion come from the table where those bones are labelled too.
pub fn map_labels(
    list: &[(u16, String)],
    names: &AnatomyNames,
    unmapped: Unmapped,
    origin: &str,
) -> Result<(LabelTable, Vec<MappedLabel>)> {
    let err = |reason: String| Error::parse(origin, reason);
    let mut mapped: Vec<MappedLabel> = Vec::with_capacity(list.len());
    // Names given so far (a set: a hostile list may have 65 536 labels).
    let mut used = std::collections::BTreeSet::new();
    let mut missing = Vec::new();
    for (id, source) in list {
        let (structure, kind) = match names.lookup(source) {
            Some(s) => (Some(s.name.clone()), s.kind),
            None => {
                let kind = match unmapped {
                    Unmapped::Error => {
                        missing.push(format!("{id} '{source}'"));
                        continue;
                    }
                    Unmapped::Fat => TissueKind::Fat,
                    Unmapped::Ignore => TissueKind::Background,
                };
                (None, kind)
            }
        };
        let base = structure
            .clone()
            .unwrap_or_else(|| kind.as_str().to_string());
        let taken = |n: &str| used.contains(n);
        let name = match kind {
            TissueKind::Bone | TissueKind::Muscle => {
                if used.contains(&base)
                    && let Some(prev) = mapped.iter().find(|m| m.name == base)
                {
                    return Err(err(format!(
                        "labels {} '{}' and {id} '{source}' both read as {base}: merge them \
                         in the segmentation, or rename one",
                        prev.id, prev.source
                    )));
                }
                base
            }
            _ if !taken(&base) => base,
            _ => format!("{base}_{id}"),
        };
        used.insert(name.clone());
        mapped.push(MappedLabel {
            id: *id,
            source: source.clone(),
            structure,
            kind,
            name,
        });
    }
    if !missing.is_empty() {
        return Err(err(format!(
            "no structure known by the name of label {} (`myoslice labels FILE` lists how \
             every label reads; to take such labels as fat or as background: `--unmapped \
             fat|ignore` in the CLI, `unmapped=\"fat\"|\"ignore\"` in Python)",
            missing.join(", label ")
        )));
    }
    let bone_here = |b: &Option<String>| {
        b.clone().filter(|b| {
            mapped
                .iter()
                .any(|m| m.kind == TissueKind::Bone && &m.name == b)
        })
    };
    let labels = mapped
        .iter()
        .map(|m| {
            let s = m.structure.as_deref().and_then(|s| names.structure(s));
            let muscle = m.kind == TissueKind::Muscle;
            Label {
                id: m.id,
                name: m.name.clone(),
                kind: m.kind,
                origin: s.filter(|_| muscle).and_then(|s| bone_here(&s.origin)),
                insertion: s.filter(|_| muscle).and_then(|s| bone_here(&s.insertion)),
            }
        })
        .collect();
    let table = LabelTable::new(labels).map_err(|e| match e {
        Error::Parse { reason, .. } => err(reason),
        other => other,
    })?;
    Ok((table, mapped))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_builtin_table_parses_and_knows_every_catalogue_muscle() {
        let names = AnatomyNames::builtin().unwrap();
        let cat = crate::muscle::MuscleCatalogue::default();
        for m in cat.muscles.keys() {
            let s = names.lookup(m).unwrap_or_else(|| panic!("{m} unknown"));
            assert_eq!((&s.name, s.kind), (m, TissueKind::Muscle));
        }
        for b in [
            "femur",
            "tibia",
            "fibula",
            "patella",
            "hip_bone",
            "sacrum_coccyx",
        ] {
            assert_eq!(
                names.lookup(b).map(|s| s.kind),
                Some(TissueKind::Bone),
                "{b}"
            );
        }
    }

    #[test]
    fn names_as_tools_and_people_write_them_map_to_one_structure() {
        let names = AnatomyNames::builtin().unwrap();
        for (given, want) in [
            ("M. Semitendinosus (left)", "semitendinosus"),
            ("semiten_l", "semitendinosus"),
            ("Biceps femoris long head", "biceps_femoris_long"),
            ("bifemlh_r", "biceps_femoris_long"),
            ("VASTUS LATERALIS", "vastus_lateralis"),
            ("Gastrocnemius medial head", "gastrocnemius_medial"),
            ("Fibularis longus", "peroneus_longus"),
            ("Left Femur", "femur"),
            ("Clear Label", "background"),
            ("Subcutaneous fat", "fat"),
        ] {
            assert_eq!(
                names.lookup(given).map(|s| s.name.as_str()),
                Some(want),
                "{given}"
            );
        }
        assert!(names.lookup("iliopsoas").is_none());
        assert!(names.lookup("femoral artery").is_none());
    }

    #[test]
    fn a_table_is_built_from_a_label_list_with_attachments_where_the_bones_are() {
        let names = AnatomyNames::builtin().unwrap();
        let list: Vec<(u16, String)> = [
            (0, "Clear Label"),
            (1, "Subcutaneous fat"),
            (2, "intermuscular fat"),
            (5, "Femur"),
            (6, "Tibia"),
            (9, "M. semitendinosus"),
            (12, "femoral artery"),
        ]
        .iter()
        .map(|(i, n)| (*i, n.to_string()))
        .collect();
        let e = map_labels(&list, names, Unmapped::Error, "seg.txt").unwrap_err();
        assert!(e.to_string().contains("label 12 'femoral artery'"), "{e}");
        let (table, how) = map_labels(&list, names, Unmapped::Fat, "seg.txt").unwrap();
        assert_eq!(table.get(2).map(|l| l.name.as_str()), Some("fat_2"));
        assert_eq!(table.kind(12), Some(TissueKind::Fat));
        let st = table.get(9).unwrap();
        assert_eq!(
            (st.name.as_str(), st.kind),
            ("semitendinosus", TissueKind::Muscle)
        );
        // The hip bone is not labelled: no origin; the tibia is: the insertion.
        assert_eq!(
            (st.origin.as_deref(), st.insertion.as_deref()),
            (None, Some("tibia"))
        );
        assert_eq!(how.iter().filter(|m| m.structure.is_none()).count(), 1);
        let (table, _) = map_labels(&list, names, Unmapped::Ignore, "seg.txt").unwrap();
        assert_eq!(table.kind(12), Some(TissueKind::Background));
        let twice = [(3, "Femur".to_string()), (4, "left femur".to_string())];
        let e = map_labels(&twice, names, Unmapped::Error, "seg.txt").unwrap_err();
        assert!(e.to_string().contains("both read as femur"), "{e}");
    }

    #[test]
    fn a_synonym_table_with_a_name_two_structures_share_is_refused() {
        let text = "[structure.a]\nkind = \"muscle\"\nnames = [\"X y\"]\n\
                    [structure.b]\nkind = \"muscle\"\nnames = [\"x-Y\"]\n";
        let e = AnatomyNames::from_toml_str(text, "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a name of 'a' too"), "{e}");
    }
}
