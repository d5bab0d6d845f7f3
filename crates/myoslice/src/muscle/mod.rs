//! Muscles: Hill-type mechanics, the catalogue, and the paper's mass-spring chains.

pub mod catalogue;
pub mod chain;
pub mod contact;
pub mod dynamics;
pub mod excursion;
pub mod hill;
pub mod scale;
pub(crate) mod snapshot;
pub mod tendon;
pub mod tether;
pub mod unit;
pub mod wrap;

pub use catalogue::{CatalogueEntry, MuscleCatalogue, MuscleGroup, ResolvedMuscle};
pub use chain::{Attachment, BodyFrames, ConeAnchor, MuscleChain};
pub use contact::ChainContact;
pub use dynamics::{ChainLoad, ChainScratch, EndForces};
pub use excursion::{Axis, Pull};
pub use hill::{FibreState, HillForce, HillParams};
pub use scale::MuscleScale;
pub(crate) use snapshot::MuscleSnapshot;
pub use tendon::TendonModel;
pub use tether::Tether;
pub use unit::{ChainOptions, MUSCLE_DENSITY, MuscleUnit};
pub use wrap::{WrapCylinder, WrapPath};
