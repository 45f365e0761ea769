//! [`CoarseSun`]: a coarse Sun sensor, one photodiode of cosine response.
//!
//! Reading: `scale · (f · max(0, cos θ) + a) + w`, with
//!
//! - `θ` the angle between the photodiode's `normal` (unit, sensor axes: the body's, turned by
//!   its [misalignment](super::mounting) when it has one) and the direction from the
//!   spacecraft to the Sun ([`sun_position`] from the scene's `epoch`); the direct term is 0
//!   outside the field of view (`θ > fov`, `fov` the half-angle, at most 90°);
//! - `f` the lit fraction of the Sun's disk ([`shadow_fraction`], the Sun sensor's shadow
//!   model): 1 in sunlight, 0 in umbra, between in penumbra; the Sun's flux is taken as 1 at
//!   any distance (a normalised output: `scale` is the reading at normal incidence);
//! - `a` the Earth's reflected light when `albedo` is on, else 0: the Earth a sphere of
//!   radius [`R_EARTH`] and uniform albedo [`ALBEDO`], a Lambertian reflector whose radiance
//!   is that of the sub-spacecraft point under the Sun, `a = ALBEDO · max(0, ŝ · r̂) · F`,
//!   `ŝ` the Sun's direction from the Earth's centre, `r̂` the spacecraft's, and `F`
//!   [`sphere_view_factor`], the view factor from the photodiode (a plate tilted by `β`
//!   from the nadir) to the Earth's sphere. The field of view limits the direct Sun only:
//!   the Earth is seen over the photodiode's whole hemisphere. For a photodiode facing the
//!   nadir `F = (R_EARTH / |r|)²`;
//! - `w ~ N(0, noise)` (one draw per sample); the reading is not clipped at 0.

use super::{Draws, Pose};
use satsim_environment::shadow::{ShadowModel, shadow_fraction};
use satsim_environment::sun::sun_position;
use satsim_environment::{Epoch, R_EARTH};
use satsim_tree::spatial::Vec3;

// The Earth's light as the effects see it (`[effects.solar_radiation] albedo`): one model.
pub use satsim_environment::earth_radiation::{ALBEDO, sphere_view_factor};

/// A coarse Sun sensor (one photodiode).
#[derive(Clone, Debug, PartialEq)]
pub struct CoarseSun {
    /// t = 0 as a date.
    pub epoch: Epoch,
    /// The Earth's shadow.
    pub shadow: ShadowModel,
    /// The photodiode's normal (unit, sensor axes).
    pub normal: Vec3,
    /// The field of view's half-angle (rad, in (0, π/2]).
    pub fov: f64,
    /// The reading at normal incidence in full sunlight.
    pub scale: f64,
    /// Per-sample standard deviation of the additive noise.
    pub noise: f64,
    /// Whether the Earth's reflected light is added.
    pub albedo: bool,
}

impl CoarseSun {
    /// The reading into `out[0]`.
    pub(super) fn read(
        &self,
        pose: &Pose,
        d: &mut Draws,
        out: &mut [f64; 6],
    ) -> Result<(), String> {
        let orbit = pose
            .orbit
            .ok_or("a coarse Sun sensor needs an orbit (an [orbit] table)")?;
        let r_sun = sun_position(self.epoch, pose.t);
        let lit = shadow_fraction(self.shadow, &orbit.r, &r_sun);
        let s = pose.to_body(&(r_sun - orbit.r).normalize());
        let c = self.normal.dot(&s);
        let direct = if lit > 0.0 && c > 0.0 && c >= self.fov.cos() {
            lit * c
        } else {
            0.0
        };
        let earth = if self.albedo {
            let r = orbit.r.norm();
            let day = r_sun.normalize().dot(&(orbit.r / r)).max(0.0);
            let nadir = pose.to_body(&(-orbit.r / r));
            ALBEDO * day * sphere_view_factor(self.normal.dot(&nadir), r / R_EARTH)
        } else {
            0.0
        };
        out[0] = self.scale * (direct + earth) + d.normal(self.noise);
        Ok(())
    }
}
