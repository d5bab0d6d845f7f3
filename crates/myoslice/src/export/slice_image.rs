//! Axial slices of a label volume as a colour picture (PNG), coloured by tissue and label.

use std::path::Path;

use crate::error::{Error, Result};
use crate::label_table::{LabelTable, TissueKind};
use crate::label_volume::LabelVolume;

/// A stable colour per label: fat yellow, bones ivory, muscles reds varied by id.
pub fn label_colour(table: &LabelTable, id: u16) -> [u8; 3] {
    match table.kind(id) {
        Some(TissueKind::Fat) => [238, 214, 140],
        Some(TissueKind::Bone) => [245, 241, 225],
        Some(TissueKind::Muscle) => {
            let h = (id as u32).wrapping_mul(2_654_435_761) >> 24; // 0..255
            let t = h as f32 / 255.0;
            [
                (150.0 + 80.0 * t) as u8,
                (40.0 + 60.0 * (1.0 - t)) as u8,
                (40.0 + 50.0 * ((t * 7.0).fract())) as u8,
            ]
        }
        _ => [24, 26, 30],
    }
}

/// Writes the axial slices nearest to each height in `z_mm` side by side, each with a
/// title strip height of zero (plain), to a PNG. Returns the slice indices used.
pub fn write_axial_slices(
    volume: &LabelVolume,
    table: &LabelTable,
    z_mm: &[f64],
    path: &Path,
) -> Result<Vec<usize>> {
    let [nx, ny, nz] = volume.dims();
    let a = volume.affine();
    let gap = 8;
    let width = z_mm.len() * nx + (z_mm.len().saturating_sub(1)) * gap;
    let mut rgb = vec![255u8; width * ny * 3];
    let mut ks = Vec::new();
    for (n, &z) in z_mm.iter().enumerate() {
        let k = (((z - a[2][3]) / a[2][2]).round().max(0.0) as usize).min(nz - 1);
        ks.push(k);
        let sl = volume.slice(k);
        for v in 0..ny {
            // Anterior (+y) at the top of the picture.
            let row = ny - 1 - v;
            for u in 0..nx {
                let c = label_colour(table, sl[u + nx * v]);
                let o = 3 * (row * width + n * (nx + gap) + u);
                rgb[o..o + 3].copy_from_slice(&c);
            }
        }
    }
    let file = std::fs::File::create(path).map_err(|e| Error::write(path, e))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width as u32, ny as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let perr = |e: png::EncodingError| Error::Png {
        path: path.into(),
        reason: e.to_string(),
    };
    enc.write_header()
        .map_err(perr)?
        .write_image_data(&rgb)
        .map_err(perr)?;
    Ok(ks)
}
