//! A bounding volume hierarchy over moving boxes (triangles, or groups of them), on
//! parry's [`Bvh`]: refitted each update with a margin, so that a leaf whose box stays
//! inside its fattened box costs nothing, and queried for overlapping pairs within one
//! tree (self-traversal) or between two.
//!
//! The pairs a traversal reports depend on the fattened boxes, hence on the history of
//! updates; callers must filter them with an exact test on the current positions (every
//! leaf box contains its current tight box grown by the query radius), which makes the
//! filtered result the same whatever the tree's history.

use glam::Vec3;
use parry3d::bounding_volume::Aabb;
use parry3d::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};

/// The boxes of a set of triangles over `positions`, each grown by `radius`.
#[derive(Debug, Clone, Copy)]
pub struct TriangleSet<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Triangles (indices into `positions`).
    pub triangles: &'a [[u32; 3]],
}

impl TriangleSet<'_> {
    /// The box of triangle `t` grown by `radius`.
    #[inline]
    pub fn aabb(&self, t: usize, radius: f32) -> Aabb {
        let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
        Aabb::new(
            a.min(b).min(c) - Vec3::splat(radius),
            a.max(b).max(c) + Vec3::splat(radius),
        )
    }
}

/// A refittable tree over `n` leaf boxes.
///
/// ```
/// use glam::Vec3;
/// use parry3d::bounding_volume::Aabb;
/// use myoslice::geometry::TriangleBvh;
/// let boxes = |shift: f32| -> Vec<Aabb> {
///     (0..10)
///         .map(|i| {
///             let p = Vec3::new(i as f32 * 0.01 + if i == 9 { shift } else { 0.0 }, 0.0, 0.0);
///             Aabb::new(p, p + Vec3::splat(0.005))
///         })
///         .collect()
/// };
/// let mut tree = TriangleBvh::new(0.002);
/// tree.update(&boxes(0.0));
/// let mut pairs = Vec::new();
/// tree.self_pairs(|a, b| pairs.push((a.min(b), a.max(b))));
/// assert!(pairs.is_empty()); // 5 mm boxes 10 mm apart
/// tree.update(&boxes(-0.008)); // the last box moves onto the one before it
/// tree.self_pairs(|a, b| pairs.push((a.min(b), a.max(b))));
/// assert_eq!(pairs, vec![(8, 9)]);
/// ```
#[derive(Clone)]
pub struct TriangleBvh {
    bvh: Bvh,
    workspace: BvhWorkspace,
    margin: f32,
    leaves: usize,
}

impl std::fmt::Debug for TriangleBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TriangleBvh")
            .field("leaves", &self.leaves)
            .field("margin", &self.margin)
            .finish()
    }
}

impl Default for TriangleBvh {
    fn default() -> Self {
        Self::new(0.0)
    }
}

impl TriangleBvh {
    /// An empty tree whose leaves are refitted only when they leave their box grown by
    /// `margin` (m).
    pub fn new(margin: f32) -> Self {
        Self {
            bvh: Bvh::new(),
            workspace: BvhWorkspace::default(),
            margin,
            leaves: 0,
        }
    }

    /// Number of leaves.
    pub fn len(&self) -> usize {
        self.leaves
    }

    /// True without leaves.
    pub fn is_empty(&self) -> bool {
        self.leaves == 0
    }

    /// Leaf `i` now has box `boxes[i]`: built anew when the number of leaves changed,
    /// else each leaf refitted (with the margin) and the tree's inner boxes updated.
    pub fn update(&mut self, boxes: &[Aabb]) {
        if boxes.len() != self.leaves || self.bvh.is_empty() {
            let grown: Vec<Aabb> = boxes
                .iter()
                .map(|b| {
                    Aabb::new(
                        b.mins - Vec3::splat(self.margin),
                        b.maxs + Vec3::splat(self.margin),
                    )
                })
                .collect();
            self.bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &grown);
            self.leaves = boxes.len();
            return;
        }
        for (i, b) in boxes.iter().enumerate() {
            self.bvh
                .insert_or_update_partially(*b, i as u32, self.margin);
        }
        self.bvh.refit(&mut self.workspace);
    }

    /// Every pair of distinct leaves whose boxes overlap, once each (in no particular
    /// order).
    pub fn self_pairs(&mut self, mut f: impl FnMut(u32, u32)) {
        if self.leaves < 2 {
            return;
        }
        self.bvh
            .traverse_bvtt_single_tree::<false>(&mut self.workspace, &mut f);
    }

    /// Every pair (leaf of this tree, leaf of `other`) whose boxes overlap.
    pub fn pairs_with(&self, other: &Self, mut f: impl FnMut(u32, u32)) {
        if self.leaves == 0 || other.leaves == 0 {
            return;
        }
        for (a, b) in self.bvh.leaf_pairs(&other.bvh, |x, y| x.intersects(y)) {
            f(a, b);
        }
    }

    /// Every leaf whose box overlaps `aabb`.
    pub fn query(&self, aabb: &Aabb, mut f: impl FnMut(u32)) {
        if self.leaves == 0 {
            return;
        }
        for leaf in self.bvh.intersect_aabb(aabb) {
            f(leaf);
        }
    }
}
