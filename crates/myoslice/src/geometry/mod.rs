//! Geometry the tissue solver queries: poses, bone signed distance fields, bounding
//! volume hierarchies over triangle sets, and exact triangle tests.

pub mod bvh;
pub mod polyline;
pub mod pose;
pub mod sdf;
pub mod triangle;

pub use bvh::{TriangleBvh, TriangleSet};
pub use polyline::closest_on_polyline;
pub use pose::Pose;
pub use sdf::{BoneSdf, SdfSample, SurfacePoint};
pub use triangle::{Feature, closest_point, triangles_cross};
