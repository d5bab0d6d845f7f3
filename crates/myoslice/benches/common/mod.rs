//! Shared setup of the benchmarks.
#![allow(dead_code)]

use std::path::PathBuf;

use myoslice::prelude::*;

/// The Visible Human leg from `../shared/data`, or `None` with a message when absent.
pub fn vh_paths() -> Option<(PathBuf, PathBuf)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/visible-human");
    let v = dir.join("vhf_left_leg_labels.nii.gz");
    let l = dir.join("vhf_left_leg_labels.json");
    if v.exists() && l.exists() {
        Some((v, l))
    } else {
        eprintln!(
            "Visible Human data not found at {}: its benchmarks are skipped",
            dir.display()
        );
        None
    }
}

/// The Visible Human lattice (default options), if the data are there.
pub fn vh_lattice() -> Option<Lattice> {
    let (v, l) = vh_paths()?;
    let vol = read_nifti(v).ok()?;
    let table = LabelTable::from_path(l).ok()?;
    Lattice::build(&vol, &table, &BuildOptions::default()).ok()
}

/// The phantom lattice (default options).
pub fn phantom_lattice() -> Lattice {
    let (v, t) = Phantom::default()
        .generate()
        .unwrap_or_else(|e| panic!("the phantom builds: {e}"));
    Lattice::build(&v, &t, &BuildOptions::default())
        .unwrap_or_else(|e| panic!("the phantom lattice builds: {e}"))
}

/// The knee flexors (hamstrings, gracilis, sartorius) excited at `level`.
pub fn excite_flexors(sim: &mut Simulation, level: f64) {
    for m in [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
        "gracilis",
        "sartorius",
    ] {
        sim.set_excitation(m, level)
            .unwrap_or_else(|e| panic!("{m}: {e}"));
    }
}

/// A rayon pool of `n` threads.
pub fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap_or_else(|e| panic!("thread pool: {e}"))
}
