//! How near the contact plane behind the knee the skin over it lies, as a height field
//! over the plane, so that the muscles under that skin keep beneath it.
//!
//! Each side's muscles keep a few millimetres from the plane, but in a deep flexion the
//! skin over them lies where its bone carries it, 12–32 mm off the plane, and the
//! bellies pressed toward the plane came out through it (the phantom at 117°: the
//! gastrocnemii and semitendinosus, 3–19 cm behind the knee axis; 1 821 vertices more
//! than 1 mm out). The height field holds, in 1 cm cells over the plane (behind the
//! axis, and along it), how near to the plane each side's skin that faces the plane
//! comes where its bone alone carries it (the crease draws it no further from the plane
//! than that, see [`super::crease`]). A muscle vertex the plane watches keeps that far
//! from the plane over its cell, and the fat's layers more, by the same rounds of ring
//! shifts as keep it off the plane itself ([`super::bone_keep_out`]). At the deepest
//! angles (134°) the skin's rigid place lies past the plane and the cover asks nothing
//! beyond the plane's own margin: there the muscles have no room (docs/tissue-history.md).

use glam::{Quat, Vec3};

use super::crease::Rigid;
use super::knee_fold::{Contact, KneeFold};

/// Cell size (m) of the height field.
const CELL_M: f32 = 0.01;
/// Cells behind the knee axis (from the axis).
const BEHIND: usize = 32;
/// Cells along the axis (centred on the knee point).
const ALONG: usize = 40;
/// Least cosine between the skin's outward direction and the way to the plane for it to
/// count (60°).
const FACING: f32 = 0.5;

/// How near to the contact plane each side's skin lies, over the plane behind the knee
/// (see the module's documentation).
#[derive(Debug, Clone)]
pub(crate) struct SkinCover {
    /// The plane's point on the knee axis (world)...
    point: Vec3,
    /// ...its direction behind the knee, and along the axis: the cells' two directions.
    behind: Vec3,
    along: Vec3,
    /// Skin's least distance from the plane per cell, thigh side then calf side
    /// (infinite where no skin lies over the cell).
    cells: Vec<f32>,
    /// Added to the skin's distance: the fat's layers under it.
    depth: f32,
}

impl SkinCover {
    /// The height field of the skin vertices `skin` (rest position, outward direction of
    /// any length, thigh side or not) carried rigidly by their bones ([`Rigid`]) at knee
    /// `fold` with the thigh at pose `thigh`; `contact` is the plane (world), `depth` (m)
    /// how far under the skin muscles keep.
    pub(crate) fn new(
        skin: &[(Vec3, Vec3, bool)],
        fold: &KneeFold,
        contact: &Contact,
        (tq, tt): (Quat, Vec3),
        depth: f32,
    ) -> Self {
        let rigid = Rigid::new(fold, (tq, tt));
        let along = contact.normal.cross(contact.behind).normalize_or_zero();
        let mut cover = Self {
            point: contact.point,
            behind: contact.behind,
            along,
            cells: vec![f32::INFINITY; 2 * BEHIND * ALONG],
            depth,
        };
        for &(r, out, thigh) in skin {
            // Skin that does not face the plane (all of it while the knee is nearly
            // straight) lies over no muscle that the plane presses on.
            let out = rigid.turn(out.normalize_or_zero(), thigh);
            if -contact.off_side(out, thigh) < FACING {
                continue;
            }
            let p = rigid.place(r, thigh);
            let (_, d) = contact.locate(p, thigh);
            if let Some(i) = cover.cell(p, thigh) {
                let c = &mut cover.cells[i];
                *c = c.min(d);
            }
        }
        cover
    }

    /// Index of the cell `p` lies over, on the side `thigh` names; None outside the
    /// field.
    fn cell(&self, p: Vec3, thigh: bool) -> Option<usize> {
        let rel = p - self.point;
        let b = (rel.dot(self.behind) / CELL_M).floor();
        let a = (rel.dot(self.along) / CELL_M + ALONG as f32 * 0.5).floor();
        if !(b >= 0.0 && b < BEHIND as f32 && a >= 0.0 && a < ALONG as f32) {
            return None;
        }
        let side = if thigh { 0 } else { BEHIND * ALONG };
        Some(side + b as usize * ALONG + a as usize)
    }

    /// How far (m) from the plane a muscle vertex at `p` on the side `thigh` names keeps
    /// to lie under the skin; negative infinity where no skin lies over it.
    pub(crate) fn floor(&self, p: Vec3, thigh: bool) -> f32 {
        match self.cell(p, thigh).map(|i| self.cells[i]) {
            Some(d) if d.is_finite() => d + self.depth,
            _ => f32::NEG_INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::KneeAxis;

    #[test]
    fn the_floor_is_the_nearest_skin_facing_the_plane_per_cell_and_side() {
        let knee = KneeAxis {
            point: Vec3::new(0.01, -0.02, 0.45),
            axis: Vec3::new(-1.0, 0.05, 0.02).normalize(),
            condyle_radius: 0.025,
        };
        let theta = 2.0;
        let fold = KneeFold::new(&knee, theta);
        let shank = Quat::from_axis_angle(fold.axis, theta);
        // The thigh turned and moved: the plane and the skin in the world.
        let (tq, tt) = (
            Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.2).normalize(), 0.4),
            Vec3::new(0.1, -0.2, 0.3),
        );
        let rest_plane = fold.contact(0.003);
        let c = Contact {
            point: tq * rest_plane.point + tt,
            normal: tq * rest_plane.normal,
            behind: tq * rest_plane.behind,
            ..rest_plane
        };
        let along = c.normal.cross(c.behind).normalize();
        let at = |b: f32, a: f32, h: f32| c.point + c.behind * b + along * a + c.normal * h;
        // Rest position and outward direction of skin that lies at `p`, facing `out`
        // (world), on the thigh or the calf.
        let thigh = |p: Vec3, out: Vec3| (tq.inverse() * (p - tt), tq.inverse() * out, true);
        let calf = |p: Vec3, out: Vec3| {
            let r = tq.inverse() * (p - tt) - fold.point;
            (
                fold.point + shank.inverse() * r,
                shank.inverse() * (tq.inverse() * out),
                false,
            )
        };
        // Toward the plane from the thigh, turned `deg` degrees about the axis.
        let tilted = |deg: f32| Quat::from_axis_angle(along, deg.to_radians()) * -c.normal;
        let skin = [
            // Thigh skin 20 and 25 mm from the plane over one cell, 30 mm over the next.
            thigh(at(0.105, 0.003, 0.025), -c.normal),
            thigh(at(0.108, 0.006, 0.020), tilted(50.0)),
            thigh(at(0.115, 0.003, 0.030), -c.normal),
            // Calf skin 15 mm from it.
            calf(at(0.105, 0.003, -0.015), c.normal),
            // Skin turned 70° from the plane, or away from it, holds nothing.
            thigh(at(0.155, 0.003, 0.010), tilted(70.0)),
            thigh(at(0.165, 0.003, 0.010), c.normal),
        ];
        let cover = SkinCover::new(&skin, &fold, &c, (tq, tt), 0.004);
        let floor = |b: f32, a: f32, h: f32, thigh: bool| cover.floor(at(b, a, h), thigh);
        // The nearest facing skin over the cell, and the depth under it, whatever the
        // height of the point asked about.
        assert!((floor(0.101, 0.001, 0.06, true) - 0.024).abs() < 1e-5);
        assert!((floor(0.109, 0.009, 0.0, true) - 0.024).abs() < 1e-5);
        assert!((floor(0.111, 0.001, 0.05, true) - 0.034).abs() < 1e-5);
        assert!((floor(0.101, 0.001, -0.05, false) - 0.019).abs() < 1e-5);
        // Nothing over cells whose skin does not face the plane, without skin, in front
        // of the axis, beyond the field, or with the other side's skin only.
        for (b, a, thigh) in [
            (0.155, 0.003, true),
            (0.165, 0.003, true),
            (0.125, 0.003, true),
            (-0.005, 0.003, true),
            (0.105, 0.25, true),
            (0.115, 0.003, false),
        ] {
            assert_eq!(
                floor(b, a, 0.02, thigh),
                f32::NEG_INFINITY,
                "{b} {a} {thigh}"
            );
        }
        // A point that is not a number lies over no cell.
        assert_eq!(cover.floor(Vec3::NAN, true), f32::NEG_INFINITY);
    }
}
