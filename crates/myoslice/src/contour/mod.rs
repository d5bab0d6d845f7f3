//! Region borders as polygons: radial (the paper's) or traced.

pub mod mask;
pub mod polygon;
pub mod radial;
pub mod trace;

pub use mask::{ComponentMask, LabelSetMask, Mask, outermost_crossing};
pub use polygon::{Polygon, iou, signed_area};
pub use radial::{PolygonMethod, RegionPolygon, polygonise, ray_dir};
pub use trace::{resample_loop, trace_outer_loops};
