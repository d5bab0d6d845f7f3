//! The tether that holds an unloaded muscle's chain in place (beyond the paper).

/// A spring (N/m) pulling each cone-anchored chain point toward its rest place while the
/// muscle pulls less than `release` (N), fading linearly to nothing at `release`.
///
/// A slack chain has no force across it to pull a point back once flexion has moved it
/// within its cone. The fascia that holds a resting muscle in place is this spring; a
/// working muscle's line of pull is unchanged. Its rest places are where the chains
/// were built, on which the tissue rests: a chain left alone stays there (within a
/// millimetre) instead of sagging and straightening away under its passive tension.
/// With it (150, 300 and 600 N/m tried; 600 kept) the muscle vertices out through the skin on
/// the way back from a deep flexion fell from 1 361–1 452 to 234–298 at 49°.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Tether {
    /// N/m per point (0: none, the paper's chain).
    pub stiffness: f32,
    /// Contraction force (N) from which the tether is off.
    pub release: f32,
}

impl Tether {
    /// The spring constant (N/m) at contraction force `c` (N).
    ///
    /// ```
    /// use myoslice::muscle::Tether;
    /// let t = Tether { stiffness: 300.0, release: 20.0 };
    /// assert_eq!(t.at(0.0), 300.0);
    /// assert_eq!(t.at(10.0), 150.0);
    /// assert_eq!(t.at(25.0), 0.0);
    /// ```
    pub fn at(&self, c: f32) -> f32 {
        if self.stiffness <= 0.0 || self.release <= 0.0 {
            return 0.0;
        }
        self.stiffness * (1.0 - c.abs() / self.release).max(0.0)
    }
}
