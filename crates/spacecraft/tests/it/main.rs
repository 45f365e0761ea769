//! The simulation's tests: one binary (one link), one module per subject.

mod flexible;
mod integrators;
mod orbit_fields;
mod physics;
