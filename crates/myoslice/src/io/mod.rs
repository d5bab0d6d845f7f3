//! Readers and writers of label volumes.

pub mod nifti;
pub mod png_stack;

pub use nifti::{MAX_VOLUME_BYTES, encode_nifti, parse_nifti, read_nifti, write_nifti};
pub use png_stack::{read_png_stack, write_png_labels};
