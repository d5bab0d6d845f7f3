//! Readers and writers of label volumes (NIfTI-1 and -2, NRRD, PNG stacks), and of the
//! label lists of segmentation tools.

pub mod input_kind;
pub mod label_lists;
pub mod nifti;
pub mod nrrd;
pub mod png_stack;

pub use input_kind::InputKind;
pub use label_lists::{LabelListFormat, LabelNames, parse_label_list, sniff_label_list};
pub use nifti::{MAX_VOLUME_BYTES, encode_nifti, parse_nifti, read_nifti, write_nifti};
pub use nrrd::{NrrdVolume, is_nrrd, parse_nrrd, read_nrrd};
pub use png_stack::{decode_png_labels, read_png_stack, read_png_stack_with, write_png_labels};

/// Reads a label volume, NIfTI-1/-2 or NRRD (told apart by content), in the body frame
/// the lattice builder slices in ([`crate::LabelVolume::in_frame`]: a scan saved in
/// sagittal or coronal slices, or in a left-posterior-superior frame, is reordered voxel
/// for voxel; an oblique one is resampled),
/// with the label names the file itself carries (a 3D Slicer segmentation's segments;
/// None otherwise).
pub fn read_label_volume(
    path: impl AsRef<std::path::Path>,
) -> crate::Result<(crate::LabelVolume, Option<LabelNames>)> {
    let path = path.as_ref();
    let raw = std::fs::read(path).map_err(|e| crate::Error::io(path, e))?;
    parse_label_volume(&raw, path)
}

/// [`read_label_volume`] of a file's bytes already read (a page's dropped file; an NRRD
/// must carry its data: a detached one's data file is looked for beside `path`).
pub fn parse_label_volume(
    raw: &[u8],
    path: &std::path::Path,
) -> crate::Result<(crate::LabelVolume, Option<LabelNames>)> {
    if is_nrrd(raw) {
        let v = parse_nrrd(raw, path)?;
        Ok((v.volume.in_frame()?, v.segments))
    } else {
        Ok((parse_nifti(raw, path)?.in_frame()?, None))
    }
}

/// A label volume (NIfTI-1/-2 or NRRD) and what its labels mean: the label table or tool's
/// label list at `labels` ([`crate::LabelTable::from_path_with`]), or else the segment
/// names a 3D Slicer segmentation carries, mapped onto known structures as `mapping`
/// says (an [`crate::label_names::Unmapped`] rule, or a
/// [`crate::label_mapping::LabelMapping`] with the user's own names file).
///
/// ```no_run
/// use myoslice::io::read_segmentation;
/// use myoslice::label_names::Unmapped;
/// // A Slicer segmentation names its own segments.
/// let (volume, table) = read_segmentation("leg.seg.nrrd", None, Unmapped::Error)?;
/// // A NIfTI label map with ITK-SNAP's label file beside it.
/// let (volume, table) =
///     read_segmentation("leg.nii.gz", Some("leg-labels.txt".as_ref()), Unmapped::Fat)?;
/// # Ok::<(), myoslice::Error>(())
/// ```
pub fn read_segmentation(
    volume: impl AsRef<std::path::Path>,
    labels: Option<&std::path::Path>,
    mapping: impl Into<crate::label_mapping::LabelMapping>,
) -> crate::Result<(crate::LabelVolume, crate::LabelTable)> {
    let volume = volume.as_ref();
    let mapping = mapping.into();
    let (v, segments) = read_label_volume(volume)?;
    let labels = match labels {
        Some(l) => {
            let text = std::fs::read_to_string(l).map_err(|e| crate::Error::io(l, e))?;
            Some((text, l.display().to_string()))
        }
        None => None,
    };
    let table = table_of(volume, segments, labels, mapping)?;
    Ok((v, table))
}

/// [`read_segmentation`] of files already read (a web page's picked or dropped files): the
/// volume's bytes with its name, and the label file's text with its name.
pub fn parse_segmentation(
    volume: &[u8],
    volume_name: &str,
    labels: Option<(&str, &str)>,
    mapping: impl Into<crate::label_mapping::LabelMapping>,
) -> crate::Result<(crate::LabelVolume, crate::LabelTable)> {
    let path = std::path::Path::new(volume_name);
    let (v, segments) = parse_label_volume(volume, path)?;
    let labels = labels.map(|(text, name)| (text.to_string(), name.to_string()));
    Ok((v, table_of(path, segments, labels, mapping.into())?))
}

/// The label table of a volume: from the label file's `(text, name)`, or else from the
/// segment names the volume carries.
fn table_of(
    volume: &std::path::Path,
    segments: Option<LabelNames>,
    labels: Option<(String, String)>,
    mapping: crate::label_mapping::LabelMapping,
) -> crate::Result<crate::LabelTable> {
    Ok(match (labels, segments) {
        (Some(_), Some(_)) => {
            return Err(crate::Error::parse(
                volume,
                "a 3D Slicer segmentation names its own segments (renumbered 1, 2, ... in \
                 the file's order), so no label file applies to it: leave the label file out",
            ));
        }
        (Some((text, name)), None) => crate::LabelTable::parse_mapped(&text, &name, mapping)?.0,
        (None, Some(list)) => {
            let origin = volume.display().to_string();
            crate::label_names::map_labels(&list, mapping.names()?, mapping.unmapped(), &origin)?.0
        }
        (None, None) => {
            return Err(crate::Error::parse(
                volume,
                "the volume names none of its labels: give a label table, an ITK-SNAP label \
                 file or a Slicer colour table with it",
            ));
        }
    })
}

/// Every file that reading `path` as [`read_input`] does touches: the volume itself, a
/// detached NRRD's data file, or a PNG stack's manifest, label file and slices. For
/// telling an edited input from the one something was built from (a cache's key); what
/// cannot be looked at is left out, and reading the input says why.
pub fn input_files(path: impl AsRef<std::path::Path>) -> Vec<std::path::PathBuf> {
    let path = path.as_ref();
    match InputKind::sniff(path) {
        Ok(InputKind::PngStack { folder, manifest }) => png_stack::stack_files(&folder, &manifest),
        _ => std::iter::once(path.to_path_buf())
            .chain(nrrd::detached_data_file(path))
            .collect(),
    }
}

/// A label volume and its table from any input myoslice reads, told apart by content
/// ([`InputKind::sniff`]): a label volume read as [`read_segmentation`] does, or a PNG
/// stack (its folder or its manifest; the manifest names the labels, so `labels` must be
/// None). A scenario is refused here: it builds a simulation of its own
/// ([`crate::Scenario::build`]).
pub fn read_input(
    path: impl AsRef<std::path::Path>,
    labels: Option<&std::path::Path>,
    mapping: impl Into<crate::label_mapping::LabelMapping>,
) -> crate::Result<(crate::LabelVolume, crate::LabelTable)> {
    let path = path.as_ref();
    match InputKind::sniff(path)? {
        InputKind::Volume => read_segmentation(path, labels, mapping),
        InputKind::PngStack { folder, manifest } => {
            if labels.is_some() {
                return Err(crate::Error::parse(
                    path,
                    "a PNG stack's manifest names its labels (labels_file or [labels]): \
                     leave the label file out",
                ));
            }
            read_png_stack_with(folder, Some(&manifest), mapping)
        }
        InputKind::Scenario => Err(crate::Error::parse(
            path,
            "a scenario: build it as a scenario (`myoslice run`, Scenario::from_path, \
             Simulation.from_scenario), which brings its own model and settings",
        )),
    }
}
