//! Work-precision measurements: what accuracy costs in time.
//!
//! A [`Sweep`] runs a [`Scene`](crate::scene::Scene) with every integrator over a range of
//! tolerances (and the fixed-step RK4 over a range of steps), measures each run's error
//! against a reference solution and its cost (wall time, minimum over several repeats, and
//! right-hand-side evaluations from [`Stats`](satsim_integrate::Stats)), and collects the
//! points into a [`Report`] that renders as CSV, a log-log SVG diagram and a markdown table.
//!
//! # Reference
//!
//! The reference is the same scene integrated by DOP853 at `rtol = atol = 1e-13`
//! ([`Sweep::reference`]). DOP853's own points are measured against a reference computed by
//! a *different* method ([`Sweep::cross_reference`], DP5(4) at `1e-13`; Radau IIA is not
//! used because at that tolerance its Newton iteration fails on the deployment scene's
//! stick-slip wheels), so that a method
//! is never judged against itself. The difference between the two references is reported as
//! the *floor*: errors below it are not measurable.
//!
//! # Error
//!
//! At each saved time `t_i` (the scene's output times) the run and the reference are
//! compared by ([`ErrorMetrics`]):
//!
//! - the bus attitude error: the rotation angle of `q_ref⁻¹ ⊗ q` (rad),
//! - the hinge angle errors `|φ_k − φ_ref,k|` (rad),
//! - the rate errors: bus angular velocity components and hinge rates (rad/s),
//!
//! and `e_i` is the largest of them. A point's error is `e` at the final time, and its RMS
//! over the saved times is reported too. Angles and rates are mixed on purpose: a
//! flight-dynamics requirement is usually "attitude to X rad and rates to Y rad/s", and the
//! largest of the two is what a tolerance must deliver.
//!
//! # Cost
//!
//! The wall time of one [`satsim_integrate::integrate`] call (the simulation is built
//! beforehand and outputs are copied into a preallocated list), minimum over
//! [`Sweep::repeats`] runs, and the right-hand-side evaluations it made (finite-difference
//! Jacobians included).
//!
//! ```
//! use satsim_tools::accuracy::attitude_angle;
//! // A rotation by 0.3 rad about z against the identity.
//! let (s, c) = (0.15f64.sin(), 0.15f64.cos());
//! let e = attitude_angle(&[1.0, 0.0, 0.0, 0.0], &[c, 0.0, 0.0, s]);
//! assert!((e - 0.3).abs() < 1e-15);
//! ```

mod metrics;
mod plot;
mod report;
mod spec;
mod sweep;
mod trajectory;

pub use metrics::{ErrorMetrics, StateError, attitude_angle, compare};
pub use plot::loglog_plot;
pub use report::{Cost, Measured, Point, Reach, ReferenceRun, Report, fmt_seconds, method_label};
pub use spec::{Setting, Sweep};
pub use sweep::sweep;
pub use trajectory::{Trajectory, run};

#[cfg(test)]
mod tests;
