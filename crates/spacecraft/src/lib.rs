//! # satsim-spacecraft: the spacecraft engine
//!
//! A hinged spacecraft on the [`satsim_tree`] engine, integrated by [`satsim_integrate`]:
//!
//! - [`effects`]: one file per effect (orbit, gravity gradient, reaction wheels, attitude and
//!   hinge control, hinge springs and stops) behind one small trait, [`effects::Effect`]; the
//!   [`effects::Registry`] of the effects a scene may enable, each reading its own
//!   `[effects.<name>]` section ([`effects::Section`]);
//! - [`sensors`]: gyros, star trackers, Sun sensors and magnetometers sampled on their own
//!   clocks with seeded noise, as one effect that applies nothing ([`sensors::Sensors`]);
//! - [`simulation`]: [`simulation::Simulation`], the tree, the enabled effects and the state
//!   layout derived from them; the right-hand side the integrators call, events, output rows,
//!   the energy budget, and runs.
//!
//! The scene files, campaigns, accuracy sweeps, linearisation, output and the 3-D view are
//! the tools around this engine (`satsim-tools`); the preprint's layout and its closed-form
//! equations are `satsim-satellite`.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod effects;
/// Built-in flight software (contract section 16): the attitude and gyro-bias MEKF.
pub mod fsw;
pub mod sensors;
pub mod simulation;
