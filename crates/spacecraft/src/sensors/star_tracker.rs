//! [`StarTracker`]: the attitude of the sensor's frame, times a small random rotation about
//! its axes; with an [`Exclusion`], flagged invalid when the Sun or the Earth is too near the
//! boresight.
//!
//! Reading: `q ⊗ exp(δθ / 2)`, `q` the attitude quaternion `[w, x, y, z]` of the sensor's
//! frame (sensor to inertial: the body's, times the [misalignment](super::mounting)'s
//! `q_R` when there is one), `δθ_i ~ N(0, noise_i)` about the sensor's axes (`noise_arcsec`
//! in the scene), `exp(δθ / 2) = [cos(|δθ|/2), sin(|δθ|/2) δθ/|δθ|]`. Of the two
//! quaternions of the measured attitude the one with `w >= 0` is given.
//!
//! The boresight is the sensor's `+z` axis (the body's `+z` without a misalignment): the
//! axis about which `noise_arcsec`'s third, usually larger, value (the roll about the line
//! of sight) acts. With an [`Exclusion`] the reading is invalid when the true boresight
//! (before the noise) is less than `sun` from the direction of the Sun (from the spacecraft,
//! eclipsed or not), or less than `earth` from the Earth's limb: the angle between the
//! boresight and the nadir (`−r / |r|`) less than the Earth's angular radius
//! `asin(R_EARTH / |r|)` plus `earth`. An invalid sample's reading is not taken: the
//! sensor holds its last valid reading (zeros before the first), and its validity is 0.

use super::{Draws, Pose};
use crate::effects::quat_mul;
use satsim_environment::sun::sun_position;
use satsim_environment::{Epoch, R_EARTH};
use satsim_tree::spatial::Vec3;

/// Arc seconds to radians.
pub const ARCSEC: f64 = std::f64::consts::PI / (180.0 * 3600.0);

/// A star tracker's noise and exclusion angles.
#[derive(Clone, Debug, PartialEq)]
pub struct StarTracker {
    /// Standard deviation of the error rotation about the sensor's x, y, z axes (rad).
    pub noise: [f64; 3],
    /// The exclusion angles, if any (then the tracker has a validity).
    pub exclusion: Option<Exclusion>,
}

/// A star tracker's exclusion angles (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Exclusion {
    /// The least angle between the boresight and the Sun (rad), with the epoch of the
    /// Sun's series; `None`: no Sun exclusion.
    pub sun: Option<(f64, Epoch)>,
    /// The least angle between the boresight and the Earth's limb (rad); `None`: no Earth
    /// exclusion.
    pub earth: Option<f64>,
}

impl Exclusion {
    /// Whether the boresight `axis` (unit, inertial) at time `t` and position `r` (m, from
    /// the Earth's centre, inertial) is clear of the Sun and the Earth.
    pub fn clear(&self, axis: &Vec3, t: f64, r: &Vec3) -> bool {
        if let Some((limit, epoch)) = self.sun {
            let sun = sun_position(epoch, t) - r;
            if angle(axis, &sun) < limit {
                return false;
            }
        }
        if let Some(limit) = self.earth {
            let d = r.norm();
            let radius = (R_EARTH / d).min(1.0).asin();
            if angle(axis, &(-r)) < radius + limit {
                return false;
            }
        }
        true
    }
}

/// The angle between two non-zero vectors (rad, in [0, π]).
fn angle(a: &Vec3, b: &Vec3) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

impl StarTracker {
    /// The largest noise a scene accepts (arc seconds, 1σ, per axis): half a turn, past
    /// which the reading says nothing of the attitude.
    pub const MAX_NOISE_ARCSEC: f64 = 648_000.0;
    /// A star tracker of noise `noise_arcsec` (arc seconds, 1σ, about the sensor's x, y, z),
    /// without exclusion.
    pub fn from_arcsec(noise_arcsec: [f64; 3]) -> Self {
        Self {
            noise: noise_arcsec.map(|a| a * ARCSEC),
            exclusion: None,
        }
    }
    /// The same tracker with the exclusion angles `exclusion`.
    pub fn with_exclusion(mut self, exclusion: Exclusion) -> Self {
        self.exclusion = Some(exclusion);
        self
    }
    /// The reading into `out[..4]`, and whether it is valid (always without an exclusion).
    pub(super) fn read(
        &self,
        pose: &Pose,
        d: &mut Draws,
        out: &mut [f64; 6],
    ) -> Result<bool, String> {
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
        out[..4].copy_from_slice(&m.map(|v| sign * v));
        let Some(ex) = &self.exclusion else {
            return Ok(true);
        };
        let orbit = pose
            .orbit
            .ok_or("a star tracker's `exclusion_deg` needs an orbit (an [orbit] table)")?;
        let boresight = pose.attitude * Vec3::z();
        Ok(ex.clear(&boresight, pose.t, &orbit.r))
    }
}
