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

use glam::{Quat, Vec3};

use crate::body::KneeAxis;
use crate::lattice::hex_volume_points;

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
        let d = p - self.point;
        let (z, y) = (d.dot(self.up), d.dot(self.front));
        let r = (z * z + y * y).sqrt();
        let by_height = smoothstep((HEIGHT_HALF - z) / (2.0 * HEIGHT_HALF));
        let angular_share = smoothstep(r / AXIS_RADIUS)
            * (1.0 - smoothstep((r - FAR_START) / (FAR_END - FAR_START)));
        if angular_share <= 0.0 {
            return by_height;
        }
        let by_angle = self.angular(y.atan2(z));
        angular_share * by_angle + (1.0 - angular_share) * by_height
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

/// A hexahedral lattice's rest shape `rest` carried by the fold (thigh rest frame). The
/// map is orientation-preserving, but a skewed hexahedron much larger than the scale on
/// which the weight varies (one reaching from near the axis to the back of the knee)
/// can still turn over between its corners. Such an element moves its corners' weights
/// toward their mean (which turns it rigidly), by the largest step that improves it and
/// turns no positive neighbour over, round after round. Returns the positions and each
/// vertex's weight.
pub fn fold_hexes(fold: &KneeFold, rest: &[Vec3], hexes: &[[u32; 8]]) -> (Vec<Vec3>, Vec<f32>) {
    let mut w: Vec<f32> = rest.iter().map(|&p| fold.weight(p)).collect();
    let place = |p: Vec3, w: f32| {
        fold.point + Quat::from_axis_angle(fold.axis, fold.theta * w) * (p - fold.point)
    };
    let mut x: Vec<Vec3> = rest.iter().zip(&w).map(|(&p, &w)| place(p, w)).collect();
    let volume = |x: &[Vec3], h: &[u32; 8]| hex_volume_points(&h.map(|i| x[i as usize].as_dvec3()));
    let mut turned: Vec<usize> = (0..hexes.len())
        .filter(|&e| volume(&x, &hexes[e]) <= 0.0)
        .collect();
    if turned.is_empty() {
        return (x, w);
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
            let own = volume(&x, &h);
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
                .map(|&o| volume(&x, &hexes[o as usize]))
                .collect();
            let mean = h.iter().map(|&i| w[i as usize]).sum::<f32>() / 8.0;
            let before = h.map(|i| (w[i as usize], x[i as usize]));
            for t in [1.0f32, 0.75, 0.5, 0.25] {
                for (k, &i) in h.iter().enumerate() {
                    let wi = before[k].0 + t * (mean - before[k].0);
                    w[i as usize] = wi;
                    x[i as usize] = place(rest[i as usize], wi);
                }
                // Accepted if this element improves and no positive neighbour turns over.
                let ok = volume(&x, &h) > own
                    && touching
                        .iter()
                        .zip(&before_vol)
                        .all(|(&o, &v0)| v0 <= 0.0 || volume(&x, &hexes[o as usize]) > 0.0);
                if ok {
                    changed = true;
                    break;
                }
                for (k, &i) in h.iter().enumerate() {
                    (w[i as usize], x[i as usize]) = before[k];
                }
            }
        }
        turned.retain(|&e| volume(&x, &hexes[e]) <= 0.0);
        if !changed || turned.is_empty() {
            break;
        }
    }
    (x, w)
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
        let rel = p - self.point;
        if rel.dot(self.behind) <= 0.0 {
            return p;
        }
        let s = if thigh { 1.0 } else { -1.0 };
        let d = rel.dot(self.normal) * s;
        if d < margin {
            p + self.normal * (s * (margin - d))
        } else {
            p
        }
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
