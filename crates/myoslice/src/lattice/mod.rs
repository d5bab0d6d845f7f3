//! The lattice body (paper, section 2): rigid bone surfaces, muscle ring lattices and the
//! fat hexahedra, built from a labelled slice stack.

mod bone_clearance;
mod builder;
pub mod checks;
pub mod fat;
pub mod frame;
mod hex_quality;
pub mod triangulate;
pub mod tube;

use glam::Vec3;

pub use bone_clearance::Clearance;
pub use builder::BuildOptions;
pub use checks::{InvariantReport, oriented_trimesh, strictly_inside, winding_number};
pub use fat::{FatLattice, InnerContact, hex_volume, hex_volume_f32, hex_volume_points, quad_area};
pub use frame::SliceFrame;
pub(crate) use hex_quality::{HEX_CORNERS, corner_jacobian};
pub use hex_quality::{corner_jacobians, hex_is_valid, min_corner_jacobian};
pub use tube::{Ring, RingInput, Slab, TubeMesh, check_closed, signed_volume};

use crate::label_table::{LabelTable, TissueKind};

/// A rigid bone: closed, outward-oriented surface (one closed shell per tracked tube).
#[derive(Debug, Clone)]
pub struct BoneMesh {
    /// Label id.
    pub label: u16,
    /// Bone name.
    pub name: String,
    /// Surface, rings (per-slice polygons, kept for anchor queries) and centres.
    pub mesh: TubeMesh,
}

/// A muscle: ring lattice with end caps, slab volume elements and a centre line.
#[derive(Debug, Clone)]
pub struct MuscleLattice {
    /// Label id.
    pub label: u16,
    /// Muscle name.
    pub name: String,
    /// Origin bone name from the label table, if given.
    pub origin: Option<String>,
    /// Insertion bone name from the label table, if given.
    pub insertion: Option<String>,
    /// Rings, surface and wedges.
    pub mesh: TubeMesh,
    /// Area-weighted centroid of the muscle's cross-sections on each slice it occupies,
    /// inferior to superior (world, m).
    pub centre_line: Vec<Vec3>,
}

/// How well one structure's polygons fit its regions.
#[derive(Debug, Clone, PartialEq)]
pub struct StructureStats {
    /// Label id.
    pub label: u16,
    /// Structure name.
    pub name: String,
    /// Tissue kind.
    pub kind: TissueKind,
    /// Number of polygons (rings on kept slices).
    pub polygons: usize,
    /// Polygons made by border tracing rather than radial rays.
    pub traced_polygons: usize,
    /// Regions too small to polygonise (fewer pixels than the minimum).
    pub dropped_regions: usize,
    /// Area-weighted mean intersection-over-union of polygon and region.
    pub mean_iou: f64,
    /// Smallest per-polygon intersection-over-union.
    pub min_iou: f64,
    /// Enclosed lattice volume (m³).
    pub lattice_volume_m3: f64,
    /// Muscles: surface vertices drawn out of bone at build (zero for bones).
    pub bone_clearance: Clearance,
}

/// The whole lattice body.
#[derive(Debug, Clone)]
pub struct Lattice {
    /// Bones, by label id.
    pub bones: Vec<BoneMesh>,
    /// Muscles, by label id.
    pub muscles: Vec<MuscleLattice>,
    /// Subcutaneous fat and skin.
    pub fat: FatLattice,
    /// For each inner fat vertex (slice-major, as [`FatLattice::inner_contact`]) resting
    /// on a muscle: `(muscle index, muscle vertex)` of its nearest muscle vertex at rest.
    pub fat_muscle_ref: Vec<Option<(u32, u32)>>,
    /// Fit statistics per bone and muscle, by label id.
    pub stats: Vec<StructureStats>,
    /// Slice geometry.
    pub frame: SliceFrame,
    /// The label table the lattice was built with.
    pub table: LabelTable,
    /// The options it was built with.
    pub options: BuildOptions,
}

impl Lattice {
    /// The bone with this name.
    pub fn bone(&self, name: &str) -> Option<&BoneMesh> {
        self.bones.iter().find(|b| b.name == name)
    }

    /// The muscle with this name.
    pub fn muscle(&self, name: &str) -> Option<&MuscleLattice> {
        self.muscles.iter().find(|m| m.name == name)
    }

    /// Total vertex counts: (bone, muscle, fat).
    pub fn vertex_counts(&self) -> (usize, usize, usize) {
        (
            self.bones.iter().map(|b| b.mesh.vertices.len()).sum(),
            self.muscles.iter().map(|m| m.mesh.vertices.len()).sum(),
            self.fat.vertices.len(),
        )
    }

    /// Enclosed volume (m³) of the fat lattice.
    pub fn fat_volume_m3(&self) -> f64 {
        self.fat
            .hexes
            .iter()
            .map(|h| hex_volume(&self.fat.vertices, h))
            .sum()
    }
}
