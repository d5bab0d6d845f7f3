//! The knee axis: medio-lateral, through the centres of the femoral condyles.

use glam::{DVec2, DVec3, Vec3};

use crate::error::{Error, Result};
use crate::lattice::BoneMesh;

/// The knee's hinge: a point on the axis and the unit axis, oriented so that a positive
/// rotation of the shank about it is flexion (the ankle moves posteriorly).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KneeAxis {
    /// A point on the axis (world, m, rest pose).
    pub point: Vec3,
    /// Unit axis; positive rotation flexes.
    pub axis: Vec3,
    /// Radius (m) of the circle fitted to the posterior-distal condyle profile.
    pub condyle_radius: f32,
}

/// Finds the flexion axis of a femur: medio-lateral (the body x axis), through the centre
/// of the circle fitted to the posterior-inferior profile of the condyles in the sagittal
/// plane (the flexion facet centre), midway between the medial and lateral condyles.
pub fn knee_axis(femur: &BoneMesh) -> Result<KneeAxis> {
    let v = &femur.mesh.vertices;
    let z_min = v.iter().map(|p| p.z).fold(f32::INFINITY, f32::min);
    let distal: Vec<DVec3> = v
        .iter()
        .filter(|p| p.z < z_min + 0.045)
        .map(|p| p.as_dvec3())
        .collect();
    if distal.len() < 20 {
        return Err(Error::Build(
            "femur has too few distal vertices to place the knee axis".into(),
        ));
    }
    let x_min = distal.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let x_max = distal.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
    // Sagittal silhouette of the posterior-inferior quadrant: the extreme point along
    // each direction from posterior (-y) round to inferior (-z).
    let mut profile: Vec<DVec2> = Vec::new();
    for k in 0..=18 {
        let phi = std::f64::consts::PI * (1.0 + 0.5 * k as f64 / 18.0); // 180..270 deg
        let d = DVec2::new(phi.cos(), phi.sin()); // (y, z)
        if let Some(p) = distal
            .iter()
            .map(|p| DVec2::new(p.y, p.z))
            .max_by(|a, b| a.dot(d).total_cmp(&b.dot(d)))
        {
            profile.push(p);
        }
    }
    let (c, r) = fit_circle(&profile)
        .ok_or_else(|| Error::Build("cannot fit the femoral condyle profile".into()))?;
    if !(0.008..0.06).contains(&r) {
        return Err(Error::Build(format!(
            "femoral condyle radius {:.1} mm is implausible; is the femur complete at the knee?",
            r * 1e3
        )));
    }
    // Flexion turns the shank so the ankle (below the knee) moves posteriorly (-y):
    // for a rotation about +x the velocity of a point below is (0, +|z|, 0) (anterior),
    // so the flexion axis is -x.
    Ok(KneeAxis {
        point: DVec3::new(0.5 * (x_min + x_max), c.x, c.y).as_vec3(),
        axis: Vec3::NEG_X,
        condyle_radius: r as f32,
    })
}

/// Least-squares (Kasa) circle through 2-D points: centre and radius.
fn fit_circle(p: &[DVec2]) -> Option<(DVec2, f64)> {
    if p.len() < 3 {
        return None;
    }
    let n = p.len() as f64;
    let m = p.iter().copied().sum::<DVec2>() / n;
    let (mut suu, mut svv, mut suv, mut suuu, mut svvv, mut suvv, mut svuu) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for q in p {
        let (u, v) = (q.x - m.x, q.y - m.y);
        suu += u * u;
        svv += v * v;
        suv += u * v;
        suuu += u * u * u;
        svvv += v * v * v;
        suvv += u * v * v;
        svuu += v * u * u;
    }
    let det = suu * svv - suv * suv;
    if det.abs() < 1e-18 {
        return None;
    }
    let b1 = 0.5 * (suuu + suvv);
    let b2 = 0.5 * (svvv + svuu);
    let uc = (b1 * svv - b2 * suv) / det;
    let vc = (suu * b2 - suv * b1) / det;
    let r = (uc * uc + vc * vc + (suu + svv) / n).sqrt();
    Some((DVec2::new(uc + m.x, vc + m.y), r))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circle_is_recovered() {
        let pts: Vec<DVec2> = (0..10)
            .map(|k| {
                let a = 3.2 + 0.15 * k as f64;
                DVec2::new(1.0 + 0.02 * a.cos(), -2.0 + 0.02 * a.sin())
            })
            .collect();
        let (c, r) = fit_circle(&pts).unwrap();
        assert!((c - DVec2::new(1.0, -2.0)).length() < 1e-9 && (r - 0.02).abs() < 1e-9);
    }
}
