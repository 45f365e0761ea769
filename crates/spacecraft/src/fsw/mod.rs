//! Built-in flight software (contract section 16): discrete blocks that read the sensors,
//! never the truth.
//!
//! - [`mekf`](crate::fsw::mekf): [`Mekf`](crate::fsw::Mekf), the multiplicative extended
//!   Kalman filter for the attitude and the gyro bias from a gyro and one or more star
//!   trackers (`[fsw.estimator] kind = "mekf"`).
//! - [`guidance`](crate::fsw::guidance): [`Guidance`](crate::fsw::Guidance), the reference
//!   attitude and rate (`[fsw.guidance] mode = "inertial"` or `"nadir"`).
//! - [`control`](crate::fsw::control): [`Pid`](crate::fsw::Pid), the attitude PID on the
//!   estimate's error to the reference and its least-squares allocation to the reaction
//!   wheels (`[fsw.control] kind = "pid"`, `actuator = "wheels"`).
//! - [`magnetic`](crate::fsw::magnetic): B-dot on the magnetometer's readings
//!   (`[fsw.bdot]`) and wheel momentum dumping (`[fsw.momentum]`), both on the magnetic
//!   torquers ([`DipoleSpec`](crate::fsw::DipoleSpec)).
//! - [`onboard`](crate::fsw::onboard): [`Onboard`](crate::fsw::Onboard), the blocks wired to a
//!   scene's sensors and clocked by them (hosted by the
//!   [`Sensors`](crate::sensors::Sensors) effect, so that they read the readings taken at
//!   the same instant).
//!
//! Each block is a plain type that the wiring drives on its own clock; the filter and the
//! law know nothing of scenes or of the simulation.

pub mod control;
pub mod guidance;
pub mod magnetic;
pub mod mekf;
pub mod onboard;

pub use control::Pid;
pub use guidance::{Guidance, Reference};
pub use magnetic::{DipoleLaw, DipoleSpec, bdot_dipole, momentum_dipole};
pub use mekf::{GyroModel, Mekf, MekfParams, SteadyState, attitude_error, steady_state};
pub use onboard::{ControlSpec, EstimatorSpec, Onboard};
