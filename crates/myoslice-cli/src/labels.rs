//! `myoslice labels FILE`: how a label table or a segmentation tool's label list reads.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Args, ValueEnum};
use myoslice::LabelTable;
use myoslice::io::{is_nrrd, parse_nrrd};
use myoslice::label_mapping::LabelMapping;
use myoslice::label_names::{Unmapped, map_labels};

/// What to do with a label name no structure is known by.
#[derive(Debug, Clone, Copy, Default, ValueEnum)]
pub(crate) enum UnmappedArg {
    /// Refuse the file, naming the labels.
    #[default]
    Error,
    /// Take them as fat.
    Fat,
    /// Take them as background.
    Ignore,
}

impl From<UnmappedArg> for Unmapped {
    fn from(a: UnmappedArg) -> Self {
        match a {
            UnmappedArg::Error => Unmapped::Error,
            UnmappedArg::Fat => Unmapped::Fat,
            UnmappedArg::Ignore => Unmapped::Ignore,
        }
    }
}

#[derive(Args)]
pub(crate) struct LabelsArgs {
    /// Label table (.json, .toml), ITK-SNAP label description file, 3D Slicer colour
    /// table (.ctbl, .txt) or 3D Slicer segmentation (.seg.nrrd).
    file: PathBuf,
    /// Label names no structure is known by: an error, or fat, or background.
    #[arg(long, value_enum, default_value_t = UnmappedArg::Error)]
    unmapped: UnmappedArg,
    /// Your own names (TOML): `[map]` label name = structure, and muscles myoslice does
    /// not know as `[structure.NAME]`.
    #[arg(long)]
    names: Option<PathBuf>,
}

/// The mapping `--unmapped` and `--names` ask for.
pub(crate) fn mapping(unmapped: UnmappedArg, names: Option<&Path>) -> Result<LabelMapping> {
    let m = LabelMapping::new(unmapped.into());
    Ok(match names {
        Some(p) => m.with_names_file(p)?,
        None => m,
    })
}

/// Prints each label, the name the file gives it and what it becomes; lists the names
/// it cannot map before failing on them.
pub(crate) fn run(a: &LabelsArgs) -> Result<()> {
    // Read once taking unknown names as asked, or as fat where that would be an error, to
    // show every label; then as asked.
    let asked = mapping(a.unmapped, a.names.as_deref())?;
    let shown = match a.unmapped {
        UnmappedArg::Error => mapping(UnmappedArg::Fat, a.names.as_deref())?,
        _ => asked.clone(),
    };
    let mut out = String::new();
    // Read once: a segmentation is parsed from these bytes, a label file as text.
    let segmentation = std::fs::read(&a.file)
        .ok()
        .filter(|raw| is_nrrd(raw))
        .map(|raw| parse_nrrd(&raw, &a.file))
        .transpose()?;
    let (table, how, segments) = match segmentation {
        Some(v) => {
            let Some(list) = v.segments else {
                anyhow::bail!(
                    "{}: a label map that names none of its labels (give its label file)",
                    a.file.display()
                );
            };
            if let Some(rule) = &v.merge {
                writeln!(out, "{rule}")?;
            }
            let origin = a.file.display().to_string();
            let (table, how) = map_labels(&list, shown.names()?, shown.unmapped(), &origin)?;
            (table, Some(how), Some((list, origin)))
        }
        None => {
            let (table, how) = LabelTable::read_mapped(&a.file, shown)?;
            (table, how, None)
        }
    };
    match &how {
        Some(how) => {
            writeln!(
                out,
                "{:>5}  {:<32}  {:<28}  kind",
                "label", "name in the file", "structure"
            )?;
            for m in how {
                writeln!(
                    out,
                    "{:>5}  {:<32}  {:<28}  {}",
                    m.id,
                    m.source,
                    m.structure.as_deref().unwrap_or("(not known)"),
                    m.kind.as_str()
                )?;
            }
            let unknown: Vec<&str> = how
                .iter()
                .filter(|m| m.structure.is_none())
                .map(|m| m.source.as_str())
                .collect();
            if !unknown.is_empty() {
                writeln!(
                    out,
                    "{} of {} labels not known: {}",
                    unknown.len(),
                    how.len(),
                    unknown.join(", ")
                )?;
            }
        }
        None => {
            writeln!(out, "{:>5}  {:<32}  kind", "label", "name")?;
            for l in table.labels() {
                writeln!(out, "{:>5}  {:<32}  {}", l.id, l.name, l.kind.as_str())?;
            }
        }
    }
    // A reader that stopped reading (`| head`) is no error.
    match std::io::stdout().lock().write_all(out.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => return Err(e.into()),
        _ => {}
    }
    // As it would be read with the option given (an error for unknown names by default).
    match segments {
        Some((list, origin)) => {
            map_labels(&list, asked.names()?, asked.unmapped(), &origin)?;
        }
        None => {
            LabelTable::from_path_with(&a.file, asked)?;
        }
    }
    Ok(())
}
