//! A scenario's model is known by every file its volume is read from: a cache keyed by
//! [`Scenario::lattice_key`] must not hand back a leg built from an older file.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use common::scratch;
use myoslice::prelude::*;

#[test]
fn an_edited_detached_data_file_makes_a_new_lattice_key() {
    let dir = scratch("inputs-nhdr");
    std::fs::write(
        dir.join("leg.nhdr"),
        "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: leg.raw\n",
    )
    .unwrap();
    std::fs::write(dir.join("leg.raw"), [0u8; 8]).unwrap();
    std::fs::write(dir.join("labels.json"), "{}").unwrap();
    std::fs::write(
        dir.join("run.toml"),
        "[model]\nsource = \"nifti\"\nvolume = \"leg.nhdr\"\nlabels = \"labels.json\"\n\
         [simulation]\nduration_s = 1\n",
    )
    .unwrap();
    let key = || {
        Scenario::from_path(dir.join("run.toml"))
            .unwrap()
            .lattice_key()
    };
    let before = key();
    assert_eq!(key(), before, "the same files give the same key");
    // Only the data file changes (its size too: a clock's resolution does not matter).
    std::fs::write(dir.join("leg.raw"), [1u8; 9]).unwrap();
    assert_ne!(key(), before);
    std::fs::remove_dir_all(dir).unwrap();
}
