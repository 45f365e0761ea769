//! [`Magnetometer`]: the geomagnetic field at the centre of mass in the sensor's axes (T:
//! the body's, turned by its [misalignment](super::mounting) when it has one), plus
//! white noise `N(0, noise)` per axis; the field model and epoch are those of the scene's
//! `[effects.magnetic]`, so that without noise the reading on the root body is that
//! effect's `magnetic_field_*` columns.

use super::{Draws, Pose};
use satsim_environment::magnetic::GeoField;

/// A magnetometer.
#[derive(Clone, Debug)]
pub struct Magnetometer {
    /// The field model (from the scene's epoch).
    pub field: GeoField,
    /// Per-sample standard deviation of the noise on each axis (T).
    pub noise: f64,
}

impl Magnetometer {
    pub(super) fn read(
        &self,
        pose: &Pose,
        d: &mut Draws,
        out: &mut [f64; 6],
    ) -> Result<(), String> {
        let orbit = pose
            .orbit
            .ok_or("a magnetometer needs an orbit (an [orbit] table)")?;
        let b = pose.to_body(&self.field.field_gcrf(pose.t, &orbit.r)) + d.vec3([self.noise; 3]);
        out[..3].copy_from_slice(b.as_slice());
        Ok(())
    }
}
