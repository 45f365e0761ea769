//! Snapshot tests of the example scenes (`examples/scenes/*.toml`): a few columns, rounded to
//! 6 significant digits, at a few instants of each run. Regenerate with
//! `INSTA_UPDATE=always cargo test -p satsim --test scenes` and review the diff.

use satsim::integrate::Output;
use satsim::satellite::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;

/// `x` to 6 significant digits; values below 1e-7 in magnitude (rounding noise around zero,
/// such as the angular momentum of a torque-free scene started at rest) print as 0.
fn round6(x: f64) -> String {
    if x.abs() < 1e-7 {
        return "0".into();
    }
    let s = format!("{x:.5e}");
    // Normalise "-0.00000e0" and keep a stable exponent form.
    s.replace("e0", "")
}

fn snapshot(name: &str, times: &[f64], columns: &[&str]) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/scenes/{name}.toml"));
    let scene = Scene::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.simulation().unwrap();
    let all = sim.columns();
    let mut rows: Vec<Vec<f64>> = Vec::new();
    sim.run(
        &scene.options,
        scene.duration,
        &Output::Interval(scene.every),
        |_, row| {
            rows.push(row.to_vec());
            Ok::<(), ()>(())
        },
    )
    .unwrap();
    let idx: Vec<usize> = columns
        .iter()
        .map(|c| {
            all.iter()
                .position(|a| a == c)
                .unwrap_or_else(|| panic!("no column {c}"))
        })
        .collect();
    let mut out = String::new();
    let _ = writeln!(out, "effects: {}", sim.effect_names().join(", "));
    let _ = writeln!(out, "state length: {}", sim.layout().len);
    for (t, what) in sim.event_log() {
        let _ = writeln!(out, "event t={}: {what}", round6(*t));
    }
    for &t in times {
        let row = rows
            .iter()
            .find(|r| (r[0] - t).abs() < 1e-9)
            .unwrap_or_else(|| panic!("no row at t = {t}"));
        let _ = writeln!(out, "t = {t}");
        for (c, &i) in columns.iter().zip(&idx) {
            let _ = writeln!(out, "  {c} = {}", round6(row[i]));
        }
    }
    out
}

const ATTITUDE: [&str; 7] = ["q_w", "q_x", "q_y", "q_z", "omega_x", "omega_y", "omega_z"];

fn with(extra: &[&'static str]) -> Vec<&'static str> {
    ATTITUDE
        .iter()
        .copied()
        .chain(extra.iter().copied())
        .collect()
}

#[test]
fn deploy() {
    let cols = with(&[
        "angle_h1",
        "angle_h2",
        "angle_h3",
        "angle_h4",
        "angle_h5",
        "wheel_x_speed",
        "wheel_y_speed",
        "wheel_z_speed",
        "kinetic_energy",
        "total_energy",
        "h_norm",
    ]);
    insta::assert_snapshot!(snapshot("deploy", &[0.0, 5.0, 20.0, 100.0, 300.0], &cols));
}

#[test]
fn tumbling() {
    let cols = with(&["kinetic_energy", "h_x", "h_y", "h_z"]);
    insta::assert_snapshot!(snapshot("tumbling", &[0.0, 100.0, 300.0, 600.0], &cols));
}

#[test]
fn libration() {
    let cols = with(&["orbit_radius", "total_energy"]);
    insta::assert_snapshot!(snapshot(
        "libration",
        &[0.0, 1000.0, 4000.0, 12000.0],
        &cols
    ));
}

#[test]
fn spin_down() {
    let cols = with(&["wheel_z_speed", "kinetic_energy", "h_z"]);
    insta::assert_snapshot!(snapshot("spin_down", &[0.0, 300.0, 1000.0, 1200.0], &cols));
}

#[test]
fn two_wings() {
    let cols = with(&[
        "angle_left_root",
        "angle_left_fold",
        "angle_right_root",
        "angle_right_fold",
        "angle_boom_root",
        "angle_boom_elbow",
        "kinetic_energy",
        "total_energy",
        "h_norm",
    ]);
    insta::assert_snapshot!(snapshot(
        "two_wings",
        &[0.0, 10.0, 50.0, 100.0, 200.0],
        &cols
    ));
}
