//! What happens to soft tissue about the knee: the fold field that carries it from the
//! thigh's motion to the shank's without ever turning an element inside out, and the
//! contact plane that keeps the back of the thigh and the calf apart.
//!
//! The paper moves fat by elastic relaxation alone and reports "heavy caves" behind the
//! knee and fat that breaks at large angles. Any rotation field `p ↦ R(θ·w(p)) p` about
//! the knee axis has Jacobian determinant `1 + θ ∂w/∂ψ`, where `ψ` is the angle about the
//! axis. A weight that blends by height alone (skinning) has `∂w/∂ψ` growing with the
//! distance behind the axis, so at deep flexion the posterior tissue folds through
//! itself. Here the weight is angular instead: it ramps from thigh (0) to shank (1)
//! over a front sector (stretching, determinant > 1) and back over a posterior sector
//! (compressing) whose width grows with the knee angle so the determinant stays at or
//! above [`MIN_JACOBIAN`]. Near the axis line, where an angle means nothing, and far from
//! the knee, where tissue must move rigidly with its bone, the weight turns into a
//! height blend, whose angular derivative vanishes there. The map is therefore
//! orientation-preserving everywhere: it is the tissue's always-valid fallback shape.

use crate::par::*;
use glam::{Quat, Vec3};

use crate::body::KneeAxis;
use crate::lattice::{hex_volume_f32, hex_volume_points};

/// Smallest Jacobian determinant the fold allows (volume may shrink to this share), up to
/// a knee angle of about 154°; beyond, the two ramps would overlap and the back ramp
/// stops widening (the validity guard still keeps the fat valid).
pub const MIN_JACOBIAN: f32 = 0.3;

/// Share of each ramp spent easing in and out (the rest is linear).
const EASE: f32 = 0.2;
/// Half-widths (rad) of the front and back ramps at small angles.
const FRONT_HALF: f32 = 0.70; // 40°
const BACK_HALF: f32 = 1.05; // 60°
/// In-plane radius (m) within which the angular weight gives way to the height blend.
const AXIS_RADIUS: f32 = 0.02;
/// In-plane radii (m) between which the angular weight gives way to rigid bone motion.
/// The height blend there is only orientation-preserving where no tissue lies at the
/// knee's own height, which holds for a limb less than `FAR_START` deep about its knee.
const FAR_START: f32 = 0.14;
const FAR_END: f32 = 0.28;
/// Half-width (m) of the height blend used near the axis and far from it.
const HEIGHT_HALF: f32 = 0.04;

fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A 0→1 ramp over `t ∈ [0, 1]`, linear in the middle with eased ends; slope at most
/// `1 / (1 − EASE)`.
fn ramp(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    let k = 1.0 / (2.0 * EASE * (1.0 - EASE));
    if t < EASE {
        k * t * t
    } else if t > 1.0 - EASE {
        1.0 - k * (1.0 - t) * (1.0 - t)
    } else {
        (t - 0.5 * EASE) / (1.0 - EASE)
    }
}

/// A rest point in the knee's frame, with the parts of its fold weight that do not
/// depend on the knee angle.
#[derive(Debug, Clone, Copy, Default)]
struct FoldPoint {
    /// Coordinates along the axis, `up` and `front`, from the axis point.
    along: f32,
    z: f32,
    y: f32,
    /// Angle about the axis from `up` toward `front`.
    psi: f32,
    angular_share: f32,
    by_height: f32,
}

impl FoldPoint {
    fn new(f: &KneeFold, p: Vec3) -> Self {
        let d = p - f.point;
        let (z, y) = (d.dot(f.up), d.dot(f.front));
        let r = (z * z + y * y).sqrt();
        let angular_share = smoothstep(r / AXIS_RADIUS)
            * (1.0 - smoothstep((r - FAR_START) / (FAR_END - FAR_START)));
        Self {
            along: d.dot(f.axis),
            z,
            y,
            psi: if angular_share > 0.0 { y.atan2(z) } else { 0.0 },
            angular_share,
            by_height: smoothstep((HEIGHT_HALF - z) / (2.0 * HEIGHT_HALF)),
        }
    }

    /// The point turned about the axis by the angle of `(sin, cos)`, in the rest frame.
    fn turned(&self, f: &KneeFold, (s, c): (f32, f32)) -> Vec3 {
        f.point
            + f.axis * self.along
            + f.up * (self.z * c - self.y * s)
            + f.front * (self.z * s + self.y * c)
    }
}

/// The fold field at one knee angle, in the thigh's rest frame.
#[derive(Debug, Clone, Copy)]
pub struct KneeFold {
    /// A point on the knee axis (rest).
    pub point: Vec3,
    /// Unit flexion axis.
    pub axis: Vec3,
    /// Unit superior direction perpendicular to the axis.
    pub up: Vec3,
    /// Unit anterior direction, `axis × up`.
    pub front: Vec3,
    /// Knee angle (rad, positive flexes).
    pub theta: f32,
    front_half: f32,
    back_half: f32,
}

impl KneeFold {
    /// The fold of a knee at angle `theta` (rad).
    pub fn new(knee: &KneeAxis, theta: f32) -> Self {
        let axis = knee.axis.normalize_or(Vec3::X);
        let up = (Vec3::Z - axis * axis.z).normalize_or(Vec3::Z);
        let front = axis.cross(up);
        // Widest slope of a ramp of half-width h is 1 / (2 h (1 − EASE)); the determinant
        // 1 − |θ| · slope stays at MIN_JACOBIAN when h = |θ| / (2 (1 − EASE)(1 − MIN)).
        let need = |t: f32| t.max(0.0) / (2.0 * (1.0 - EASE) * (1.0 - MIN_JACOBIAN));
        let back_half = BACK_HALF.max(need(theta));
        let front_half = FRONT_HALF.max(need(-theta));
        // The two ramps must not overlap: a thigh core and a shank core remain.
        let room = std::f32::consts::PI - 0.05;
        let (front_half, back_half) = if front_half + back_half > room {
            if theta >= 0.0 {
                (
                    front_half.min(FRONT_HALF),
                    room - front_half.min(FRONT_HALF),
                )
            } else {
                (room - back_half.min(BACK_HALF), back_half.min(BACK_HALF))
            }
        } else {
            (front_half, back_half)
        };
        Self {
            point: knee.point,
            axis,
            up,
            front,
            theta,
            front_half,
            back_half,
        }
    }

    /// Half-width (rad) of the posterior ramp at this angle.
    pub fn back_half_width(&self) -> f32 {
        self.back_half
    }

    /// Angular weight: `ψ` from `up` toward `front`, 0 on the thigh side, 1 on the shank's.
    fn angular(&self, psi: f32) -> f32 {
        use std::f32::consts::{FRAC_PI_2, PI, TAU};
        let a0 = FRAC_PI_2 - self.front_half;
        let a1 = FRAC_PI_2 + self.front_half;
        let b0 = 1.5 * PI - self.back_half;
        let b1 = 1.5 * PI + self.back_half;
        let mut p = psi.rem_euclid(TAU);
        if p < a0 {
            p += TAU;
        }
        if p <= a1 {
            ramp((p - a0) / (a1 - a0))
        } else if p < b0 {
            1.0
        } else if p <= b1 {
            1.0 - ramp((p - b0) / (b1 - b0))
        } else {
            0.0
        }
    }

    /// Share of the shank's rotation taken by tissue at rest position `p`.
    pub fn weight(&self, p: Vec3) -> f32 {
        self.weight_of(&FoldPoint::new(self, p))
    }

    /// [`Self::weight`] of a point whose angle-free parts are known.
    fn weight_of(&self, f: &FoldPoint) -> f32 {
        if f.angular_share <= 0.0 {
            return f.by_height;
        }
        let by_angle = self.angular(f.psi);
        f.angular_share * by_angle + (1.0 - f.angular_share) * f.by_height
    }

    /// The rotation tissue at rest position `p` takes.
    pub fn rotation(&self, p: Vec3) -> Quat {
        Quat::from_axis_angle(self.axis, self.theta * self.weight(p))
    }

    /// Where tissue at rest position `p` goes (thigh rest frame).
    pub fn map(&self, p: Vec3) -> Vec3 {
        self.point + self.rotation(p) * (p - self.point)
    }

    /// How much the fold rules tissue at rest position `p` rather than its bone's rigid
    /// motion: `sqrt(4 w (1 − w))`, 1 where the weight is ½, 0 where it is 0 or 1.
    pub fn nearness(&self, p: Vec3) -> f32 {
        let w = self.weight(p);
        (4.0 * w * (1.0 - w)).clamp(0.0, 1.0).sqrt()
    }

    /// True for rest positions behind the knee axis (where the contact plane acts).
    pub fn is_posterior(&self, p: Vec3) -> bool {
        (p - self.point).dot(self.front) < 0.0
    }

    /// The contact plane at this angle, through the axis and bisecting the knee angle.
    pub fn contact(&self, margin: f32) -> Contact {
        let half = Quat::from_axis_angle(self.axis, 0.5 * self.theta);
        Contact {
            point: self.point,
            normal: half * self.up,
            behind: half * -self.front,
            muscle_margin: margin,
        }
    }
}

/// Rounds of repair for elements the fold turns over (see [`fold_hexes`]).
const SMOOTHING_ROUNDS: usize = 6;

/// Where the fold can bend tissue: within [`FAR_END`] of the knee axis or within
/// [`HEIGHT_HALF`] of its level. Elsewhere the weight is exactly 0 (thigh) or 1 (shank)
/// at every knee angle, so that tissue moves rigidly with its bone and needs no
/// trigonometry and no check.
#[derive(Debug, Clone)]
pub struct FoldZone {
    /// Per vertex: [`ZONE`], or its fixed weight 0 or 1.
    kind: Vec<u8>,
    /// Per vertex, its place in the knee's frame and the angle-free parts of its weight.
    points: Vec<FoldPoint>,
    /// Elements that can bend: a corner in the zone, or corners on both bones.
    elements: Vec<u32>,
}

const THIGH: u8 = 0;
const SHANK: u8 = 1;
const ZONE: u8 = 2;

impl FoldZone {
    /// The zone of a knee for a lattice at rest.
    pub fn new(knee: &KneeAxis, rest: &[Vec3], hexes: &[[u32; 8]]) -> Self {
        let f = KneeFold::new(knee, 0.0);
        let points: Vec<FoldPoint> = rest.iter().map(|&p| FoldPoint::new(&f, p)).collect();
        let kind: Vec<u8> = points
            .iter()
            .map(|fp| {
                let (z, y) = (fp.z, fp.y);
                if (z * z + y * y).sqrt() < FAR_END || z.abs() < HEIGHT_HALF {
                    ZONE
                } else if z >= HEIGHT_HALF {
                    THIGH
                } else {
                    SHANK
                }
            })
            .collect();
        // Elements with a corner in the zone, or (not seen in a lattice, whose slices are
        // closer than the zone is tall) with corners fixed to both bones.
        let elements = (0..hexes.len() as u32)
            .filter(|&e| {
                let k = hexes[e as usize].map(|v| kind[v as usize]);
                k.iter().any(|&c| c == ZONE || c != k[0])
            })
            .collect();
        Self {
            kind,
            points,
            elements,
        }
    }

    /// The weight of vertex `v` in `fold` (see [`KneeFold::weight`]).
    pub fn weight(&self, fold: &KneeFold, v: usize) -> f32 {
        match self.kind[v] {
            THIGH => 0.0,
            SHANK => 1.0,
            _ => fold.weight_of(&self.points[v]),
        }
    }

    /// Whether vertex `v` can bend (else it moves rigidly with its bone).
    pub fn contains(&self, v: usize) -> bool {
        self.kind[v] == ZONE
    }

    /// Elements that can bend (the others move rigidly with one bone).
    pub fn elements(&self) -> &[u32] {
        &self.elements
    }
}

/// A hexahedral lattice's rest shape `rest` carried by the fold and then by `frame` (the
/// thigh's pose), into `x`, with each vertex's weight into `w`. The map is
/// orientation-preserving, but a skewed hexahedron much larger than the scale on which
/// the weight varies (one reaching from near the axis to the back of the knee) can still
/// turn over between its corners. Such an element moves its corners' weights toward their
/// mean (which turns it rigidly), by the largest step that improves it and turns no
/// positive neighbour over, round after round.
pub fn fold_hexes(
    fold: &KneeFold,
    zone: &FoldZone,
    rest: &[Vec3],
    hexes: &[[u32; 8]],
    (tq, tt): (Quat, Vec3),
    x: &mut Vec<Vec3>,
    w: &mut Vec<f32>,
) {
    let shank = Quat::from_axis_angle(fold.axis, fold.theta);
    let frame = glam::Mat3::from_quat(tq);
    let place =
        |i: usize, w: f32| frame * zone.points[i].turned(fold, (fold.theta * w).sin_cos()) + tt;
    x.resize(rest.len(), Vec3::ZERO);
    w.resize(rest.len(), 0.0);
    x.par_iter_mut()
        .zip(w.par_iter_mut())
        .enumerate()
        .for_each(|(i, (xi, wi))| {
            let p = rest[i];
            (*wi, *xi) = match zone.kind[i] {
                THIGH => (0.0, frame * p + tt),
                SHANK => (1.0, frame * (fold.point + shank * (p - fold.point)) + tt),
                _ => {
                    let wt = fold.weight_of(&zone.points[i]);
                    (wt, place(i, wt))
                }
            };
        });
    let volume = |x: &[Vec3], h: &[u32; 8]| hex_volume_points(&h.map(|i| x[i as usize].as_dvec3()));
    // Screened in single precision; anything near flat is looked at again in double.
    let mut turned: Vec<usize> = zone
        .elements
        .par_iter()
        .map(|&e| e as usize)
        .filter(|&e| hex_volume_f32(x, &hexes[e]) <= 1e-12 && volume(x, &hexes[e]) <= 0.0)
        .collect();
    if turned.is_empty() {
        return;
    }
    // Vertex → elements, only when something needs fixing (rare).
    let mut of_vertex: Vec<Vec<u32>> = vec![Vec::new(); rest.len()];
    for (e, h) in hexes.iter().enumerate() {
        for &v in h {
            of_vertex[v as usize].push(e as u32);
        }
    }
    for _ in 0..SMOOTHING_ROUNDS {
        let mut changed = false;
        for &e in &turned {
            let h = hexes[e];
            let own = volume(x, &h);
            if own > 0.0 {
                continue;
            }
            let mut touching: Vec<u32> = h
                .iter()
                .flat_map(|&v| of_vertex[v as usize].iter().copied())
                .collect();
            touching.sort_unstable();
            touching.dedup();
            let before_vol: Vec<f64> = touching
                .iter()
                .map(|&o| volume(x, &hexes[o as usize]))
                .collect();
            let mean = h.iter().map(|&i| w[i as usize]).sum::<f32>() / 8.0;
            let before = h.map(|i| (w[i as usize], x[i as usize]));
            for t in [1.0f32, 0.75, 0.5, 0.25] {
                for (k, &i) in h.iter().enumerate() {
                    let wi = before[k].0 + t * (mean - before[k].0);
                    w[i as usize] = wi;
                    x[i as usize] = place(i as usize, wi);
                }
                // Accepted if this element improves and no positive neighbour turns over.
                let ok = volume(x, &h) > own
                    && touching
                        .iter()
                        .zip(&before_vol)
                        .all(|(&o, &v0)| v0 <= 0.0 || volume(x, &hexes[o as usize]) > 0.0);
                if ok {
                    changed = true;
                    break;
                }
                for (k, &i) in h.iter().enumerate() {
                    (w[i as usize], x[i as usize]) = before[k];
                }
            }
        }
        turned.retain(|&e| volume(x, &hexes[e]) <= 0.0);
        if !changed || turned.is_empty() {
            break;
        }
    }
}

/// Contact behind the knee: the plane through the knee axis that bisects the knee angle.
/// Tissue of the thigh keeps to its side, tissue of the calf to the other, so the back
/// of the thigh and the calf press on each other there and never pass through. It acts
/// only behind the axis (in front, the two sides are far apart).
#[derive(Debug, Clone, Copy)]
pub struct Contact {
    /// Knee axis point (thigh rest frame).
    pub point: Vec3,
    /// Unit normal of the plane, toward the thigh.
    pub normal: Vec3,
    /// Unit direction in the plane pointing behind the knee.
    pub behind: Vec3,
    /// Distance (m) muscles keep from the plane.
    pub muscle_margin: f32,
}

impl Contact {
    /// Where `p` goes; `thigh` says which side it belongs to, `margin` (m) how far from
    /// the plane it stays.
    pub fn apply(&self, p: Vec3, thigh: bool, margin: f32) -> Vec3 {
        let (behind, d) = self.locate(p, thigh);
        if behind <= 0.0 {
            return p;
        }
        if d < margin {
            self.toward_side(p, thigh, margin - d)
        } else {
            p
        }
    }

    /// How far `p` lies behind the knee axis (along [`Self::behind`]) and how far from
    /// the plane on the side `thigh` names (the thigh's, or the calf's; negative past
    /// the plane).
    pub fn locate(&self, p: Vec3, thigh: bool) -> (f32, f32) {
        let rel = p - self.point;
        (rel.dot(self.behind), self.off_side(rel, thigh))
    }

    /// The part of `v` along the plane's normal that points away from the plane on the
    /// side `thigh` names.
    pub fn off_side(&self, v: Vec3, thigh: bool) -> f32 {
        let d = v.dot(self.normal);
        if thigh { d } else { -d }
    }

    /// `p` moved `by` (m) along the plane's normal, away from the plane on the side
    /// `thigh` names (toward it, where `by` is negative).
    pub fn toward_side(&self, p: Vec3, thigh: bool, by: f32) -> Vec3 {
        p + self.normal * if thigh { by } else { -by }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knee() -> KneeAxis {
        KneeAxis {
            point: Vec3::new(0.01, -0.02, 0.45),
            // Flexion moves the ankle posteriorly (−y): axis × up must point anterior.
            axis: Vec3::new(-1.0, 0.05, 0.02).normalize(),
            condyle_radius: 0.025,
        }
    }

    /// Jacobian determinant of the map at `p` by central differences.
    fn jacobian(f: &KneeFold, p: Vec3) -> f32 {
        let h = 1e-4;
        let col = |e: Vec3| (f.map(p + e * h) - f.map(p - e * h)) / (2.0 * h);
        let (a, b, c) = (col(Vec3::X), col(Vec3::Y), col(Vec3::Z));
        a.dot(b.cross(c))
    }

    #[test]
    fn the_fold_preserves_orientation_over_the_whole_knee_range() {
        let k = knee();
        let front = k.axis.cross(Vec3::Z).normalize();
        for deg in [-20.0f32, 0.0, 30.0, 60.0, 90.0, 120.0, 140.0] {
            let f = KneeFold::new(&k, deg.to_radians());
            let mut worst = f32::INFINITY;
            // The body at the knee lies within 12 cm of the axis front to back.
            for iz in -30..=30 {
                for iy in -19..=19 {
                    for ix in [-0.06f32, 0.0, 0.05] {
                        let p = k.point
                            + Vec3::Z * (iz as f32 * 0.011)
                            + front * (iy as f32 * 0.0063)
                            + k.axis * ix;
                        worst = worst.min(jacobian(&f, p));
                    }
                }
            }
            assert!(
                worst > 0.5 * MIN_JACOBIAN,
                "at {deg}°, Jacobian determinant {worst}"
            );
        }
    }

    #[test]
    fn outside_the_zone_the_weight_is_fixed_at_every_angle() {
        let k = knee();
        let pts: Vec<Vec3> = (-40..=40)
            .flat_map(|iz| {
                (-6..=6)
                    .map(move |iy| k.point + Vec3::new(0.01, iy as f32 * 0.02, iz as f32 * 0.01))
            })
            .collect();
        let zone = FoldZone::new(&k, &pts, &[]);
        let outside = (0..pts.len()).filter(|&i| !zone.contains(i)).count();
        assert!(
            outside > pts.len() / 4,
            "{outside} of {} outside",
            pts.len()
        );
        for deg in [-20.0f32, 0.0, 45.0, 100.0, 140.0] {
            let f = KneeFold::new(&k, deg.to_radians());
            for (i, &p) in pts.iter().enumerate() {
                if !zone.contains(i) {
                    let fixed = if zone.kind[i] == SHANK { 1.0 } else { 0.0 };
                    assert_eq!(f.weight(p), fixed, "{p} at {deg}°");
                }
            }
        }
    }

    #[test]
    fn far_tissue_moves_rigidly_with_its_bone() {
        let k = knee();
        let f = KneeFold::new(&k, 2.2);
        for y in [-0.09f32, 0.0, 0.08] {
            let above = k.point + Vec3::new(0.0, y, 0.33);
            assert!(f.map(above).distance(above) < 1e-6, "thigh point moved");
            let below = k.point + Vec3::new(0.0, y, -0.33);
            let shank = k.point + Quat::from_axis_angle(f.axis, 2.2) * (below - k.point);
            assert!(f.map(below).distance(shank) < 1e-5, "shank point off");
        }
    }

    #[test]
    fn the_back_of_the_thigh_stays_on_its_side_of_the_contact_plane() {
        let k = knee();
        for deg in [30.0f32, 90.0, 140.0] {
            let f = KneeFold::new(&k, deg.to_radians());
            let c = f.contact(0.0);
            for iz in 1..=20 {
                for depth in [0.02f32, 0.05, 0.09] {
                    let up = k.point + f.up * (iz as f32 * 0.01) - f.front * depth;
                    let down = k.point - f.up * (iz as f32 * 0.01) - f.front * depth;
                    assert!((f.map(up) - c.point).dot(c.normal) > 0.0);
                    assert!((f.map(down) - c.point).dot(c.normal) < 0.0);
                }
            }
        }
    }
}
