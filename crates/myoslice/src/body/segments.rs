//! Segment inertia from Dempster's table (as tabulated by Winter, Table 4.1), scaled by
//! body mass and height — not from bone volume.

/// Mass, centre of mass and inertia of one segment along its long axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentInertia {
    /// Mass (kg).
    pub mass: f64,
    /// Segment length (m): proximal to distal joint.
    pub length: f64,
    /// Distance of the centre of mass from the proximal joint (m).
    pub com_from_proximal: f64,
    /// Moment of inertia about the centre of mass, transverse axes (kg m²).
    pub inertia_transverse: f64,
    /// Moment of inertia about the long axis (kg m²).
    pub inertia_long: f64,
}

impl SegmentInertia {
    /// Moment of inertia about a transverse axis through the proximal joint (kg m²).
    pub fn inertia_about_proximal(&self) -> f64 {
        self.inertia_transverse + self.mass * self.com_from_proximal.powi(2)
    }
}

/// Dempster's "foot + leg" segment (the shank with the foot, moved by the knee):
/// mass 0.061 of body mass, centre of mass at 0.606 of the leg length (femoral condyles
/// to medial malleolus, 0.246 of height) from the knee, radius of gyration 0.416 of the
/// leg length about the centre of mass. The long-axis inertia, which Dempster does not
/// give, is that of a solid cylinder of radius `long_axis_radius` (m).
pub fn shank_and_foot(body_mass: f64, height: f64, long_axis_radius: f64) -> SegmentInertia {
    let length = 0.246 * height;
    let mass = 0.061 * body_mass;
    let k = 0.416 * length;
    SegmentInertia {
        mass,
        length,
        com_from_proximal: 0.606 * length,
        inertia_transverse: mass * k * k,
        inertia_long: 0.5 * mass * long_axis_radius.powi(2),
    }
}

/// Dempster's thigh (greater trochanter to femoral condyles): mass 0.100, centre of mass
/// 0.433 from proximal, radius of gyration 0.323 of the thigh length (0.245 of height).
pub fn thigh(body_mass: f64, height: f64, long_axis_radius: f64) -> SegmentInertia {
    let length = 0.245 * height;
    let mass = 0.100 * body_mass;
    let k = 0.323 * length;
    SegmentInertia {
        mass,
        length,
        com_from_proximal: 0.433 * length,
        inertia_transverse: mass * k * k,
        inertia_long: 0.5 * mass * long_axis_radius.powi(2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dempster_fractions_scale_with_mass_and_height() {
        let s = shank_and_foot(70.0, 1.75, 0.05);
        assert!((s.mass - 4.27).abs() < 1e-9);
        assert!((s.length - 0.4305).abs() < 1e-9);
        assert!((s.com_from_proximal - 0.606 * 0.4305).abs() < 1e-12);
        // Radius of gyration about the knee: 0.735 of the length in Winter's table.
        let k_prox = (s.inertia_about_proximal() / s.mass).sqrt() / s.length;
        assert!((k_prox - 0.735).abs() < 0.005, "{k_prox}");
    }
}
