//! NRRD label volumes as 3D Slicer and ITK write them: attached or detached, raw or gzip,
//! either byte order, LPS or RAS space, and Slicer segmentations with their segment names
//! and layers; hostile files are refused naming the file, never a panic.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use std::io::Write as _;
use std::path::Path;

use common::scratch;
use myoslice::io::{parse_nrrd, read_label_volume, read_nrrd, read_segmentation};
use myoslice::label_names::Unmapped;
use myoslice::prelude::*;
use proptest::prelude::*;

/// A 3 × 2 × 4 volume of labels 0..=5 with 2 mm × 1 mm × 5 mm voxels.
fn small() -> (Vec<u16>, [usize; 3]) {
    let dims = [3, 2, 4];
    ((0..24).map(|i| (i * 7 % 6) as u16).collect(), dims)
}

fn gzip(b: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

/// Header lines (without the magic and the blank line) and the voxel bytes.
fn nrrd(header: &str, data: &[u8]) -> Vec<u8> {
    let mut out =
        format!("NRRD0004\n# Complete NRRD file format specification at:\n{header}\n").into_bytes();
    out.extend_from_slice(data);
    out
}

#[test]
fn a_slicer_label_map_in_lps_space_reads_into_our_frame() {
    let (data, dims) = small();
    let bytes: Vec<u8> = data.iter().map(|v| *v as u8).collect();
    let raw = nrrd(
        "type: unsigned char\ndimension: 3\nspace: left-posterior-superior\nsizes: 3 2 4\n\
         space directions: (2,0,0) (0,1,0) (0,0,5)\nkinds: domain domain domain\n\
         encoding: raw\nspace origin: (10,-20,300)\n",
        &bytes,
    );
    let v = parse_nrrd(&raw, Path::new("map.nrrd")).unwrap();
    assert_eq!(v.volume.dims(), dims);
    assert!(v.segments.is_none() && v.merge.is_none());
    // LPS x and y point the other way from ours.
    let a = v.volume.affine();
    assert_eq!([a[0][0], a[1][1], a[2][2]], [-2.0, -1.0, 5.0]);
    assert_eq!([a[0][3], a[1][3], a[2][3]], [-10.0, 20.0, 300.0]);
    assert_eq!(v.volume, LabelVolume::new(dims, *a, data).unwrap());
}

#[test]
fn gzip_big_endian_and_detached_data_read_the_same_voxels() {
    let (data, dims) = small();
    let be: Vec<u8> = data.iter().flat_map(|v| v.to_be_bytes()).collect();
    let le: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
    let head = "dimension: 3\nspace: right-anterior-superior\nsizes: 3 2 4\n\
                space directions: (2,0,0) (0,1,0) (0,0,5)\n";
    let want = LabelVolume::axis_aligned(dims, [2.0, 1.0, 5.0], [0.0; 3], data).unwrap();
    let gz = nrrd(
        &format!("type: ushort\n{head}encoding: gzip\nendian: big\n"),
        &gzip(&be),
    );
    assert_eq!(parse_nrrd(&gz, Path::new("a.nrrd")).unwrap().volume, want);
    let dir = scratch("nrrd-detached");
    std::fs::write(dir.join("leg.raw"), &le).unwrap();
    std::fs::write(
        dir.join("leg.nhdr"),
        format!(
            "NRRD0004\ntype: uint16\n{head}encoding: raw\nendian: little\ndata file: leg.raw\n"
        ),
    )
    .unwrap();
    assert_eq!(read_nrrd(dir.join("leg.nhdr")).unwrap().volume, want);
    // What a cache must watch: the header and its data file.
    assert_eq!(
        myoslice::io::input_files(dir.join("leg.nhdr")),
        [dir.join("leg.nhdr"), dir.join("leg.raw")]
    );
    // `spacings` instead of space directions.
    let sp = nrrd(
        "type: short\ndimension: 3\nsizes: 3 2 4\nspacings: 2 1 5\nencoding: raw\nendian: little\n",
        &le,
    );
    assert_eq!(parse_nrrd(&sp, Path::new("s.nrrd")).unwrap().volume, want);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_slicer_segmentation_merges_its_layers_and_names_its_segments() {
    // Two layers over 3 × 1 × 1 voxels, layers fastest: the femur (layer 0, value 1) in
    // the first two voxels; the semitendinosus (layer 1, value 1) over the second one;
    // the fat (layer 0, value 2) nowhere, and the third voxel in no segment.
    let data = [1u8, 0, 1, 1, 0, 0];
    let raw = nrrd(
        "type: unsigned char\ndimension: 4\nspace: left-posterior-superior\nsizes: 2 3 1 1\n\
         space directions: none (1,0,0) (0,1,0) (0,0,1)\nkinds: list domain domain domain\n\
         encoding: raw\nspace origin: (0,0,0)\n\
         Segment0_ID:=Segment_1\nSegment0_Name:=Left femur\nSegment0_LabelValue:=1\nSegment0_Layer:=0\n\
         Segment1_Name:=M. semitendinosus\nSegment1_LabelValue:=1\nSegment1_Layer:=1\n\
         Segment2_Name:=Subcutaneous fat\nSegment2_LabelValue:=2\nSegment2_Layer:=0\n",
        &data,
    );
    let dir = scratch("nrrd-seg");
    let path = dir.join("leg.seg.nrrd");
    std::fs::write(&path, &raw).unwrap();
    let v = read_nrrd(&path).unwrap();
    assert_eq!(
        v.segments.as_deref().unwrap(),
        &[
            (0, "Background".to_string()),
            (1, "Left femur".to_string()),
            (2, "M. semitendinosus".to_string()),
            (3, "Subcutaneous fat".to_string())
        ]
    );
    assert!(v.merge.as_deref().unwrap().contains("last layer"));
    assert_eq!(v.volume.dims(), [3, 1, 1]);
    assert_eq!(v.volume.data(), &[1, 2, 0]);
    let (_, segments) = read_label_volume(&path).unwrap();
    assert_eq!(segments.map(|s| s.len()), Some(4));
    // Its names map onto structures with no label file.
    let (volume, table) = read_segmentation(&path, None, Unmapped::Error).unwrap();
    assert_eq!(volume, v.volume.canonical());
    assert_eq!(
        table.get(2).map(|l| l.name.as_str()),
        Some("semitendinosus")
    );
    assert_eq!(table.kind(1), Some(TissueKind::Bone));
    // Every voxel's label is in the table, the unlabelled one as background.
    assert_eq!(table.kind(0), Some(TissueKind::Background));
    volume.check_labels(&table).unwrap();
    // Its labels are renumbered: a label file cannot apply to it.
    let labels = dir.join("labels.txt");
    std::fs::write(&labels, "0 Background 0 0 0 0\n1 femur 1 1 1 255\n").unwrap();
    let e = read_segmentation(&path, Some(&labels), Unmapped::Error).unwrap_err();
    assert!(e.to_string().contains("names its own segments"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_segmentation_from_before_shared_layers_has_a_layer_per_segment() {
    // Slicer 4.10: no _Layer or _LabelValue, each segment in its own layer with value 1.
    let raw = nrrd(
        "type: uchar\ndimension: 4\nsizes: 2 2 1 1\n\
         space directions: none (1,0,0) (0,1,0) (0,0,1)\nencoding: raw\n\
         Segment0_Name:=femur\nSegment1_Name:=tibia\n",
        &[1, 0, 0, 1],
    );
    let v = parse_nrrd(&raw, Path::new("old.seg.nrrd")).unwrap();
    assert_eq!(v.volume.data(), &[1, 2]);
}

#[test]
fn skipped_lines_and_bytes_are_skipped_where_the_format_says() {
    let (data, dims) = small();
    let bytes: Vec<u8> = data.iter().map(|v| *v as u8).collect();
    let want = LabelVolume::axis_aligned(dims, [1.0; 3], [0.0; 3], data).unwrap();
    // Raw: two text lines, then three bytes, then the voxels.
    let mut body = b"first line\nsecond\nxyz".to_vec();
    body.extend(&bytes);
    let raw = nrrd(
        "type: uchar\ndimension: 3\nsizes: 3 2 4\nline skip: 2\nbyte skip: 3\n",
        &body,
    );
    assert_eq!(parse_nrrd(&raw, Path::new("l.nrrd")).unwrap().volume, want);
    // Gzip: the byte skip counts in the decompressed data.
    let mut inner = vec![9u8; 5];
    inner.extend(&bytes);
    let raw = nrrd(
        "type: uchar\ndimension: 3\nsizes: 3 2 4\nencoding: gzip\nbyte skip: 5\n",
        &gzip(&inner),
    );
    assert_eq!(parse_nrrd(&raw, Path::new("g.nrrd")).unwrap().volume, want);
}

#[test]
fn a_plain_label_map_without_names_needs_a_label_file() {
    let (data, _) = small();
    let bytes: Vec<u8> = data.iter().map(|v| *v as u8).collect();
    let dir = scratch("nrrd-plain");
    let path = dir.join("map.nrrd");
    std::fs::write(
        &path,
        nrrd(
            "type: uchar\ndimension: 3\nsizes: 3 2 4\nencoding: raw\n",
            &bytes,
        ),
    )
    .unwrap();
    let e = read_segmentation(&path, None, Unmapped::Error)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("map.nrrd") && e.contains("names none of its labels"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn the_phantom_written_as_nrrd_reads_back_identical() {
    let (volume, table) = Phantom::default().generate().unwrap();
    let [nx, ny, nz] = volume.dims();
    let a = volume.affine();
    let col = |c: usize| format!("({},{},{})", a[0][c], a[1][c], a[2][c]);
    let bytes: Vec<u8> = (0..nx * ny * nz)
        .flat_map(|i| volume.data()[i].to_le_bytes())
        .collect();
    let raw = nrrd(
        &format!(
            "type: uint16\ndimension: 3\nspace: right-anterior-superior\nsizes: {nx} {ny} {nz}\n\
             space directions: {} {} {}\nencoding: gzip\nendian: little\nspace origin: ({},{},{})\n",
            col(0),
            col(1),
            col(2),
            a[0][3],
            a[1][3],
            a[2][3]
        ),
        &gzip(&bytes),
    );
    let back = parse_nrrd(&raw, Path::new("phantom.nrrd")).unwrap();
    assert_eq!(back.volume, volume);
    // Saved in sagittal slices (k along x, toward the left) in an LPS frame, as another
    // tool might: read back in the builder's order, the same volume.
    let mut sagittal = Vec::with_capacity(nx * ny * nz);
    for i in (0..nx).rev() {
        for k in 0..nz {
            for j in 0..ny {
                sagittal.extend(volume.get(i, j, k).to_le_bytes());
            }
        }
    }
    // Voxel axes: j (fastest), k, then i reversed; LPS negates x and y.
    let dir = |x: f64, y: f64, z: f64| format!("({},{},{})", -x, -y, z);
    let raw = nrrd(
        &format!(
            "type: uint16\ndimension: 3\nspace: left-posterior-superior\nsizes: {ny} {nz} {nx}\n\
             space directions: {} {} {}\nencoding: raw\nendian: little\nspace origin: {}\n",
            dir(0.0, a[1][1], 0.0),
            dir(0.0, 0.0, a[2][2]),
            dir(-a[0][0], 0.0, 0.0),
            dir(a[0][3] + a[0][0] * (nx - 1) as f64, a[1][3], a[2][3]),
        ),
        &sagittal,
    );
    let dir_ = scratch("nrrd-sagittal");
    let path = dir_.join("sagittal.nrrd");
    std::fs::write(&path, &raw).unwrap();
    let (read, _) = read_label_volume(&path).unwrap();
    assert_eq!(read, volume);
    std::fs::remove_dir_all(dir_).unwrap();
    // And builds the same lattice.
    let opts = BuildOptions::default();
    let (l0, l1) = (
        Lattice::build(&volume, &table, &opts).unwrap(),
        Lattice::build(&back.volume, &table, &opts).unwrap(),
    );
    assert_eq!(l0.fat.vertices, l1.fat.vertices);
}

#[test]
fn hostile_headers_are_refused_naming_the_file() {
    for (head, data, says) in [
        (
            "type: float\ndimension: 3\nsizes: 1 1 1\n",
            vec![0u8; 4],
            "not a label type",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 100000 100000 100000\n",
            vec![],
            "cap",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 2 2 2\n",
            vec![0u8; 7],
            "need 8",
        ),
        (
            "type: uchar\ndimension: 2\nsizes: 2 2\n",
            vec![0u8; 4],
            "3 axes",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: bzip2\n",
            vec![0],
            "bzip2",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\nspace: scanner-xyz\n",
            vec![0],
            "scanner-xyz",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\nspace directions: (1,0) (0,1,0) (0,0,1)\n",
            vec![0],
            "3 numbers",
        ),
        (
            "type: int\ndimension: 3\nsizes: 1 1 1\nendian: little\n",
            (-4i32).to_le_bytes().to_vec(),
            "not a label",
        ),
        ("dimension: 3\nsizes: 1 1 1\n", vec![0], "no 'type'"),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: gzip\n",
            vec![1, 2, 3],
            "gzip",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\ndata file: absent.raw\n",
            vec![],
            "absent.raw",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\ndata file: /dev/zero\n",
            vec![],
            "not a regular file",
        ),
        (
            "type: uchar\ndimension: 4\nsizes: 1 1 1 2\nspace directions: (1,0,0) (0,1,0) (0,0,1) none\n",
            vec![0; 2],
            "after 'none' for a layer axis",
        ),
        (
            "type: uchar\ndimension: 4\nsizes: 1 1 1 2\nkinds: domain domain domain list\n",
            vec![0; 2],
            "kinds",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\nspacings: 1 nan 1\n",
            vec![0],
            "spacing 'nan'",
        ),
        (
            "type: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: gzip\nline skip: 1\n",
            vec![0],
            "line skip",
        ),
    ] {
        let raw = nrrd(head, &data);
        let e = parse_nrrd(&raw, Path::new("hostile.nrrd"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{head}: {e}");
        assert!(
            e.contains("hostile.nrrd") || e.contains("absent.raw") || e.contains("/dev/zero"),
            "{e}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Any byte of a small segmentation changed, or the file cut short: an error or a
    /// volume, never a panic.
    #[test]
    fn a_damaged_nrrd_never_panics(
        edits in proptest::collection::vec((0usize..700, any::<u8>()), 0..4),
        cut in proptest::option::of(0usize..700),
    ) {
        let mut raw = nrrd(
            "type: unsigned char\ndimension: 4\nsizes: 2 2 1 1\n\
             space directions: none (1,0,0) (0,1,0) (0,0,1)\nencoding: raw\n\
             Segment0_Name:=femur\nSegment0_LabelValue:=1\nSegment0_Layer:=0\n\
             Segment1_Name:=tibia\nSegment1_LabelValue:=1\nSegment1_Layer:=1\n",
            &[1, 0, 1, 1],
        );
        for (at, b) in edits {
            let n = raw.len();
            raw[at % n] = b;
        }
        if let Some(c) = cut {
            raw.truncate(c.min(raw.len()));
        }
        if let Err(e) = parse_nrrd(&raw, Path::new("damaged.nrrd")) {
            prop_assert!(e.to_string().contains("damaged.nrrd"), "{e}");
        }
    }
}
