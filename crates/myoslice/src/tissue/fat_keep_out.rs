//! Fat kept out of bone in front of the knee. The knee fold turns the fat there by less
//! than the shank, so the patella, which moves with the shank, comes under skin that lay
//! over the joint line at rest, nearer the axis than the patella: from about 70° it came
//! out through the skin (at most 108 vertices and 6.9 mm on the phantom, 111 and 7.6 mm
//! on the Visible Human). The paper's rule, inner fat vertices touching bone slide on it,
//! watches only the bone each inner vertex touched at rest. Here each fat vertex above the
//! inner layer that the fold can bring near a bone is watched against it, and kept out of
//! it by a clearance that grows with its layer, so the skin lifts over the bone instead of
//! letting it through. Behind the knee the contact plane and the crease rule the fat
//! (watching it there too brought more muscle out through the skin at deep flexion).

use glam::{Quat, Vec3};
use parry3d::shape::TriMesh;
use rayon::prelude::*;

use super::bone_slide::BoneMesh;
use super::knee_fold::{FoldZone, KneeFold};
use crate::body::{BodyId, KneeAxis};

/// Clearance (m) kept from bone per layer above the inner one: the skin of a two-layer
/// lattice keeps 3 mm off bone, its inner vertices only outside it.
const CLEARANCE_PER_LAYER: f32 = 0.0015;
/// A pair is watched when, at some knee angle of the sweep, its vertex comes within its
/// clearance and this much more of the bone (m).
const WATCH_M: f32 = 0.02;
/// Knee angles (degrees) the build sweeps to find the pairs to watch: every 5° up to the
/// deepest flexion the fold is built for.
const SWEEP_STEP_DEG: usize = 5;
const SWEEP_TOP_DEG: usize = 160;

/// What a pair last learnt: where its walk starts, and a place (bone frame) its vertex was
/// known to lie at least so far outside the bone (m; 0 when not known).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PairMemory {
    triangle: u32,
    at: Vec3,
    clear_by: f32,
}

/// The (fat vertex, bone) pairs to watch, grouped by vertex, with what each pair last
/// learnt.
#[derive(Debug, Clone, Default)]
pub(crate) struct FatKeepOut {
    /// Watched vertices, ascending, with their clearance (m).
    vertices: Vec<(u32, f32)>,
    /// Pairs of `vertices[i]`: `bones[start[i]..start[i + 1]]`, bone index ascending.
    start: Vec<u32>,
    bones: Vec<u32>,
    /// What each pair last learnt (parallel to `bones`).
    memory: Vec<PairMemory>,
}

impl FatKeepOut {
    /// The pairs to watch: each fat vertex the fold can move (`zone`) against each bone
    /// it comes near at some knee angle, carried by the fold (the fat's first guess)
    /// while the bone moves with its body. `layer_of` gives a vertex's layer (0 inner).
    pub(crate) fn new(
        knee: &KneeAxis,
        rest: &[Vec3],
        zone: &FoldZone,
        layer_of: impl Fn(usize) -> usize + Sync,
        meshes: &[BoneMesh],
        surfaces: &[(BodyId, TriMesh)],
    ) -> Self {
        let folds: Vec<KneeFold> = (0..=SWEEP_TOP_DEG)
            .step_by(SWEEP_STEP_DEG)
            .map(|d| KneeFold::new(knee, (d as f32).to_radians()))
            .collect();
        let boxes: Vec<(Vec3, Vec3)> = surfaces
            .iter()
            .map(|(_, m)| {
                m.vertices().iter().fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(lo, hi), v| (lo.min(*v), hi.max(*v)),
                )
            })
            .collect();
        let watched: Vec<(u32, f32, Vec<u32>)> = (0..rest.len())
            .into_par_iter()
            // The inner layer faces muscle or slides on its bone (the paper's rules); what
            // must cover a bone is the layers over it.
            .filter(|&v| layer_of(v) > 0 && zone.contains(v) && !folds[0].is_posterior(rest[v]))
            .filter_map(|v| {
                let clear = CLEARANCE_PER_LAYER * layer_of(v) as f32;
                // Where the fold carries the vertex, in each body's rest frame (the shank
                // turns about the axis).
                let thigh: Vec<Vec3> = folds.iter().map(|f| f.map(rest[v])).collect();
                let shank: Vec<Vec3> = folds
                    .iter()
                    .zip(&thigh)
                    .map(|(f, p)| {
                        f.point + Quat::from_axis_angle(f.axis, -f.theta) * (*p - f.point)
                    })
                    .collect();
                let near: Vec<u32> = (0..meshes.len() as u32)
                    .filter(|&b| {
                        let (mesh, tree) = (&meshes[b as usize], &surfaces[b as usize].1);
                        let (lo, hi) = boxes[b as usize];
                        let swept = match mesh.body() {
                            BodyId::Thigh => &thigh,
                            BodyId::Shank => &shank,
                        };
                        swept.iter().any(|&p| {
                            let off_box = (lo - p).max(p - hi).max(Vec3::ZERO).length();
                            off_box < clear + WATCH_M && mesh.clear_bound(p, tree) < clear + WATCH_M
                        })
                    })
                    .collect();
                (!near.is_empty()).then_some((v as u32, clear, near))
            })
            .collect();
        let mut out = Self::default();
        out.start.push(0);
        for (v, clear, near) in watched {
            out.vertices.push((v, clear));
            for b in near {
                let (mesh, tree) = (&meshes[b as usize], &surfaces[b as usize].1);
                out.bones.push(b);
                out.memory.push(PairMemory {
                    triangle: mesh.walk_from_tree(tree, rest[v as usize]).triangle,
                    at: Vec3::ZERO,
                    clear_by: 0.0,
                });
            }
            out.start.push(out.bones.len() as u32);
        }
        out
    }

    /// What each pair last learnt: the state an update changes.
    pub(crate) fn memory(&self) -> Vec<PairMemory> {
        self.memory.clone()
    }

    /// Puts back what [`Self::memory`] took.
    pub(crate) fn recall(&mut self, memory: Vec<PairMemory>) {
        self.memory = memory;
    }

    /// Moves each watched vertex of `x` that lies inside a bone, or nearer it than its
    /// clearance, out along the bone's normal to its clearance; `pose` gives the bodies'
    /// poses (rotation, translation). A vertex watched against two bones is kept from each
    /// in turn, in bone order.
    pub(crate) fn apply(
        &mut self,
        x: &mut [Vec3],
        meshes: &[BoneMesh],
        surfaces: &[(BodyId, TriMesh)],
        pose: impl Fn(BodyId) -> (Quat, Vec3) + Sync,
    ) {
        let xs = &*x;
        let (start, bones) = (&self.start, &self.bones);
        // Each vertex's pairs are a contiguous run of `memory`: split it per vertex, so
        // vertices go in parallel and each is written back once, in order.
        let mut runs: Vec<&mut [PairMemory]> = Vec::with_capacity(self.vertices.len());
        let mut rest = self.memory.as_mut_slice();
        for w in start.windows(2) {
            let (run, tail) = rest.split_at_mut((w[1] - w[0]) as usize);
            runs.push(run);
            rest = tail;
        }
        let moved: Vec<Option<(u32, Vec3)>> = self
            .vertices
            .par_iter()
            .zip(runs.into_par_iter())
            .enumerate()
            .map(|(i, (&(v, clear), memory))| {
                let mut p = xs[v as usize];
                let mut moved = false;
                for (k, b) in bones[start[i] as usize..start[i + 1] as usize]
                    .iter()
                    .enumerate()
                {
                    let (mesh, tree) = (&meshes[*b as usize], &surfaces[*b as usize].1);
                    let (q, t) = pose(mesh.body());
                    let local = q.inverse() * (p - t);
                    let m = &mut memory[k];
                    // Most watched vertices are well clear: still within the ball they were
                    // last known clear by, or vouched for by the distance grid.
                    if m.clear_by - local.distance(m.at) > clear {
                        continue;
                    }
                    let bound = mesh.clear_bound(local, tree);
                    if bound > clear {
                        (m.at, m.clear_by) = (local, bound);
                        continue;
                    }
                    let w = mesh.walk_checked(m.triangle, local, tree);
                    let d = w.point.distance(local);
                    (m.triangle, m.at, m.clear_by) = (w.triangle, local, 0.0);
                    if !w.inside && d >= clear {
                        m.clear_by = d;
                        continue;
                    }
                    let out = if w.inside {
                        w.point - local
                    } else {
                        local - w.point
                    };
                    let out = out
                        .try_normalize()
                        .unwrap_or_else(|| mesh.normal(w.triangle));
                    p = q * (w.point + out * clear) + t;
                    moved = true;
                }
                moved.then_some((v, p))
            })
            .collect();
        for (v, p) in moved.into_iter().flatten() {
            x[v as usize] = p;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box bone `lo..hi` (rest frame) on `body`, with its parry mesh.
    fn box_bone(body: BodyId, lo: Vec3, hi: Vec3) -> (BoneMesh, (BodyId, TriMesh)) {
        let mesh = crate::tissue::test_shapes::box_mesh(lo, hi);
        (BoneMesh::new(body, &mesh), (body, mesh))
    }

    /// Signed distance from `p` to the box `lo..hi` (negative inside).
    fn box_distance(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
        let q = (lo - p).max(p - hi);
        q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
    }

    #[test]
    fn skin_the_fold_carries_into_a_shank_bone_is_lifted_to_its_clearance_and_only_it() {
        // Knee axis x through the origin: up is +z, front is −y. A patella-like box on
        // the shank in front of the knee, above the joint line (ψ about 42–63° from up).
        let knee = KneeAxis {
            point: Vec3::ZERO,
            axis: Vec3::X,
            condyle_radius: 0.02,
        };
        let (lo, hi) = (Vec3::new(-0.01, -0.06, 0.03), Vec3::new(0.01, -0.045, 0.05));
        let (mesh, surface) = box_bone(BodyId::Shank, lo, hi);
        let at = |psi: f32, r: f32| {
            let psi = psi.to_radians();
            Vec3::new(0.0, -r * psi.sin(), r * psi.cos())
        };
        // Skin (layer 2) on an arc below the box, where the fold turns it by less than the
        // shank, so the box sweeps through it; an inner vertex (layer 0) on the same arc;
        // skin behind the knee; skin far in front of the box, never near it.
        let mut rest: Vec<Vec3> = (0..12).map(|k| at(95.0 + 5.0 * k as f32, 0.052)).collect();
        let inner = rest.len();
        rest.push(at(100.0, 0.052));
        let behind = rest.len();
        rest.push(at(250.0, 0.052));
        let far = rest.len();
        rest.push(at(70.0, 0.20));
        let layer_of = |v: usize| if v == inner { 0 } else { 2 };
        let zone = FoldZone::new(&knee, &rest, &[]);
        let meshes = [mesh];
        let surfaces = [surface];
        let mut keep = FatKeepOut::new(&knee, &rest, &zone, layer_of, &meshes, &surfaces);
        // The arc's skin near the box, not the inner vertex, the skin behind the knee nor
        // the skin far off.
        let watched: Vec<u32> = keep.vertices.iter().map(|v| v.0).collect();
        assert!(watched.iter().all(|&v| (v as usize) < inner), "{watched:?}");
        assert!(watched.len() >= 4, "{watched:?}");
        assert!(
            [inner, behind, far]
                .iter()
                .all(|v| !watched.contains(&(*v as u32)))
        );
        let clear = 2.0 * CLEARANCE_PER_LAYER;
        let mut lifted = 0;
        for deg in (1..=30).map(|k| 5.0 * k as f32) {
            let theta = deg.to_radians();
            let fold = KneeFold::new(&knee, theta);
            let turn = Quat::from_axis_angle(Vec3::X, theta);
            let mut x: Vec<Vec3> = rest.iter().map(|&p| fold.map(p)).collect();
            let before = x.clone();
            keep.apply(&mut x, &meshes, &surfaces, |b| match b {
                BodyId::Thigh => (Quat::IDENTITY, Vec3::ZERO),
                BodyId::Shank => (turn, Vec3::ZERO),
            });
            for (v, (p, b)) in x.iter().zip(&before).enumerate() {
                let d = box_distance(turn.inverse() * *p, lo, hi);
                if v < inner {
                    assert!(
                        d > clear - 1e-5,
                        "{deg}°: skin vertex {v} {d} m from the bone"
                    );
                }
                if watched.contains(&(v as u32)) {
                    if p != b {
                        lifted += 1;
                        // Moved no further than to its clearance.
                        assert!(d < clear + 1e-5, "{deg}°: vertex {v} lifted to {d} m");
                    }
                } else {
                    assert_eq!(p, b, "{deg}°: unwatched vertex {v} moved");
                }
            }
        }
        assert!(lifted >= 3, "only {lifted} vertices lifted off the bone");
    }

    #[test]
    fn a_vertex_inside_a_bone_or_too_near_it_goes_out_along_the_normal_to_its_clearance() {
        let (lo, hi) = (Vec3::ZERO, Vec3::splat(0.02));
        let (mesh, surface) = box_bone(BodyId::Thigh, lo, hi);
        let mut keep = FatKeepOut {
            vertices: vec![(0, 0.003), (1, 0.003), (2, 0.003)],
            start: vec![0, 1, 2, 3],
            bones: vec![0; 3],
            memory: vec![
                PairMemory {
                    triangle: 0,
                    at: Vec3::ZERO,
                    clear_by: 0.0,
                };
                3
            ],
        };
        // Inside near the top face, just above it, and well clear of it.
        let mut x = vec![
            Vec3::new(0.01, 0.01, 0.019),
            Vec3::new(0.01, 0.01, 0.021),
            Vec3::new(0.01, 0.01, 0.03),
        ];
        let pose = |_| (Quat::IDENTITY, Vec3::ZERO);
        keep.apply(&mut x, &[mesh], &[surface], pose);
        let top = Vec3::new(0.01, 0.01, 0.023);
        assert!(x[0].distance(top) < 1e-6, "{:?}", x[0]);
        assert!(x[1].distance(top) < 1e-6, "{:?}", x[1]);
        assert_eq!(x[2], Vec3::new(0.01, 0.01, 0.03));
    }
}
