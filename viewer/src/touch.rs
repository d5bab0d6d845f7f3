//! Fingers on the view: one drags the camera round, two pinch to zoom and move together to
//! pan (a phone or a tablet, in the web page).

use winit::event::TouchPhase;

/// What the fingers asked of the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Gesture {
    /// Orbit by this drag (px).
    Orbit(f32, f32),
    /// Zoom by this factor (>1 moves away) and pan by this drag (px).
    PinchPan {
        /// The factor for [`crate::OrbitCamera::zoom`].
        zoom: f32,
        /// The midpoint's drag (px).
        pan: (f32, f32),
    },
}

/// The fingers down on the view (touch id, last position in pixels).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Touches {
    fingers: Vec<(u64, (f64, f64))>,
}

impl Touches {
    /// Takes finger `id`'s event at `at`; `panel` when the panel has it (such a finger
    /// moves nothing). Returns what a move asks of the camera.
    pub fn event(
        &mut self,
        id: u64,
        phase: TouchPhase,
        at: (f64, f64),
        panel: bool,
    ) -> Option<Gesture> {
        let before = self.fingers.clone();
        match phase {
            TouchPhase::Started if !panel => self.fingers.push((id, at)),
            TouchPhase::Moved => {
                if let Some(f) = self.fingers.iter_mut().find(|f| f.0 == id) {
                    f.1 = at;
                }
            }
            TouchPhase::Ended | TouchPhase::Cancelled => self.fingers.retain(|f| f.0 != id),
            TouchPhase::Started => {}
        }
        if phase != TouchPhase::Moved {
            return None;
        }
        match (before.as_slice(), self.fingers.as_slice()) {
            ([(a, p)], [(b, q)]) if a == b => {
                Some(Gesture::Orbit((q.0 - p.0) as f32, (q.1 - p.1) as f32))
            }
            ([(a0, p0), (a1, p1)], [(b0, q0), (b1, q1)]) if a0 == b0 && a1 == b1 => {
                let (d0, d1) = (
                    (p0.0 - p1.0).hypot(p0.1 - p1.1),
                    (q0.0 - q1.0).hypot(q0.1 - q1.1),
                );
                let zoom = if d0 > 1.0 && d1 > 1.0 {
                    (d0 / d1) as f32
                } else {
                    1.0
                };
                let mid = |a: &(f64, f64), b: &(f64, f64)| ((a.0 + b.0) * 0.5, (a.1 + b.1) * 0.5);
                let (m0, m1) = (mid(p0, p1), mid(q0, q1));
                Some(Gesture::PinchPan {
                    zoom,
                    pan: ((m1.0 - m0.0) as f32, (m1.1 - m0.1) as f32),
                })
            }
            _ => None,
        }
    }

    /// Whether no finger is down.
    pub fn is_empty(&self) -> bool {
        self.fingers.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_finger_orbits_two_pinch_to_zoom_and_a_touch_on_the_panel_moves_nothing() {
        let mut t = Touches::default();
        assert_eq!(t.event(1, TouchPhase::Started, (100.0, 100.0), false), None);
        assert_eq!(
            t.event(1, TouchPhase::Moved, (140.0, 90.0), false),
            Some(Gesture::Orbit(40.0, -10.0))
        );
        t.event(2, TouchPhase::Started, (240.0, 90.0), false);
        // The fingers spread from 100 px apart to 200, their midpoint 50 px to the right:
        // in by half, and a pan.
        assert_eq!(
            t.event(2, TouchPhase::Moved, (340.0, 90.0), false),
            Some(Gesture::PinchPan {
                zoom: 0.5,
                pan: (50.0, 0.0)
            })
        );
        t.event(1, TouchPhase::Ended, (140.0, 100.0), false);
        t.event(2, TouchPhase::Cancelled, (340.0, 100.0), false);
        assert!(t.is_empty());
        t.event(3, TouchPhase::Started, (10.0, 10.0), true);
        assert_eq!(
            t.event(3, TouchPhase::Moved, (90.0, 60.0), true),
            None,
            "the panel's"
        );
        assert!(t.is_empty());
    }
}
