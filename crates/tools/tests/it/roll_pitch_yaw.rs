//! The orbit effect's `roll`, `pitch`, `yaw` columns: the bus' attitude relative to the
//! local orbital frame (z to nadir, y along the negative orbit normal, x completing the
//! triad), sequence z-y'-x'', in radians.

use nalgebra::UnitQuaternion;
use satsim_integrate::{Method, Options, Output};
use satsim_spacecraft::effects::orbit::{Elements, R_EARTH};
use satsim_spacecraft::effects::{Orbit, OrbitModel};
use satsim_spacecraft::simulation::Simulation;
use satsim_tools::scene::Scene;
use std::path::Path;

fn examples() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples"))
}

/// Roll, pitch and yaw at every step of one orbit of a torque-free body with a spherical
/// inertia (its inertial rate stays the orbit's), started at `offset` from the orbital
/// frame of a circular orbit and turning at the orbit's rate.
fn held(offset: UnitQuaternion<f64>) -> Vec<[f64; 3]> {
    let text = r#"duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[50.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 0.0, 50.0]]
"#;
    let scene = Scene::parse(text, &examples().join("scenes/test.toml")).expect("scene");
    let a = R_EARTH + 600e3;
    let orbit = Orbit::from_elements(
        OrbitModel::Kepler,
        &Elements {
            raan: 0.4,
            argp: 0.3,
            nu: 1.0,
            ..Elements::circular(a, 0.9)
        },
    );
    let own = [
        orbit.r0.x, orbit.r0.y, orbit.r0.z, orbit.v0.x, orbit.v0.y, orbit.v0.z,
    ];
    let lvlh = orbit.state(&own).orbital_frame();
    let attitude = lvlh * offset;
    // The orbital frame turns at r × v / r² (inertial); the bus turns with it.
    let rate = attitude.inverse_transform_vector(&(orbit.r0.cross(&orbit.v0) / (a * a)));
    let mut state = scene.initial.clone();
    // nalgebra stores [x, y, z, w]; the state is [w, x, y, z].
    let c = attitude.quaternion().coords;
    state.q[..4].copy_from_slice(&[c.w, c.x, c.y, c.z]);
    state.v[..3].copy_from_slice(rate.as_slice());
    let mut sim = Simulation::builder(scene.model)
        .initial(state)
        .effect(orbit)
        .build()
        .expect("builds");
    let cols = sim.columns();
    let at = |n: &str| cols.iter().position(|c| c == n).expect(n);
    let (r, p, y) = (at("roll"), at("pitch"), at("yaw"));
    let period = std::f64::consts::TAU * (a * a * a / 3.986004418e14).sqrt();
    let options = Options {
        method: Method::Dp54,
        rtol: 1e-11,
        atol: 1e-14,
        ..Options::default()
    };
    let mut rows = Vec::new();
    sim.run(
        &options,
        period,
        &Output::Interval(period / 50.0),
        |_, row| {
            rows.push([row[r], row[p], row[y]]);
            Ok::<(), ()>(())
        },
    )
    .expect("runs");
    assert_eq!(rows.len(), 51);
    rows
}

#[test]
fn a_bus_held_in_the_orbital_frame_reads_zero() {
    for rpy in held(UnitQuaternion::identity()) {
        assert!(rpy.iter().all(|a| a.abs() < 1e-7), "{rpy:?}");
    }
}

#[test]
fn a_known_offset_reads_back() {
    let (roll, pitch, yaw) = (0.1, -0.2, 0.3);
    // z-y'-x'': yaw about z, then pitch about the new y, then roll about the newest x.
    let offset = UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), yaw)
        * UnitQuaternion::from_axis_angle(&nalgebra::Vector3::y_axis(), pitch)
        * UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), roll);
    for rpy in held(offset) {
        let err = [rpy[0] - roll, rpy[1] - pitch, rpy[2] - yaw];
        assert!(err.iter().all(|e| e.abs() < 1e-7), "{rpy:?}");
    }
}

#[test]
fn the_libration_scene_starts_at_its_pitch_offset_and_librates_in_pitch() {
    // examples/scenes/libration.toml: the orbital frame times 0.1 rad about y, on an
    // equatorial orbit; a planar libration, so roll and yaw stay zero.
    let scene = Scene::read(examples().join("scenes/libration.toml")).expect("scene");
    let mut sim = scene.simulation().expect("builds");
    let cols = sim.columns();
    let at = |n: &str| cols.iter().position(|c| c == n).expect(n);
    let (r, p, y) = (at("roll"), at("pitch"), at("yaw"));
    let mut rows = Vec::new();
    sim.run(
        &scene.options,
        scene.duration,
        &Output::Interval(scene.every),
        |_, row| {
            rows.push([row[r], row[p], row[y]]);
            Ok::<(), ()>(())
        },
    )
    .expect("runs");
    assert!((rows[0][1] - 0.1).abs() < 1e-9, "{:?}", rows[0]);
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
            (l.min(x[1]), h.max(x[1]))
        });
    // It swings to about −0.1 and back (energy is conserved in the rotating frame).
    assert!(lo < -0.09 && hi <= 0.1 + 1e-6, "pitch within [{lo}, {hi}]");
    for x in &rows {
        assert!(x[0].abs() < 1e-8 && x[2].abs() < 1e-8, "{x:?}");
    }
}
