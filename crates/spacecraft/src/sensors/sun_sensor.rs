//! [`SunSensor`]: the unit vector from the spacecraft to the Sun, in the sensor's axes (the
//! body's, turned by its [misalignment](super::mounting) when it has one).
//!
//! The Sun is [`sun_position`] (from the scene's `epoch`), seen from the centre of mass (the
//! parallax over the spacecraft is negligible); the Earth's shadow is [`shadow_fraction`]
//! with the solar-pressure effect's model when it is enabled, else the conical one. In umbra
//! (lit fraction 0) the reading is zeros; with any part of the Sun's disk visible (penumbra
//! included) it is the unit vector, turned by a small random rotation `δθ_i ~ N(0, noise)`
//! about the sensor's axes.

use super::{Draws, Pose};
use nalgebra::UnitQuaternion;
use satsim_environment::Epoch;
use satsim_environment::shadow::{ShadowModel, shadow_fraction};
use satsim_environment::sun::sun_position;
use satsim_tree::spatial::Vec3;

/// A Sun sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct SunSensor {
    /// t = 0 as a date.
    pub epoch: Epoch,
    /// The Earth's shadow.
    pub shadow: ShadowModel,
    /// Standard deviation of the error rotation about each sensor axis (rad).
    pub noise: f64,
}

impl SunSensor {
    pub(super) fn read(
        &self,
        pose: &Pose,
        d: &mut Draws,
        out: &mut [f64; 6],
    ) -> Result<(), String> {
        let orbit = pose
            .orbit
            .ok_or("a Sun sensor needs an orbit (an [orbit] table)")?;
        let r_sun = sun_position(self.epoch, pose.t);
        let lit = shadow_fraction(self.shadow, &orbit.r, &r_sun);
        let err = d.vec3([self.noise; 3]);
        let s = if lit > 0.0 {
            let s = pose.to_body(&(r_sun - orbit.r).normalize());
            if self.noise > 0.0 {
                UnitQuaternion::from_scaled_axis(err) * s
            } else {
                s
            }
        } else {
            Vec3::zeros()
        };
        out[..3].copy_from_slice(s.as_slice());
        Ok(())
    }
}
