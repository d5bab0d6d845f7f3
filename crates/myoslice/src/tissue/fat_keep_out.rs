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

use crate::par::*;
use glam::{Quat, Vec3};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh;

use super::knee_fold::{FoldZone, KneeFold};
use crate::body::{BodyId, KneeAxis};
use crate::geometry::BoneSdf;

/// Clearance (m) kept from bone per layer above the inner one (the inner layer is not
/// watched): the skin of a two-layer lattice keeps 5 mm off bone, about the skin and
/// subcutaneous tissue over the patella (at 3 mm, 6 patella vertices still showed, up
/// to 2.8 mm, between the skin's vertices; at 5 mm, 2 and 2.0).
const CLEARANCE_PER_LAYER: f32 = 0.0025;
/// A pair is watched when, at some knee angle of the sweep, its vertex comes within its
/// clearance and this much more of the bone (m).
const WATCH_M: f32 = 0.02;
/// Knee angles (degrees) the build sweeps to find the pairs to watch: every 5°, from past
/// any extension to past any flexion a knee's limits allow.
const SWEEP_STEP_DEG: usize = 5;
const SWEEP_FROM_DEG: i32 = -30;
const SWEEP_TO_DEG: i32 = 180;
/// Farthest (m) a vertex inside a bone looks for its way out away from the knee axis,
/// about a patella's thickness: further, that way runs along a bone (the femur's shaft,
/// the tibial tuberosity), and the nearest way out serves.
const MAX_EXIT_M: f32 = 0.03;

/// The (fat vertex, bone) pairs to watch, grouped by vertex. Nothing is remembered from
/// one update to the next: each pair asks its bone's distance field afresh.
#[derive(Debug, Clone, Default)]
pub(crate) struct FatKeepOut {
    /// Watched vertices, ascending.
    vertices: Vec<u32>,
    /// Pairs of `vertices[i]`: `bones[start[i]..start[i + 1]]`, bone index ascending.
    start: Vec<u32>,
    bones: Vec<u32>,
    /// Clearance (m) each pair keeps: its layer's, or its rest distance from the bone
    /// where that is less (so the rest shape itself is never pushed).
    clears: Vec<f32>,
    /// The knee axis (a point on it and its direction), the same in both bodies' rest
    /// frames: in front of the knee the skin lies further from it than the bone under it.
    axis: (Vec3, Vec3),
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
        sdfs: &[BoneSdf],
        surfaces: &[(BodyId, TriMesh)],
    ) -> Self {
        let folds: Vec<KneeFold> = (SWEEP_FROM_DEG..=SWEEP_TO_DEG)
            .step_by(SWEEP_STEP_DEG)
            .map(|d| KneeFold::new(knee, (d as f32).to_radians()))
            .collect();
        let boxes: Vec<(Vec3, Vec3)> = surfaces
            .iter()
            .map(|(_, m)| (m.local_aabb().mins, m.local_aabb().maxs))
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
                let near: Vec<u32> = (0..surfaces.len() as u32)
                    .filter(|&b| {
                        let (body, tree) = &surfaces[b as usize];
                        let (lo, hi) = boxes[b as usize];
                        let swept = match body {
                            BodyId::Thigh => &thigh,
                            BodyId::Shank => &shank,
                        };
                        swept.iter().any(|&p| {
                            let off_box = (lo - p).max(p - hi).max(Vec3::ZERO).length();
                            off_box < clear + WATCH_M
                                && sdfs[b as usize].nearest(tree, p, clear + WATCH_M).is_some()
                        })
                    })
                    .collect();
                (!near.is_empty()).then_some((v as u32, clear, near))
            })
            .collect();
        let mut out = Self {
            axis: (knee.point, knee.axis.normalize_or(Vec3::X)),
            ..Self::default()
        };
        out.start.push(0);
        for (v, clear, near) in watched {
            out.vertices.push(v);
            for b in near {
                let tree = &surfaces[b as usize].1;
                let rest_d = sdfs[b as usize]
                    .nearest(tree, rest[v as usize], f32::INFINITY)
                    .map_or(0.0, |s| s.distance.max(0.0));
                out.bones.push(b);
                out.clears.push(clear.min(rest_d));
            }
            out.start.push(out.bones.len() as u32);
        }
        out
    }

    /// Moves each free watched vertex of `x` (`free`: those the update relaxes, whose
    /// elements the guard checks) that lies nearer a bone than its clearance away from
    /// the bone's nearest point to its clearance, and one inside a bone out away from the
    /// knee axis (the nearest way out of a vertex deep in the patella can lead behind it),
    /// to its clearance past where it leaves the bone; `pose` gives the bodies' poses
    /// (rotation, translation). A vertex watched against two bones is kept from each in
    /// turn, in bone order. Returns the vertices it moved, ascending.
    pub(crate) fn apply(
        &self,
        x: &mut [Vec3],
        free: &[bool],
        sdfs: &[BoneSdf],
        surfaces: &[(BodyId, TriMesh)],
        pose: impl Fn(BodyId) -> (Quat, Vec3) + Sync,
    ) -> Vec<u32> {
        let xs = &*x;
        let (start, bones, clears, (axis_at, axis)) =
            (&self.start, &self.bones, &self.clears, self.axis);
        let moved: Vec<Option<(u32, Vec3)>> = self
            .vertices
            .par_iter()
            .enumerate()
            .map(|(i, &v)| {
                if !free[v as usize] {
                    return None;
                }
                let mut p = xs[v as usize];
                let mut moved = false;
                for (k, b) in bones[start[i] as usize..start[i + 1] as usize]
                    .iter()
                    .enumerate()
                {
                    let (sdf, (body, tree)) = (&sdfs[*b as usize], &surfaces[*b as usize]);
                    let clear = clears[start[i] as usize + k];
                    let (q, t) = pose(*body);
                    let local = q.inverse() * (p - t);
                    // Most watched vertices are well clear: the field says so at once.
                    let Some(w) = sdf.nearest(tree, local, clear) else {
                        continue;
                    };
                    let inside = w.distance < 0.0;
                    if !inside && w.distance >= clear {
                        continue;
                    }
                    let radial = local - axis_at;
                    let away = (radial - axis * radial.dot(axis)).try_normalize();
                    let exit = away.filter(|_| inside).and_then(|dir| {
                        let toi = tree.cast_local_ray(&Ray::new(local, dir), MAX_EXIT_M, false)?;
                        let exit = local + dir * (toi + clear);
                        // Left through a face aslant the way out: its clearance from the
                        // nearest point, not along the way. Back in the bone (a concave
                        // part, or a surface that crosses itself): the nearest way out.
                        match sdf.nearest(tree, exit, clear) {
                            None => Some(exit),
                            Some(near) if near.distance < 0.0 => None,
                            Some(near) => Some(near.point + near.normal * clear),
                        }
                    });
                    let out = if w.normal == Vec3::ZERO {
                        away.unwrap_or(Vec3::Z)
                    } else {
                        w.normal
                    };
                    let to = exit.unwrap_or(w.point + out * clear);
                    p = q * to + t;
                    moved = true;
                }
                moved.then_some((v, p))
            })
            .collect();
        moved
            .into_iter()
            .flatten()
            .map(|(v, p)| {
                x[v as usize] = p;
                v
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box bone `lo..hi` (rest frame) on `body`: its distance field and parry mesh.
    fn box_bone(body: BodyId, lo: Vec3, hi: Vec3) -> (BoneSdf, (BodyId, TriMesh)) {
        let mesh = crate::tissue::test_shapes::box_mesh(lo, hi);
        let sdf = BoneSdf::new(mesh.vertices(), mesh.indices(), 0.002, 0.01);
        (sdf, (body, mesh))
    }

    /// Signed distance from `p` to the box `lo..hi` (negative inside).
    fn box_distance(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
        let q = (lo - p).max(p - hi);
        q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
    }

    #[test]
    fn skin_the_fold_carries_through_a_shank_bone_keeps_its_clearance_outside_it() {
        // Knee axis x through the origin: up is +z, front is −y. A patella-like box on
        // the shank in front of the knee, above the joint line (ψ about 42–63° from up,
        // 54–78 mm from the axis).
        let knee = KneeAxis {
            point: Vec3::ZERO,
            axis: Vec3::X,
            condyle_radius: 0.02,
        };
        let (lo, hi) = (Vec3::new(-0.01, -0.06, 0.03), Vec3::new(0.01, -0.045, 0.05));
        let (sdf, surface) = box_bone(BodyId::Shank, lo, hi);
        let at = |psi: f32, r: f32| {
            let psi = psi.to_radians();
            Vec3::new(0.0, -r * psi.sin(), r * psi.cos())
        };
        // Skin (layer 2) on an arc 60 mm from the axis below the box, where the fold turns
        // it by less than the shank, so the box sweeps through it (at rest 3.5 cm away,
        // too far to watch by its rest place alone); an inner vertex (layer 0) on the same
        // arc; skin behind the knee; skin far in front of the box, never near it.
        let mut rest: Vec<Vec3> = (0..12).map(|k| at(95.0 + 5.0 * k as f32, 0.06)).collect();
        let inner = rest.len();
        rest.push(at(100.0, 0.06));
        let behind = rest.len();
        rest.push(at(250.0, 0.06));
        let far = rest.len();
        rest.push(at(70.0, 0.20));
        // Skin 2 mm above the box's top at rest: it keeps those 2 mm, not its layer's.
        let close = rest.len();
        rest.push(Vec3::new(0.0, -0.05, 0.052));
        let layer_of = |v: usize| if v == inner { 0 } else { 2 };
        let zone = FoldZone::new(&knee, &rest, &[]);
        let sdfs = [sdf];
        let surfaces = [surface];
        let keep = FatKeepOut::new(&knee, &rest, &zone, layer_of, &sdfs, &surfaces);
        // The arc's skin near the box, not the inner vertex, the skin behind the knee nor
        // the skin far off.
        let watched: Vec<u32> = keep.vertices.clone();
        assert!(
            watched
                .iter()
                .all(|&v| (v as usize) < inner || v as usize == close),
            "{watched:?}"
        );
        assert!(watched.len() >= 4, "{watched:?}");
        assert!(
            [inner, behind, far]
                .iter()
                .all(|v| !watched.contains(&(*v as u32)))
        );
        let clear = 2.0 * CLEARANCE_PER_LAYER;
        let free = vec![true; rest.len()];
        // At rest nothing moves.
        let mut x = rest.clone();
        let pose = |_| (Quat::IDENTITY, Vec3::ZERO);
        keep.apply(&mut x, &free, &sdfs, &surfaces, pose);
        assert_eq!(x, rest);
        assert!(watched.contains(&(close as u32)));
        let (mut inside, mut lifted) = (0, 0);
        for deg in (1..=30).map(|k| 5.0 * k as f32) {
            let theta = deg.to_radians();
            let fold = KneeFold::new(&knee, theta);
            let turn = Quat::from_axis_angle(Vec3::X, theta);
            let mut x: Vec<Vec3> = rest.iter().map(|&p| fold.map(p)).collect();
            let before = x.clone();
            keep.apply(&mut x, &free, &sdfs, &surfaces, |b| match b {
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
                if !watched.contains(&(v as u32)) {
                    assert_eq!(p, b, "{deg}°: unwatched vertex {v} moved");
                } else if p != b {
                    lifted += 1;
                    // Moved no further than to its clearance; out of the bone away from
                    // the axis, past the bone's far side from it.
                    assert!(d < clear + 1e-5, "{deg}°: vertex {v} lifted to {d} m");
                    if box_distance(turn.inverse() * *b, lo, hi) < 0.0 {
                        inside += 1;
                        let r = |p: Vec3| p.y.hypot(p.z);
                        assert!(r(*p) > r(*b), "{deg}°: vertex {v} pushed toward the axis");
                    }
                }
            }
        }
        assert!(
            lifted >= 3 && inside >= 1,
            "{lifted} vertices lifted, {inside} from inside"
        );
    }

    /// A keep-out of one box bone `0..20 mm` on the thigh for `n` vertices, clearance 3 mm,
    /// its axis along x through (10, 10, −1000) mm (so away from it is +z at the box).
    fn box_keep_out(n: usize) -> (FatKeepOut, BoneSdf, (BodyId, TriMesh)) {
        let (sdf, surface) = box_bone(BodyId::Thigh, Vec3::ZERO, Vec3::splat(0.02));
        let keep = FatKeepOut {
            vertices: (0..n as u32).collect(),
            start: (0..=n as u32).collect(),
            bones: vec![0; n],
            clears: vec![0.003; n],
            axis: (Vec3::new(0.01, 0.01, -1.0), Vec3::X),
        };
        (keep, sdf, surface)
    }

    #[test]
    fn a_free_vertex_inside_a_bone_or_too_near_it_goes_out_to_its_clearance() {
        let (keep, sdf, surface) = box_keep_out(5);
        // Inside under the top face (away from the axis is up), just above the top face,
        // just beside the side face x = 20 mm, well clear, and inside but not free.
        let mut x = vec![
            Vec3::new(0.01, 0.01, 0.015),
            Vec3::new(0.01, 0.01, 0.021),
            Vec3::new(0.021, 0.01, 0.01),
            Vec3::new(0.01, 0.01, 0.03),
            Vec3::new(0.01, 0.01, 0.015),
        ];
        let free = [true, true, true, true, false];
        let pose = |_| (Quat::IDENTITY, Vec3::ZERO);
        keep.apply(&mut x, &free, &[sdf], &[surface], pose);
        let top = Vec3::new(0.01, 0.01, 0.023);
        assert!(x[0].distance(top) < 1e-6, "{:?}", x[0]);
        assert!(x[1].distance(top) < 1e-6, "{:?}", x[1]);
        assert!(
            x[2].distance(Vec3::new(0.023, 0.01, 0.01)) < 1e-6,
            "{:?}",
            x[2]
        );
        assert_eq!(x[3], Vec3::new(0.01, 0.01, 0.03));
        assert_eq!(x[4], Vec3::new(0.01, 0.01, 0.015));
    }

    #[test]
    fn a_vertex_coming_nearer_step_by_step_is_pushed_once_within_its_clearance() {
        let (keep, sdf, surface) = box_keep_out(1);
        let (sdfs, surfaces) = ([sdf], [surface]);
        let pose = |_| (Quat::IDENTITY, Vec3::ZERO);
        // Far above the box, then nearer step by step, then inside: each time it is kept
        // at least its clearance out.
        for z in [0.06, 0.05, 0.04, 0.03, 0.024, 0.022, 0.01] {
            let mut x = vec![Vec3::new(0.01, 0.01, z)];
            keep.apply(&mut x, &[true], &sdfs, &surfaces, pose);
            assert!(x[0].z > 0.023 - 1e-6, "from {z}: {:?}", x[0]);
            assert_eq!(x[0].z == z, z >= 0.023, "from {z}: {:?}", x[0]);
        }
    }
}
