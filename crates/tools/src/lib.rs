//! # satsim-tools: the tools around the spacecraft engine
//!
//! Each module is a room of its own, over [`satsim_spacecraft`]'s simulation:
//!
//! - [`scene`]: scene files (model, initial state, integrator, `[effects.*]` through the
//!   engine's registry) into a [`satsim_spacecraft::simulation::Simulation`];
//!   [`scene_keys`]: the keys of a scene, for `--set` overrides and campaign dispersions;
//! - [`campaign`]: Monte Carlo campaigns (draws, parallel runs, shards, statistics, plots);
//! - [`accuracy`]: what accuracy costs in time (sweeps of integrators and tolerances);
//! - [`linearize`] and [`modes`]: linear models about a state, and their modes;
//! - [`output`]: CSV and SVG output; [`view`]: the 3-D view (`view.html`);
//! - [`api`]: the one-call entry points the Python module wraps; [`stepping`]: a scene
//!   stepped from the caller's code (`satsim.Simulation`).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod accuracy;
pub mod api;
pub mod campaign;
pub mod environment;
pub mod linearize;
pub mod modes;
mod numbers;
pub mod output;
pub mod scene;
pub mod scene_keys;
pub mod stepping;
pub mod view;
