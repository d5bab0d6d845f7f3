//! A corrupt or hostile NIfTI file gives an error, never a panic or an abort: random
//! byte changes and truncations of a valid file, compressed and not, and headers that
//! claim more data than any leg (a gzip bomb is not decompressed).

#![allow(clippy::unwrap_used)] // tests fail loudly by design

use std::io::Write;
use std::path::Path;

use myoslice::io::{MAX_VOLUME_BYTES, encode_nifti, parse_nifti};
use myoslice::prelude::*;
use proptest::prelude::*;

/// A small valid volume's NIfTI bytes.
fn valid() -> Vec<u8> {
    let (nx, ny, nz) = (6, 5, 4);
    let data: Vec<u16> = (0..nx * ny * nz).map(|i| (i % 7) as u16).collect();
    let v = LabelVolume::axis_aligned([nx, ny, nz], [1.0, 1.5, 2.0], [0.0; 3], data).unwrap();
    encode_nifti(&v)
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn parse(bytes: &[u8]) -> myoslice::Result<LabelVolume> {
    parse_nifti(bytes, Path::new("hostile.nii.gz"))
}

/// `bytes` with dimensions `dims` written into its header.
fn with_dims(mut bytes: Vec<u8>, dims: [i16; 3]) -> Vec<u8> {
    for (i, d) in dims.iter().enumerate() {
        bytes[42 + 2 * i..44 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    bytes
}

#[test]
fn the_valid_file_parses_compressed_and_not() {
    let b = valid();
    assert_eq!(parse(&b).unwrap().dims(), [6, 5, 4]);
    assert_eq!(parse(&gzip(&b)).unwrap().dims(), [6, 5, 4]);
}

#[test]
fn a_header_claiming_a_trillion_voxels_is_refused_without_reading_them() {
    // 32767³ uint8 voxels: 3.5 × 10¹³ bytes.
    let b = with_dims(valid(), [i16::MAX; 3]);
    let e = parse(&b).unwrap_err().to_string();
    assert!(e.contains("cap") && e.contains("hostile.nii.gz"), "{e}");
    let e = parse(&gzip(&b)).unwrap_err().to_string();
    assert!(
        e.contains("cap") && e.contains(&MAX_VOLUME_BYTES.to_string()),
        "{e}"
    );
}

#[test]
fn a_gzip_bomb_is_decompressed_no_further_than_the_header_claims() {
    // A valid small volume followed by 64 MB of zeros (64 kB compressed): only the
    // header's share is read, so the volume is the small one.
    let mut b = valid();
    let n = b.len();
    b.resize(n + (64 << 20), 0);
    let v = parse(&gzip(&b)).unwrap();
    assert_eq!(v.dims(), [6, 5, 4]);
    // The same bomb behind a header that claims it all, and more than the cap.
    let e = parse(&gzip(&with_dims(b, [2048, 2048, 2048])))
        .unwrap_err()
        .to_string();
    assert!(e.contains("cap"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn changed_bytes_never_panic(
        changes in proptest::collection::vec((0usize..500, any::<u8>()), 1..12),
        cut in 0usize..600,
        compress in any::<bool>(),
    ) {
        let mut b = valid();
        for (at, byte) in changes {
            let i = at % b.len();
            b[i] = byte;
        }
        b.truncate(cut.max(1).min(b.len()));
        let bytes = if compress { gzip(&b) } else { b };
        if let Err(e) = parse(&bytes) {
            prop_assert!(e.to_string().contains("hostile.nii.gz"), "{e}");
        }
    }

    #[test]
    fn changed_compressed_bytes_never_panic(
        changes in proptest::collection::vec((0usize..400, any::<u8>()), 1..8),
    ) {
        let mut z = gzip(&valid());
        for (at, byte) in changes {
            let i = at % z.len();
            z[i] = byte;
        }
        if let Err(e) = parse(&z) {
            prop_assert!(e.to_string().contains("hostile.nii.gz"), "{e}");
        }
    }
}
