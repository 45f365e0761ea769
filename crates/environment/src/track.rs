//! [`Track`]: a body's ephemeris along a run, computed at knots a fixed step apart and
//! interpolated linearly in between (the Sun's and the Moon's, [`crate::sun::SunTrack`] and
//! [`crate::moon::MoonTrack`]). The knots depend only on `t`, so the result does not depend on
//! the order of the calls (a campaign's runs, a restarted step, the environment report all see
//! the same positions).

use crate::{Epoch, Vec3};

/// An ephemeris `at(epoch, t)` at knots `step` seconds apart, interpolated in between.
#[derive(Clone, Debug)]
pub struct Track {
    epoch: Epoch,
    step: f64,
    at: fn(Epoch, f64) -> Vec3,
    knot: i64,
    at_knot: Vec3,
    at_next: Vec3,
}

impl Track {
    /// The ephemeris `at` along a run that starts at `epoch`, knots `step` (s) apart.
    pub fn new(epoch: Epoch, step: f64, at: fn(Epoch, f64) -> Vec3) -> Self {
        Self {
            epoch,
            step,
            at,
            knot: i64::MIN,
            at_knot: Vec3::zeros(),
            at_next: Vec3::zeros(),
        }
    }

    /// The position (m, GCRF, from the Earth's centre) at `epoch + t`.
    pub fn position(&mut self, t: f64) -> Vec3 {
        let s = t / self.step;
        let k = s.floor();
        if !k.is_finite() {
            return (self.at)(self.epoch, t);
        }
        let knot = k as i64;
        if knot != self.knot {
            self.at_knot = (self.at)(self.epoch, k * self.step);
            self.at_next = (self.at)(self.epoch, (k + 1.0) * self.step);
            self.knot = knot;
        }
        self.at_knot + (self.at_next - self.at_knot) * (s - k)
    }
}
