//! Excitation schedules: piecewise-linear functions of time.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A piecewise-linear schedule `[(time s, value)]`, held constant before the first and
/// after the last point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    points: Vec<(f64, f64)>,
}

impl Schedule {
    /// A schedule through `points`, which must have increasing times and values in [0, 1].
    ///
    /// ```
    /// use myoslice::simulation::Schedule;
    /// let s = Schedule::new(vec![(0.0, 0.0), (0.5, 1.0)])?;
    /// assert_eq!(s.value(0.25), 0.5);
    /// assert_eq!(s.value(2.0), 1.0);
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn new(points: Vec<(f64, f64)>) -> Result<Self> {
        if points.is_empty() {
            return Err(Error::invalid(
                "schedule",
                "[]",
                "expected at least one (time, value) point",
            ));
        }
        for (i, &(t, v)) in points.iter().enumerate() {
            if !t.is_finite() || t < 0.0 {
                return Err(Error::invalid(
                    format!("schedule point {i} time"),
                    t,
                    "expected a finite time >= 0",
                ));
            }
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return Err(Error::invalid(
                    format!("schedule point {i} value"),
                    v,
                    "expected an excitation in [0, 1]",
                ));
            }
            if i > 0 && t <= points[i - 1].0 {
                return Err(Error::invalid(
                    format!("schedule point {i} time"),
                    t,
                    "times must increase",
                ));
            }
        }
        Ok(Self { points })
    }

    /// A constant schedule.
    pub fn constant(v: f64) -> Result<Self> {
        Self::new(vec![(0.0, v)])
    }

    /// The points.
    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }

    /// Value at time `t`.
    pub fn value(&self, t: f64) -> f64 {
        let p = &self.points;
        let i = p.partition_point(|&(pt, _)| pt <= t);
        if i == 0 {
            return p[0].1;
        }
        if i == p.len() {
            return p[p.len() - 1].1;
        }
        let ((t0, v0), (t1, v1)) = (p[i - 1], p[i]);
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedules_interpolate_and_reject_bad_points() {
        let s = Schedule::new(vec![(0.1, 0.0), (0.3, 1.0), (0.4, 0.2)]).unwrap();
        assert_eq!(s.value(0.0), 0.0);
        assert!((s.value(0.2) - 0.5).abs() < 1e-12);
        assert!((s.value(0.35) - 0.6).abs() < 1e-12);
        assert_eq!(s.value(9.0), 0.2);
        assert!(Schedule::new(vec![]).is_err());
        assert!(Schedule::new(vec![(0.0, 1.5)]).is_err());
        assert!(Schedule::new(vec![(0.2, 0.5), (0.1, 0.5)]).is_err());
        assert!(Schedule::new(vec![(f64::NAN, 0.5)]).is_err());
    }
}
