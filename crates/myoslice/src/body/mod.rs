//! The rigid skeleton: segment inertia, the knee axis and the rapier bodies.

pub mod knee;
pub mod segments;
pub mod skeleton;

pub use knee::{KneeAxis, knee_axis};
pub use segments::{SegmentInertia, shank_and_foot, thigh};
pub use skeleton::{BodyId, Skeleton, SkeletonOptions, SkeletonSnapshot, body_of_bone};
