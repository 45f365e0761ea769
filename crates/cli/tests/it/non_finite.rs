//! No command presents a non-finite number as a result: absurd rates (1e160 rad/s) or
//! masses (1e-120 kg) either give finite output or exit 2 with one message naming the file
//! and the quantity that overflowed, never `null`, never a panic.

use crate::common;
use common::{root, satsim_in};
use std::path::PathBuf;
use std::process::Output;

/// A folder with the example model and a state whose hinge rates are `rate`, and a model
/// whose masses are scaled by `mass_scale` (`tiny.toml`).
fn setup(test: &str, rate: &str) -> PathBuf {
    let dir =
        satsim_testkit::temp_dir_with(&format!("nonfinite-{test}"), &["examples/satellite.toml"]);
    let state = std::fs::read_to_string(root().join("examples/state.json"))
        .unwrap()
        .replace(
            "\"rate\":   [0.01, 0.02, -0.01, 0.05, -0.04]",
            &format!("\"rate\":   [{rate}, 0.02, -0.01, 0.05, -0.04]"),
        );
    assert!(state.contains(rate), "{state}");
    std::fs::write(dir.join("state.json"), state).unwrap();
    let model = std::fs::read_to_string(root().join("examples/satellite.toml")).unwrap();
    let tiny = model
        .replace("mass = 800.0", "mass = 8e-118")
        .replace("mass = 20.0", "mass = 2e-119");
    assert_ne!(tiny, model);
    std::fs::write(dir.join("tiny.toml"), tiny).unwrap();
    dir
}

/// Exit 2, one line on stderr containing every needle, nothing on stdout, no panic.
fn refused(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(
        !err.contains("internal error") && !err.contains("panicked"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    for n in needles {
        assert!(err.contains(n), "no `{n}` in: {err}");
    }
}

/// Exit 0 with only finite numbers (no `null`, `NaN` or `inf`), or refused as above.
fn finite_or_refused(o: &Output, needles: &[&str]) {
    if o.status.code() == Some(0) {
        let out = String::from_utf8_lossy(&o.stdout);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        fn walk(v: &serde_json::Value) {
            match v {
                serde_json::Value::Null => panic!("null in the output"),
                serde_json::Value::Number(n) => assert!(n.as_f64().unwrap().is_finite()),
                serde_json::Value::Array(a) => a.iter().for_each(walk),
                serde_json::Value::Object(m) => m.values().for_each(walk),
                _ => {}
            }
        }
        walk(&v);
    } else {
        refused(o, needles);
    }
}

#[test]
fn preprint_refuses_rates_that_overflow_naming_the_quantity() {
    let dir = setup("preprint", "1e160");
    let o = satsim_in(
        &dir,
        &[
            "preprint",
            "--model",
            "satellite.toml",
            "--state",
            "state.json",
        ],
    );
    refused(&o, &["state.json", "N_", "not finite"]);
}

#[test]
fn preprint_with_tiny_masses_never_panics() {
    let dir = setup("preprint-tiny", "0.01");
    let o = satsim_in(
        &dir,
        &["preprint", "--model", "tiny.toml", "--state", "state.json"],
    );
    finite_or_refused(&o, &["tiny.toml"]);
    // A massless model: the linear block is singular, said as such.
    let model = std::fs::read_to_string(dir.join("satellite.toml"))
        .unwrap()
        .replace("mass = 800.0", "mass = 0.0")
        .replace("mass = 20.0", "mass = 0.0");
    std::fs::write(dir.join("massless.toml"), model).unwrap();
    let o = satsim_in(
        &dir,
        &[
            "preprint",
            "--model",
            "massless.toml",
            "--state",
            "state.json",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    // Either the model reader refuses it, or the preprint says the base is singular.
    refused(&o, &["massless.toml"]);
    assert!(!err.contains("null"), "{err}");
}

#[test]
fn dynamics_refuses_rates_that_overflow() {
    let dir = setup("dynamics", "1e160");
    let o = satsim_in(
        &dir,
        &[
            "dynamics",
            "--model",
            "satellite.toml",
            "--state",
            "state.json",
        ],
    );
    refused(&o, &["state.json", "overflow"]);
    let o = satsim_in(
        &dir,
        &["dynamics", "--model", "tiny.toml", "--state", "state.json"],
    );
    finite_or_refused(&o, &["state.json"]);
}

#[test]
fn bench_refuses_rates_that_overflow() {
    let dir = setup("bench", "1e160");
    let o = satsim_in(
        &dir,
        &[
            "bench",
            "--model",
            "satellite.toml",
            "--state",
            "state.json",
            "--calls",
            "10",
        ],
    );
    refused(&o, &["state.json", "not finite"]);
}

const SCENE: &str = r#"model = "satellite.toml"
initial = "state.json"
duration = 1.0
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.5
plots = false
"#;

#[test]
fn run_and_accuracy_refuse_a_start_that_overflows_naming_the_column() {
    let dir = setup("run", "1e160");
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    let o = satsim_in(&dir, &["run", "scene.toml"]);
    refused(&o, &["scene.toml", "`kinetic_energy` is not finite"]);
    let o = satsim_in(&dir, &["accuracy", "scene.toml", "--quick"]);
    refused(&o, &["scene.toml", "not finite"]);
}
