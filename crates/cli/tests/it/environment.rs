//! `satsim environment` (contract section 12): the keys and their meaning on the example
//! deployment in orbit, the state reached at `--at T`, and exit status 2 on bad input.

use crate::common;
use common::{json, root, satsim_in};
use serde_json::Value;
use std::path::PathBuf;

fn setup(test: &str) -> PathBuf {
    let dir = satsim_testkit::temp_dir_with(&format!("env-{test}"), &["examples/satellite.toml"]);
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::copy(
        root().join("examples/scenes/deploy_in_orbit.toml"),
        dir.join("scenes/orbit.toml"),
    )
    .unwrap();
    dir
}

fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().expect("an array");
    assert_eq!(a.len(), 3);
    [0, 1, 2].map(|k| a[k].as_f64().expect("a number"))
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

#[test]
fn environment_prints_the_world_and_every_effects_loads() {
    let dir = setup("keys");
    let v = json(&satsim_in(&dir, &["environment", "scenes/orbit.toml"]));
    assert_eq!(v["t"], 0.0);
    assert_eq!(v["epoch"], "2026-03-20T12:00:00 UTC");
    let r = norm(vec3(&v["position"]));
    assert!((r - 6_878_137.0).abs() < 1e-3, "|r| = {r}");
    let speed = norm(vec3(&v["velocity"]));
    assert!((speed - (3.986004418e14f64 / r).sqrt()).abs() < 1e-6);
    assert!((norm(vec3(&v["sun"])) - 1.0).abs() < 1e-12);
    let d = v["sun_distance"].as_f64().unwrap();
    assert!((d / 1.496e11 - 1.0).abs() < 0.02, "{d}");
    let nu = v["shadow"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&nu));
    let rho = v["density"].as_f64().unwrap();
    assert!((rho / 6.967e-13 - 1.0).abs() < 1e-9, "{rho}");
    let b = norm(vec3(&v["magnetic_field"]));
    assert!(b > 1.5e-5 && b < 6.5e-5, "|B| = {b}");
    let effects = v["effects"].as_object().unwrap();
    for name in ["gravity_gradient", "drag", "magnetic", "hinge_springs"] {
        let e = &effects[name];
        let bodies = e["bodies"].as_object().expect("bodies");
        assert_eq!(bodies.len(), 6, "{name}");
        for body in ["bus", "link1", "link2", "panel1", "panel2", "panel3"] {
            vec3(&bodies[body]["force"]);
            vec3(&bodies[body]["torque"]);
        }
        assert_eq!(e["generalized_forces"].as_array().unwrap().len(), 11);
    }
    // The controllers and the orbit apply no load of their own.
    assert!(!effects.contains_key("orbit") && !effects.contains_key("attitude_control"));
}

#[test]
fn at_t_gives_the_state_the_run_reaches() {
    let dir = setup("at");
    let a = json(&satsim_in(
        &dir,
        &["environment", "scenes/orbit.toml", "--at", "300"],
    ));
    assert_eq!(a["t"], 300.0);
    // The same scene run for 300 s ends at the same orbit position.
    let out = dir.join("out");
    let o = satsim_in(
        &dir,
        &[
            "run",
            "scenes/orbit.toml",
            "--set",
            "duration=300",
            "--set",
            "output.every=300",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let col = |n: &str| last[header.iter().position(|c| *c == n).unwrap()];
    let p = vec3(&a["position"]);
    assert_eq!(p, [col("orbit_r_x"), col("orbit_r_y"), col("orbit_r_z")]);
    assert_eq!(a["shadow"].as_f64().unwrap(), col("shadow"));
    assert_eq!(a["density"].as_f64().unwrap(), col("density"));
}

#[test]
fn bad_input_exits_2_naming_the_file() {
    let dir = setup("bad");
    for (args, needle) in [
        (
            vec!["environment", "scenes/orbit.toml", "--at", "-1"],
            "--at",
        ),
        (
            vec!["environment", "scenes/orbit.toml", "--at", "1e9"],
            "--at",
        ),
        (vec!["environment", "scenes/missing.toml"], "missing.toml"),
        (
            vec![
                "environment",
                "scenes/orbit.toml",
                "--set",
                "epoch=\"yesterday\"",
            ],
            "orbit.toml",
        ),
    ] {
        let o = satsim_in(&dir, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(o.stdout.is_empty());
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    }
}

#[test]
fn environment_prints_the_gravity_the_moon_and_the_third_bodies_pull() {
    let dir = setup("gravity");
    let path = dir.join("scenes/orbit.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    // Without `gravity`: today's point mass, and no third bodies.
    let v = json(&satsim_in(&dir, &["environment", "scenes/orbit.toml"]));
    let r = vec3(&v["position"]);
    let g = vec3(&v["gravity"]);
    let point = 3.986004418e14 / norm(r).powi(2);
    assert!((norm(g) - point).abs() < 1e-12 * point, "{g:?}");
    assert!(v.get("moon").is_none() && v.get("third_body").is_none());
    let text = text.replacen(
        "model = \"kepler\"",
        "gravity = { model = \"egm2008\", degree = 20, order = 20 }\nthird_body = [\"sun\", \"moon\"]",
        1,
    );
    std::fs::write(&path, text).unwrap();
    let v = json(&satsim_in(&dir, &["environment", "scenes/orbit.toml"]));
    // The harmonics change the pull by about 1e-3 (J2) and turn it off the vertical.
    let g = vec3(&v["gravity"]);
    let change = (norm(g) - point).abs() / point;
    assert!(change > 1e-4 && change < 3e-3, "{change}");
    let moon = norm(vec3(&v["moon"]));
    assert!(moon > 356e6 && moon < 407e6, "{moon}");
    let a = norm(vec3(&v["third_body"]));
    assert!(a > 1e-7 && a < 3e-6, "{a}");
}
