//! Slices of a label volume and their connected regions.

pub mod components;
pub mod stack;

pub use components::{Region, SliceComponents, label_components};
pub use stack::{SliceReduction, SliceStack};
