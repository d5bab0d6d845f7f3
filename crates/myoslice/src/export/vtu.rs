//! VTK XML unstructured grids (`.vtu`) and series (`.pvd`) for ParaView.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};

/// VTK cell types used here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum CellType {
    /// VTK_TRIANGLE.
    Triangle = 5,
    /// VTK_QUAD.
    Quad = 9,
    /// VTK_HEXAHEDRON.
    Hexahedron = 12,
    /// VTK_WEDGE.
    Wedge = 13,
}

/// An unstructured grid being assembled.
#[derive(Debug, Clone, Default)]
pub struct VtuMesh {
    points: Vec<Vec3>,
    connectivity: Vec<u32>,
    offsets: Vec<u32>,
    types: Vec<u8>,
    cell_data: Vec<(String, Vec<f32>)>,
    cell_data_i: Vec<(String, Vec<i32>)>,
}

impl VtuMesh {
    /// Adds points; returns the index of the first.
    pub fn add_points(&mut self, pts: &[Vec3]) -> u32 {
        let base = self.points.len() as u32;
        self.points.extend_from_slice(pts);
        base
    }

    /// Adds a cell of `kind` over point indices (already offset).
    pub fn add_cell(&mut self, kind: CellType, ids: &[u32]) {
        self.connectivity.extend_from_slice(ids);
        self.offsets.push(self.connectivity.len() as u32);
        self.types.push(kind as u8);
    }

    /// Number of cells so far.
    pub fn cells(&self) -> usize {
        self.types.len()
    }

    /// Attaches a float cell array (one value per cell, in cell order).
    pub fn cell_scalars(&mut self, name: &str, values: Vec<f32>) {
        self.cell_data.push((name.to_string(), values));
    }

    /// Attaches an integer cell array.
    pub fn cell_ints(&mut self, name: &str, values: Vec<i32>) {
        self.cell_data_i.push((name.to_string(), values));
    }

    /// The document as a string (binary arrays, base64-encoded inline).
    pub fn to_xml(&self) -> Result<String> {
        let n = self.cells();
        for (name, v) in &self.cell_data {
            if v.len() != n {
                return Err(Error::Build(format!(
                    "cell array {name} has {} values for {n} cells",
                    v.len()
                )));
            }
        }
        for (name, v) in &self.cell_data_i {
            if v.len() != n {
                return Err(Error::Build(format!(
                    "cell array {name} has {} values for {n} cells",
                    v.len()
                )));
            }
        }
        let mut s = String::new();
        let _ = writeln!(s, "<?xml version=\"1.0\"?>");
        let _ = writeln!(
            s,
            "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\" compressor=\"vtkZLibDataCompressor\">"
        );
        let _ = writeln!(s, "<UnstructuredGrid>");
        let _ = writeln!(
            s,
            "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
            self.points.len(),
            n
        );
        let _ = writeln!(s, "<Points>");
        let pts: Vec<f32> = self.points.iter().flat_map(|p| p.to_array()).collect();
        array(&mut s, "Float32", "Points", 3, bytes_f32(&pts));
        let _ = writeln!(s, "</Points>");
        let _ = writeln!(s, "<Cells>");
        array(
            &mut s,
            "Int32",
            "connectivity",
            1,
            self.connectivity
                .iter()
                .flat_map(|v| (*v as i32).to_le_bytes())
                .collect(),
        );
        array(
            &mut s,
            "Int32",
            "offsets",
            1,
            self.offsets
                .iter()
                .flat_map(|v| (*v as i32).to_le_bytes())
                .collect(),
        );
        array(&mut s, "UInt8", "types", 1, self.types.clone());
        let _ = writeln!(s, "</Cells>");
        let _ = writeln!(s, "<CellData>");
        for (name, v) in &self.cell_data_i {
            array(
                &mut s,
                "Int32",
                name,
                1,
                v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            );
        }
        for (name, v) in &self.cell_data {
            array(&mut s, "Float32", name, 1, bytes_f32(v));
        }
        let _ = writeln!(s, "</CellData>");
        let _ = writeln!(s, "</Piece>\n</UnstructuredGrid>\n</VTKFile>");
        Ok(s)
    }

    /// Writes the grid to `path` (written to a temporary name, then renamed, so a reader
    /// never sees half a file).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomic(path, self.to_xml()?.as_bytes())
    }
}

/// Writes a ParaView `.pvd` series listing `(time, file name)` pairs.
pub fn write_pvd(path: &Path, frames: &[(f64, String)]) -> Result<()> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
    );
    for (t, f) in frames {
        let _ = writeln!(
            s,
            "<DataSet timestep=\"{t}\" part=\"0\" file=\"{}\"/>",
            xml_escape(f)
        );
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    write_atomic(path, s.as_bytes())
}

/// Writes bytes to a temporary file beside `path`, then renames it into place.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("partial");
    {
        // Closed before the rename.
        let mut f = std::fs::File::create(&tmp).map_err(|e| Error::write(&tmp, e))?;
        f.write_all(bytes).map_err(|e| Error::write(&tmp, e))?;
        f.sync_all().map_err(|e| Error::write(&tmp, e))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| Error::write(path, e))
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn bytes_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// One inline binary array, zlib-compressed as VTK reads it: a base64 header
/// `[blocks = 1, block size, last block size, compressed size]` (UInt32), then the
/// base64 of the compressed block.
fn array(s: &mut String, ty: &str, name: &str, comps: usize, data: Vec<u8>) {
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    let _ = z.write_all(&data);
    let compressed = z.finish().unwrap_or_default();
    let n = data.len() as u32;
    let header: Vec<u8> = [1u32, n, n, compressed.len() as u32]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let _ = writeln!(
        s,
        "<DataArray type=\"{ty}\" Name=\"{}\" NumberOfComponents=\"{comps}\" format=\"binary\">{}{}</DataArray>",
        xml_escape(name),
        base64(&header),
        base64(&compressed)
    );
}

/// Standard base64 with padding.
pub fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        out.push(T[(n >> 18) as usize & 63] as char);
        out.push(T[(n >> 12) as usize & 63] as char);
        out.push(if c.len() > 1 {
            T[(n >> 6) as usize & 63] as char
        } else {
            '='
        });
        out.push(if c.len() > 2 {
            T[n as usize & 63] as char
        } else {
            '='
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_known_vectors() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn mismatched_cell_arrays_are_refused() {
        let mut m = VtuMesh::default();
        m.add_points(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
        m.add_cell(CellType::Triangle, &[0, 1, 2]);
        m.cell_scalars("x", vec![1.0, 2.0]);
        assert!(m.to_xml().is_err());
    }
}
