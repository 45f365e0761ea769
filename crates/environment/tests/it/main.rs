//! The environment's tests: one binary (one link), one module per subject.

mod earth;
mod gravity;
mod lattice;
mod magnetic;
mod moon;
mod msis;
mod shadow;
mod sun;
