//! Actuators mounted off their design: a wheel's or a thruster's `misalignment` turns its true
//! axis (the one the dynamics use) by a fixed rotation, while the flight software keeps the
//! nominal one. Each check has its exact
//! answer: from rest, a wheel's torque leaves the bus turning about the wheel's true axis
//! (its momentum and the bus's cancel, and that axis is a principal axis of an isotropic
//! bus with the rotor), and a thruster's impulse is `thrust · t` along its true direction.

use satsim_tools::scene::Scene;
use satsim_tree::spatial::Vec3;
use std::path::Path;

fn parse(text: &str) -> Result<Scene, String> {
    Scene::parse(text, Path::new("mounting.toml")).map_err(|e| e.to_string())
}

/// An isotropic bus at rest with `effects`, RK4 at 0.01 s for 2 s.
fn scene(effects: &str) -> String {
    format!(
        r#"duration = 2.0
[model]
[[model.body]]
name = "bus"
mass = 80.0
inertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.1
plots = false
view = false
{effects}
"#
    )
}

/// The rotation of vector `r` applied to `v`.
fn turned(r: [f64; 3], v: Vec3) -> Vec3 {
    nalgebra::UnitQuaternion::from_scaled_axis(Vec3::from(r)) * v
}

fn final_state(scene: &Scene) -> (Vec3, Vec3, Vec3) {
    let mut sim = scene.simulation().expect("the scene builds");
    let (t, x) = sim
        .state_at(&scene.options, scene.duration)
        .expect("the run completes");
    let d = sim.diagnostics(t, &x).unwrap();
    let layout = sim.layout();
    let w = Vec3::from_column_slice(&x[layout.omega.clone()]);
    (d.p, d.h, w)
}

#[test]
fn a_misaligned_wheel_turns_the_bus_about_its_true_axis() {
    let m = [0.02, -0.01, 0.0];
    let wheel = |mis: &str| {
        scene(&format!(
            "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"z\"\naxis = [0.0, 0.0, 1.0]\ninertia = 0.02\ntorque = 0.01\n{mis}\n"
        ))
    };
    let (_, h, w) = final_state(&parse(&wheel(&format!("misalignment = {m:?}"))).unwrap());
    let axis = turned(m, Vec3::z());
    assert!(h.norm() < 1e-12, "momentum from rest: {h:?}");
    let along = -w.normalize();
    assert!(
        (along - axis).norm() < 1e-9,
        "the bus turns about {along:?}, the wheel's true axis is {axis:?}"
    );
    // Without the key: exactly about −z.
    let (_, _, w0) = final_state(&parse(&wheel("")).unwrap());
    assert!(w0[0] == 0.0 && w0[1] == 0.0 && w0[2] < 0.0, "{w0:?}");
}

#[test]
fn a_misaligned_thruster_pushes_along_its_true_direction() {
    let m = [0.0, 0.01, -0.03];
    let at = Vec3::new(0.0, 1.0, 0.0);
    let text = scene(&format!(
        "[effects.thrusters]\nperiod = 0.1\n[[effects.thrusters.thruster]]\nname = \"x\"\nat = [0.0, 1.0, 0.0]\ndirection = [1.0, 0.0, 0.0]\nthrust = 2.0\nduty = 1.0\nmisalignment = {m:?}\n"
    ));
    let (_, _, w) = final_state(&parse(&text).unwrap());
    // The torque `at × F` is constant in the bus's axes and the bus isotropic: the bus turns
    // about that torque's axis at `|τ| t / J`, exactly (no gyroscopic term).
    let tau = at.cross(&(turned(m, Vec3::x()) * 2.0));
    let expected = tau * 2.0 / 10.0;
    assert!(
        (w - expected).norm() < 1e-12 * expected.norm(),
        "rate {w:?}, expected {expected:?}"
    );
    // The nominal direction would give a turn about −z only.
    assert!(w[0].abs() > 1e-3 * w.norm());
}

#[test]
fn bad_mountings_are_errors_at_their_line() {
    let cases = [
        (
            "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"z\"\naxis = [0.0, 0.0, 1.0]\ninertia = 0.02\nbody = \"gimbal\"\n",
            "unknown body `gimbal` (the model's bodies: bus)",
        ),
        (
            "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"z\"\naxis = [0.0, 0.0, 1.0]\ninertia = 0.02\nmisalignment = [0.0, 4.0, 0.0]\n",
            "`misalignment` must be three finite angles within ±π (rad)",
        ),
        (
            "[effects.thrusters]\nperiod = 0.1\n[[effects.thrusters.thruster]]\nname = \"x\"\nat = [0.0, 1.0, 0.0]\ndirection = [1.0, 0.0, 0.0]\nthrust = 2.0\nmisalignment = [0.0, 0.0, nan]\n",
            "`misalignment` must be three finite angles within ±π (rad)",
        ),
    ];
    for (effects, want) in cases {
        let Err(e) = parse(&scene(effects)) else {
            panic!("accepted: {effects}")
        };
        assert!(e.contains(want), "{e}");
        assert!(e.contains("mounting.toml:"), "no line in: {e}");
    }
}
