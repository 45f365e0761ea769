//! [`Gps`]: a GPS receiver's navigation solution, the centre of mass's position and
//! velocity in the GCRF (the orbit's inertial frame, m and m/s) plus white noise.
//!
//! Reading `[x, y, z, vx, vy, vz]`: `r + N(0, noise_position)` and `v + N(0, noise_velocity)`
//! per axis, drawn in that order (the position's three, then the velocity's). The antenna's
//! offset from the centre of mass and the receiver's clock are not modelled: the reading
//! does not depend on the body's attitude, and the body only names where the receiver is.

use super::{Draws, Pose};

/// A GPS receiver.
#[derive(Clone, Debug, PartialEq)]
pub struct Gps {
    /// Per-sample standard deviation of the position's noise on each axis (m).
    pub noise_position: f64,
    /// Per-sample standard deviation of the velocity's noise on each axis (m/s).
    pub noise_velocity: f64,
}

impl Gps {
    /// The reading into `out[..6]`.
    pub(super) fn read(
        &self,
        pose: &Pose,
        d: &mut Draws,
        out: &mut [f64; 6],
    ) -> Result<(), String> {
        let orbit = pose
            .orbit
            .ok_or("a GPS receiver needs an orbit (an [orbit] table)")?;
        let r = orbit.r + d.vec3([self.noise_position; 3]);
        let v = orbit.v + d.vec3([self.noise_velocity; 3]);
        out[..3].copy_from_slice(r.as_slice());
        out[3..].copy_from_slice(v.as_slice());
        Ok(())
    }
}
