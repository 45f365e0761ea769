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
use std::f64::consts::PI;

/// The Earth's uniform albedo (the Bond albedo, 0.3).
pub const ALBEDO: f64 = 0.3;

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

/// The view factor from a small plate to a sphere: the plate at `h` radii from the
/// sphere's centre (`h >= 1`), its normal at `β` from the direction to the centre
/// (`cos_beta = cos β`). The closed form (Howell's catalogue of configuration factors,
/// "differential planar element to sphere"): `cos β / h²` while the whole sphere is above the
/// plate's horizon (`cos β >= 1/h`); 0 when none of it is (`cos β <= −1/h`); between,
///
/// `1/2 − asin(x / (h sin β)) / π + (cos β acos(−x cot β) − x √(1 − h² cos² β)) / (π h²)`,
/// `x = √(h² − 1)`.
///
/// ```
/// use satsim_spacecraft::sensors::coarse_sun::sphere_view_factor;
/// assert_eq!(sphere_view_factor(1.0, 2.0), 0.25); // facing the centre: (R / r)²
/// assert_eq!(sphere_view_factor(-0.6, 2.0), 0.0);  // facing away
/// ```
pub fn sphere_view_factor(cos_beta: f64, h: f64) -> f64 {
    let h = h.max(1.0);
    let cos_beta = cos_beta.clamp(-1.0, 1.0);
    let h2 = h * h;
    if cos_beta * h >= 1.0 {
        return cos_beta / h2;
    }
    if cos_beta * h <= -1.0 {
        return 0.0;
    }
    let sin_beta = (1.0 - cos_beta * cos_beta).sqrt();
    let x = (h2 - 1.0).sqrt();
    let a = (x / (h * sin_beta)).min(1.0).asin();
    let b = (-x * cos_beta / sin_beta).clamp(-1.0, 1.0).acos();
    let c = (1.0 - h2 * cos_beta * cos_beta).max(0.0).sqrt();
    (0.5 - a / PI + (cos_beta * b - x * c) / (PI * h2)).max(0.0)
}
