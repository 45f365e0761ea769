//! Built-in flight software (contract section 16): discrete blocks that read the sensors,
//! never the truth.
//!
//! - [`mekf`](crate::fsw::mekf): [`Mekf`](crate::fsw::Mekf), the multiplicative extended
//!   Kalman filter for the attitude and the gyro bias from a gyro and one or more star
//!   trackers (`[fsw.estimator] kind = "mekf"`).
//!
//! Each block is a plain, allocation-free-per-step type that the scene wiring drives on its
//! own clock; it knows nothing of scenes or of the simulation.

pub mod mekf;

pub use mekf::{GyroModel, Mekf, MekfParams, SteadyState, attitude_error, steady_state};
