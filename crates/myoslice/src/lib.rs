//! # myoslice
//!
//! A deformable human lower limb built from labelled anatomical slices (bone, muscle,
//! fat) and moved by its own muscles, after Inaba, Miyazaki and Hasegawa, and beyond.
//!
//! The data flow runs one way: label volume → slices → contours → lattice → body model →
//! simulation → frames. This crate holds all of it and is headless; the viewer, the
//! Python package and the CLI are thin fronts over [`Simulation`].
//!
//! Frame and units: SI inside (m, kg, s, N, rad); +z superior, +y anterior, +x toward
//! the subject's right. Slice data arrive in mm and are converted at the edge.
#![warn(missing_docs)]

pub mod body;
pub mod contour;
pub mod error;
pub mod export;
#[doc(hidden)]
pub mod fuzz_targets;
pub mod geometry;
pub mod io;
pub mod label_mapping;
pub mod label_names;
pub mod label_table;
pub mod label_volume;
pub mod lattice;
pub mod muscle;
mod par;
pub mod phantom;
pub mod report;
pub mod scenario;
pub mod simulation;
pub mod slices;
pub mod spatial;
pub mod tissue;
pub mod tracking;

pub use error::{Error, Result};
pub use label_table::{Label, LabelTable, TissueKind};
pub use label_volume::LabelVolume;
pub use lattice::{BoneMesh, BuildOptions, FatLattice, Lattice, MuscleLattice, StructureStats};
pub use report::{BuildReport, StructureReport};
pub use simulation::{Simulation, SimulationConfig, StepTimers};
pub use slices::SliceReduction;

/// The types most programs need.
pub mod prelude {
    pub use crate::error::{Error, Result};
    pub use crate::io::{read_nifti, read_png_stack};
    pub use crate::label_mapping::LabelMapping;
    pub use crate::label_names::Unmapped;
    pub use crate::label_table::{LabelTable, TissueKind};
    pub use crate::label_volume::LabelVolume;
    pub use crate::lattice::{BuildOptions, Lattice};
    pub use crate::phantom::Phantom;
    pub use crate::scenario::Scenario;
    pub use crate::simulation::{MuscleModel, Schedule, Simulation, SimulationConfig, TendonModel};
    pub use crate::slices::SliceReduction;
}
