//! What each reader must survive, whatever the bytes: the bodies of the cargo-fuzz
//! targets in `fuzz/`, also replayed over the kept corpus by `cargo test` on stable
//! (`tests/fuzz_corpus.rs`). Each returns whether the input was accepted; a panic, a
//! hang or an allocation past the stated caps ([`crate::io::MAX_VOLUME_BYTES`],
//! [`crate::io::png_stack::MAX_SLICE_BYTES`]) is the failure.

use std::path::Path;

use crate::label_names::{AnatomyNames, Unmapped, map_labels};

/// A NIfTI-1 or NIfTI-2 file (gzip or not).
pub fn nifti(data: &[u8]) -> bool {
    crate::io::parse_nifti(data, Path::new("fuzz.nii")).is_ok_and(|v| {
        // What was accepted can be brought into the builder's frame (reordered or
        // resampled within its cap).
        let _ = v.in_frame();
        true
    })
}

/// A NRRD file with attached data (a detached one would read another file).
pub fn nrrd(data: &[u8]) -> bool {
    // Field names compare without spaces or case: "data file", "DataFile :", ...
    let squeezed: Vec<u8> = data
        .iter()
        .filter(|b| !b.is_ascii_whitespace())
        .map(u8::to_ascii_lowercase)
        .collect();
    if squeezed.windows(8).any(|w| w == b"datafile") {
        return false;
    }
    crate::io::parse_nrrd(data, Path::new("fuzz.nrrd")).is_ok_and(|v| {
        let _ = v.volume.in_frame();
        true
    })
}

/// An ITK-SNAP label description file or a Slicer colour table, names mapped.
pub fn label_list(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let Ok(names) = AnatomyNames::builtin() else {
        return false;
    };
    crate::io::parse_label_list(text, "fuzz.txt")
        .and_then(|list| map_labels(&list, names, Unmapped::Fat, "fuzz.txt"))
        .is_ok()
}

/// Our label table, as JSON and as TOML.
pub fn label_table(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let json = crate::LabelTable::from_json_str(text, "fuzz.json").is_ok();
    let toml = crate::LabelTable::from_toml_str(text, "fuzz.toml").is_ok();
    json || toml
}

/// A scenario file, and its options validated as a build would.
pub fn scenario(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    crate::scenario::Scenario::from_str_at(text, Path::new("fuzz.toml"))
        .is_ok_and(|s| s.config().validate().is_ok() && s.build_options().validate().is_ok())
}

/// One slice of a PNG stack (grey ids, or colours of a manifest's map).
pub fn png_slice(data: &[u8]) -> bool {
    let colors = [([255, 0, 0], 1), ([0, 255, 0], 2)].into_iter().collect();
    crate::io::decode_png_labels(data, Path::new("fuzz.png"), &colors).is_ok()
}

/// A user's names file (`[map]`, `[structure.NAME]`) over the built-in synonyms.
pub fn names(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    crate::label_mapping::LabelMapping::new(Unmapped::Error)
        .with_names_str(text, "fuzz.toml")
        .is_ok()
}

/// A target: whether it accepted the bytes.
pub type Target = fn(&[u8]) -> bool;

/// Every target by name, for the corpus replay.
pub const TARGETS: [(&str, Target); 7] = [
    ("nifti", nifti),
    ("nrrd", nrrd),
    ("label_list", label_list),
    ("label_table", label_table),
    ("scenario", scenario),
    ("png_slice", png_slice),
    ("names", names),
];
