//! Hill-type muscle-tendon mechanics after De Groote et al. (2016), "Evaluation of direct
//! collocation optimal control problem formulations for solving the muscle redundancy
//! problem", Ann. Biomed. Eng. 44(10): the curve family, fibre damping and activation
//! dynamics (with OpenSim's recommended smoothing, b = 10).

/// Active force-length coefficients `(b1, b2, b3, b4)` of the three Gaussian-like terms.
const FL: [[f64; 4]; 3] = [
    [
        0.814_483_478_343_008,
        1.055_033_428_970_575,
        0.162_384_573_599_574,
        0.063_303_448_465_465,
    ],
    [
        0.433_004_984_392_647,
        0.716_775_413_397_760,
        -0.029_947_116_970_696,
        0.200_356_847_296_188,
    ],
    [0.1, 1.0, 0.353_553_390_593_274, 0.0],
];
/// Passive force-length: shape factor and strain at one normalised force.
const K_PE: f64 = 4.0;
const E0: f64 = 0.6;
/// exp(K_PE) − 1, the passive curve's normaliser (so that it reaches 1 at 1 + E0).
const PASSIVE_SCALE: f64 = 53.598_150_033_144_236;
/// Force-velocity coefficients.
const D1: f64 = -0.318_323_436_899_127;
const D2: f64 = -8.149_156_043_475_250;
const D3: f64 = -0.374_121_508_647_863;
const D4: f64 = 0.885_644_059_915_004;
/// Tendon force-length.
const C1: f64 = 0.2;
const C2: f64 = 0.995;
const C3: f64 = 0.250;
const K_T: f64 = 35.0;

/// Active force-length multiplier at normalised fibre length `l` (1 at optimal length).
pub fn active_force_length(l: f64) -> f64 {
    FL.iter()
        .map(|b| {
            let den = b[2] + b[3] * l;
            b[0] * (-0.5 * (l - b[1]).powi(2) / (den * den)).exp()
        })
        .sum()
}

/// Passive force-length multiplier (slightly negative below optimal length, as published).
pub fn passive_force_length(l: f64) -> f64 {
    ((K_PE * (l - 1.0) / E0).exp() - 1.0) / PASSIVE_SCALE
}

/// Force-velocity multiplier at normalised fibre velocity `v` (lengths of optimal fibre
/// per second divided by the maximum contraction velocity; negative = shortening).
pub fn force_velocity(v: f64) -> f64 {
    let x = D2 * v + D3;
    D1 * (x + (x * x + 1.0).sqrt()).ln() + D4
}

/// [`active_force_length`] and its slope d/dl, from one exponential per term.
pub fn active_force_length_and_slope(l: f64) -> (f64, f64) {
    FL.iter().fold((0.0, 0.0), |(f, df), b| {
        let den = b[2] + b[3] * l;
        let u = (l - b[1]) / den;
        let e = b[0] * (-0.5 * u * u).exp();
        // d/dl of −u²/2, with u' = (den − (l − b1)·b3) / den² = (1 − u·b3) / den.
        (f + e, df - e * u * (1.0 - u * b[3]) / den)
    })
}

/// [`passive_force_length`] and its slope d/dl.
pub fn passive_force_length_and_slope(l: f64) -> (f64, f64) {
    let e = (K_PE * (l - 1.0) / E0).exp();
    ((e - 1.0) / PASSIVE_SCALE, K_PE / E0 * e / PASSIVE_SCALE)
}

/// [`force_velocity`] and its slope d/dv.
pub fn force_velocity_and_slope(v: f64) -> (f64, f64) {
    let x = D2 * v + D3;
    let r = (x * x + 1.0).sqrt();
    (D1 * (x + r).ln() + D4, D1 * D2 / r)
}

/// [`tendon_force_length`] and its slope d/dl.
pub fn tendon_force_length_and_slope(l: f64) -> (f64, f64) {
    let e = C1 * (K_T * (l - C2)).exp();
    (e - C3, K_T * e)
}

/// Inverse of [`force_velocity`]: normalised velocity at which the multiplier is `f`.
pub fn force_velocity_inverse(f: f64) -> f64 {
    (((f - D4) / D1).sinh() - D3) / D2
}

/// Tendon force (normalised by max isometric force) at normalised tendon length.
pub fn tendon_force_length(l: f64) -> f64 {
    C1 * (K_T * (l - C2)).exp() - C3
}

/// First-order activation dynamics: `da/dt` for excitation `e` and activation `a`, with
/// activation/deactivation time constants `tau_a`, `tau_d` (s) scaled by `0.5 + 1.5a` and
/// a smooth switch of steepness `b` (De Groote 2016, Eq. 1-2).
pub fn activation_rate(e: f64, a: f64, tau_a: f64, tau_d: f64, b: f64) -> f64 {
    let f = 0.5 * (b * (e - a)).tanh();
    let s = 0.5 + 1.5 * a;
    ((f + 0.5) / (tau_a * s) + (-f + 0.5) * s / tau_d) * (e - a)
}

/// Parameters of one muscle-tendon unit (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HillParams {
    /// Maximum isometric force (N).
    pub max_isometric_force: f64,
    /// Optimal fibre length (m).
    pub optimal_fibre_length: f64,
    /// Tendon slack length (m).
    pub tendon_slack_length: f64,
    /// Pennation angle at optimal fibre length (rad).
    pub pennation: f64,
    /// Maximum contraction velocity (optimal fibre lengths per second).
    pub max_contraction_velocity: f64,
    /// Activation time constant (s), 0.015 in De Groote 2016.
    pub tau_activation: f64,
    /// Deactivation time constant (s), 0.060 in De Groote 2016.
    pub tau_deactivation: f64,
    /// Fibre damping (normalised), 0.01 in De Groote 2016.
    pub fibre_damping: f64,
}

impl HillParams {
    /// Parameters with De Groote's time constants and damping.
    pub fn new(fmax: f64, lopt: f64, lts: f64, pennation: f64, vmax: f64) -> Self {
        Self {
            max_isometric_force: fmax,
            optimal_fibre_length: lopt,
            tendon_slack_length: lts,
            pennation,
            max_contraction_velocity: vmax,
            tau_activation: 0.015,
            tau_deactivation: 0.060,
            fibre_damping: 0.01,
        }
    }

    /// Fibre length, pennation angle and fibre velocity for a rigid tendon, from the
    /// muscle-tendon length and lengthening velocity (constant-thickness pennation).
    pub fn rigid_tendon_kinematics(&self, l_mt: f64, v_mt: f64) -> FibreState {
        let h = self.optimal_fibre_length * self.pennation.sin();
        let along = (l_mt - self.tendon_slack_length).max(1e-4 * self.optimal_fibre_length);
        let l_m = (h * h + along * along).sqrt();
        let cos_a = along / l_m;
        FibreState {
            length: l_m,
            cos_pennation: cos_a,
            velocity: v_mt * cos_a,
        }
    }

    /// Muscle-tendon force (N, along the tendon) for activation `a` and fibre state.
    pub fn force(&self, a: f64, fibre: &FibreState) -> HillForce {
        let (l, v, active, fpe) = self.fibre_parts(a, fibre);
        let fibre_force = self.max_isometric_force * (active + fpe + self.fibre_damping * v);
        HillForce {
            tendon: (fibre_force * fibre.cos_pennation).max(0.0),
            active_fraction: active,
            passive_fraction: fpe,
            normalised_length: l,
            normalised_velocity: v,
        }
    }

    /// Normalised length and velocity, the active part `a·f_L·f_V` and `f_PE`.
    #[inline]
    fn fibre_parts(&self, a: f64, fibre: &FibreState) -> (f64, f64, f64, f64) {
        let l = fibre.length / self.optimal_fibre_length;
        let v = fibre.velocity / (self.max_contraction_velocity * self.optimal_fibre_length);
        let fpe = passive_force_length(l);
        // An inactive fibre skips the active curves (exactly: they are finite).
        let active = if a > 0.0 {
            a * active_force_length(l) * force_velocity(v.clamp(-1.0, 1.0))
        } else {
            0.0
        };
        (l, v, active, fpe)
    }
}

/// Fibre kinematics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FibreState {
    /// Fibre length (m).
    pub length: f64,
    /// Cosine of the pennation angle.
    pub cos_pennation: f64,
    /// Fibre lengthening velocity (m/s).
    pub velocity: f64,
}

/// The force and its parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HillForce {
    /// Tendon force (N), never negative: muscles pull.
    pub tendon: f64,
    /// `a · f_L · f_V`.
    pub active_fraction: f64,
    /// `f_PE`.
    pub passive_fraction: f64,
    /// Fibre length / optimal.
    pub normalised_length: f64,
    /// Fibre velocity / (v_max · optimal length).
    pub normalised_velocity: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_passive_normaliser_is_exp_k_pe_minus_one() {
        assert!((PASSIVE_SCALE - (K_PE.exp() - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn each_curve_and_slope_pair_matches_the_curve_and_its_finite_difference() {
        type Pair = fn(f64) -> (f64, f64);
        type Curve = fn(f64) -> f64;
        let pairs: [(Pair, Curve, [f64; 2]); 4] = [
            (
                active_force_length_and_slope,
                active_force_length,
                [0.3, 1.8],
            ),
            (
                passive_force_length_and_slope,
                passive_force_length,
                [0.5, 1.8],
            ),
            (force_velocity_and_slope, force_velocity, [-1.0, 1.0]),
            (
                tendon_force_length_and_slope,
                tendon_force_length,
                [0.95, 1.1],
            ),
        ];
        for (pair, curve, [lo, hi]) in pairs {
            for k in 0..=40 {
                let x = lo + (hi - lo) * f64::from(k) / 40.0;
                let (f, df) = pair(x);
                assert!(
                    (f - curve(x)).abs() <= 1e-12 * (1.0 + f.abs()),
                    "value at {x}"
                );
                let d = 1e-6;
                let fd = (curve(x + d) - curve(x - d)) / (2.0 * d);
                assert!(
                    (df - fd).abs() <= 1e-6 * (1.0 + fd.abs()),
                    "slope at {x}: {df} vs {fd}"
                );
            }
        }
    }

    #[test]
    fn curves_have_their_landmarks() {
        assert!((active_force_length(1.0) - 1.0).abs() < 0.01);
        assert!(active_force_length(0.4) < 0.2 && active_force_length(1.7) < 0.2);
        assert!(passive_force_length(0.9).abs() < 0.01);
        assert!((passive_force_length(1.6) - 1.0).abs() < 1e-9);
        assert!((force_velocity(0.0) - 1.0).abs() < 0.01);
        assert!(force_velocity(-1.0).abs() < 0.02);
        assert!((force_velocity_inverse(force_velocity(0.37)) - 0.37).abs() < 1e-9);
        assert!(tendon_force_length(1.0).abs() < 0.02);
    }
}
