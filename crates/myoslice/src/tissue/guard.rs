//! The validity guard (beyond the paper, which reports fat that breaks): where the relaxed
//! fat has an element below its allowed volume, or body-surface triangles behind the
//! knee that cross, the vertices involved give back half of their way to the knee fold
//! (always valid), and the vertices around them keep at most halfway between all of
//! theirs and that share (a soft edge); what that moved is checked again, round after
//! round, and a vertex still involved after three halvings takes its place in the fold.
//! Elsewhere the relaxed shape stands.
//!
//! After the first round only what the last round moved is looked at again.

use crate::par::*;
use glam::Vec3;

use super::fat_solver::FatSolver;
use super::intersect::{Aabb, TriangleGrid, crossing_pairs_near, crossing_pairs_of_few};
use crate::lattice::hex_volume_f32 as hex_volume;

/// Queried triangles up to which a round checks them without a grid.
const FEW: usize = 64;

/// Most rounds (each moves at least one vertex further toward the fold).
const MAX_ROUNDS: usize = 64;

/// From this round on a vertex found bad goes to the fold at once, as it did before the
/// halving below: halving takes up to four rounds a vertex where one did, and the rounds
/// must end well before [`MAX_ROUNDS`].
const HALVING_ROUNDS: usize = 32;

/// A vertex found in a bad element or a crossing keeps this share of its way from the
/// fold (halved, round after round: 1, 1/2, 1/4, 1/8)...
const GIVE_BACK: f32 = 0.5;
/// ...and a vertex found bad again at or below this share takes its place in the fold.
/// (Sent to the fold at once, the crease's skin lost the muscles it had followed out:
/// more muscle vertices out through it at deep flexion, see docs/tissue-history.md.)
const LAST_SHARE: f32 = 0.2;

/// Marks vertex `i` bad, listing it the first time.
fn mark(bad: &mut [bool], list: &mut Vec<usize>, i: usize) {
    if !bad[i] {
        bad[i] = true;
        list.push(i);
    }
}

/// Reused buffers of the guard.
#[derive(Debug, Clone, Default)]
pub(crate) struct Guard {
    relaxed: Vec<Vec3>,
    share: Vec<f32>,
    bad: Vec<bool>,
    /// The vertices marked in `bad` (each once).
    bad_list: Vec<usize>,
    moved_now: Vec<bool>,
    moved_list: Vec<usize>,
    bad_el: Vec<usize>,
    boxes: Vec<Aabb>,
    query: Vec<u32>,
    live: Vec<bool>,
}

impl Guard {
    /// Whether the last run moved vertex `v` off the relaxed shape.
    pub(crate) fn moved(&self, v: usize) -> bool {
        self.share.get(v).is_some_and(|&s| s < 1.0)
    }

    /// Runs the guard on `fat` (relaxed), falling back toward `safe`; `triangles` are
    /// the guarded body-surface triangles, `surface` whether to check them. Elements may
    /// not shrink to half of `eps` × their rest volume (or half their fold volume, if
    /// that is smaller). Returns how many vertices moved off the relaxed shape.
    pub(crate) fn run(
        &mut self,
        fat: &mut FatSolver,
        safe: &[Vec3],
        triangles: &[[u32; 3]],
        eps: f32,
        surface: bool,
    ) -> usize {
        let n = fat.x.len();
        self.relaxed.clone_from(&fat.x);
        for v in [&mut self.bad, &mut self.moved_now] {
            v.clear();
            v.resize(n, false);
        }
        self.share.clear();
        self.share.resize(n, 1.0);
        self.moved_list.clear();
        self.bad_list.clear();
        let too_small = |x: &[Vec3], e: usize, fat: &FatSolver| {
            let h = &fat.hexes[e];
            let v = hex_volume(x, h);
            let full = eps * fat.rest_volume[e] as f32;
            // The fold's volume can only lower the floor: it matters below this one.
            v <= 0.5 * full && v <= 0.5 * full.min(hex_volume(safe, h)).max(0.0)
        };
        // Elements outside the relaxed region are rigid copies of the fold's (valid), to
        // within 0.1 mm (`RIGID_TOLERANCE_M2`), far less than an element's thickness.
        self.bad_el = (0..fat.hexes.len())
            .into_par_iter()
            .filter(|&e| fat.active[e] && too_small(&fat.x, e, fat))
            .collect();
        // Triangles outside the relaxed region are where the fold put them, to within
        // 0.1 mm, less than the contact gap (the tests check the whole skin for
        // crossings), so only pairs with a live triangle can cross.
        if surface {
            self.live.clear();
            self.live.extend(
                triangles
                    .iter()
                    .map(|t| t.iter().any(|&i| fat.free[i as usize])),
            );
        }
        for round in 0..MAX_ROUNDS {
            if round > 0 {
                // Only elements touching a vertex just moved can have changed.
                self.bad_el.clear();
                for &v in &self.moved_list {
                    self.bad_el.extend(fat.elements_of(v));
                }
                self.bad_el.sort_unstable();
                self.bad_el.dedup();
                let x = &fat.x;
                self.bad_el.retain(|&e| too_small(x, e, fat));
            }
            for &e in &self.bad_el {
                for &i in &fat.hexes[e] {
                    mark(&mut self.bad, &mut self.bad_list, i as usize);
                }
            }
            if surface {
                // After the first round only triangles with a vertex just moved can have
                // changed.
                if round > 0 {
                    for (l, t) in self.live.iter_mut().zip(triangles) {
                        *l = t.iter().any(|&i| self.moved_now[i as usize]);
                    }
                }
                self.query.clear();
                self.query
                    .extend((0..triangles.len() as u32).filter(|&i| self.live[i as usize]));
                // Only the queried triangles' boxes can have changed since the last round.
                if round == 0 {
                    self.boxes.clear();
                    self.boxes
                        .extend(triangles.iter().map(|t| Aabb::of(&fat.x, t)));
                } else {
                    for &i in &self.query {
                        self.boxes[i as usize] = Aabb::of(&fat.x, &triangles[i as usize]);
                    }
                }
                let live = &self.live;
                let queried = |i: u32| live[i as usize];
                // A grid pays for itself only for many queries; after the first round it
                // covers only the triangles near the queried ones.
                let pairs = if round > 0 && self.query.len() > FEW {
                    crossing_pairs_near(&fat.x, triangles, &self.boxes, &self.query, queried)
                } else if self.query.len() > FEW {
                    TriangleGrid::new(&self.boxes, triangles, &fat.x).map_or_else(Vec::new, |g| {
                        g.crossing_pairs(&fat.x, triangles, &self.boxes, &self.query, queried)
                    })
                } else {
                    crossing_pairs_of_few(&fat.x, triangles, &self.boxes, &self.query, queried)
                };
                for (a, b) in pairs {
                    for &i in triangles[a as usize].iter().chain(&triangles[b as usize]) {
                        mark(&mut self.bad, &mut self.bad_list, i as usize);
                    }
                }
            }
            // Stop when nothing is wrong, or nothing is left to give back.
            for &v in &self.moved_list {
                self.moved_now[v] = false;
            }
            self.moved_list.clear();
            self.bad_list.sort_unstable();
            for &i in &self.bad_list {
                self.bad[i] = false;
                if self.share[i] > 0.0 {
                    self.moved_now[i] = true;
                    self.moved_list.push(i);
                    self.share[i] = if round < HALVING_ROUNDS && self.share[i] > LAST_SHARE {
                        self.share[i] * GIVE_BACK
                    } else {
                        0.0
                    };
                }
            }
            self.bad_list.clear();
            if self.moved_list.is_empty() {
                break;
            }
            // The vertices around give back part of it too: a soft edge, not a step from
            // one vertex to the next.
            let n_bad = self.moved_list.len();
            for k in 0..n_bad {
                let v = self.moved_list[k];
                let cap = 0.5 * (1.0 + self.share[v]);
                for e in fat.elements_of(v) {
                    for &u in &fat.hexes[e] {
                        let u = u as usize;
                        if self.share[u] > cap {
                            self.share[u] = cap;
                            if !self.moved_now[u] {
                                self.moved_now[u] = true;
                                self.moved_list.push(u);
                            }
                        }
                    }
                }
            }
            for &i in &self.moved_list {
                fat.x[i] = safe[i] + (self.relaxed[i] - safe[i]) * self.share[i];
            }
            if round + 1 == MAX_ROUNDS {
                // Out of rounds (not seen in practice): whatever was touched takes the fold.
                for (i, sh) in self.share.iter_mut().enumerate() {
                    if *sh < 1.0 {
                        *sh = 0.0;
                        fat.x[i] = safe[i];
                    }
                }
            }
        }
        self.share.iter().filter(|&&s| s < 1.0).count()
    }
}
