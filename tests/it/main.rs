//! The facade's tests: one binary (one link), one module per subject. `hard_cases` holds the
//! 100-orbit run, `#[ignore]`d in the plain test run (CI runs it by name:
//! `cargo test --workspace --test it -- --ignored --exact hard_cases::hundred_orbits_torque_free`).

mod docs;
mod fuzz_regressions;
mod hard_cases;
mod model_roundtrip;
mod scenes;
