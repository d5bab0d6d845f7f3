//! The built-in lower-limb phantom: a definition measured on the Visible Human leg, and
//! its rasterisation into a label volume at any voxel size.

pub mod definition;
pub mod generate;
pub mod measure;

pub use definition::{PhantomDefinition, PhantomHeader, PhantomStructure};
pub use generate::{Phantom, definition_table, generate, leg_definition};
pub use measure::measure_phantom;
