//! The engine's tests: one binary (one link), one module per subject; `common` holds the
//! preprint satellite. The modules that read model files need the `files` feature (the
//! default).

mod chains;
mod common;
mod flexible;
mod flexible_chains;
mod flexible_dynamics;
mod flexible_field;
#[cfg(feature = "files")]
mod flexible_io;
mod flexible_spin;
#[cfg(feature = "files")]
mod gimbal_lock;
mod gyrostat;
mod no_alloc;
#[cfg(feature = "files")]
mod pinocchio;
mod properties;

// `no_alloc` and `flexible` count the allocations of the per-call algorithms (per thread:
// the other tests run in parallel threads).
#[global_allocator]
static GLOBAL: satsim_testkit::alloc::Counting = satsim_testkit::alloc::Counting;
