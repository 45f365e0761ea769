//! The Earth's shadow: the fraction of the Sun's disk seen from a satellite.
//!
//! Conical: the apparent disks of the Sun and the Earth as seen from the satellite, and the
//! area of their overlap (Montenbruck & Gill, Satellite Orbits, 2000, section 3.4.2), with
//! the Sun's radius 696 000 km and the Earth's [`R_EARTH`] (a sphere: the flattening moves
//! the shadow's edge by up to 21 km, a few seconds of a low orbit). Cylindrical: the Earth's
//! shadow as a cylinder of radius [`R_EARTH`] along the Sun's direction, no penumbra.

use crate::{R_EARTH, Vec3};
use std::f64::consts::PI;

/// The Sun's radius (m), the value Montenbruck & Gill use.
pub const R_SUN: f64 = 696_000e3;

/// How the Earth's shadow is modelled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ShadowModel {
    /// Umbra and penumbra from the apparent disks of the Sun and the Earth.
    #[default]
    Conical,
    /// A cylinder behind the Earth: all or nothing.
    Cylindrical,
    /// No shadow: always in full sun.
    None,
}

impl ShadowModel {
    /// The model named `name` ("conical", "cylindrical", "none"), or `None` for another name.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "conical" => Some(Self::Conical),
            "cylindrical" => Some(Self::Cylindrical),
            "none" => Some(Self::None),
            _ => None,
        }
    }

    /// The model's name, as [`ShadowModel::from_name`] reads it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Conical => "conical",
            Self::Cylindrical => "cylindrical",
            Self::None => "none",
        }
    }
}

/// The fraction ν in [0, 1] of the Sun's disk seen from `r_sat` (1: full sun; 0: umbra),
/// both positions from the Earth's centre (m, GCRF). A satellite inside the Earth (|r| <=
/// R_E) sees no Sun (0 with the conical and cylindrical models); a NaN position gives NaN.
///
/// ```
/// use satsim_environment::{Vec3, shadow::{ShadowModel, shadow_fraction}};
/// let sun = Vec3::new(1.496e11, 0.0, 0.0);
/// let behind = Vec3::new(-7.0e6, 0.0, 0.0);
/// assert_eq!(shadow_fraction(ShadowModel::Conical, &behind, &sun), 0.0);
/// assert_eq!(shadow_fraction(ShadowModel::Cylindrical, &-behind, &sun), 1.0);
/// ```
pub fn shadow_fraction(model: ShadowModel, r_sat: &Vec3, r_sun: &Vec3) -> f64 {
    match model {
        ShadowModel::None => 1.0,
        ShadowModel::Cylindrical => cylindrical(r_sat, r_sun),
        ShadowModel::Conical => conical(r_sat, r_sun),
    }
}

fn cylindrical(r: &Vec3, r_sun: &Vec3) -> f64 {
    let s = r_sun.normalize();
    let along = r.dot(&s);
    let off_axis = (r - s * along).norm();
    if r.norm() <= R_EARTH || (along < 0.0 && off_axis < R_EARTH) {
        0.0
    } else if r.iter().chain(r_sun.iter()).any(|x| x.is_nan()) {
        f64::NAN
    } else {
        1.0
    }
}

fn conical(r: &Vec3, r_sun: &Vec3) -> f64 {
    let to_sun = r_sun - r;
    let (d_sat, d_sun) = (r.norm(), to_sun.norm());
    if d_sat <= R_EARTH {
        return 0.0;
    }
    // Apparent radii of the Sun (a) and the Earth (b), and their centres' separation (c).
    let a = (R_SUN / d_sun).min(1.0).asin();
    let b = (R_EARTH / d_sat).asin();
    let c = (-r.dot(&to_sun) / (d_sat * d_sun)).clamp(-1.0, 1.0).acos();
    if c >= a + b {
        1.0
    } else if c <= b - a {
        0.0
    } else if c <= a - b {
        // Annular: the Earth's disk wholly inside the Sun's.
        1.0 - (b * b) / (a * a)
    } else {
        // Partial overlap of two circles (Montenbruck & Gill eq. 3.87), written as the two
        // circular segments either side of the common chord: half-chord y from Heron's
        // formula (the small factor a + b − c taken directly), the half-angles by atan2, so
        // that a sliver of overlap is not lost in the cancellation of b²-sized terms.
        let x = (c * c + a * a - b * b) / (2.0 * c);
        let heron = (a + b + c) * (b + c - a) * (a + c - b) * (a + b - c);
        let y = heron.max(0.0).sqrt() / (2.0 * c);
        let area = a * a * segment(y.atan2(x)) + b * b * segment(y.atan2(c - x));
        (1.0 - area / (PI * a * a)).clamp(0.0, 1.0)
    }
}

/// The area of the circular segment of half-angle `t` in a unit circle, t − sin t cos t, by
/// its series where the difference would cancel.
fn segment(t: f64) -> f64 {
    let u = 2.0 * t;
    if u.abs() < 1e-2 {
        // (u − sin u) / 2 = (u³/6 − u⁵/120 + u⁷/5040 − …) / 2.
        let u2 = u * u;
        u * u2 / 12.0 * (1.0 - u2 / 20.0 * (1.0 - u2 / 42.0))
    } else {
        (u - u.sin()) / 2.0
    }
}
