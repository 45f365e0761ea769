//! Built-in flight software (contract section 16): discrete blocks that read the sensors,
//! never the truth.
//!
//! - [`mekf`](crate::fsw::mekf): [`Mekf`](crate::fsw::Mekf), the multiplicative extended
//!   Kalman filter for the attitude and the gyro bias, on attitude (star tracker) or
//!   direction (Sun sensor, magnetometer) updates; [`triad`](mod@crate::fsw::triad) starts it
//!   from two directions.
//! - [`estimator`](crate::fsw::estimator): the filter wired to a gyro and a star tracker
//!   (`[fsw.estimator] kind = "mekf"`) or to a Sun sensor and a magnetometer (`"sun_mag"`,
//!   the safe mode's).
//! - [`guidance`](crate::fsw::guidance): [`Guidance`](crate::fsw::Guidance), the reference
//!   attitude, rate and acceleration (`[fsw.guidance] mode = "inertial"`, `"nadir"`,
//!   `"sun"`, `"target"`), shaped by [`slew`](crate::fsw::slew) within `max_rate` and
//!   `max_acceleration`.
//! - [`control`](crate::fsw::control): [`Pid`](crate::fsw::Pid), the attitude PID on the
//!   estimate's error to the reference, and its least-squares
//!   [`Allocation`](crate::fsw::Allocation) to the reaction wheels or the torquers
//!   (`[fsw.control] kind = "pid"`); [`thrust`](crate::fsw::thrust): its
//!   [`ThrustAllocation`](crate::fsw::ThrustAllocation) to thrusters, which only push
//!   (non-negative least squares, [`nnls`](crate::fsw::nnls)).
//! - [`magnetic`](crate::fsw::magnetic): B-dot on the magnetometer's readings
//!   (`[fsw.bdot]`) and wheel momentum dumping (`[fsw.momentum]`), both on the magnetic
//!   torquers ([`DipoleSpec`](crate::fsw::DipoleSpec)).
//! - [`modes`](crate::fsw::modes): [`Mode`](crate::fsw::Mode), which blocks run and the
//!   [`Condition`](crate::fsw::Condition) that ends it (`[[fsw.mode]]`).
//! - [`onboard`](crate::fsw::onboard): [`Onboard`](crate::fsw::Onboard), the blocks wired to a
//!   scene's sensors, clocked by them and run in modes (hosted by the
//!   [`Sensors`](crate::sensors::Sensors) effect, so that they read the readings taken at
//!   the same instant).
//!
//! Each block is a plain type that the wiring drives on its own clock; the filter and the
//! law know nothing of scenes or of the simulation.

pub mod control;
pub mod estimator;
pub mod guidance;
pub mod magnetic;
pub mod mekf;
pub mod modes;
pub mod onboard;
pub mod slew;
pub mod thrust;
pub mod triad;

pub use control::{Allocation, Pid, inertia_is_valid};
pub use estimator::{Aiding, EstimatorSpec, gyro_mean};
pub use guidance::{Guidance, Reference, geodetic_to_itrf};
pub use magnetic::{DipoleLaw, DipoleSpec, bdot_dipole, momentum_dipole};
pub use mekf::{GyroModel, Mekf, MekfParams, SteadyState, attitude_error, steady_state};
pub use modes::{Condition, Mode};
pub use onboard::{Actuator, ControlSpec, Onboard};
pub use slew::Slew;
pub use thrust::{ThrustAllocation, nnls};
pub use triad::{TRIAD_MIN_SIN, triad, triad_covariance};
