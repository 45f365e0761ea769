//! The environment's tests: one binary (one link), one module per subject.

mod earth;
mod magnetic;
mod shadow;
mod sun;
