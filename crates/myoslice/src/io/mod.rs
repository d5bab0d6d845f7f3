//! Readers and writers of label volumes, and of the label lists of segmentation tools.

pub mod label_lists;
pub mod nifti;
pub mod png_stack;

pub use label_lists::{LabelListFormat, parse_label_list, sniff_label_list};
pub use nifti::{MAX_VOLUME_BYTES, encode_nifti, parse_nifti, read_nifti, write_nifti};
pub use png_stack::{read_png_stack, write_png_labels};
