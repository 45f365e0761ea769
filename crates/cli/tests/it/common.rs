//! Helpers shared by the command-line tests (the rest is `satsim_testkit`'s).
#![allow(dead_code)] // each module uses its own subset

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

/// Runs the `satsim` binary built for these tests in `dir`.
pub fn satsim_in(dir: &Path, args: &[&str]) -> Output {
    satsim_testkit::run_in(env!("CARGO_BIN_EXE_satsim"), dir, args)
}

/// The repository root.
pub fn root() -> PathBuf {
    satsim_testkit::root()
}

/// The one JSON object a successful command printed.
pub fn json(o: &Output) -> Value {
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

/// A JSON array of numbers.
pub fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// Every row has every column and parses; returns (header, rows).
pub fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.ends_with('\n'), "the last row is complete");
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            let r: Vec<f64> = l
                .split(',')
                .map(|v| {
                    v.parse::<f64>()
                        .unwrap_or_else(|_| panic!("bad number in {l}"))
                })
                .collect();
            assert_eq!(r.len(), header.len(), "{l}");
            r
        })
        .collect();
    (header, rows)
}
