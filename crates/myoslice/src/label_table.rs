//! Label tables: what each voxel label of a volume means.
//!
//! The format is the one of the Visible Human data in `../shared/data/visible-human/`:
//! a top-level `labels` map from id (as a string) to a record with `name`, `kind`
//! (`background | fat | bone | muscle`) and, for muscles, optional `origin` and `insertion`
//! bone names. Other keys are allowed and ignored, so annotated tables load as they are.
//! The same structure is read from JSON or TOML. A segmentation tool's label list (ITK-SNAP,
//! 3D Slicer) is read too, its names mapped by [`crate::label_names`].

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::io::{parse_label_list, sniff_label_list};
use crate::label_mapping::LabelMapping;
use crate::label_names::{MappedLabel, Unmapped, map_labels};

/// What a label stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TissueKind {
    /// Outside the body.
    Background,
    /// Fat and every other soft tissue that is not a listed muscle.
    Fat,
    /// A rigid bone.
    Bone,
    /// A skeletal muscle.
    Muscle,
}

impl TissueKind {
    /// Lower-case name as used in files and reports.
    pub fn as_str(self) -> &'static str {
        match self {
            TissueKind::Background => "background",
            TissueKind::Fat => "fat",
            TissueKind::Bone => "bone",
            TissueKind::Muscle => "muscle",
        }
    }
}

/// One entry of a label table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Label {
    /// Voxel value.
    pub id: u16,
    /// Unique structure name, e.g. `semitendinosus`.
    pub name: String,
    /// Tissue kind.
    pub kind: TissueKind,
    /// Origin bone name (muscles only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<String>,
    /// Insertion bone name (muscles only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub insertion: Option<String>,
}

#[derive(Deserialize)]
struct RawRecord {
    name: String,
    kind: TissueKind,
    #[serde(default)]
    origin: Option<String>,
    #[serde(default)]
    insertion: Option<String>,
}

#[derive(Deserialize)]
struct RawTable {
    labels: BTreeMap<String, RawRecord>,
}

#[derive(Serialize)]
struct OutTable<'a> {
    labels: BTreeMap<String, &'a Label>,
}

/// The meaning of every label of a volume, sorted by id.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelTable {
    labels: Vec<Label>,
    by_id: Vec<Option<u32>>,
}

impl LabelTable {
    /// Builds a table from labels, checking ids, names, kinds and attachments.
    pub fn new(mut labels: Vec<Label>) -> Result<Self> {
        labels.sort_by_key(|l| l.id);
        let src = "label table";
        for w in labels.windows(2) {
            if w[0].id == w[1].id {
                return Err(parse_err(
                    src,
                    format!("label id {} is defined twice", w[0].id),
                ));
            }
        }
        let mut names = BTreeMap::new();
        for l in &labels {
            if l.name.trim().is_empty() {
                return Err(parse_err(src, format!("label {} has an empty name", l.id)));
            }
            if let Some(prev) = names.insert(l.name.as_str(), l.id) {
                return Err(parse_err(
                    src,
                    format!("name '{}' is used by labels {prev} and {}", l.name, l.id),
                ));
            }
        }
        for l in &labels {
            for (role, bone) in [("origin", &l.origin), ("insertion", &l.insertion)] {
                let Some(bone) = bone else { continue };
                if l.kind != TissueKind::Muscle {
                    return Err(parse_err(
                        src,
                        format!("label '{}' is not a muscle but has an {role}", l.name),
                    ));
                }
                let ok = labels
                    .iter()
                    .any(|b| b.kind == TissueKind::Bone && &b.name == bone);
                if !ok {
                    return Err(parse_err(
                        src,
                        format!(
                            "muscle '{}': {role} '{bone}' is not a bone label of the table",
                            l.name
                        ),
                    ));
                }
            }
        }
        let max = labels.last().map_or(0, |l| l.id as usize);
        let mut by_id = vec![None; max + 1];
        for (i, l) in labels.iter().enumerate() {
            by_id[l.id as usize] = Some(i as u32);
        }
        Ok(Self { labels, by_id })
    }

    /// Parses a table from JSON text; `origin` names the source in error messages.
    pub fn from_json_str(text: &str, origin: &str) -> Result<Self> {
        let raw: RawTable =
            serde_json::from_str(text).map_err(|e| parse_err(origin, e.to_string()))?;
        Self::from_raw(raw, origin)
    }

    /// Parses a table from TOML text; `origin` names the source in error messages.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        let raw: RawTable = toml::from_str(text).map_err(|e| parse_err(origin, e.to_string()))?;
        Self::from_raw(raw, origin)
    }

    /// Reads a label table: our own `.json` or `.toml`, or a segmentation tool's label
    /// list (an ITK-SNAP label description file, a 3D Slicer colour table), told apart
    /// by content. A tool's names are mapped onto known structures
    /// ([`crate::label_names`]); a name the table does not know is an error.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_path_with(path, Unmapped::Error)
    }

    /// [`Self::from_path`], taking a tool's unknown label names as `unmapped` says.
    /// (`unmapped` may be a [`LabelMapping`] that carries the user's own names too).
    pub fn from_path_with(
        path: impl AsRef<Path>,
        unmapped: impl Into<LabelMapping>,
    ) -> Result<Self> {
        Ok(Self::read_mapped(path, unmapped)?.0)
    }

    /// [`Self::from_path_with`], with how each label of a tool's list was read (None for
    /// our own formats, whose names are ours already).
    pub fn read_mapped(
        path: impl AsRef<Path>,
        mapping: impl Into<LabelMapping>,
    ) -> Result<(Self, Option<Vec<MappedLabel>>)> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse_mapped(&text, &path.display().to_string(), mapping)
    }

    /// [`Self::read_mapped`] of a file's text already read (a page's dropped file);
    /// `origin` is its name, whose `.toml` ending counts as for a path.
    pub fn parse_mapped(
        text: &str,
        origin: &str,
        mapping: impl Into<LabelMapping>,
    ) -> Result<(Self, Option<Vec<MappedLabel>>)> {
        let mapping = mapping.into();
        let origin = origin.to_string();
        let toml_ext = Path::new(&origin)
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        if text.trim_start().starts_with('{') {
            return Ok((Self::from_json_str(text, &origin)?, None));
        }
        if toml_ext || sniff_label_list(text).is_none() {
            return Ok((Self::from_toml_str(text, &origin)?, None));
        }
        let list = parse_label_list(text, &origin)?;
        let (table, how) = map_labels(&list, mapping.names()?, mapping.unmapped(), &origin)?;
        Ok((table, Some(how)))
    }

    fn from_raw(raw: RawTable, origin: &str) -> Result<Self> {
        let mut labels = Vec::with_capacity(raw.labels.len());
        for (key, r) in raw.labels {
            let id: u16 = key.trim().parse().map_err(|_| {
                parse_err(
                    origin,
                    format!("label key '{key}' is not an id in 0..=65535"),
                )
            })?;
            labels.push(Label {
                id,
                name: r.name,
                kind: r.kind,
                origin: r.origin,
                insertion: r.insertion,
            });
        }
        Self::new(labels).map_err(|e| match e {
            Error::Parse { reason, .. } => parse_err(origin, reason),
            other => other,
        })
    }

    /// Serialises the table as JSON in the format it reads.
    pub fn to_json(&self) -> String {
        let out = OutTable {
            labels: self.labels.iter().map(|l| (l.id.to_string(), l)).collect(),
        };
        serde_json::to_string_pretty(&out).unwrap_or_default()
    }

    /// All labels, sorted by id.
    pub fn labels(&self) -> &[Label] {
        &self.labels
    }

    /// The label with this id, if defined.
    pub fn get(&self, id: u16) -> Option<&Label> {
        let i = (*self.by_id.get(id as usize)?)?;
        self.labels.get(i as usize)
    }

    /// The kind of a label id, `None` if undefined.
    pub fn kind(&self, id: u16) -> Option<TissueKind> {
        self.get(id).map(|l| l.kind)
    }

    /// The label with this name.
    pub fn by_name(&self, name: &str) -> Result<&Label> {
        self.labels.iter().find(|l| l.name == name).ok_or_else(|| {
            Error::unknown_name("label", name, self.labels.iter().map(|l| l.name.as_str()))
        })
    }

    /// Labels of one kind, by id.
    pub fn of_kind(&self, kind: TissueKind) -> impl Iterator<Item = &Label> {
        self.labels.iter().filter(move |l| l.kind == kind)
    }

    /// A lookup table id → kind for fast per-voxel classification (undefined → `None`).
    pub fn kind_lut(&self) -> Vec<Option<TissueKind>> {
        let mut lut = vec![None; self.by_id.len()];
        for l in &self.labels {
            lut[l.id as usize] = Some(l.kind);
        }
        lut
    }
}

fn parse_err(origin: &str, reason: String) -> Error {
    Error::parse(origin, reason)
}

#[cfg(test)]
mod tests {
    use super::*;

    const JSON: &str = r#"{"title": "x", "labels": {
        "0": {"name": "background", "kind": "background", "voxels": 12},
        "1": {"name": "fat", "kind": "fat"},
        "2": {"name": "femur", "kind": "bone"},
        "3": {"name": "tibia", "kind": "bone"},
        "10": {"name": "semitendinosus", "kind": "muscle", "origin": "femur", "insertion": "tibia"}
    }}"#;

    #[test]
    fn json_and_toml_tables_agree_and_extra_keys_are_ignored() {
        let a = LabelTable::from_json_str(JSON, "t.json").unwrap();
        let b = LabelTable::from_toml_str(
            r#"
            [labels.0]
            name = "background"
            kind = "background"
            [labels.1]
            name = "fat"
            kind = "fat"
            [labels.2]
            name = "femur"
            kind = "bone"
            [labels.3]
            name = "tibia"
            kind = "bone"
            [labels.10]
            name = "semitendinosus"
            kind = "muscle"
            origin = "femur"
            insertion = "tibia"
            "#,
            "t.toml",
        )
        .unwrap();
        assert_eq!(a, b);
        assert_eq!(a.get(10).unwrap().insertion.as_deref(), Some("tibia"));
        assert_eq!(a.kind(3), Some(TissueKind::Bone));
        assert_eq!(a.kind(4), None);
        let again = LabelTable::from_json_str(&a.to_json(), "round").unwrap();
        assert_eq!(a, again);
    }

    #[test]
    fn bad_tables_are_rejected_with_a_reason() {
        let dup = r#"{"labels": {"1": {"name": "a", "kind": "fat"}, "01": {"name": "b", "kind": "fat"}}}"#;
        let e = LabelTable::from_json_str(dup, "d.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("defined twice"), "{e}");
        let bad_kind = r#"{"labels": {"1": {"name": "a", "kind": "skin"}}}"#;
        let e = LabelTable::from_json_str(bad_kind, "k.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("k.json") && e.contains("skin"), "{e}");
        let bad_bone =
            r#"{"labels": {"1": {"name": "m", "kind": "muscle", "origin": "calcaneus"}}}"#;
        let e = LabelTable::from_json_str(bad_bone, "b.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("calcaneus"), "{e}");
        let bad_id = r#"{"labels": {"x": {"name": "m", "kind": "fat"}}}"#;
        assert!(LabelTable::from_json_str(bad_id, "i.json").is_err());
        assert!(LabelTable::from_json_str("{", "g.json").is_err());
    }
}
