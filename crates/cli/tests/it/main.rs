//! The command line's tests: one binary (one link), one module per command or subject; each
//! runs the `satsim` binary built for it in a folder of its own (`satsim_testkit::temp_dir`).
//! `common` holds the runner of that binary.

mod accuracy;
mod campaign;
mod cli_ux;
mod common;
mod contract;
mod environment;
mod flexible;
mod limits;
mod linearize;
mod non_finite;
mod robustness;
mod run;
mod run_memory;
mod sensors;
mod view;
