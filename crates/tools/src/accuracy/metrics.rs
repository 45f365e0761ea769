//! The error of a run against the reference: per state ([`StateError`]) and over a
//! trajectory ([`ErrorMetrics`], [`compare`]).

use super::trajectory::Trajectory;
use satsim_spacecraft::simulation::StateLayout;

/// The rotation angle (rad, in `[0, π]`) of `q_ref⁻¹ ⊗ q` for Hamilton quaternions
/// `[w, x, y, z]` (normalised here, so a slightly denormalised input is fine).
pub fn attitude_angle(q_ref: &[f64], q: &[f64]) -> f64 {
    let (a, b) = (q_ref, q);
    // conj(a) ⊗ b
    let w = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    let x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
    let y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
    let z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
    let v = (x * x + y * y + z * z).sqrt();
    2.0 * v.atan2(w.abs())
}

/// Errors of one state against a reference state at the same time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StateError {
    /// Bus attitude error (rad); 0 for a fixed base.
    pub attitude: f64,
    /// Largest hinge angle error (rad).
    pub angles: f64,
    /// Largest bus angular velocity component or hinge rate error (rad/s).
    pub rates: f64,
}

impl StateError {
    /// `x` against `x_ref`.
    pub fn of(layout: &StateLayout, x_ref: &[f64], x: &[f64]) -> Self {
        let max_diff = |r: std::ops::Range<usize>| {
            r.map(|i| (x[i] - x_ref[i]).abs()).fold(0.0, |m: f64, d| {
                if d.is_nan() { f64::NAN } else { m.max(d) }
            })
        };
        let attitude = if layout.free {
            let a = layout.attitude.clone();
            attitude_angle(&x_ref[a.clone()], &x[a])
        } else {
            0.0
        };
        Self {
            attitude,
            angles: max_diff(layout.angles.clone()),
            rates: max_diff(layout.omega.clone()).max(max_diff(layout.rates.clone())),
        }
    }
    /// The largest of the three (NaN if any is NaN).
    pub fn max(&self) -> f64 {
        let v = [self.attitude, self.angles, self.rates];
        if v.iter().any(|e| e.is_nan()) {
            return f64::NAN;
        }
        v.into_iter().fold(0.0, f64::max)
    }
}

/// The error of a run against a reference, see the module documentation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorMetrics {
    /// The three errors at the final time.
    pub at_end: StateError,
    /// `max` of [`ErrorMetrics::at_end`]: the headline error.
    pub final_max: f64,
    /// RMS over the saved times of the per-time largest error.
    pub rms: f64,
    /// Largest per-time error over the saved times.
    pub max_over_time: f64,
}

/// Compares two trajectories saved at the same times. Every metric returned is finite (an
/// overflowing difference is an error).
pub fn compare(
    layout: &StateLayout,
    reference: &Trajectory,
    run: &Trajectory,
) -> Result<ErrorMetrics, String> {
    if reference.times.len() != run.times.len()
        || reference
            .times
            .iter()
            .zip(&run.times)
            .any(|(a, b)| (a - b).abs() > 1e-9 * a.abs().max(1.0))
    {
        return Err(format!(
            "saved times differ ({} against {} rows)",
            run.times.len(),
            reference.times.len()
        ));
    }
    let Some((last_ref, last)) = reference.states.last().zip(run.states.last()) else {
        return Err("no saved state".into());
    };
    let at_end = StateError::of(layout, last_ref, last);
    let mut sum = 0.0;
    let mut worst: f64 = 0.0;
    for (a, b) in reference.states.iter().zip(&run.states) {
        let e = StateError::of(layout, a, b).max();
        sum += e * e;
        worst = if e.is_nan() { f64::NAN } else { worst.max(e) };
    }
    let m = ErrorMetrics {
        at_end,
        final_max: at_end.max(),
        rms: (sum / run.states.len() as f64).sqrt(),
        max_over_time: worst,
    };
    // A non-finite error is never reported as a measurement.
    if [m.final_max, m.rms, m.max_over_time]
        .iter()
        .all(|e| e.is_finite())
    {
        Ok(m)
    } else {
        Err("the error against the reference is not finite (the states overflow)".into())
    }
}
