//! `satsim run` (contract section 7): the trajectory CSV, plots, exit statuses.

use crate::common;
use common::{csv, satsim_in};
use std::path::PathBuf;

fn temp_dir(test: &str) -> PathBuf {
    satsim_testkit::temp_dir(&format!("run-{test}"))
}

const SCENE: &str = r#"model = "satellite.toml"
initial = "state.json"
duration = 6.0
[integrator]
method = "rk4"
step = 0.01
[output]
every = 1.0
[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
damping = [1.0, 1.0, 1.0, 0.5, 0.5]
"#;

fn setup(test: &str) -> PathBuf {
    satsim_testkit::temp_dir_with(
        &format!("run-{test}"),
        &["examples/satellite.toml", "examples/state.json"],
    )
}

#[test]
fn run_writes_the_contract_columns_and_plots() {
    let dir = setup("ok");
    std::fs::write(dir.join("springs.toml"), SCENE).unwrap();
    let o = satsim_in(&dir, &["run", "springs.toml"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = csv(&dir.join("out/springs/trajectory.csv"));
    for c in [
        "t",
        "q_w",
        "q_x",
        "q_y",
        "q_z",
        "omega_x",
        "omega_y",
        "omega_z",
        "angle_h1",
        "rate_h5",
        "kinetic_energy",
        "h_x",
        "h_y",
        "h_z",
    ] {
        assert!(header.iter().any(|h| h == c), "{c}");
    }
    let times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(times, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    // The initial row is the state file's state.
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    assert_eq!(rows[0][col("angle_h4")], 1.2);
    assert_eq!(rows[0][col("omega_y")], -0.002);
    assert!(dir.join("out/springs/energy.svg").is_file());
    let summary = String::from_utf8_lossy(&o.stdout);
    assert!(
        summary.contains("hinge_springs") && summary.contains("trajectory.csv"),
        "{summary}"
    );
    // --out
    let o = satsim_in(&dir, &["run", "springs.toml", "--out", "elsewhere"]);
    assert!(o.status.success());
    assert!(dir.join("elsewhere/trajectory.csv").is_file());
}

#[test]
fn a_run_failure_leaves_a_valid_csv_and_exits_1() {
    let dir = setup("fail");
    let text = SCENE.replace(
        "method = \"rk4\"\nstep = 0.01",
        "method = \"dp54\"\nrtol = 1e-12\natol = 1e-14\nmax_steps = 60",
    );
    std::fs::write(dir.join("short.toml"), text).unwrap();
    let o = satsim_in(&dir, &["run", "short.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("maximum number of steps exceeded at t =")
            && err.contains("holds the rows up to t ="),
        "{err}"
    );
    let (_, rows) = csv(&dir.join("out/short/trajectory.csv"));
    assert!(!rows.is_empty() && rows.len() < 7, "{}", rows.len());
}

#[test]
fn bad_scenes_exit_2_with_the_line() {
    let dir = setup("bad");
    std::fs::write(
        dir.join("bad.toml"),
        SCENE.replace("every = 1.0", "evry = 1.0"),
    )
    .unwrap();
    let o = satsim_in(&dir, &["run", "bad.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bad.toml:8") && err.contains("unknown key `evry`"),
        "{err}"
    );
    std::fs::write(
        dir.join("gg.toml"),
        format!("{SCENE}[effects.gravity_gradient]\n"),
    )
    .unwrap();
    let o = satsim_in(&dir, &["run", "gg.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("needs an [orbit] table"), "{err}");
    let o = satsim_in(&dir, &["run", "missing.toml"]);
    assert_eq!(o.status.code(), Some(2));
    let o = satsim_in(&dir, &["run"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("<SCENE.toml>"));
}

#[test]
fn no_arguments_runs_the_default_scene() {
    let dir = temp_dir("default");
    let o = satsim_in(&dir, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("deploy.toml"));
    let (_, rows) = csv(&dir.join("out/deploy/trajectory.csv"));
    assert_eq!(rows.len(), 301);
}

#[test]
fn the_summary_counts_every_event_a_fault_too() {
    // The faults scene's wheel fails at 60 s: an event of the log with no crossing for the
    // integrator to find. The run line counts what the listing and events.csv hold.
    let dir = satsim_testkit::temp_dir_with("run-fault-count", &["examples/scenes/faults.toml"]);
    let o = satsim_in(&dir, &["run", "faults.toml", "--set", "duration=100"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let ran = out
        .lines()
        .find(|l| l.starts_with("ran "))
        .expect("a ran line");
    assert!(ran.contains(", 1 events,"), "{ran}");
    assert!(out.contains("fault: wheel `y` off"), "{out}");
    let events = std::fs::read_to_string(dir.join("out/faults/events.csv")).unwrap();
    assert_eq!(events.lines().count(), 2, "{events}");
}

#[test]
fn an_explicit_method_held_by_a_stiff_hinge_says_so_after_the_run() {
    // The stiff hinge (56.7 Hz) under DP5(4): the steps sit at the method's stability limit
    // on it, and the run names the hinge and the implicit method; under its own Radau IIA,
    // nothing.
    let dir = temp_dir("held-steps");
    let scene = common::root().join("examples/scenes/stiff_hinge.toml");
    let scene = scene.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["run", scene, "--out", "o", "--set", "duration=10"];
        args.extend_from_slice(extra);
        let o = satsim_in(&dir, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let err = run(&["--set", "integrator.method=dp54"]);
    assert!(
        err.contains("stiff_hinge.toml: the ")
            && err.contains("steps of dp54 averaged")
            && err.contains("its stability limit on hinge `h5` (56.669 Hz), 7.039e-3 s")
            && err.contains("`integrator.method = \"radau5\"` (implicit) steps over it"),
        "{err}"
    );
    let err = run(&[]);
    assert!(!err.contains("held the steps"), "{err}");
}
