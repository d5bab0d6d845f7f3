//! The tendon models, and a compliant tendon (De Groote et al. 2016): the fibre length
//! becomes a state. Each step finds it by backward Euler: the fibre length at which the
//! tendon, stretched by what the fibre leaves of the muscle-tendon length, pulls exactly
//! as hard as the fibre does along it at the velocity that length implies.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, parse_choice};

use super::hill::{
    FibreState, HillParams, active_force_length_and_slope, force_velocity_and_slope,
    passive_force_length_and_slope, tendon_force_length, tendon_force_length_and_slope,
};

/// How the Hill units' tendons behave.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TendonModel {
    /// Inextensible: the fibre takes every change of the muscle-tendon length.
    #[default]
    Rigid,
    /// Elastic (De Groote 2016's tendon curve, about 4.7 % strain at max isometric
    /// force): the fibre length is a state found by backward Euler every step.
    Compliant,
}

impl TendonModel {
    /// Every model, in the order fronts list them.
    pub const ALL: [Self; 2] = [Self::Rigid, Self::Compliant];

    /// The name used in scenarios, the CLI and Python (`"rigid"`, `"compliant"`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Rigid => "rigid",
            Self::Compliant => "compliant",
        }
    }
}

impl std::str::FromStr for TendonModel {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        parse_choice("tendon", s, &Self::ALL, |m| m.name())
    }
}

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
        let solve = Balance::new(self, a, l_mt, prev, h);
        let (mut lo, mut hi) = (1e-4 * self.optimal_fibre_length, l_mt);
        if l_mt.is_nan() || hi <= lo {
            return solve.state(lo);
        }
        let height = solve.height;
        let prev_x = (prev * prev - height * height).max(0.0).sqrt();
        let mut x = prev_x.clamp(lo, hi);
        let (mut r, mut slope) = solve.residual(x);
        // Bracket [lo, hi] with residual ≤ 0 at hi. At hi = l_mt the tendon has no length
        // left and cannot pull. The residual at lo is known to be positive once a point
        // there has been evaluated (`lo_pulls`); the first bisection checks the bottom.
        let mut lo_pulls = r > 0.0;
        if lo_pulls {
            lo = x;
        } else {
            hi = x;
        }
        // Safeguarded Newton from the previous fibre length, bisecting whenever the step
        // would leave the bracket.
        let tol = 1e-10 * self.optimal_fibre_length;
        for k in 0..MAX_ITERATIONS {
            // The first pass reuses the residual that set up the bracket.
            if k > 0 {
                (r, slope) = solve.residual(x);
                if r > 0.0 {
                    (lo, lo_pulls) = (x, true);
                } else {
                    hi = x;
                }
            }
            if r == 0.0 {
                break; // an exact root (or a slack unit: nothing pulls)
            }
            let newton = x - r / slope;
            if newton.is_finite() && (newton - x).abs() <= tol {
                // Converged. (Tested before the bracket: the last step may land on its
                // end in rounding, which would send a bisection far from the root.)
                x = newton;
                break;
            }
            let next = if newton.is_finite() && newton > lo && newton < hi {
                newton
            } else {
                if !lo_pulls {
                    if solve.residual(lo).0 <= 0.0 {
                        // A unit shorter than its slack tendon with a pulling fibre: the
                        // fibre shortens as far as it can.
                        return solve.state(lo);
                    }
                    lo_pulls = true;
                }
                0.5 * (lo + hi)
            };
            let done = hi - lo <= tol;
            x = next;
            if done {
                break;
            }
        }
        solve.state(x)
    }
}

/// The fixed inputs of one solve, over its unknown: the fibre's length `x` (m) along the
/// tendon (fibre length sqrt(x² + height²), constant-thickness pennation).
struct Balance<'a> {
    p: &'a HillParams,
    a: f64,
    l_mt: f64,
    prev: f64,
    h: Option<f64>,
    /// The fibre's constant thickness across the tendon (m).
    height: f64,
}

impl<'a> Balance<'a> {
    fn new(p: &'a HillParams, a: f64, l_mt: f64, prev: f64, h: Option<f64>) -> Self {
        let height = p.optimal_fibre_length * p.pennation.sin();
        Self {
            p,
            a,
            l_mt,
            prev,
            h,
            height,
        }
    }

    /// The fibre state at `x`.
    fn state(&self, x: f64) -> FibreState {
        let length = (x * x + self.height * self.height).sqrt();
        FibreState {
            length,
            cos_pennation: x / length,
            velocity: self.h.map_or(0.0, |h| (length - self.prev) / h),
        }
    }

    /// Tendon pull minus fibre pull along the tendon (N) at `x`, and its slope d/dx: the
    /// residual the step solves. De Groote's passive curve dips below zero short of
    /// optimal length, so a fibre never pushes; the residual never rises with x. The same
    /// curves as [`HillParams::force`], each exponential evaluated once for value and
    /// slope.
    fn residual(&self, x: f64) -> (f64, f64) {
        let Self {
            p,
            a,
            l_mt,
            prev,
            h,
            height,
        } = *self;
        let (fmax, lopt, lts) = (
            p.max_isometric_force,
            p.optimal_fibre_length,
            p.tendon_slack_length,
        );
        let v_scale = 1.0 / (p.max_contraction_velocity * lopt);
        let length = (x * x + height * height).sqrt();
        let cos = x / length;
        let dcos = height * height / (length * length * length);
        // Fibre length and velocity (normalised) and their slopes along x.
        let (l, dl) = (length / lopt, cos / lopt);
        let (v, dv) = match h {
            Some(h) => ((length - prev) / h * v_scale, cos / h * v_scale),
            None => (0.0, 0.0),
        };
        let (fpe, dfpe) = passive_force_length_and_slope(l);
        let (act, dact) = if a > 0.0 {
            let (fl, dfl) = active_force_length_and_slope(l);
            let (fv, dfv) = force_velocity_and_slope(v.clamp(-1.0, 1.0));
            let dfv = if v.abs() < 1.0 { dfv * dv } else { 0.0 };
            (a * fl * fv, a * (dfl * dl * fv + fl * dfv))
        } else {
            (0.0, 0.0)
        };
        let frac = act + fpe + p.fibre_damping * v;
        let dfrac = dact + dfpe * dl + p.fibre_damping * dv;
        let (fibre, dfibre) = if frac > 0.0 {
            (fmax * frac * cos, fmax * (dfrac * cos + frac * dcos))
        } else {
            (0.0, 0.0)
        };
        let (ft, dft) = tendon_force_length_and_slope((l_mt - x) / lts);
        let (tendon, dtendon) = if ft > 0.0 {
            (fmax * ft, -fmax * dft / lts)
        } else {
            (0.0, 0.0)
        };
        (tendon - fibre, dtendon - dfibre)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_balance_slope_is_the_derivative_of_the_balance() {
        // Pennate and not, static and stepping, active and passive, shortening and
        // lengthening (prev on either side of x), all within the force-velocity curve's
        // unclamped range (|x − prev| < h·v_max·l_opt = 0.01 m).
        for (pennation, a, h, prev) in [
            (0.0, 1.0, Some(1e-2), 0.101),
            (0.3, 0.7, Some(1e-2), 0.099),
            (0.3, 0.0, Some(1e-2), 0.1),
            (0.2, 0.5, None, 0.1),
        ] {
            let p = HillParams::new(1000.0, 0.1, 0.25, pennation, 10.0);
            let l_mt = 0.1 + 0.25 * 1.03;
            for k in 0..20 {
                let x = 0.092 + 0.0008 * f64::from(k);
                let solve = Balance::new(&p, a, l_mt, prev, h);
                let (r, dr) = solve.residual(x);
                let d = 1e-9;
                let fd = (solve.residual(x + d).0 - solve.residual(x - d).0) / (2.0 * d);
                assert!(
                    (dr - fd).abs() <= 1e-4 * (1.0 + fd.abs()),
                    "pennation {pennation}, a {a}, x {x}: r {r}, slope {dr} vs {fd}"
                );
            }
        }
    }
}
