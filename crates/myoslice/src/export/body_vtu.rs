//! The lattice body (at rest or deformed) as one VTK unstructured grid.

use glam::Vec3;

use super::vtu::{CellType, VtuMesh};
use crate::label_table::TissueKind;
use crate::lattice::Lattice;

/// Current vertex positions of every part of a lattice body.
#[derive(Debug, Clone, Copy)]
pub struct BodyPositions<'a> {
    /// Per bone, its vertices.
    pub bones: &'a [Vec<Vec3>],
    /// Per muscle, its vertices.
    pub muscles: &'a [Vec<Vec3>],
    /// Fat vertices.
    pub fat: &'a [Vec3],
}

/// Per fat element scalars to attach (cell order of the fat hexahedra).
#[derive(Debug, Clone, Copy)]
pub struct FatScalars<'a> {
    /// Body-surface area change of the element's outer face (ratio − 1; 0 inside).
    pub area_change: &'a [f32],
    /// Deformation degree (paper Eq. 5), metres.
    pub deformation_degree: &'a [f32],
    /// Volume ratio to rest.
    pub volume_ratio: &'a [f32],
}

fn kind_code(k: TissueKind) -> i32 {
    match k {
        TissueKind::Background => 0,
        TissueKind::Fat => 1,
        TissueKind::Bone => 2,
        TissueKind::Muscle => 3,
    }
}

/// Builds the grid: bone and muscle surface triangles and fat hexahedra, with cell data
/// `structure_id` (label), `kind` (1 fat, 2 bone, 3 muscle) and, when given, the fat
/// element scalars (zero on bone and muscle cells).
pub fn body_vtu(
    lattice: &Lattice,
    pos: BodyPositions<'_>,
    fat_scalars: Option<FatScalars<'_>>,
) -> VtuMesh {
    let mut m = VtuMesh::default();
    let mut ids = Vec::new();
    let mut kinds = Vec::new();
    for (b, verts) in lattice.bones.iter().zip(pos.bones) {
        let base = m.add_points(verts);
        for t in &b.mesh.triangles {
            m.add_cell(CellType::Triangle, &t.map(|i| base + i));
            ids.push(i32::from(b.label));
            kinds.push(kind_code(TissueKind::Bone));
        }
    }
    for (mu, verts) in lattice.muscles.iter().zip(pos.muscles) {
        let base = m.add_points(verts);
        for t in &mu.mesh.triangles {
            m.add_cell(CellType::Triangle, &t.map(|i| base + i));
            ids.push(i32::from(mu.label));
            kinds.push(kind_code(TissueKind::Muscle));
        }
    }
    let fat_label = lattice
        .table
        .of_kind(TissueKind::Fat)
        .next()
        .map_or(1, |l| i32::from(l.id));
    let first_fat_cell = m.cells();
    let base = m.add_points(pos.fat);
    for h in &lattice.fat.hexes {
        m.add_cell(CellType::Hexahedron, &h.map(|i| base + i));
        ids.push(fat_label);
        kinds.push(kind_code(TissueKind::Fat));
    }
    let n = m.cells();
    m.cell_ints("structure_id", ids);
    m.cell_ints("kind", kinds);
    if let Some(fs) = fat_scalars {
        for (name, vals) in [
            ("area_change", fs.area_change),
            ("deformation_degree", fs.deformation_degree),
            ("volume_ratio", fs.volume_ratio),
        ] {
            let mut v = vec![0.0f32; n];
            v[first_fat_cell..first_fat_cell + vals.len()].copy_from_slice(vals);
            m.cell_scalars(name, v);
        }
    }
    m
}

/// The rest-pose body of a lattice.
pub fn rest_vtu(lattice: &Lattice) -> VtuMesh {
    let bones: Vec<Vec<Vec3>> = lattice
        .bones
        .iter()
        .map(|b| b.mesh.vertices.clone())
        .collect();
    let muscles: Vec<Vec<Vec3>> = lattice
        .muscles
        .iter()
        .map(|m| m.mesh.vertices.clone())
        .collect();
    body_vtu(
        lattice,
        BodyPositions {
            bones: &bones,
            muscles: &muscles,
            fat: &lattice.fat.vertices,
        },
        None,
    )
}
