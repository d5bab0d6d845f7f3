//! Writers for other tools: pictures, ParaView, Blender, time series.

pub mod slice_image;

pub use slice_image::{label_colour, write_axial_slices};
pub mod vtu;

pub use vtu::{CellType, VtuMesh, write_atomic, write_pvd};
pub mod body_vtu;

pub use body_vtu::{BodyPositions, FatScalars, body_vtu, rest_vtu};
pub mod gltf;
pub mod run;

pub use gltf::{MorphMesh, RigidMesh, encode_glb};
pub use run::{RunAudit, RunOutputs, RunSummary, RunWriter};
pub mod scenario_run;

pub use scenario_run::{RunProgress, run_scenario, run_scenario_with};
