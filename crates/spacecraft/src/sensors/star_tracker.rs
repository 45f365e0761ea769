//! [`StarTracker`]: the body's attitude, times a small random rotation about its axes.
//!
//! Reading: `q ⊗ exp(δθ / 2)`, `q` the body's attitude quaternion `[w, x, y, z]` (body to
//! inertial), `δθ_i ~ N(0, noise_i)` about the body's axes (`noise_arcsec` in the scene),
//! `exp(δθ / 2) = [cos(|δθ|/2), sin(|δθ|/2) δθ/|δθ|]`. Of the two quaternions of the
//! measured attitude the one with `w >= 0` is given.

use super::{Draws, Pose};
use crate::effects::quat_mul;

/// Arc seconds to radians.
pub const ARCSEC: f64 = std::f64::consts::PI / (180.0 * 3600.0);

/// A star tracker's noise.
#[derive(Clone, Debug, PartialEq)]
pub struct StarTracker {
    /// Standard deviation of the error rotation about the body's x, y, z axes (rad).
    pub noise: [f64; 3],
}

impl StarTracker {
    /// The largest noise a scene accepts (arc seconds, 1σ, per axis): half a turn, past
    /// which the reading says nothing of the attitude.
    pub const MAX_NOISE_ARCSEC: f64 = 648_000.0;
    /// A star tracker of noise `noise_arcsec` (arc seconds, 1σ, about the body's x, y, z).
    pub fn from_arcsec(noise_arcsec: [f64; 3]) -> Self {
        Self {
            noise: noise_arcsec.map(|a| a * ARCSEC),
        }
    }
    pub(super) fn read(&self, pose: &Pose, d: &mut Draws, out: &mut [f64; 4]) {
        let q = pose.attitude.quaternion();
        let q = [q.w, q.i, q.j, q.k];
        let dt = d.vec3(self.noise);
        let angle = dt.norm();
        let dq = if angle == 0.0 {
            [1.0, 0.0, 0.0, 0.0]
        } else {
            let (s, c) = (0.5 * angle).sin_cos();
            let a = dt * (s / angle);
            [c, a.x, a.y, a.z]
        };
        let m = quat_mul(&q, &dq);
        let sign = if m[0] < 0.0 { -1.0 } else { 1.0 };
        *out = m.map(|v| sign * v);
    }
}
