//! Orbit camera about the leg: yaw, pitch and distance around a target, +z up.

use glam::{Mat4, Vec3};

/// Named viewpoints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraPreset {
    /// From the front (anterior), looking back.
    Front,
    /// From the subject's left (lateral side of the left leg).
    Side,
    /// From behind (posterior).
    Back,
    /// From the subject's right (medial side of the left leg).
    Medial,
    /// A three-quarter view from front-left, slightly above.
    Oblique,
}

impl CameraPreset {
    /// Parses `front|side|back|medial|oblique`.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "front" => Self::Front,
            "side" | "lateral" => Self::Side,
            "back" => Self::Back,
            "medial" => Self::Medial,
            "oblique" => Self::Oblique,
            _ => return None,
        })
    }

    /// All presets with their names.
    pub const ALL: [(CameraPreset, &'static str); 5] = [
        (Self::Front, "front"),
        (Self::Side, "side"),
        (Self::Back, "back"),
        (Self::Medial, "medial"),
        (Self::Oblique, "oblique"),
    ];
}

/// An orbit camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    /// Point looked at.
    pub target: Vec3,
    /// Distance from the target (m).
    pub distance: f32,
    /// Angle about +z from +y (rad): 0 looks from the front.
    pub yaw: f32,
    /// Elevation (rad), clamped to ±1.5.
    pub pitch: f32,
    /// Vertical field of view (rad).
    pub fov_y: f32,
}

impl OrbitCamera {
    /// A camera framing the box `[lo, hi]` from a preset, for a viewport of `aspect`
    /// (width / height): the box's projected corners fill about 90 % of the tighter
    /// direction, centred.
    pub fn framing(lo: Vec3, hi: Vec3, preset: CameraPreset, aspect: f32) -> Self {
        let (yaw, pitch) = match preset {
            CameraPreset::Front => (0.0, 0.05),
            // +x is the subject's right: the lateral side of a left leg is at -x.
            CameraPreset::Side => (std::f32::consts::FRAC_PI_2, 0.05),
            CameraPreset::Back => (std::f32::consts::PI, 0.05),
            CameraPreset::Medial => (-std::f32::consts::FRAC_PI_2, 0.05),
            CameraPreset::Oblique => (0.6, 0.3),
        };
        let fov_y = 35f32.to_radians();
        let mut cam = Self {
            target: 0.5 * (lo + hi),
            distance: 1.0,
            yaw,
            pitch,
            fov_y,
        };
        // View axes: toward the eye, right and up.
        let back = (cam.eye() - cam.target).normalize_or(Vec3::Y);
        let right = Vec3::Z.cross(back).normalize_or(Vec3::X);
        let up = back.cross(right);
        let corners: Vec<Vec3> = (0..8)
            .map(|c| {
                Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        // Centre the target on the box as seen from the eye.
        let span = |axis: Vec3| {
            corners
                .iter()
                .map(|p| (*p - cam.target).dot(axis))
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                })
        };
        let (r0, r1) = span(right);
        let (u0, u1) = span(up);
        cam.target += right * (0.5 * (r0 + r1)) + up * (0.5 * (u0 + u1));
        let t = (0.5 * fov_y).tan() * 0.9;
        let aspect = aspect.max(1e-3);
        cam.distance = corners
            .iter()
            .map(|p| {
                let d = *p - cam.target;
                d.dot(back) + (d.dot(right).abs() / (t * aspect)).max(d.dot(up).abs() / t)
            })
            .fold(0.05f32, f32::max);
        cam
    }

    /// Camera position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        // Yaw 0 puts the eye on +y (anterior), looking toward -y.
        self.target + Vec3::new(-sy * cp, cy * cp, sp) * self.distance
    }

    /// View matrix.
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Z)
    }

    /// Projection matrix for an aspect ratio (width / height), depth 0..1.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let near = (self.distance * 0.01).max(1e-3);
        glam::camera::rh::proj::directx::perspective(
            self.fov_y,
            aspect.max(1e-3),
            near,
            self.distance * 10.0 + 10.0,
        )
    }

    /// Orbits by pixel drags (`dx`, `dy`) with `speed` rad per pixel.
    pub fn orbit(&mut self, dx: f32, dy: f32, speed: f32) {
        self.yaw -= dx * speed;
        self.pitch = (self.pitch + dy * speed).clamp(-1.5, 1.5);
    }

    /// Pans in the view plane by pixel drags for a viewport of `height` pixels.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let view = self.view();
        let right = Vec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
        let up = Vec3::new(view.x_axis.y, view.y_axis.y, view.z_axis.y);
        let per_px = 2.0 * self.distance * (0.5 * self.fov_y).tan() / height.max(1.0);
        self.target += (-right * dx + up * dy) * per_px;
    }

    /// Zooms by a factor (>1 moves away).
    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance * factor).clamp(0.05, 20.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_puts_the_whole_box_in_view() {
        let (lo, hi) = (Vec3::new(-0.1, -0.1, 0.0), Vec3::new(0.1, 0.1, 0.9));
        for (p, _) in CameraPreset::ALL {
            let c = OrbitCamera::framing(lo, hi, p, 1.0);
            let vp = c.projection(1.0) * c.view();
            for corner in 0..8 {
                let q = Vec3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                );
                let clip = vp * q.extend(1.0);
                let ndc = clip.truncate() / clip.w;
                assert!(
                    ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && ndc.z > 0.0 && ndc.z < 1.0,
                    "{p:?}: {ndc}"
                );
            }
        }
    }

    #[test]
    fn the_side_preset_sees_the_left_legs_lateral_side() {
        let c = OrbitCamera::framing(Vec3::ZERO, Vec3::ONE, CameraPreset::Side, 1.5);
        assert!(c.eye().x < c.target.x);
        let m = OrbitCamera::framing(Vec3::ZERO, Vec3::ONE, CameraPreset::Medial, 1.5);
        assert!(m.eye().x > m.target.x);
    }

    #[test]
    fn the_front_preset_looks_at_the_front_and_orbit_clamps_pitch() {
        let mut c = OrbitCamera::framing(Vec3::ZERO, Vec3::ONE, CameraPreset::Front, 1.5);
        assert!(c.eye().y > c.target.y);
        let b = OrbitCamera::framing(Vec3::ZERO, Vec3::ONE, CameraPreset::Back, 1.5);
        assert!(b.eye().y < b.target.y);
        c.orbit(0.0, 1e4, 0.01);
        assert_eq!(c.pitch, 1.5);
        let d = c.distance;
        c.zoom(2.0);
        assert!((c.distance - 2.0 * d).abs() < 1e-5);
    }
}
