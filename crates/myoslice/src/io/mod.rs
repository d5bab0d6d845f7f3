//! Readers and writers of label volumes (NIfTI-1, NRRD, PNG stacks), and of the label
//! lists of segmentation tools.

pub mod label_lists;
pub mod nifti;
pub mod nrrd;
pub mod png_stack;

pub use label_lists::{LabelListFormat, LabelNames, parse_label_list, sniff_label_list};
pub use nifti::{MAX_VOLUME_BYTES, encode_nifti, parse_nifti, read_nifti, write_nifti};
pub use nrrd::{NrrdVolume, is_nrrd, parse_nrrd, read_nrrd};
pub use png_stack::{decode_png_labels, read_png_stack, write_png_labels};

/// Reads a label volume, NIfTI-1 or NRRD (told apart by content), in the order the lattice
/// builder slices it ([`crate::LabelVolume::canonical`]: a scan saved in sagittal or
/// coronal slices, or in a left-posterior-superior frame, is reordered voxel for voxel),
/// with the label names the file itself carries (a 3D Slicer segmentation's segments;
/// None otherwise).
pub fn read_label_volume(
    path: impl AsRef<std::path::Path>,
) -> crate::Result<(crate::LabelVolume, Option<LabelNames>)> {
    let path = path.as_ref();
    let raw = std::fs::read(path).map_err(|e| crate::Error::io(path, e))?;
    if is_nrrd(&raw) {
        let v = parse_nrrd(&raw, path)?;
        Ok((v.volume.canonical(), v.segments))
    } else {
        Ok((parse_nifti(&raw, path)?.canonical(), None))
    }
}

/// A label volume (NIfTI-1 or NRRD) and what its labels mean: the label table or tool's
/// label list at `labels` ([`crate::LabelTable::from_path_with`]), or else the segment
/// names a 3D Slicer segmentation carries, mapped onto known structures as `unmapped`
/// says.
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
    unmapped: crate::label_names::Unmapped,
) -> crate::Result<(crate::LabelVolume, crate::LabelTable)> {
    let volume = volume.as_ref();
    let (v, segments) = read_label_volume(volume)?;
    let table = match (labels, segments) {
        (Some(_), Some(_)) => {
            return Err(crate::Error::parse(
                volume,
                "a 3D Slicer segmentation names its own segments (renumbered 1, 2, ... in \
                 the file's order), so no label file applies to it: leave the label file out",
            ));
        }
        (Some(l), None) => crate::LabelTable::from_path_with(l, unmapped)?,
        (None, Some(list)) => {
            let names = crate::label_names::AnatomyNames::builtin()?;
            let origin = volume.display().to_string();
            crate::label_names::map_labels(&list, names, unmapped, &origin)?.0
        }
        (None, None) => {
            return Err(crate::Error::parse(
                volume,
                "the volume names none of its labels: give a label table, an ITK-SNAP label \
                 file or a Slicer colour table with it",
            ));
        }
    };
    Ok((v, table))
}
