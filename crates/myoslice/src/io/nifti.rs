//! NIfTI-1 label volumes (`.nii`, `.nii.gz`).
//!
//! Reads single-file NIfTI-1 (`n+1`) with uint8, int16 or uint16 labels, in either byte
//! order, gzip-compressed or not. The voxel-to-world affine comes from the sform when
//! present, else the qform, else the voxel sizes; spatial units are converted to mm.

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};
use crate::label_volume::LabelVolume;

const HEADER_LEN: usize = 348;

/// Reads a NIfTI-1 label volume from a file.
pub fn read_nifti(path: impl AsRef<Path>) -> Result<LabelVolume> {
    let path = path.as_ref();
    let raw = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_nifti(&raw, path)
}

/// Parses NIfTI-1 bytes (gzip-compressed or not); `path` is only used in messages.
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
    if bytes.len() < HEADER_LEN {
        return Err(err(format!(
            "file has {} bytes, shorter than the 348-byte NIfTI-1 header",
            bytes.len()
        )));
    }
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
    let mut out = Vec::with_capacity(HEADER_LEN + 4);
    (&mut dec)
        .take(HEADER_LEN as u64 + 4)
        .read_to_end(&mut out)
        .map_err(corrupt)?;
    if out.len() < HEADER_LEN {
        // Too short for a header: the caller says so.
        return Ok(out);
    }
    let claimed = Header::parse(&out)?.claimed_bytes();
    if claimed > MAX_VOLUME_BYTES {
        return Err(format!(
            "the header claims {claimed} bytes of data, more than the {MAX_VOLUME_BYTES}-byte cap on a label volume"
        ));
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

struct Header {
    big: bool,
    dims: [usize; 3],
    datatype: i16,
    vox_offset: usize,
    affine: [[f64; 4]; 3],
    slope: f32,
    inter: f32,
}

fn rd_i16(b: &[u8], o: usize, big: bool) -> i16 {
    let a = [b[o], b[o + 1]];
    if big {
        i16::from_be_bytes(a)
    } else {
        i16::from_le_bytes(a)
    }
}

fn rd_i32(b: &[u8], o: usize, big: bool) -> i32 {
    let a = [b[o], b[o + 1], b[o + 2], b[o + 3]];
    if big {
        i32::from_be_bytes(a)
    } else {
        i32::from_le_bytes(a)
    }
}

fn rd_f32(b: &[u8], o: usize, big: bool) -> f32 {
    f32::from_bits(rd_i32(b, o, big) as u32)
}

impl Header {
    fn parse(b: &[u8]) -> std::result::Result<Self, String> {
        let big = match (
            i32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            i32::from_be_bytes([b[0], b[1], b[2], b[3]]),
        ) {
            (348, _) => false,
            (_, 348) => true,
            _ => return Err("sizeof_hdr is not 348: not a NIfTI-1 file".into()),
        };
        let magic = &b[344..348];
        if magic == b"ni1\0" {
            return Err("two-file NIfTI (.hdr/.img) is not supported; convert to .nii".into());
        }
        if magic != b"n+1\0" {
            return Err("magic is not 'n+1': not a NIfTI-1 file".into());
        }
        let ndim = rd_i16(b, 40, big);
        let dim: Vec<i16> = (0..7).map(|i| rd_i16(b, 42 + 2 * i, big)).collect();
        if !(3..=7).contains(&ndim) || dim[3..ndim as usize].iter().any(|&d| d != 1) {
            return Err(format!(
                "expected a 3-D volume, got {ndim} dimensions {:?}",
                &dim[..ndim.clamp(0, 7) as usize]
            ));
        }
        if dim[..3].iter().any(|&d| d < 1) {
            return Err(format!("dimensions {:?} must all be >= 1", &dim[..3]));
        }
        let dims = [dim[0] as usize, dim[1] as usize, dim[2] as usize];
        let datatype = rd_i16(b, 70, big);
        let pixdim: Vec<f32> = (0..8).map(|i| rd_f32(b, 76 + 4 * i, big)).collect();
        let vox_offset = rd_f32(b, 108, big);
        if !(vox_offset.is_finite() && vox_offset >= HEADER_LEN as f32) {
            return Err(format!("vox_offset {vox_offset} is invalid"));
        }
        let slope = rd_f32(b, 112, big);
        let inter = rd_f32(b, 116, big);
        let unit = match b[123] & 0x07 {
            1 => 1000.0,
            3 => 1e-3,
            _ => 1.0,
        };
        let qform_code = rd_i16(b, 252, big);
        let sform_code = rd_i16(b, 254, big);
        let mut affine = [[0.0f64; 4]; 3];
        if sform_code > 0 {
            for (r, row) in affine.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    *v = f64::from(rd_f32(b, 280 + 16 * r + 4 * c, big)) * unit;
                }
            }
        } else if qform_code > 0 {
            let (qb, qc, qd) = (
                f64::from(rd_f32(b, 256, big)),
                f64::from(rd_f32(b, 260, big)),
                f64::from(rd_f32(b, 264, big)),
            );
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
            let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
            let sz = [
                f64::from(pixdim[1]),
                f64::from(pixdim[2]),
                f64::from(pixdim[3]) * qfac,
            ];
            for r in 0..3 {
                for c in 0..3 {
                    affine[r][c] = rot[r][c] * sz[c] * unit;
                }
                affine[r][3] = f64::from(rd_f32(b, 268 + 4 * r, big)) * unit;
            }
        } else {
            for r in 0..3 {
                affine[r][r] = f64::from(pixdim[r + 1]) * unit;
            }
        }
        if affine.iter().flatten().any(|v| !v.is_finite()) {
            return Err("the voxel-to-world transform is not finite".into());
        }
        Ok(Self {
            big,
            dims,
            datatype,
            vox_offset: vox_offset as usize,
            affine,
            slope,
            inter,
        })
    }

    /// Bytes the header says the file holds: the voxel offset and the voxels, at two
    /// bytes a voxel for any type but uint8 (an unsupported type is refused later).
    fn claimed_bytes(&self) -> u64 {
        let per = if self.datatype == 2 { 1 } else { 2 };
        self.dims
            .iter()
            .fold(per, |a: u64, &d| a.saturating_mul(d as u64))
            .saturating_add(self.vox_offset as u64)
    }

    fn read_voxels(&self, b: &[u8]) -> std::result::Result<LabelVolume, String> {
        let n = self.dims[0] * self.dims[1] * self.dims[2];
        let (bytes_per, name) = match self.datatype {
            2 => (1, "uint8"),
            4 => (2, "int16"),
            512 => (2, "uint16"),
            16 => {
                return Err(
                    "datatype float32 (16) is not a label type; expected uint8, int16 or uint16"
                        .into(),
                );
            }
            64 => {
                return Err(
                    "datatype float64 (64) is not a label type; expected uint8, int16 or uint16"
                        .into(),
                );
            }
            t => {
                return Err(format!(
                    "datatype {t} is not supported for labels; expected uint8 (2), int16 (4) or uint16 (512)"
                ));
            }
        };
        if self.slope != 0.0 && (self.slope != 1.0 || self.inter != 0.0) {
            return Err(format!(
                "scl_slope {} / scl_inter {} would rescale the labels; label volumes must be unscaled",
                self.slope, self.inter
            ));
        }
        let need = n * bytes_per;
        let avail = b.len().saturating_sub(self.vox_offset);
        if avail < need {
            return Err(format!(
                "truncated: {name} voxels of a {}x{}x{} volume need {need} bytes after the header, found {avail}",
                self.dims[0], self.dims[1], self.dims[2]
            ));
        }
        let src = &b[self.vox_offset..self.vox_offset + need];
        let data: Vec<u16> = match self.datatype {
            2 => src.iter().map(|&v| u16::from(v)).collect(),
            4 => {
                let mut out = Vec::with_capacity(n);
                for c in src.chunks_exact(2) {
                    let v = rd_i16(c, 0, self.big);
                    if v < 0 {
                        return Err(format!("negative label {v} in an int16 volume"));
                    }
                    out.push(v as u16);
                }
                out
            }
            _ => src
                .chunks_exact(2)
                .map(|c| rd_i16(c, 0, self.big) as u16)
                .collect(),
        };
        LabelVolume::new(self.dims, self.affine, data).map_err(|e| e.to_string())
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
        let e = parse_nifti(&float, p).unwrap_err().to_string();
        assert!(e.contains("float32"), "{e}");
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
                .contains("negative")
        );
        b.clear();
    }
}
