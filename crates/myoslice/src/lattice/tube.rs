//! Closed tube surfaces from tracked rings: vertex j of a ring joins vertex j of the next
//! (paper, section 2.2, "3D construction"), with flat end caps half a slice step beyond
//! the first and last rings so that each ring stands for the slab of voxels around it.

use glam::Vec3;

use super::triangulate::ear_clip;
use crate::contour::PolygonMethod;

/// One cross-section of a tube, in world coordinates.
#[derive(Debug, Clone)]
pub struct RingInput {
    /// Kept-slice index.
    pub slice: usize,
    /// Ring vertices (world, m), counter-clockwise in slice pixel coordinates.
    pub points: Vec<Vec3>,
    /// The same vertices in slice pixel coordinates (for cap triangulation).
    pub points_2d: Vec<[f64; 2]>,
    /// Ring centre (world, m): the point its rays start from.
    pub centre: Vec3,
    /// How the polygon was made.
    pub method: PolygonMethod,
    /// Pixel area of the region (for area-weighted statistics).
    pub area_px: u32,
    /// Intersection over union of the polygon with its region.
    pub iou: f64,
}

/// A ring as stored in a lattice: where its vertices are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ring {
    /// Source slice index of the volume (cap rings carry that of the ring they close).
    pub k: u32,
    /// Index of the ring's first surface vertex; the ring has `rays` consecutive vertices.
    pub first: u32,
    /// Index of the ring's centre vertex (interior, not on the surface).
    pub centre: u32,
    /// True for the extruded copies that close a tube.
    pub cap: bool,
}

/// Growing vertex, triangle, ring and wedge buffers of one structure.
#[derive(Debug, Clone, Default)]
pub struct TubeMesh {
    /// Vertices (world, m): ring vertices and ring centres.
    pub vertices: Vec<Vec3>,
    /// Closed, outward-oriented surface triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Rings in tube order; `tubes` delimits them.
    pub rings: Vec<Ring>,
    /// Range of `rings` of each tube.
    pub tubes: Vec<std::ops::Range<u32>>,
    /// Volume elements: the slabs between consecutive rings of each tube.
    pub slabs: Vec<Slab>,
}

/// A volume element of a tube: the solid between two consecutive rings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slab {
    /// Indices (into [`TubeMesh::rings`]) of the lower and upper ring.
    pub rings: [u32; 2],
    /// Volume at rest (m³), positive.
    pub volume: f64,
}

impl TubeMesh {
    /// Appends one closed tube through `rings` (consecutive slices). `below` and `above`
    /// are the world offsets of the two end caps.
    /// `source_k` maps the rings' slice indices to source slices of the volume.
    pub fn add_tube(&mut self, rings: &[RingInput], below: Vec3, above: Vec3, source_k: &[usize]) {
        let Some(first) = rings.first() else { return };
        let last = &rings[rings.len() - 1];
        let n = first.points.len();
        let tri_start = self.triangles.len();
        let ring_start = self.rings.len() as u32;
        let push_ring = |mesh: &mut TubeMesh, r: &RingInput, off: Vec3, cap: bool| {
            let first_v = mesh.vertices.len() as u32;
            mesh.vertices.extend(r.points.iter().map(|&p| p + off));
            let centre = mesh.vertices.len() as u32;
            mesh.vertices.push(r.centre + off);
            mesh.rings.push(Ring {
                k: source_k[r.slice] as u32,
                first: first_v,
                centre,
                cap,
            });
        };
        push_ring(self, first, below, true);
        for r in rings {
            push_ring(self, r, Vec3::ZERO, false);
        }
        push_ring(self, last, above, true);
        let ring_end = self.rings.len() as u32;
        let n32 = n as u32;
        let ring_ids: Vec<u32> = (ring_start..ring_end).collect();
        for w in ring_ids.windows(2) {
            let (ra, rb) = (self.rings[w[0] as usize], self.rings[w[1] as usize]);
            for j in 0..n32 {
                let j1 = (j + 1) % n32;
                let (a0, a1) = (ra.first + j, ra.first + j1);
                let (b0, b1) = (rb.first + j, rb.first + j1);
                self.triangles.push([a0, a1, b1]);
                self.triangles.push([a0, b1, b0]);
            }
        }
        // Caps: triangulate the end polygons; the bottom one faces the other way.
        let bottom = self.rings[ring_start as usize];
        let top = self.rings[ring_end as usize - 1];
        for t in ear_clip(&first.points_2d) {
            self.triangles.push([
                bottom.first + t[0],
                bottom.first + t[2],
                bottom.first + t[1],
            ]);
        }
        for t in ear_clip(&last.points_2d) {
            self.triangles
                .push([top.first + t[0], top.first + t[1], top.first + t[2]]);
        }
        // Orient outward: the enclosed volume must be positive.
        let sign = if signed_volume(&self.vertices, &self.triangles[tri_start..]) < 0.0 {
            for t in &mut self.triangles[tri_start..] {
                t.swap(1, 2);
            }
            -1.0
        } else {
            1.0
        };
        // Volume elements: the slab between each pair of consecutive rings, closed by
        // the triangulated ring polygons (positive for any ring shape, star or not).
        let polys: Vec<Vec<[u32; 3]>> = std::iter::once(&first.points_2d)
            .chain(rings.iter().map(|r| &r.points_2d))
            .chain(std::iter::once(&last.points_2d))
            .map(|p| ear_clip(p))
            .collect();
        for (i, w) in ring_ids.windows(2).enumerate() {
            let mut slab = Slab {
                rings: [w[0], w[1]],
                volume: 0.0,
            };
            slab.volume = sign * self.slab_signed_volume(&slab, &polys[i], &polys[i + 1]);
            self.slabs.push(slab);
        }
        self.tubes.push(ring_start..ring_end);
    }

    fn slab_signed_volume(&self, slab: &Slab, tri_a: &[[u32; 3]], tri_b: &[[u32; 3]]) -> f64 {
        let (ra, rb) = (
            self.rings[slab.rings[0] as usize],
            self.rings[slab.rings[1] as usize],
        );
        let n = ra.centre - ra.first;
        let mut tris = Vec::with_capacity(2 * n as usize + tri_a.len() + tri_b.len());
        for j in 0..n {
            let j1 = (j + 1) % n;
            tris.push([ra.first + j, ra.first + j1, rb.first + j1]);
            tris.push([ra.first + j, rb.first + j1, rb.first + j]);
        }
        tris.extend(
            tri_a
                .iter()
                .map(|t| [ra.first + t[0], ra.first + t[2], ra.first + t[1]]),
        );
        tris.extend(
            tri_b
                .iter()
                .map(|t| [rb.first + t[0], rb.first + t[1], rb.first + t[2]]),
        );
        signed_volume(&self.vertices, &tris)
    }

    /// Number of vertices per ring (0 when empty).
    pub fn ring_len(&self) -> usize {
        self.rings
            .first()
            .map_or(0, |r| (r.centre - r.first) as usize)
    }

    /// Enclosed volume (m³) of all tubes.
    pub fn volume(&self) -> f64 {
        signed_volume(&self.vertices, &self.triangles)
    }
}

/// Signed volume (m³) enclosed by a closed triangle set (divergence theorem, f64).
pub fn signed_volume(vertices: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    let mut v = 0.0;
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize].as_dvec3());
        v += a.dot(b.cross(c));
    }
    v / 6.0
}

/// Checks that every edge of a triangle set is shared by exactly two triangles, in
/// opposite directions (closed and consistently oriented). Returns the first bad edge.
pub fn check_closed(triangles: &[[u32; 3]]) -> Result<(), (u32, u32)> {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    edges.sort_unstable();
    for w in edges.windows(2) {
        if w[0] == w[1] {
            return Err(w[0]);
        }
    }
    for &(a, b) in &edges {
        if edges.binary_search(&(b, a)).is_err() {
            return Err((a, b));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_ring(slice: usize, z: f32, half: f32) -> RingInput {
        let p2 = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
        RingInput {
            slice,
            points: p2
                .iter()
                .map(|p| Vec3::new(p[0] as f32 * half, p[1] as f32 * half, z))
                .collect(),
            points_2d: p2.to_vec(),
            centre: Vec3::new(0.0, 0.0, z),
            method: PolygonMethod::Radial,
            area_px: 4,
            iou: 1.0,
        }
    }

    #[test]
    fn a_square_tube_is_closed_outward_and_has_the_prism_volume() {
        let mut m = TubeMesh::default();
        let rings = [square_ring(0, 0.0, 1.0), square_ring(1, 1.0, 1.0)];
        m.add_tube(
            &rings,
            Vec3::new(0.0, 0.0, -0.5),
            Vec3::new(0.0, 0.0, 0.5),
            &[0, 1],
        );
        assert!(check_closed(&m.triangles).is_ok());
        assert!((m.volume() - 8.0).abs() < 1e-5, "{}", m.volume());
        let ssum: f64 = m.slabs.iter().map(|s| s.volume).sum();
        assert!((ssum - 8.0).abs() < 1e-5, "{ssum}");
        assert!(m.slabs.iter().all(|s| s.volume > 0.0));
    }
}
