//! [`Guidance`]: the reference attitude and rate the control points the body at
//! (`[fsw.guidance]`, contract section 16).
//!
//! - [`Guidance::Inertial`]: a fixed attitude `q_ref` (body to inertial), `ω_ref = 0`.
//! - [`Guidance::Nadir`]: the local orbital frame (LVLH) of
//!   [`OrbitState::orbital_frame`] — z towards the Earth's centre, y along the negative
//!   orbit normal `−r × v`, x = y × z (along the velocity on a circular orbit) — times a fixed
//!   offset, turning at [`OrbitState::orbital_rate`] `r × v / r²`: the same frame as
//!   `[effects.attitude_control] target = "orbital"` and the state file's
//!   `frame = "orbital"`.
//!
//! The reference rate is given in the reference's own axes (the body axes the reference
//! asks for): for nadir on a circular orbit `(0, −n, 0)`, `n` the mean motion. Guidance reads
//! the orbit (position and velocity of the centre of mass): the orbit is not a sensor, so
//! the nadir reference is the true orbital frame, as a flight computer with a perfect
//! on-board orbit would have it.

use crate::effects::OrbitState;
use nalgebra::{UnitQuaternion, Vector3};

/// A guidance law (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Guidance {
    /// A fixed inertial attitude (body to inertial).
    Inertial(UnitQuaternion<f64>),
    /// The local orbital frame times this offset (body to orbital).
    Nadir(UnitQuaternion<f64>),
}

/// A reference: the attitude (body to inertial) and the rate (rad/s, in the reference's
/// axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    /// Attitude, body to inertial.
    pub attitude: UnitQuaternion<f64>,
    /// Angular velocity, the reference's axes (rad/s).
    pub rate: Vector3<f64>,
}

impl Guidance {
    /// Whether the law reads the orbit.
    pub fn needs_orbit(&self) -> bool {
        matches!(self, Guidance::Nadir(_))
    }
    /// The reference at an instant where the orbit is `orbit` (an error when the law needs
    /// it and there is none).
    ///
    /// ```
    /// use nalgebra::{UnitQuaternion, Vector3};
    /// use satsim_spacecraft::effects::OrbitState;
    /// use satsim_spacecraft::fsw::Guidance;
    /// let o = OrbitState { r: Vector3::new(7e6, 0.0, 0.0), v: Vector3::new(0.0, 7.5e3, 0.0), mu: 3.986e14 };
    /// let r = Guidance::Nadir(UnitQuaternion::identity()).reference(Some(&o)).unwrap();
    /// assert_eq!(r.attitude, o.orbital_frame());
    /// assert!((r.rate - Vector3::new(0.0, -7.5e3 / 7e6, 0.0)).norm() < 1e-18);
    /// ```
    pub fn reference(&self, orbit: Option<&OrbitState>) -> Result<Reference, String> {
        match self {
            Guidance::Inertial(q) => Ok(Reference {
                attitude: *q,
                rate: Vector3::zeros(),
            }),
            Guidance::Nadir(offset) => {
                let o = orbit.ok_or("fsw.guidance mode = \"nadir\" needs an orbit")?;
                let lvlh = o.orbital_frame();
                let attitude = if *offset == UnitQuaternion::identity() {
                    lvlh
                } else {
                    lvlh * offset
                };
                let rate = attitude.inverse_transform_vector(&o.orbital_rate());
                Ok(Reference { attitude, rate })
            }
        }
    }
}
