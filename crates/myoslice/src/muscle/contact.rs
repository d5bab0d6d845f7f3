//! Muscles pressing on one another (beyond the paper): each chain point keeps its
//! distance from the neighbouring muscles' centre lines, so that a muscle pulled straight
//! by its own tension slides along its neighbours instead of through them.
//!
//! The paper's chains pass through each other freely: a contracting sartorius or
//! semimembranosus cuts across the muscles beside it, and the cross-sections riding on it
//! follow. A belly's chain point and the nearest belly segment of a neighbouring chain
//! keep at least the distance they had at rest, or the sum of the two muscles' radii
//! where they were further apart, grown with the muscles' bulge as they shorten; the
//! correction is a position projection after each step, shared by inverse mass, with the
//! approaching velocity removed (an inelastic contact: fascia, not a spring). Tendons,
//! thin and stiff, take no part (their closely spaced points, pushed, drove a chain's
//! step unstable).

use glam::Vec3;

use super::MuscleUnit;
use crate::geometry::closest_on_polyline;
use crate::lattice::MuscleLattice;

/// Pairs are kept for chain points within this distance (m) of touching a neighbour at
/// rest (by their radii): nearer muscles may come into contact as they bulge.
const PAIR_MARGIN_M: f32 = 0.004;

/// A chain point further than this (m) from every ring centre of its muscle lies on
/// tendon and gets [`TENDON_RADIUS_M`].
const RING_REACH_M: f32 = 0.012;

/// Radius (m) of a tendon's chain point.
const TENDON_RADIUS_M: f32 = 0.003;

/// How many segments either side of its rest neighbour a pair looks for the nearest one.
const SEGMENT_WINDOW: usize = 3;

/// Projection sweeps per step.
const SWEEPS: usize = 2;

/// A chain point of one muscle facing another muscle's chain.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pair {
    /// The point's muscle and index on its chain.
    a: u32,
    i: u32,
    /// The other muscle, and its segment nearest the point at rest.
    b: u32,
    seg: u32,
    /// Least distance (m) kept at rest between the point and the other centre line.
    gap: f32,
}

/// The chain-to-chain contacts of a set of muscles, found at rest.
///
/// ```
/// use myoslice::muscle::ChainContact;
/// let none = ChainContact::default();
/// assert_eq!(none.pairs(), 0);
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ChainContact {
    pairs: Vec<Pair>,
}

/// Radius (m) of each chain point of a muscle: the mean radius of its nearest ring.
fn point_radii(chain: &[Vec3], lattice: &MuscleLattice) -> Vec<f32> {
    let mesh = &lattice.mesh;
    let n = mesh.ring_len() as u32;
    let rings: Vec<(Vec3, f32)> = mesh
        .rings
        .iter()
        .map(|r| {
            let c = mesh.vertices[r.centre as usize];
            let sum: f32 = (r.first..r.first + n)
                .map(|v| mesh.vertices[v as usize].distance(c))
                .sum();
            (c, sum / n.max(1) as f32)
        })
        .collect();
    chain
        .iter()
        .map(|p| {
            let near = rings
                .iter()
                .map(|(c, r)| (c.distance(*p), *r))
                .fold((f32::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a });
            if near.0 <= RING_REACH_M {
                near.1
            } else {
                TENDON_RADIUS_M
            }
        })
        .collect()
}

impl ChainContact {
    /// The contacts of `muscles` (their chains at rest), whose cross-sections are the
    /// rings of `lattices` (indexed by [`MuscleUnit::lattice_index`]).
    pub fn new(muscles: &[MuscleUnit], lattices: &[MuscleLattice]) -> Self {
        let radii: Vec<Vec<f32>> = muscles
            .iter()
            .map(|m| match lattices.get(m.lattice_index) {
                Some(l) => point_radii(&m.chain.x, l),
                None => vec![TENDON_RADIUS_M; m.chain.len()],
            })
            .collect();
        let mut pairs = Vec::new();
        for (a, ma) in muscles.iter().enumerate() {
            for i in 1..ma.chain.len().saturating_sub(1) {
                // Tendons are thin and stiff: only the bellies press on one another.
                let belly = !ma.chain.tendon[i - 1] || !ma.chain.tendon[i];
                if ma.chain.mass[i] <= 0.0 || !belly {
                    continue;
                }
                let p = ma.chain.x[i];
                for (b, mb) in muscles.iter().enumerate() {
                    let nb = mb.chain.len();
                    if b == a || nb < 2 {
                        continue;
                    }
                    let Some((seg, t, q)) =
                        closest_on_polyline(&mb.chain.x, 0..nb - 1, |s| !mb.chain.tendon[s], p)
                    else {
                        continue;
                    };
                    let rb = radii[b][seg] + (radii[b][seg + 1] - radii[b][seg]) * t;
                    let touch = radii[a][i] + rb;
                    let d = p.distance(q);
                    if d < touch + PAIR_MARGIN_M {
                        pairs.push(Pair {
                            a: a as u32,
                            i: i as u32,
                            b: b as u32,
                            seg: seg as u32,
                            gap: d.min(touch),
                        });
                    }
                }
            }
        }
        Self { pairs }
    }

    /// How many point–chain pairs are watched.
    pub fn pairs(&self) -> usize {
        self.pairs.len()
    }

    /// Pushes apart the chain points of `muscles` that came closer to a neighbour than
    /// they may. `moving[m]` says whether muscle `m`'s chain moves by its own dynamics
    /// (others are carried by their bone and only push). Returns whether any point
    /// moved.
    pub fn project(&self, muscles: &mut [MuscleUnit], moving: &[bool]) -> bool {
        let bulge: Vec<f32> = muscles
            .iter()
            .map(|m| {
                let c = &m.chain;
                (c.belly_rest / c.belly_length().max(1e-6)).sqrt().max(1.0)
            })
            .collect();
        let mut any = false;
        for _ in 0..SWEEPS {
            for pair in &self.pairs {
                let (a, b) = (pair.a as usize, pair.b as usize);
                if !(moving[a] || moving[b]) {
                    continue;
                }
                let i = pair.i as usize;
                let (ca, cb) = pair_mut(muscles, a, b);
                let (ca, cb) = (&mut ca.chain, &mut cb.chain);
                let nb = cb.x.len();
                let lo = (pair.seg as usize).saturating_sub(SEGMENT_WINDOW);
                let hi = (pair.seg as usize + SEGMENT_WINDOW + 1).min(nb - 1);
                let p = ca.x[i];
                let Some((s, t, q)) = closest_on_polyline(&cb.x, lo..hi, |s| !cb.tendon[s], p)
                else {
                    continue;
                };
                let gap = pair.gap * 0.5 * (bulge[a] + bulge[b]);
                let d = p.distance(q);
                if d >= gap || d < 1e-6 {
                    continue;
                }
                let inv = |c: &super::MuscleChain, k: usize, moves: bool| {
                    if moves && c.mass[k] > 0.0 {
                        1.0 / c.mass[k]
                    } else {
                        0.0
                    }
                };
                let wa = inv(ca, i, moving[a]);
                let (w0, w1) = (inv(cb, s, moving[b]), inv(cb, s + 1, moving[b]));
                let (u0, u1) = (1.0 - t, t);
                let w = wa + u0 * u0 * w0 + u1 * u1 * w1;
                if w <= 0.0 {
                    continue;
                }
                let n = (p - q) / d;
                let lambda = (gap - d) / w;
                any = true;
                ca.x[i] += n * (lambda * wa);
                stop_approach(&mut ca.v[i], n);
                for (k, u, wk) in [(s, u0, w0), (s + 1, u1, w1)] {
                    if wk > 0.0 {
                        cb.x[k] -= n * (lambda * u * wk);
                        stop_approach(&mut cb.v[k], -n);
                    }
                }
            }
        }
        any
    }
}

/// Removes the part of `v` that moves against `n` (toward the other muscle).
fn stop_approach(v: &mut Vec3, n: Vec3) {
    let vn = v.dot(n);
    if vn < 0.0 {
        *v -= n * vn;
    }
}

/// Two distinct muscles, mutably.
fn pair_mut(m: &mut [MuscleUnit], a: usize, b: usize) -> (&mut MuscleUnit, &mut MuscleUnit) {
    if a < b {
        let (lo, hi) = m.split_at_mut(b);
        (&mut lo[a], &mut hi[0])
    } else {
        let (lo, hi) = m.split_at_mut(a);
        (&mut hi[0], &mut lo[b])
    }
}
