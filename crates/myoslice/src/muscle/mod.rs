//! Muscles: Hill-type mechanics, the catalogue, and the paper's mass-spring chains.

pub mod catalogue;
pub mod chain;
pub mod excursion;
pub mod hill;
pub mod unit;
pub mod wrap;

pub use catalogue::{CatalogueEntry, MuscleCatalogue, MuscleGroup, ResolvedMuscle};
pub use chain::{Attachment, BodyFrames, ChainLoad, ConeAnchor, EndForces, MuscleChain};
pub use excursion::{Axis, Pull};
pub use hill::{FibreState, HillForce, HillParams};
pub use unit::{ChainOptions, MUSCLE_DENSITY, MuscleUnit};
pub use wrap::{WrapCylinder, WrapPath};
