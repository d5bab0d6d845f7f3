//! NIfTI label volumes (`.nii`, `.nii.gz`), versions 1 and 2.
//!
//! Reads single-file NIfTI-1 (`n+1`) and NIfTI-2 (`n+2`) in either byte order,
//! gzip-compressed or not, with labels stored as any integer type of 8 to 32 bits (values
//! 0 to 65 535) or as floats holding whole numbers (as some pipelines save label maps). The
//! voxel-to-world affine comes from the sform when present, else the qform, else the
//! voxel sizes; spatial units are converted to mm.
//!
//! Our own reader rather than the `nifti` crate: it checks every size against
//! [`MAX_VOLUME_BYTES`] before allocating or decompressing, which the fuzzing of this
//! module holds it to, and it needs no `ndarray`.

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};
use crate::label_volume::LabelVolume;

/// NIfTI-1's header size (and its `sizeof_hdr`).
const NIFTI1_LEN: usize = 348;
/// NIfTI-2's header size.
const NIFTI2_LEN: usize = 540;

/// Reads a NIfTI-1 or NIfTI-2 label volume from a file.
pub fn read_nifti(path: impl AsRef<Path>) -> Result<LabelVolume> {
    let path = path.as_ref();
    let raw = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_nifti(&raw, path)
}

/// Parses NIfTI-1 or NIfTI-2 bytes (gzip-compressed or not); `path` is only used in
/// messages.
pub fn parse_nifti(raw: &[u8], path: &Path) -> Result<LabelVolume> {
    let err = |reason: String| Error::Nifti {
        path: path.to_path_buf(),
        reason,
    };
    let bytes: std::borrow::Cow<'_, [u8]> = if raw.starts_with(&[0x1f, 0x8b]) {
        gunzip_bounded(raw).map_err(err)?.into()
    } else {
        raw.into()
    };
    let h = Header::parse(&bytes).map_err(err)?;
    let volume = h.read_voxels(&bytes).map_err(err)?;
    Ok(volume)
}

/// Most bytes a label volume may take (header and voxels): 4 GiB, a 1024 × 1024 × 2048
/// uint16 volume. Checked against what the header claims before anything that size is
/// allocated or decompressed, so a corrupt header or a gzip bomb gives an error, not an
/// abort.
pub const MAX_VOLUME_BYTES: u64 = 4 << 30;

/// Decompresses a gzip NIfTI no further than its header says the file reaches (header,
/// then voxels): the header is read first, and a claim beyond [`MAX_VOLUME_BYTES`] is
/// refused before the voxels are decompressed.
fn gunzip_bounded(raw: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let corrupt = |e: std::io::Error| format!("gzip stream is corrupt or truncated ({e})");
    let mut dec = flate2::read::MultiGzDecoder::new(raw);
    let mut out = Vec::with_capacity(NIFTI2_LEN + 4);
    (&mut dec)
        .take(NIFTI1_LEN as u64)
        .read_to_end(&mut out)
        .map_err(corrupt)?;
    if out.len() < NIFTI1_LEN {
        // Too short for a header: the parser says so.
        return Ok(out);
    }
    if header_len(&out).is_some_and(|(len, _)| len == NIFTI2_LEN) {
        (&mut dec)
            .take((NIFTI2_LEN - NIFTI1_LEN) as u64)
            .read_to_end(&mut out)
            .map_err(corrupt)?;
    }
    let claimed = Header::parse(&out)?.claimed_bytes();
    if claimed > MAX_VOLUME_BYTES {
        return Err(too_big(claimed));
    }
    // What the header claims (the voxels' check names a shortfall), and not a byte more.
    let rest = claimed.saturating_sub(out.len() as u64);
    out.reserve(
        usize::try_from(rest)
            .unwrap_or(0)
            .min(raw.len().saturating_mul(64)),
    );
    dec.take(rest).read_to_end(&mut out).map_err(corrupt)?;
    Ok(out)
}

fn too_big(claimed: u64) -> String {
    format!(
        "the header claims {claimed} bytes of data, more than the {MAX_VOLUME_BYTES}-byte cap on a label volume"
    )
}

/// The header's size by its `sizeof_hdr` (348: NIfTI-1, 540: NIfTI-2) and whether it is
/// big-endian.
pub(crate) fn header_len(b: &[u8]) -> Option<(usize, bool)> {
    let h: [u8; 4] = b.get(..4)?.try_into().ok()?;
    [
        (NIFTI1_LEN, false),
        (NIFTI2_LEN, false),
        (NIFTI1_LEN, true),
        (NIFTI2_LEN, true),
    ]
    .into_iter()
    .find(|&(len, big)| {
        let v = if big {
            i32::from_be_bytes(h)
        } else {
            i32::from_le_bytes(h)
        };
        v == len as i32
    })
}

/// A voxel type a label volume may be stored as.
#[derive(Clone, Copy)]
enum Voxel {
    U8,
    I8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Voxel {
    fn of(datatype: i16) -> std::result::Result<Self, String> {
        Ok(match datatype {
            2 => Self::U8,
            256 => Self::I8,
            4 => Self::I16,
            512 => Self::U16,
            8 => Self::I32,
            768 => Self::U32,
            16 => Self::F32,
            64 => Self::F64,
            t => {
                return Err(format!(
                    "datatype {t} is not supported for labels; expected an integer type \
                     (uint8 2, int8 256, int16 4, uint16 512, int32 8, uint32 768) or a float \
                     holding whole numbers (float32 16, float64 64)"
                ));
            }
        })
    }

    fn bytes(self) -> usize {
        match self {
            Self::U8 | Self::I8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::U8 => "uint8",
            Self::I8 => "int8",
            Self::I16 => "int16",
            Self::U16 => "uint16",
            Self::I32 => "int32",
            Self::U32 => "uint32",
            Self::F32 => "float32",
            Self::F64 => "float64",
        }
    }

    /// The value of one voxel's bytes, as f64 (exact for every type here).
    fn value(self, c: &[u8], big: bool) -> f64 {
        let mut a = [0u8; 8];
        a[..c.len()].copy_from_slice(c);
        if big {
            a[..c.len()].reverse();
        }
        match self {
            Self::U8 => f64::from(a[0]),
            Self::I8 => f64::from(a[0] as i8),
            Self::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            Self::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            Self::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Self::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Self::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Self::F64 => f64::from_le_bytes(a),
        }
    }
}

struct Header {
    big: bool,
    dims: [usize; 3],
    datatype: i16,
    vox_offset: u64,
    affine: [[f64; 4]; 3],
    slope: f64,
    inter: f64,
}

/// Reads the fields of either version at their offsets, in the file's byte order.
struct Fields<'a> {
    b: &'a [u8],
    big: bool,
}

impl Fields<'_> {
    fn bytes<const N: usize>(&self, o: usize) -> [u8; N] {
        let mut a = [0u8; N];
        a.copy_from_slice(&self.b[o..o + N]);
        if self.big {
            a.reverse();
        }
        a
    }
    fn i16(&self, o: usize) -> i16 {
        i16::from_le_bytes(self.bytes(o))
    }
    fn i32(&self, o: usize) -> i32 {
        i32::from_le_bytes(self.bytes(o))
    }
    fn i64(&self, o: usize) -> i64 {
        i64::from_le_bytes(self.bytes(o))
    }
    fn f32(&self, o: usize) -> f64 {
        f64::from(f32::from_le_bytes(self.bytes(o)))
    }
    fn f64(&self, o: usize) -> f64 {
        f64::from_le_bytes(self.bytes(o))
    }
}

/// The fields both versions have, read at the offsets of the file's version.
struct Common {
    dim: [i64; 8],
    datatype: i16,
    pixdim: [f64; 8],
    vox_offset: f64,
    slope: f64,
    inter: f64,
    qform_code: i32,
    sform_code: i32,
    quatern: [f64; 3],
    qoffset: [f64; 3],
    srow: [[f64; 4]; 3],
    units: u8,
}

impl Header {
    fn parse(b: &[u8]) -> std::result::Result<Self, String> {
        let Some((len, big)) = header_len(b) else {
            if b.len() < NIFTI1_LEN {
                return Err(format!(
                    "file has {} bytes, shorter than the 348-byte NIfTI-1 header",
                    b.len()
                ));
            }
            return Err("sizeof_hdr is neither 348 nor 540: not a NIfTI-1 or NIfTI-2 file".into());
        };
        if b.len() < len {
            let v = if len == NIFTI1_LEN { 1 } else { 2 };
            return Err(format!(
                "file has {} bytes, shorter than the {len}-byte NIfTI-{v} header",
                b.len()
            ));
        }
        let f = Fields { b, big };
        let c = if len == NIFTI1_LEN {
            match &b[344..348] {
                b"n+1\0" => {}
                b"ni1\0" => {
                    return Err(
                        "two-file NIfTI (.hdr/.img) is not supported; convert to .nii".into(),
                    );
                }
                _ => return Err("magic is not 'n+1': not a NIfTI-1 file".into()),
            }
            Common {
                dim: std::array::from_fn(|i| i64::from(f.i16(40 + 2 * i))),
                datatype: f.i16(70),
                pixdim: std::array::from_fn(|i| f.f32(76 + 4 * i)),
                vox_offset: f.f32(108),
                slope: f.f32(112),
                inter: f.f32(116),
                qform_code: i32::from(f.i16(252)),
                sform_code: i32::from(f.i16(254)),
                quatern: std::array::from_fn(|i| f.f32(256 + 4 * i)),
                qoffset: std::array::from_fn(|i| f.f32(268 + 4 * i)),
                srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f32(280 + 16 * r + 4 * c))),
                units: b[123],
            }
        } else {
            match &b[4..12] {
                b"n+2\0\r\n\x1a\n" => {}
                b"ni2\0\r\n\x1a\n" => {
                    return Err(
                        "two-file NIfTI (.hdr/.img) is not supported; convert to .nii".into(),
                    );
                }
                _ => return Err("magic is not 'n+2': not a NIfTI-2 file".into()),
            }
            Common {
                dim: std::array::from_fn(|i| f.i64(16 + 8 * i)),
                datatype: f.i16(12),
                pixdim: std::array::from_fn(|i| f.f64(104 + 8 * i)),
                vox_offset: f.i64(168) as f64,
                slope: f.f64(176),
                inter: f.f64(184),
                qform_code: f.i32(344),
                sform_code: f.i32(348),
                quatern: std::array::from_fn(|i| f.f64(352 + 8 * i)),
                qoffset: std::array::from_fn(|i| f.f64(376 + 8 * i)),
                srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f64(400 + 32 * r + 8 * c))),
                units: (f.i32(500) & 0xff) as u8,
            }
        };
        Self::from_common(&c, big, len)
    }

    fn from_common(c: &Common, big: bool, len: usize) -> std::result::Result<Self, String> {
        let ndim = c.dim[0];
        let dim = &c.dim[1..];
        if !(3..=7).contains(&ndim) || dim[3..ndim as usize].iter().any(|&d| d != 1) {
            return Err(format!(
                "expected a 3-D volume, got {ndim} dimensions {:?}",
                &dim[..ndim.clamp(0, 7) as usize]
            ));
        }
        if dim[..3].iter().any(|&d| d < 1) {
            return Err(format!("dimensions {:?} must all be >= 1", &dim[..3]));
        }
        let dims: [usize; 3] =
            std::array::from_fn(|i| usize::try_from(dim[i]).unwrap_or(usize::MAX));
        if !(c.vox_offset.is_finite() && c.vox_offset >= len as f64 && c.vox_offset < 1e15) {
            return Err(format!("vox_offset {} is invalid", c.vox_offset));
        }
        let unit = match c.units & 0x07 {
            1 => 1000.0,
            3 => 1e-3,
            _ => 1.0,
        };
        let mut affine = [[0.0f64; 4]; 3];
        if c.sform_code > 0 {
            for (row, srow) in affine.iter_mut().zip(&c.srow) {
                for (v, s) in row.iter_mut().zip(srow) {
                    *v = s * unit;
                }
            }
        } else if c.qform_code > 0 {
            let [qb, qc, qd] = c.quatern;
            let qa = (1.0 - (qb * qb + qc * qc + qd * qd)).max(0.0).sqrt();
            let rot = [
                [
                    qa * qa + qb * qb - qc * qc - qd * qd,
                    2.0 * (qb * qc - qa * qd),
                    2.0 * (qb * qd + qa * qc),
                ],
                [
                    2.0 * (qb * qc + qa * qd),
                    qa * qa + qc * qc - qb * qb - qd * qd,
                    2.0 * (qc * qd - qa * qb),
                ],
                [
                    2.0 * (qb * qd - qa * qc),
                    2.0 * (qc * qd + qa * qb),
                    qa * qa + qd * qd - qb * qb - qc * qc,
                ],
            ];
            let qfac = if c.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
            let sz = [c.pixdim[1], c.pixdim[2], c.pixdim[3] * qfac];
            for r in 0..3 {
                for k in 0..3 {
                    affine[r][k] = rot[r][k] * sz[k] * unit;
                }
                affine[r][3] = c.qoffset[r] * unit;
            }
        } else {
            for r in 0..3 {
                affine[r][r] = c.pixdim[r + 1] * unit;
            }
        }
        if affine.iter().flatten().any(|v| !v.is_finite()) {
            return Err("the voxel-to-world transform is not finite".into());
        }
        Ok(Self {
            big,
            dims,
            datatype: c.datatype,
            vox_offset: c.vox_offset as u64,
            affine,
            slope: c.slope,
            inter: c.inter,
        })
    }

    /// Bytes the header says the file holds: the voxel offset and the voxels (at one byte
    /// a voxel for a type it cannot read, refused later by name).
    fn claimed_bytes(&self) -> u64 {
        let per = Voxel::of(self.datatype).map_or(1, Voxel::bytes) as u64;
        self.dims
            .iter()
            .fold(per, |a: u64, &d| a.saturating_mul(d as u64))
            .saturating_add(self.vox_offset)
    }

    fn read_voxels(&self, b: &[u8]) -> std::result::Result<LabelVolume, String> {
        let voxel = Voxel::of(self.datatype)?;
        let claimed = self.claimed_bytes();
        if claimed > MAX_VOLUME_BYTES {
            return Err(too_big(claimed));
        }
        // Within the cap, so these fit in usize.
        let n = self.dims.iter().product::<usize>();
        if self.slope != 0.0 && (self.slope != 1.0 || self.inter != 0.0) {
            return Err(format!(
                "scl_slope {} / scl_inter {} would rescale the labels; label volumes must be unscaled",
                self.slope, self.inter
            ));
        }
        let need = n * voxel.bytes();
        let start = self.vox_offset as usize;
        let avail = b.len().saturating_sub(start);
        if avail < need {
            return Err(format!(
                "truncated: {} voxels of a {}x{}x{} volume need {need} bytes after the header, found {avail}",
                voxel.name(),
                self.dims[0],
                self.dims[1],
                self.dims[2]
            ));
        }
        let src = &b[start..start + need];
        let data = match voxel {
            // Every value of these is a label: no check per voxel.
            Voxel::U8 => src.iter().map(|&v| u16::from(v)).collect(),
            Voxel::U16 => src
                .chunks_exact(2)
                .map(|c| {
                    let a = [c[0], c[1]];
                    if self.big {
                        u16::from_be_bytes(a)
                    } else {
                        u16::from_le_bytes(a)
                    }
                })
                .collect(),
            _ => Self::checked_labels(src, voxel, self.big)?,
        };
        LabelVolume::new(self.dims, self.affine, data).map_err(|e| e.to_string())
    }

    /// Labels of a type that can hold other values: each must be a whole number 0 to
    /// 65 535.
    fn checked_labels(
        src: &[u8],
        voxel: Voxel,
        big: bool,
    ) -> std::result::Result<Vec<u16>, String> {
        let mut data = Vec::with_capacity(src.len() / voxel.bytes());
        for (i, c) in src.chunks_exact(voxel.bytes()).enumerate() {
            let v = voxel.value(c, big);
            if !(v.fract() == 0.0 && (0.0..=65535.0).contains(&v)) {
                return Err(format!(
                    "voxel {i} holds {v}, not a label: labels are whole numbers 0 to 65535 \
                     ({} volume)",
                    voxel.name()
                ));
            }
            data.push(v as u16);
        }
        Ok(data)
    }
}

/// Writes a NIfTI-1 uint8/uint16 label volume (gzip when the name ends in `.gz`).
pub fn write_nifti(path: impl AsRef<Path>, volume: &LabelVolume) -> Result<()> {
    let path = path.as_ref();
    let bytes = encode_nifti(volume);
    let out = if path.extension().is_some_and(|e| e == "gz") {
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut enc, &bytes).map_err(|e| Error::write(path, e))?;
        enc.finish().map_err(|e| Error::write(path, e))?
    } else {
        bytes
    };
    std::fs::write(path, out).map_err(|e| Error::write(path, e))
}

/// Encodes a label volume as little-endian NIfTI-1 bytes (uint8 when every label fits).
pub fn encode_nifti(volume: &LabelVolume) -> Vec<u8> {
    let wide = volume.data().iter().any(|&v| v > 255);
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let d = volume.dims();
    let dim: [i16; 8] = [3, d[0] as i16, d[1] as i16, d[2] as i16, 1, 1, 1, 1];
    for (i, v) in dim.iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    let (dt, bp): (i16, i16) = if wide { (512, 16) } else { (2, 8) };
    h[70..72].copy_from_slice(&dt.to_le_bytes());
    h[72..74].copy_from_slice(&bp.to_le_bytes());
    let sp = volume.spacing_mm();
    let pix = [
        1.0f32,
        sp[0] as f32,
        sp[1] as f32,
        sp[2] as f32,
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    for (i, v) in pix.iter().enumerate() {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&v.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[123] = 2; // mm
    h[254..256].copy_from_slice(&1i16.to_le_bytes());
    for (r, row) in volume.affine().iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            let o = 280 + 16 * r + 4 * c;
            h[o..o + 4].copy_from_slice(&(*v as f32).to_le_bytes());
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    for &v in volume.data() {
        if wide {
            h.extend_from_slice(&v.to_le_bytes());
        } else {
            h.push(v as u8);
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> LabelVolume {
        let data: Vec<u16> = (0..24).map(|v| (v % 5) as u16).collect();
        LabelVolume::axis_aligned([2, 3, 4], [1.0, 1.0, 2.0], [10.0, 20.0, 30.0], data).unwrap()
    }

    #[test]
    fn write_then_read_round_trips_plain_and_gzip() {
        let v = small();
        let p = Path::new("mem.nii");
        assert_eq!(parse_nifti(&encode_nifti(&v), p).unwrap(), v);
        let dir = std::env::temp_dir().join(format!("myoslice-nifti-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("v.nii.gz");
        write_nifti(&f, &v).unwrap();
        assert_eq!(read_nifti(&f).unwrap(), v);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn corrupt_files_get_clear_errors() {
        let v = small();
        let good = encode_nifti(&v);
        let p = Path::new("x.nii");
        let short = parse_nifti(&good[..100], p).unwrap_err().to_string();
        assert!(short.contains("shorter than"), "{short}");
        let trunc = parse_nifti(&good[..good.len() - 3], p)
            .unwrap_err()
            .to_string();
        assert!(trunc.contains("truncated"), "{trunc}");
        let mut float = good.clone();
        float[70..72].copy_from_slice(&16i16.to_le_bytes());
        // Two bytes of uint8 labels now read as one float32 each: the data run short.
        let e = parse_nifti(&float, p).unwrap_err().to_string();
        assert!(e.contains("float32") && e.contains("truncated"), "{e}");
        let mut complex = good.clone();
        complex[70..72].copy_from_slice(&32i16.to_le_bytes());
        let e = parse_nifti(&complex, p).unwrap_err().to_string();
        assert!(e.contains("datatype 32"), "{e}");
        let mut dims4 = good.clone();
        dims4[40..42].copy_from_slice(&4i16.to_le_bytes());
        dims4[48..50].copy_from_slice(&3i16.to_le_bytes());
        let e = parse_nifti(&dims4, p).unwrap_err().to_string();
        assert!(e.contains("3-D"), "{e}");
        let garbage = [0x1f, 0x8b, 8, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9];
        let e = parse_nifti(&garbage, p).unwrap_err().to_string();
        assert!(e.contains("gzip"), "{e}");
        let mut zero = good.clone();
        zero[42..44].copy_from_slice(&0i16.to_le_bytes());
        assert!(parse_nifti(&zero, p).is_err());
        assert!(
            read_nifti("/nonexistent/file.nii")
                .unwrap_err()
                .to_string()
                .contains("cannot read")
        );
    }

    /// `v` as NIfTI-2 bytes: labels as `datatype` (little- or big-endian), an sform.
    fn nifti2(v: &LabelVolume, datatype: i16, big: bool) -> Vec<u8> {
        let mut h = vec![0u8; 544];
        let put = |h: &mut Vec<u8>, o: usize, b: &[u8]| {
            let mut b = b.to_vec();
            if big {
                b.reverse();
            }
            h[o..o + b.len()].copy_from_slice(&b);
        };
        put(&mut h, 0, &540i32.to_le_bytes());
        h[4..12].copy_from_slice(b"n+2\0\r\n\x1a\n");
        put(&mut h, 12, &datatype.to_le_bytes());
        let d = v.dims();
        let dim = [3, d[0] as i64, d[1] as i64, d[2] as i64, 1, 1, 1, 1];
        for (i, x) in dim.iter().enumerate() {
            put(&mut h, 16 + 8 * i, &x.to_le_bytes());
        }
        put(&mut h, 168, &544i64.to_le_bytes());
        put(&mut h, 348, &1i32.to_le_bytes());
        for (r, row) in v.affine().iter().enumerate() {
            for (c, x) in row.iter().enumerate() {
                put(&mut h, 400 + 32 * r + 8 * c, &x.to_le_bytes());
            }
        }
        put(&mut h, 500, &2i32.to_le_bytes());
        for &l in v.data() {
            let x = f64::from(l);
            let bytes = match datatype {
                2 => vec![l as u8],
                512 => l.to_le_bytes().to_vec(),
                8 => (l as i32).to_le_bytes().to_vec(),
                16 => (x as f32).to_le_bytes().to_vec(),
                64 => x.to_le_bytes().to_vec(),
                t => panic!("{t}"),
            };
            let at = h.len();
            h.resize(at + bytes.len(), 0);
            put(&mut h, at, &bytes);
        }
        h
    }

    #[test]
    fn nifti2_volumes_of_any_label_type_read_as_nifti1_does() {
        let v = small();
        let p = Path::new("v.nii");
        for datatype in [2, 512, 8, 16, 64] {
            for big in [false, true] {
                let bytes = nifti2(&v, datatype, big);
                assert_eq!(parse_nifti(&bytes, p).unwrap(), v, "{datatype} {big}");
            }
        }
        // Through gzip too: the 540-byte header is read before the voxels.
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut enc, &nifti2(&v, 512, false)).unwrap();
        let gz = enc.finish().unwrap();
        assert_eq!(parse_nifti(&gz, p).unwrap(), v);
        // A float that is no whole number is no label.
        let mut bad = nifti2(&v, 16, false);
        let at = bad.len() - 4;
        bad[at..].copy_from_slice(&2.5f32.to_le_bytes());
        let e = parse_nifti(&bad, p).unwrap_err().to_string();
        assert!(e.contains("holds 2.5, not a label"), "{e}");
        // A header claiming 2^40 voxels a side is refused before anything is allocated.
        let mut huge = nifti2(&v, 2, false);
        for i in 1..4 {
            huge[16 + 8 * i..24 + 8 * i].copy_from_slice(&(1i64 << 40).to_le_bytes());
        }
        let e = parse_nifti(&huge, p).unwrap_err().to_string();
        assert!(e.contains("cap on a label volume"), "{e}");
        // Cut inside the NIfTI-2 header.
        let e = parse_nifti(&nifti2(&v, 2, false)[..400], p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("540-byte NIfTI-2 header"), "{e}");
    }

    #[test]
    fn int16_and_big_endian_volumes_are_read() {
        let v = small();
        let mut b = encode_nifti(&v);
        // Re-encode as big-endian int16.
        let n = 24;
        let mut be = vec![0u8; 352];
        be.copy_from_slice(&b[..352]);
        let swap16 = |buf: &mut [u8], o: usize| buf.swap(o, o + 1);
        let swap32 = |buf: &mut [u8], o: usize| {
            buf.swap(o, o + 3);
            buf.swap(o + 1, o + 2);
        };
        swap32(&mut be, 0);
        for i in 0..8 {
            swap16(&mut be, 40 + 2 * i);
        }
        be[70..72].copy_from_slice(&4i16.to_be_bytes());
        be[72..74].copy_from_slice(&16i16.to_be_bytes());
        for i in 0..8 {
            swap32(&mut be, 76 + 4 * i);
        }
        swap32(&mut be, 108);
        swap16(&mut be, 254);
        for i in 0..12 {
            swap32(&mut be, 280 + 4 * i);
        }
        for &x in &b[352..352 + n] {
            be.extend_from_slice(&i16::from(x).to_be_bytes());
        }
        assert_eq!(parse_nifti(&be, Path::new("be.nii")).unwrap(), v);
        // A negative int16 label is refused.
        let len = be.len();
        be[len - 2..].copy_from_slice(&(-3i16).to_be_bytes());
        assert!(
            parse_nifti(&be, Path::new("neg.nii"))
                .unwrap_err()
                .to_string()
                .contains("holds -3, not a label")
        );
        b.clear();
    }
}
