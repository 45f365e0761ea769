//! `satsim run` with `[sensors]`: the readings are columns of `trajectory.csv`, and bad
//! sensor input exits with status 2 naming the scene file and line.

use crate::common;

use common::satsim_in;
use std::path::PathBuf;

const SCENE: &str = r#"duration = 1.0

[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 12.0, 0.0], [0.0, 0.0, 8.0]]

[initial]
base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.05, -0.02, 0.03] }

[integrator]
method = "rk4"
step = 0.01

[output]
every = 0.5
plots = false
view = false

[sensors]
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.5
"#;

fn setup(test: &str, text: &str) -> PathBuf {
    let dir = satsim_testkit::temp_dir(&format!("sensors-{test}"));
    std::fs::write(dir.join("scene.toml"), text).unwrap();
    dir
}

#[test]
fn readings_are_columns_and_bad_input_exits_2_at_its_line() {
    let dir = setup("ok", SCENE);
    let o = satsim_in(&dir, &["run", "scene.toml", "--out", "out"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.join("out/trajectory.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    let at = |c: &str| row[header.iter().position(|h| *h == c).unwrap()];
    // No noise: the first reading is the initial rate.
    assert_eq!(at("gyro_x"), at("omega_x"));
    assert_eq!(at("gyro_z"), at("omega_z"));

    let bad = SCENE.replace("body = \"bus\"", "body = \"boom\"");
    let line = bad.lines().position(|l| l.contains("boom")).unwrap() + 1;
    let dir = setup("bad", &bad);
    let o = satsim_in(&dir, &["run", "scene.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("scene.toml:{line}")), "{err}");
    assert!(err.contains("unknown body `boom`"), "{err}");
}
