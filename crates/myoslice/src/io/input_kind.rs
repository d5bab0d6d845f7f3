//! What a file given to myoslice is, told by its content rather than its name.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// How much of a file is read to tell what it is.
pub const HEAD_BYTES: usize = 4096;

/// What kind of input a path holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum InputKind {
    /// A label volume: NIfTI-1/-2 (plain or gzip) or NRRD (`.nrrd`, `.nhdr`,
    /// `.seg.nrrd`).
    Volume,
    /// A folder of PNG slices and its manifest.
    PngStack {
        /// The folder of slices.
        folder: PathBuf,
        /// The manifest.
        manifest: PathBuf,
    },
    /// A scenario (TOML with `[model]` / `[simulation]`).
    Scenario,
}

impl InputKind {
    /// Reads the start of `path` (or looks into the folder) and says what it is.
    ///
    /// ```no_run
    /// use myoslice::io::InputKind;
    /// assert_eq!(InputKind::sniff("leg.seg.nrrd")?, InputKind::Volume);
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn sniff(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        if path.is_dir() {
            let manifest = path.join("manifest.toml");
            if !manifest.is_file() {
                return Err(Error::parse(
                    path,
                    "a folder is read as PNG slices, but it has no manifest.toml",
                ));
            }
            return Ok(Self::PngStack {
                folder: path.to_path_buf(),
                manifest,
            });
        }
        let mut head = Vec::with_capacity(HEAD_BYTES);
        std::fs::File::open(path)
            .and_then(|f| f.take(HEAD_BYTES as u64).read_to_end(&mut head))
            .map_err(|e| Error::io(path, e))?;
        Self::sniff_head(&head, path)
    }

    /// What a file is from its first [`HEAD_BYTES`] (or all of it, if shorter) and its
    /// name (a web page's dropped file: no file system to look in). A PNG stack's
    /// manifest names its folder as `path`'s.
    pub fn sniff_head(head: &[u8], path: &Path) -> Result<Self> {
        let head = &head[..head.len().min(HEAD_BYTES)];
        if head.starts_with(&[0x1f, 0x8b])
            || super::is_nrrd(head)
            || super::nifti::header_len(head).is_some()
        {
            return Ok(Self::Volume);
        }
        // Text: a scenario or a PNG stack's manifest, by their keys. Only the start was
        // read, so keys are looked for line by line rather than by parsing.
        let text = String::from_utf8_lossy(head);
        let text = text.trim_start_matches('\u{feff}');
        let has = |key: &str| {
            text.lines().any(|l| {
                let l = l.trim_start();
                l.starts_with(key) && l[key.len()..].trim_start().starts_with(['=', ']', '.'])
            })
        };
        if has("[model") || has("[simulation") || has("[excitation") {
            return Ok(Self::Scenario);
        }
        if has("pixel_size_mm") || has("slice_interval_mm") {
            return Ok(Self::PngStack {
                folder: path
                    .parent()
                    .filter(|p| !p.as_os_str().is_empty())
                    .unwrap_or(Path::new("."))
                    .to_path_buf(),
                manifest: path.to_path_buf(),
            });
        }
        // Binary, or named as a volume: the volume readers say what is wrong with it
        // (a damaged header), which says more than that nothing matched.
        let named_volume = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .is_some_and(|n| {
                [".nii", ".nii.gz", ".nrrd", ".nhdr", ".gz"]
                    .iter()
                    .any(|e| n.ends_with(e))
            });
        // Text cut inside a character at the 4 KiB mark is still text.
        let binary = std::str::from_utf8(head).is_err_and(|e| e.error_len().is_some());
        if named_volume || head.contains(&0) || binary {
            return Ok(Self::Volume);
        }
        Err(Error::parse(
            path,
            "neither a label volume (NIfTI, NRRD, 3D Slicer segmentation), a PNG stack's \
             manifest nor a scenario",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_are_told_apart_by_content_whatever_their_names() {
        let dir = std::env::temp_dir().join(format!("myoslice-kind-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cases: [(&str, &[u8], Option<InputKind>); 6] = [
            ("a.txt", b"NRRD0004\ntype: uint8\n", Some(InputKind::Volume)),
            ("b.bin", &[0x1f, 0x8b, 8, 0], Some(InputKind::Volume)),
            ("c.dat", &[0x5c, 0x01, 0, 0, 1, 2], Some(InputKind::Volume)),
            (
                "d.cfg",
                b"# x\n[model]\nsource = \"phantom\"\n",
                Some(InputKind::Scenario),
            ),
            (
                "e.toml",
                b"pixel_size_mm = [1, 1]\nslice_interval_mm = 2\n",
                None,
            ),
            ("f.txt", b"hello", None),
        ];
        for (name, bytes, want) in cases {
            let p = dir.join(name);
            std::fs::write(&p, bytes).unwrap();
            match (InputKind::sniff(&p), want) {
                (Ok(k), Some(w)) => assert_eq!(k, w, "{name}"),
                (Ok(InputKind::PngStack { manifest, .. }), None) if name == "e.toml" => {
                    assert_eq!(manifest, p)
                }
                (Err(e), None) if name == "f.txt" => {
                    assert!(e.to_string().contains("neither"), "{e}")
                }
                (got, _) => panic!("{name}: {got:?}"),
            }
        }
        let e = InputKind::sniff(&dir).unwrap_err().to_string();
        assert!(e.contains("manifest.toml"), "{e}");
        // A damaged volume goes to its reader, which names what is wrong.
        let nii = dir.join("leg.nii");
        std::fs::write(&nii, b"not a header").unwrap();
        assert_eq!(InputKind::sniff(&nii).unwrap(), InputKind::Volume);
        let e = crate::io::read_input(&nii, None, crate::label_names::Unmapped::Error)
            .unwrap_err()
            .to_string();
        assert!(e.contains("348-byte NIfTI-1 header"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
