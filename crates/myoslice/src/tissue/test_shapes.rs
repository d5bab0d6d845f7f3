//! Shapes shared by the tissue's unit tests.

use glam::Vec3;
use parry3d::shape::TriMesh;

/// A box `lo..hi` (m) as a closed mesh with outward triangles.
pub(crate) fn box_mesh(lo: Vec3, hi: Vec3) -> TriMesh {
    let v: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let t: Vec<[u32; 3]> = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    TriMesh::new(v, t).unwrap_or_else(|e| panic!("{e}"))
}
