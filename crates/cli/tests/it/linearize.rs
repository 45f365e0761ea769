//! `satsim linearize` and `satsim modes` (contract section 9): the JSON keys, shapes and
//! normalisation, the `--along` sweep, and exit status 2 on bad input.

use crate::common;
use common::{json, numbers, satsim_in};
use std::path::PathBuf;
use std::process::Output;

fn setup(test: &str) -> PathBuf {
    let dir = satsim_testkit::temp_dir_with(&format!("lin-{test}"), &["examples/satellite.toml"]);
    std::fs::write(dir.join("springs.toml"), SCENE).unwrap();
    dir
}

const SCENE: &str = r#"model = "satellite.toml"
duration = 1.0
[initial]
hinges = { angle = [0.0, 0.0, 0.0, 0.5, -0.5], rate = [0.0, 0.0, 0.0, 0.0, 0.0] }
[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
damping = [1.0, 1.0, 1.0, 0.2, 0.2]
reference = [0.0, 0.0, 0.0, 0.5, -0.5]
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.1
speed = 100.0
"#;

fn fails(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(o.stdout.is_empty(), "partial output");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

#[test]
fn linearize_prints_states_inputs_a_and_b() {
    let dir = setup("lin");
    let v = json(&satsim_in(&dir, &["linearize", "springs.toml"]));
    let states: Vec<&str> = v["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    let mut expected = vec![
        "att_x", "att_y", "att_z", "omega_x", "omega_y", "omega_z", "vel_x", "vel_y", "vel_z",
    ];
    let angles: Vec<String> = (1..=5).map(|k| format!("angle_h{k}")).collect();
    let rates: Vec<String> = (1..=5).map(|k| format!("rate_h{k}")).collect();
    expected.extend(angles.iter().map(String::as_str));
    expected.extend(rates.iter().map(String::as_str));
    expected.push("wheel_y_speed");
    assert_eq!(states, expected);
    let inputs: Vec<&str> = v["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    assert_eq!(
        inputs,
        [
            "torque_h1",
            "torque_h2",
            "torque_h3",
            "torque_h4",
            "torque_h5",
            "wheel_y"
        ]
    );
    let a = v["A"].as_array().unwrap();
    let b = v["B"].as_array().unwrap();
    assert_eq!(a.len(), states.len());
    assert_eq!(b.len(), states.len());
    for r in a {
        assert_eq!(r.as_array().unwrap().len(), states.len());
    }
    for r in b {
        assert_eq!(r.as_array().unwrap().len(), inputs.len());
    }
    // angle_h4' = rate_h4.
    assert_eq!(a[12][17].as_f64().unwrap(), 1.0);
    // The spring acts: d(rate_h4')/d(angle_h4) < 0.
    assert!(a[17][12].as_f64().unwrap() < 0.0);
}

#[test]
fn modes_prints_ascending_frequencies_and_normalised_shapes() {
    let dir = setup("modes");
    let v = json(&satsim_in(&dir, &["modes", "springs.toml"]));
    let f = numbers(&v["frequencies_hz"]);
    let z = v["damping_ratios"].as_array().unwrap();
    assert!(f.len() >= 5, "{f:?}");
    assert_eq!(z.len(), f.len());
    assert!(f.windows(2).all(|w| w[0] <= w[1]), "{f:?}");
    assert!(v["rigid_modes"].as_u64().is_some());
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), f.len());
    for (m, fk) in modes.iter().zip(&f) {
        assert_eq!(m["frequency_hz"].as_f64().unwrap(), *fk);
        assert!(m["damping_ratio"].as_f64().unwrap() > 0.0);
        let shape = m["shape"].as_object().unwrap();
        let largest = (1..=5)
            .map(|k| shape[&format!("angle_h{k}")].as_f64().unwrap().abs())
            .fold(0.0f64, f64::max);
        assert_eq!(largest, 1.0, "{shape:?}");
    }
}

#[test]
fn modes_along_sweeps_and_plots() {
    let dir = setup("along");
    let o = satsim_in(
        &dir,
        &[
            "modes",
            "springs.toml",
            "--along",
            "h4=0.5:1.5:5,h5=-0.5:-1.5",
            "--plot",
            "sweep.svg",
        ],
    );
    let v = json(&o);
    assert_eq!(v["along"], serde_json::json!(["h4", "h5"]));
    let points = v["points"].as_array().unwrap();
    assert_eq!(points.len(), 5);
    assert_eq!(points[2]["angles"], serde_json::json!([1.0, -1.0]));
    // Folding the panels changes the frequencies.
    assert_ne!(
        points[0]["frequencies_hz"], points[4]["frequencies_hz"],
        "{points:?}"
    );
    let svg = std::fs::read_to_string(dir.join("sweep.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("mode 1"));
}

#[test]
fn bad_input_exits_2_naming_the_file() {
    let dir = setup("bad");
    for cmd in ["linearize", "modes"] {
        fails(&satsim_in(&dir, &[cmd, "missing.toml"]), &["missing.toml"]);
        std::fs::write(dir.join("broken.toml"), "duration = \n").unwrap();
        fails(&satsim_in(&dir, &[cmd, "broken.toml"]), &["broken.toml:1"]);
        // An effect whose needs are not met.
        std::fs::write(
            dir.join("needs.toml"),
            format!("{SCENE}[effects.gravity_gradient]\n"),
        )
        .unwrap();
        fails(
            &satsim_in(&dir, &[cmd, "needs.toml"]),
            &["needs.toml", "orbit"],
        );
        fails(
            &satsim_in(&dir, &[cmd]),
            &["required arguments were not provided", "<SCENE.toml>"],
        );
    }
    // A gimbal lock (h2 = 90 degrees through massless links): a clear error, no numbers.
    std::fs::write(
        dir.join("locked.toml"),
        SCENE.replace(
            "angle = [0.0, 0.0, 0.0,",
            "angle = [0.0, 1.5707963267948966, 0.0,",
        ),
    )
    .unwrap();
    for cmd in ["linearize", "modes"] {
        fails(
            &satsim_in(&dir, &[cmd, "locked.toml"]),
            &["locked.toml", "singular configuration"],
        );
    }
    fails(
        &satsim_in(&dir, &["modes", "springs.toml", "--along", "h9=0:1:3"]),
        &["springs.toml", "h9"],
    );
    fails(
        &satsim_in(&dir, &["modes", "springs.toml", "--along", "h4=0:1:1"]),
        &["--along", "N"],
    );
    fails(
        &satsim_in(&dir, &["modes", "springs.toml", "--along", "h4"]),
        &["--along"],
    );
    fails(
        &satsim_in(&dir, &["modes", "springs.toml", "--plot", "x.svg"]),
        &["--plot", "--along"],
    );
}

#[test]
fn a_linearisation_beyond_the_range_of_f64_exits_2_not_0() {
    // A gimbal spring of 1e308 printed frequencies of 1e296 Hz with negative damping
    // ratios and exit status 0.
    let dir = setup("range");
    std::fs::write(
        dir.join("extreme.toml"),
        SCENE.replace(
            "stiffness = [50.0, 50.0, 50.0,",
            "stiffness = [1e308, 1e308, 1e308,",
        ),
    )
    .unwrap();
    for cmd in ["linearize", "modes"] {
        fails(
            &satsim_in(&dir, &[cmd, "extreme.toml"]),
            &["extreme.toml", "out of range", "1.3e154"],
        );
    }
}
