//! Muscle surfaces drawn clear of bone at build. No voxel is both muscle and bone, but
//! the surfaces made from them can overlap: polygons are drawn over their regions with
//! an IoU below 1, tube walls run straight between slices where the bone's shape
//! changes, and end caps stand beyond the last ring. Each muscle vertex found inside a
//! bone is drawn in along its ray, toward its ring's centre, to just past the bone's
//! surface; an end cap whose walls reach into a bone comes back toward its ring.
//! Every ring stays in its plane, so the slab volumes are corrected exactly.

use crate::par::*;
use glam::Vec3;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::query::{PointQuery, Ray, RayCast};
use parry3d::shape::TriMesh;

use super::checks::oriented_trimesh;
use super::tube::{Slab, TubeMesh};
use super::{BoneMesh, MuscleLattice};
use crate::contour::signed_area;

/// How far (m) past the bone's surface, along its ray, a drawn-in vertex ends up.
const CLEARANCE_M: f32 = 0.0005;

/// Deepest (m) a muscle vertex is looked for inside a bone (the search stops there, which
/// keeps it fast away from bone).
const MAX_DEPTH_M: f32 = 0.03;

/// A vertex is drawn in along its ray no further than this many times its depth under
/// the bone's nearest surface...
const MAX_DETOUR: f32 = 4.0;
/// ...plus this (m).
const DETOUR_SLACK_M: f32 = 0.002;

/// Least share of its distance from the ring centre a vertex keeps (one that would need
/// more stays where it is), and of its offset from its ring an end cap keeps (even if
/// that leaves its walls in bone): nothing collapses.
const MIN_SHARE: f32 = 0.1;

/// What clearing one muscle did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Clearance {
    /// Surface vertices drawn out of bone.
    pub drawn_in: usize,
    /// Surface vertices inside a bone after clearing: their ray leaves it only near the
    /// ring's centre, much further on than the bone's nearest surface or not at all, the
    /// move would make their ring cross itself or turn over, or an end cap could not
    /// come back far enough. Vertices deeper than [`MAX_DEPTH_M`] are not looked for.
    pub left_inside: usize,
}

/// A bone's surface ready for containment and ray queries.
struct BoneQuery {
    tri: TriMesh,
    aabb: Aabb,
}

impl BoneQuery {
    /// Whether `p` lies inside the bone, no deeper than [`MAX_DEPTH_M`], by the
    /// pseudo-normals of its nearest surface point. A bone may be several closed tubes
    /// that overlap; then this can miss a point inside one tube near another's wall (the
    /// vertex is left where it is), but it cannot find a point outside them all inside:
    /// its nearest point is on their union's outer wall. (The winding number would settle
    /// the first case too, at a third of a second more to build the phantom.)
    fn inside(&self, p: Vec3) -> bool {
        self.aabb.contains_local_point(p)
            && self
                .tri
                .project_local_point_with_max_dist(p, false, MAX_DEPTH_M)
                .is_some_and(|proj| proj.is_inside && proj.point.distance_squared(p) > 1e-12)
    }
}

/// Draws every muscle's surface vertices out of `bones` (see the module doc) and
/// corrects the slab volumes; returns what was done, in muscle order.
pub(crate) fn clear_muscles_of_bone(
    muscles: &mut [MuscleLattice],
    bones: &[BoneMesh],
) -> Vec<Clearance> {
    let queries: Vec<BoneQuery> = bones
        .iter()
        .filter_map(|b| {
            let tri = oriented_trimesh(&b.mesh.vertices, &b.mesh.triangles)?;
            let aabb = tri.local_aabb();
            Some(BoneQuery { tri, aabb })
        })
        .collect();
    muscles
        .par_iter_mut()
        .map(|m| clear_tube(&mut m.mesh, &queries))
        .collect()
}

fn clear_tube(mesh: &mut TubeMesh, bones: &[BoneQuery]) -> Clearance {
    let n = mesh.ring_len();
    if n < 3 || mesh.slabs.is_empty() {
        return Clearance::default();
    }
    let in_bone = |x: &[Vec3], v: usize| bones.iter().any(|b| b.inside(x[v]));
    let surface: Vec<usize> = mesh
        .rings
        .iter()
        .flat_map(|r| r.first as usize..r.first as usize + n)
        .collect();
    let mut was_inside: Vec<usize> = surface
        .iter()
        .copied()
        .filter(|&v| in_bone(&mesh.vertices, v))
        .collect();
    was_inside.sort_unstable();
    let old = mesh.vertices.clone();
    let rings: Vec<usize> = (0..mesh.rings.len()).collect();
    let (caps, walls): (Vec<usize>, Vec<usize>) = rings.iter().partition(|&&r| mesh.rings[r].cap);
    // Only vertices found inside can need drawing in: a wall vertex moves only by itself.
    draw_in(mesh, &walls, bones, |v| {
        was_inside.binary_search(&v).is_ok()
    });
    // A cap is its end ring moved on along the tube: it follows what the end ring did,
    // and comes back toward it where the walls between them reach into bone.
    for tube in mesh.tubes.clone() {
        let (first, last) = (tube.start as usize, tube.end as usize - 1);
        pull_cap(mesh, &old, first, first + 1, bones);
        pull_cap(mesh, &old, last, last - 1, bones);
    }
    // Pulled caps may have moved into bone: all their vertices are looked at again.
    draw_in(mesh, &caps, bones, |_| true);
    let moved = |r: &super::tube::Ring| {
        (r.first..=r.centre).any(|v| mesh.vertices[v as usize] != old[v as usize])
    };
    let changed: Vec<bool> = mesh.rings.iter().map(moved).collect();
    if changed.iter().any(|&c| c) {
        // Stored slab volumes are positive whatever way the rings run: the sign that
        // relates them to the fans is the whole tube's.
        let sign = mesh
            .slabs
            .iter()
            .map(|s| fan_signed_volume(mesh, &old, s))
            .sum::<f64>()
            .signum();
        for s in 0..mesh.slabs.len() {
            let slab = mesh.slabs[s];
            if slab.rings.iter().any(|&r| changed[r as usize]) {
                let before = fan_signed_volume(mesh, &old, &slab);
                let after = fan_signed_volume(mesh, &mesh.vertices, &slab);
                mesh.slabs[s].volume += sign * (after - before);
            }
        }
    }
    let still = was_inside
        .iter()
        .filter(|&&v| in_bone(&mesh.vertices, v))
        .count();
    // A vertex that was clear and has not moved still is.
    let moved_in = surface
        .iter()
        .filter(|&&v| mesh.vertices[v] != old[v] && was_inside.binary_search(&v).is_err())
        .filter(|&&v| in_bone(&mesh.vertices, v))
        .count();
    let left_inside = still + moved_in;
    Clearance {
        drawn_in: was_inside.len() - still,
        left_inside,
    }
}

/// Draws each vertex of `rings` that `candidate` admits and is found inside a bone along
/// its ray, see [`way_out`] (out of each bone it is found in, in turn).
fn draw_in(
    mesh: &mut TubeMesh,
    rings: &[usize],
    bones: &[BoneQuery],
    candidate: impl Fn(usize) -> bool,
) {
    let n = mesh.ring_len();
    for &r in rings {
        let ring = mesh.rings[r];
        let centre = mesh.vertices[ring.centre as usize];
        let ids = ring.first as usize..ring.first as usize + n;
        for j in (0..n).filter(|&j| candidate(ring.first as usize + j)) {
            for _ in 0..bones.len() {
                let p = mesh.vertices[ring.first as usize + j];
                let Some(bone) = bones.iter().find(|b| b.inside(p)) else {
                    break;
                };
                match way_out(bone, centre, p) {
                    Some(t) if stays_simple(&mesh.vertices[ids.clone()], j, t) => {
                        mesh.vertices[ring.first as usize + j] = t;
                    }
                    _ => break,
                }
            }
        }
    }
}

/// Rebuilds cap ring `cap` (centre included) as a copy of its end ring `end` moved along
/// the cap's offset, by as much of it as keeps the walls between them out of bone, but
/// at least [`MIN_SHARE`] of it (the end slab keeps a volume, even if that is not clear).
/// `old` holds the positions before any clearing; a cap neither pulled nor following a
/// moved end ring is left as it was.
fn pull_cap(mesh: &mut TubeMesh, old: &[Vec3], cap: usize, end: usize, bones: &[BoneQuery]) {
    let n = mesh.ring_len();
    let (c, e) = (mesh.rings[cap], mesh.rings[end]);
    let off = old[c.centre as usize] - old[e.centre as usize];
    let len = off.length();
    if len < 1e-9 {
        return;
    }
    let dir = off / len;
    let mut share = 1.0f32;
    for j in 0..n {
        let from = mesh.vertices[e.first as usize + j];
        let wall = Aabb::new(from.min(from + off), from.max(from + off));
        for b in bones.iter().filter(|b| b.aabb.intersects(&wall)) {
            // Along the wall nothing helps a vertex whose end is already in the bone.
            if b.inside(from) {
                continue;
            }
            if let Some(t) = b.tri.cast_local_ray(&Ray::new(from, dir), len, false) {
                share = share.min(((t - CLEARANCE_M) / len).max(MIN_SHARE));
            }
        }
    }
    let end_ids = e.first as usize..=e.centre as usize;
    if share == 1.0 && mesh.vertices[end_ids.clone()] == old[end_ids] {
        return;
    }
    // The centre comes right after the ring's vertices (see `TubeMesh::add_tube`).
    for j in 0..=n {
        mesh.vertices[c.first as usize + j] = mesh.vertices[e.first as usize + j] + off * share;
    }
}

/// Where `p` (inside `bone`) goes: from `p` toward its ring centre `c`, just past where
/// that ray leaves the bone (the least move that keeps the vertex on its ray). None when
/// the ray leaves no nearer than [`MIN_SHARE`] of the way to the centre.
fn way_out(bone: &BoneQuery, c: Vec3, p: Vec3) -> Option<Vec3> {
    let d = c - p;
    let len = d.length();
    if len < 1e-9 {
        return None;
    }
    let dir = d / len;
    let exit = bone.tri.cast_local_ray(&Ray::new(p, dir), len, false)?;
    // A ray leaving far further on than the bone's nearest surface runs along the bone
    // (or across it): following it would carry the vertex past the bone, not out.
    let depth = bone.tri.project_local_point(p, false).point.distance(p);
    let to = p + dir * (exit + CLEARANCE_M);
    (exit <= MAX_DETOUR * depth + DETOUR_SLACK_M
        && exit + CLEARANCE_M <= (1.0 - MIN_SHARE) * len
        && !bone.inside(to))
    .then_some(to)
}

/// Whether ring `ring` (planar, closed) stays a simple polygon turning the same way when
/// its vertex `j` moves to `to`: the two edges at `j` may not meet any edge not adjacent
/// to them, and the signed area keeps its sign.
fn stays_simple(ring: &[Vec3], j: usize, to: Vec3) -> bool {
    let n = ring.len();
    let normal = newell_normal(ring);
    if normal == Vec3::ZERO {
        return false;
    }
    let u = normal.any_orthonormal_vector();
    let w = normal.cross(u);
    let flat = |p: Vec3| [p.dot(u), p.dot(w)];
    let at = |i: usize| if i == j { flat(to) } else { flat(ring[i]) };
    // The normal was taken from the ring as it is, so its area is positive before the
    // move.
    let moved_ring: Vec<[f64; 2]> = (0..n).map(|i| at(i).map(f64::from)).collect();
    if signed_area(&moved_ring) <= 0.0 {
        return false;
    }
    let (prev, next) = ((j + n - 1) % n, (j + 1) % n);
    let moved = [(prev, j), (j, next)];
    (0..n).all(|e| {
        let e1 = (e + 1) % n;
        moved.iter().all(|&(a, b)| {
            // Edges sharing an end meet there by construction.
            [a, b].contains(&e) || [a, b].contains(&e1) || !meet(at(a), at(b), at(e), at(e1))
        })
    })
}

fn newell_normal(ring: &[Vec3]) -> Vec3 {
    let n = ring.len();
    let mut s = Vec3::ZERO;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        s += Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    s.normalize_or_zero()
}

/// Whether segments `ab` and `cd` meet: cross, touch, or (conservatively) lie on one
/// line.
fn meet(a: [f32; 2], b: [f32; 2], c: [f32; 2], d: [f32; 2]) -> bool {
    let orient = |p: [f32; 2], q: [f32; 2], r: [f32; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0
}

/// Signed volume of a slab closed by fans from its rings' centres, with vertex positions
/// `x`. For planar rings (each lies on its slice) a fan from a point in the plane closes
/// a ring exactly as any triangulation does, so differences of this are the slab's.
fn fan_signed_volume(mesh: &TubeMesh, x: &[Vec3], slab: &Slab) -> f64 {
    let (ra, rb) = (
        mesh.rings[slab.rings[0] as usize],
        mesh.rings[slab.rings[1] as usize],
    );
    let n = ra.centre - ra.first;
    let p = |i: u32| x[i as usize].as_dvec3();
    let tri = |a: u32, b: u32, c: u32| p(a).dot(p(b).cross(p(c)));
    let mut v = 0.0;
    for j in 0..n {
        let j1 = (j + 1) % n;
        v += tri(ra.first + j, ra.first + j1, rb.first + j1);
        v += tri(ra.first + j, rb.first + j1, rb.first + j);
        v += tri(ra.centre, ra.first + j1, ra.first + j);
        v += tri(rb.centre, rb.first + j, rb.first + j1);
    }
    v / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::PolygonMethod;
    use crate::lattice::tube::{RingInput, check_closed};

    /// A ring of `n` points round (cx, cy) at height z, as a slice polygon.
    fn ring(slice: usize, c: [f32; 2], z: f32, half: f32, n: usize, square: bool) -> RingInput {
        let p2: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                let (s, co) = a.sin_cos();
                // A square: the circle's rays cut at the sides.
                let k = if square {
                    1.0 / co.abs().max(s.abs())
                } else {
                    1.0
                };
                [co * k, s * k]
            })
            .collect();
        RingInput {
            slice,
            points: p2
                .iter()
                .map(|p| Vec3::new(c[0] + p[0] as f32 * half, c[1] + p[1] as f32 * half, z))
                .collect(),
            points_2d: p2.clone(),
            centre: Vec3::new(c[0], c[1], z),
            method: PolygonMethod::Radial,
            area_px: 4,
            iou: 1.0,
        }
    }

    fn tube(rings: &[RingInput], half_step: f32) -> TubeMesh {
        let mut m = TubeMesh::default();
        let k: Vec<usize> = (0..=rings.iter().map(|r| r.slice).max().unwrap_or(0)).collect();
        let off = Vec3::new(0.0, 0.0, half_step);
        m.add_tube(rings, -off, off, &k);
        m
    }

    /// A square bone 2 cm wide from z = -5 mm to 35 mm.
    fn bone() -> BoneQuery {
        let rings: Vec<RingInput> = (0..4)
            .map(|i| ring(i, [0.0, 0.0], 0.01 * i as f32, 0.01, 16, true))
            .collect();
        let m = tube(&rings, 0.005);
        let tri = oriented_trimesh(&m.vertices, &m.triangles).unwrap();
        let aabb = tri.local_aabb();
        BoneQuery { tri, aabb }
    }

    fn in_box(p: Vec3, z: [f32; 2]) -> bool {
        p.x.abs() < 0.01 && p.y.abs() < 0.01 && p.z > z[0] && p.z < z[1]
    }

    /// The slabs add up to the volume the surface encloses, every one positive.
    fn assert_slabs_add_up(m: &TubeMesh) {
        let sum: f64 = m.slabs.iter().map(|s| s.volume).sum();
        assert!(
            (sum - m.volume()).abs() < 1e-6 * m.volume(),
            "{sum} {}",
            m.volume()
        );
        assert!(m.slabs.iter().all(|s| s.volume > 0.0));
    }

    /// A round muscle 2 cm in radius whose side reaches 5 mm into the bone; `mirrored`,
    /// its rings run the other way round (as a mirrored voxel grid gives), so the tube
    /// turns its triangles over.
    fn muscle_beside_the_bone(mirrored: bool) -> TubeMesh {
        let rings: Vec<RingInput> = (1..3)
            .map(|i| {
                let mut r = ring(i, [0.025, 0.0], 0.01 * i as f32, 0.02, 32, false);
                if mirrored {
                    r.points.reverse();
                    r.points_2d.reverse();
                }
                r
            })
            .collect();
        tube(&rings, 0.005)
    }

    #[test]
    fn a_muscle_beside_a_bone_is_drawn_out_of_it_along_its_rays() {
        let bones = [bone()];
        let mut m = muscle_beside_the_bone(false);
        let before = m.clone();
        let inside = |m: &TubeMesh| {
            m.vertices
                .iter()
                .filter(|p| in_box(**p, [-0.005, 0.035]))
                .count()
        };
        assert!(inside(&m) > 0);
        let done = clear_tube(&mut m, &bones);
        // Ring centres are interior vertices: only surface vertices are counted.
        assert_eq!(inside(&m), 0, "{done:?}");
        assert!(done.drawn_in > 0 && done.left_inside == 0, "{done:?}");
        assert!(check_closed(&m.triangles).is_ok());
        // Every moved vertex stayed on the ray from its ring's centre, and came inward.
        for r in &m.rings {
            let c = m.vertices[r.centre as usize];
            for v in r.first..r.centre {
                let (a, b) = (before.vertices[v as usize] - c, m.vertices[v as usize] - c);
                assert!(a.cross(b).length() < 1e-9 && b.length() <= a.length() + 1e-7);
            }
        }
        // The slabs still add up to the volume the surface encloses, which shrank.
        assert_slabs_add_up(&m);
        assert!(m.volume() < before.volume());
    }

    #[test]
    fn an_end_cap_reaching_into_a_bone_comes_back_out_of_it() {
        let bones = [bone()];
        // A muscle standing on the bone's top (35 mm): its lower cap, half a slice
        // (6 mm) below its first ring at 40 mm, reaches 1 mm into the bone.
        let rings: Vec<RingInput> = (0..2)
            .map(|i| ring(i, [0.0, 0.0], 0.04 + 0.012 * i as f32, 0.005, 16, false))
            .collect();
        let mut m = tube(&rings, 0.006);
        let cap = m.rings[0];
        assert!(in_box(m.vertices[cap.first as usize], [-0.005, 0.035]));
        let done = clear_tube(&mut m, &bones);
        assert_eq!(
            done,
            Clearance {
                drawn_in: 16,
                left_inside: 0
            }
        );
        // The cap stays flat, now just above the bone.
        let zs: Vec<f32> = (cap.first..=cap.centre)
            .map(|v| m.vertices[v as usize].z)
            .collect();
        assert!(
            zs.iter().all(|z| (z - 0.035 - CLEARANCE_M).abs() < 1e-6),
            "{zs:?}"
        );
        assert_slabs_add_up(&m);
    }

    #[test]
    fn a_mirrored_muscle_keeps_its_slab_volumes_right() {
        let bones = [bone()];
        let mut m = muscle_beside_the_bone(true);
        let before = m.clone();
        let done = clear_tube(&mut m, &bones);
        assert!(done.drawn_in > 0 && done.left_inside == 0, "{done:?}");
        assert!(m.volume() > 0.0 && m.volume() < before.volume());
        assert_slabs_add_up(&m);
    }

    #[test]
    fn a_muscle_clear_of_bone_is_left_as_it_is() {
        let bones = [bone()];
        let rings: Vec<RingInput> = (1..3)
            .map(|i| ring(i, [0.04, 0.0], 0.01 * i as f32, 0.02, 32, false))
            .collect();
        let mut m = tube(&rings, 0.005);
        let before = m.clone();
        assert_eq!(clear_tube(&mut m, &bones), Clearance::default());
        assert_eq!(m.vertices, before.vertices);
        assert_eq!(m.slabs, before.slabs);
    }
}
