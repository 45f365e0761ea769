//! Helpers shared by the command-line integration tests.
#![allow(dead_code)] // each test crate uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `satsim` binary built for these tests in `dir`.
pub fn satsim_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run satsim")
}

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}
