//! ODE integrators for satsim, written in-house: classic RK4, Dormand-Prince
//! 5(4), Hairer's DOP853 and the implicit Radau IIA (order 5), with dense
//! output, event location (with reset/stop actions) and a projection hook.
//!
//! The state is a flat `&[f64]`; a problem implements [`System`] and is run
//! by [`integrate`]. All work buffers are allocated once per run; the step
//! loop does not allocate (except to record located events). Several runs of
//! one fixed-step scene can advance in lockstep, each stage's right-hand sides
//! evaluated together ([`lanes::integrate_lanes`]).
//!
//! ```
//! use std::ops::ControlFlow;
//! use satsim_integrate::{integrate, Method, Options, Output, System, SystemError};
//!
//! /// x'' = -x, x(0) = 1.
//! struct Oscillator;
//! impl System for Oscillator {
//!     fn dim(&self) -> usize { 2 }
//!     fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
//!         dx[0] = x[1];
//!         dx[1] = -x[0];
//!         Ok(())
//!     }
//! }
//!
//! let method: Method = "dp54".parse().unwrap();
//! let opts = Options::new(method).with_tolerances(1e-9, 1e-12);
//! let stats = integrate(&mut Oscillator, &opts, 0.0, &[1.0, 0.0], 1.0,
//!                       &Output::Times(vec![]), |_, _| ControlFlow::Continue(()))?;
//! assert!((stats.x_final[0] - 1f64.cos()).abs() < 1e-8);
//! # Ok::<(), satsim_integrate::IntegrateError>(())
//! ```
// `unsafe` only to call the instances compiled for AVX2 where the CPU has it (`wide.rs`),
// each call with its safety comment.
#![deny(unsafe_code)]
#![warn(missing_docs)]
// Index loops over stage/component arrays read like the published formulas.
#![allow(clippy::needless_range_loop)]

mod carry;
mod common;
mod dense_lu;
mod dop853;
mod dp54;
mod driver;
mod error;
mod events;
mod grid;
mod hessenberg;
mod jacobian;
pub mod lanes;
mod options;
mod radau5;
mod rk4;
mod stability;
mod stage_matrices;
mod system;
mod wide;

#[cfg(test)]
mod tests;

pub use carry::{Carry, integrate_on};
pub use driver::{Stats, Steps, StopReason, integrate};
pub use error::{IntegrateError, NonFiniteEntry};
pub use grid::DecimalGrid;
pub use options::{Method, Options, Output, UnknownMethod};
pub use system::{EventAction, EventDirection, STOP_ROUNDOFF, System, SystemError, stop_due};
