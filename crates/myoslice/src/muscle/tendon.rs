//! A compliant tendon (De Groote et al. 2016): the fibre length becomes a state. Each step
//! finds it by backward Euler: the fibre length at which the tendon, stretched by what the
//! fibre leaves of the muscle-tendon length, pulls exactly as hard as the fibre does along
//! it at the velocity that length implies.

use super::hill::{FibreState, HillParams, tendon_force_length};

/// Iterations of the safeguarded Newton solve; it converges in a handful.
const MAX_ITERATIONS: usize = 60;

impl HillParams {
    /// Tendon force (N) at tendon length `l_t` (m): never pushing.
    pub fn tendon_force(&self, l_t: f64) -> f64 {
        self.max_isometric_force * tendon_force_length(l_t / self.tendon_slack_length).max(0.0)
    }

    /// The fibre state with a compliant tendon, at muscle-tendon length `l_mt` (m) and
    /// activation `a`: one backward-Euler step of `h` seconds from fibre length `prev`
    /// (m), or with `h = None` the static equilibrium (no fibre velocity; where several
    /// lengths balance, the one the search from `prev` finds). Neither part pushes: a
    /// slack unit (tendon below its zero-force length, fibre not pulling) keeps its fibre
    /// length.
    ///
    /// ```
    /// use myoslice::muscle::HillParams;
    /// let p = HillParams::new(1000.0, 0.1, 0.2, 0.0, 10.0);
    /// // Fully active and held at optimal fibre length plus a stretched tendon.
    /// let l_mt = 0.1 + 0.2 * 1.047;
    /// let f = p.compliant_tendon_step(1.0, l_mt, 0.1, None);
    /// let tendon = p.tendon_force(l_mt - f.length);
    /// let fibre = p.force(1.0, &f).tendon;
    /// assert!((tendon - fibre).abs() < 1e-6 * 1000.0);
    /// ```
    pub fn compliant_tendon_step(
        &self,
        a: f64,
        l_mt: f64,
        prev: f64,
        h: Option<f64>,
    ) -> FibreState {
        let height = self.optimal_fibre_length * self.pennation.sin();
        // Unknown: the fibre's length along the tendon, x; fibre length sqrt(x² + height²).
        let state = |x: f64| {
            let length = (x * x + height * height).sqrt();
            FibreState {
                length,
                cos_pennation: x / length,
                velocity: h.map_or(0.0, |h| (length - prev) / h),
            }
        };
        // Tendon pull minus fibre pull along the tendon (De Groote's passive curve dips
        // below zero short of optimal length: a fibre never pushes). Never rises with x.
        let residual = |x: f64| {
            let s = state(x);
            let fibre = self.max_isometric_force * self.fibre_force_fraction(a, &s).max(0.0);
            self.tendon_force(l_mt - x) - fibre * s.cos_pennation
        };
        let (mut lo, mut hi) = (1e-4 * self.optimal_fibre_length, l_mt);
        if l_mt.is_nan() || hi <= lo {
            return state(lo);
        }
        let prev_x = (prev * prev - height * height).max(0.0).sqrt();
        let mut x = prev_x.clamp(lo, hi);
        let mut r = residual(x);
        if r == 0.0 {
            return state(x); // slack: nothing pulls
        }
        // Bracket [lo, hi] with residual > 0 at lo and ≤ 0 at hi. At hi = l_mt the tendon
        // has no length left and cannot pull.
        if r > 0.0 {
            lo = x;
        } else {
            hi = x;
            if residual(lo) <= 0.0 {
                // A unit shorter than its slack tendon with a pulling fibre: the fibre
                // shortens as far as it can.
                return state(lo);
            }
        }
        // Safeguarded Newton from the previous fibre length, bisecting whenever the step
        // would leave the bracket.
        let dx = 1e-7 * self.optimal_fibre_length;
        let tol = 1e-10 * self.optimal_fibre_length;
        for k in 0..MAX_ITERATIONS {
            // The first pass reuses the residual that set up the bracket.
            if k > 0 {
                r = residual(x);
                if r > 0.0 {
                    lo = x;
                } else {
                    hi = x;
                }
            }
            let slope = (residual(x + dx) - r) / dx;
            let newton = x - r / slope;
            let next = if newton.is_finite() && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            let done = (next - x).abs() <= tol || hi - lo <= tol;
            x = next;
            if done {
                break;
            }
        }
        state(x)
    }
}
