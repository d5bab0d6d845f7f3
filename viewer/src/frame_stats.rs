//! Frame-time figures of an interactive session.

/// Frame-time figures of a session.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Frames presented.
    pub frames: u64,
    /// The first frame (ms): start-up, pipeline compilation.
    pub first_ms: f64,
    /// Wall time of the frames after the first (s).
    pub wall_s: f64,
    /// Of which simulating (s).
    pub sim_s: f64,
    /// Slowest frame after the first (ms).
    pub worst_ms: f64,
}

impl FrameStats {
    pub(crate) fn add(&mut self, frame_s: f64, sim_s: f64) {
        if self.frames == 0 {
            self.first_ms = frame_s * 1e3;
        } else {
            self.worst_ms = self.worst_ms.max(frame_s * 1e3);
            self.wall_s += frame_s;
            self.sim_s += sim_s;
        }
        self.frames += 1;
    }

    /// Mean frame time after the first (ms).
    pub fn mean_ms(&self) -> f64 {
        1e3 * self.wall_s / self.frames.saturating_sub(1).max(1) as f64
    }

    /// Mean simulation time per frame after the first (ms).
    pub fn mean_sim_ms(&self) -> f64 {
        1e3 * self.sim_s / self.frames.saturating_sub(1).max(1) as f64
    }
}
