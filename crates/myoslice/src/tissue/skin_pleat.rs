//! Skin that bunches up lies on itself. Where the contact pulls the skin of one side
//! toward the plane (the thigh's behind a knee bent 70–100°), rows of it that lay
//! centimetres apart at rest come to lie within millimetres of the plane and cross one
//! another: a pleat. Real skin folds over itself there, one layer on the other, so
//! for each pair of crossing skin triangles of the same side the one that lay farther
//! from the joint at rest goes on top: its vertices move away from the plane, along its
//! normal, to a skin's thickness past the other's farthest vertex. A few rounds, each
//! looking again only at the triangles the last one moved.
//!
//! Left to the guard, those crossings had it fall back toward the knee fold, which folds
//! fat elements behind a bent knee (docs/tissue-history.md).

use super::Tissue;
use super::intersect::{Aabb, TriangleGrid, crossing_pairs_near};
use super::knee_fold::Contact;

/// How far (m) a layer of a pleat lies past the one under it, along the plane's normal:
/// about the thickness of the skin.
const PLEAT_THICKNESS_M: f32 = 0.001;

/// Most rounds of stacking: each finds the crossings left and stacks them.
const PLEAT_ROUNDS: usize = 4;

impl Tissue {
    /// Stacks the pleats of the guarded skin (see the module): moves the free vertices
    /// of the upper layer of each crossing pair of one side's triangles; returns them
    /// (ascending, each once).
    pub(super) fn stack_pleats(&mut self, contact: &Contact) -> Vec<u32> {
        let fixed = std::sync::Arc::clone(&self.fixed);
        let triangles = &fixed.guard_triangles;
        let (x, rest, free) = (&mut self.fat.x, &self.fat.rest, &self.fat.free);
        let joint = self.knee.point;
        let from_joint =
            |t: &[u32; 3]| -> f32 { t.iter().map(|&v| rest[v as usize].distance(joint)).sum() };
        let mut moved: Vec<u32> = Vec::new();
        // Only pairs with a live triangle can cross (see the guard): first those with a
        // free vertex, then those with a vertex the last round moved.
        let mut live: Vec<bool> = triangles
            .iter()
            .map(|t| t.iter().any(|&v| free[v as usize]))
            .collect();
        let mut boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of(x, t)).collect();
        let mut moved_now = vec![false; x.len()];
        for round in 0..PLEAT_ROUNDS {
            let query: Vec<u32> = (0..triangles.len() as u32)
                .filter(|&i| live[i as usize])
                .collect();
            if query.is_empty() {
                break;
            }
            let queried = |i: u32| live[i as usize];
            let mut pairs = if round == 0 {
                TriangleGrid::new(&boxes, triangles, x).map_or_else(Vec::new, |g| {
                    g.crossing_pairs(x, triangles, &boxes, &query, queried)
                })
            } else {
                crossing_pairs_near(x, triangles, &boxes, &query, queried)
            };
            if pairs.is_empty() {
                break;
            }
            pairs.sort_unstable();
            for (a, b) in pairs {
                let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
                let side = fixed.thigh_side[ta[0] as usize];
                if !ta
                    .iter()
                    .chain(&tb)
                    .all(|&v| fixed.thigh_side[v as usize] == side)
                {
                    continue;
                }
                let (under, over) = if from_joint(&ta) <= from_joint(&tb) {
                    (ta, tb)
                } else {
                    (tb, ta)
                };
                let top = under
                    .iter()
                    .map(|&v| contact.locate(x[v as usize], side).1)
                    .fold(f32::MIN, f32::max)
                    + PLEAT_THICKNESS_M;
                for &v in &over {
                    let v = v as usize;
                    let d = contact.locate(x[v], side).1;
                    if free[v] && d < top {
                        x[v] = contact.toward_side(x[v], side, top - d);
                        moved.push(v as u32);
                        moved_now[v] = true;
                    }
                }
            }
            // The next round looks again at the triangles this one moved.
            for (i, t) in triangles.iter().enumerate() {
                live[i] = t.iter().any(|&v| moved_now[v as usize]);
                if live[i] {
                    boxes[i] = Aabb::of(x, t);
                }
            }
            moved_now.fill(false);
        }
        moved.sort_unstable();
        moved.dedup();
        moved
    }
}
