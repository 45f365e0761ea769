//! Cost of the right-hand side with effects on and off, and of one orbit of the preprint
//! satellite with three wheels (the issue's peer comparison: Basilisk 2.12 takes ~4.7 s for
//! one 5926 s orbit at dt = 0.1 s with RK4; the target is < 0.1 s).
//!
//! `cargo bench -p satsim-satellite --bench rhs`

use criterion::{Criterion, criterion_group, criterion_main};
use satsim_integrate::{Method, Options, Output, System};
use satsim_tools::scene::Scene;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

const BASE: &str = r#"model = "../satellite.toml"
duration = 5926.0
[initial]
hinges = { angle = [0.0, 0.0, 0.0, 1.2, -1.0], rate = [0.01, 0.0, 0.0, 0.05, -0.04] }
base = { angular_velocity = [0.001, -0.002, 0.0015] }
[integrator]
method = "rk4"
step = 0.1
"#;

const ALL: &str = r#"[orbit]
altitude = 500e3
inclination_deg = 51.6
[effects.gravity_gradient]
model = "full"
[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
damping = [40.0, 40.0, 40.0, 4.0, 4.0]
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "x"
axis = [1.0, 0.0, 0.0]
inertia = 0.1
viscous = 1e-5
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.1
viscous = 1e-5
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.1
viscous = 1e-5
[effects.attitude_control]
kp = 9.0
kd = 150.0
"#;

const WHEELS_ONLY: &str = r#"[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
damping = [40.0, 40.0, 40.0, 4.0, 4.0]
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "x"
axis = [1.0, 0.0, 0.0]
inertia = 0.1
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.1
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.1
[effects.attitude_control]
kp = 9.0
kd = 150.0
"#;

fn scene(extra: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/bench.toml");
    Scene::parse(&format!("{BASE}{extra}"), &path).expect("bench scene")
}

fn rhs(c: &mut Criterion) {
    let mut g = c.benchmark_group("rhs");
    for (name, extra) in [
        ("torque_free", ""),
        ("springs_wheels_control", WHEELS_ONLY),
        ("all_effects", ALL),
    ] {
        let mut sim = scene(extra).simulation().unwrap();
        let x = sim.x0().to_vec();
        let mut dx = vec![0.0; x.len()];
        g.bench_function(name, |b| {
            b.iter(|| sim.rhs(0.0, black_box(&x), &mut dx).unwrap());
        });
    }
    g.finish();
}

fn one_orbit(c: &mut Criterion) {
    let mut g = c.benchmark_group("one_orbit_rk4_dt0.1");
    g.sample_size(10);
    for (name, extra) in [
        ("springs_wheels_control", WHEELS_ONLY),
        ("all_effects", ALL),
    ] {
        let s = scene(extra);
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut sim = s.simulation().unwrap();
                let x0 = sim.x0().to_vec();
                let opts = Options::new(Method::Rk4).with_fixed_step(0.1);
                satsim_integrate::integrate(
                    &mut sim,
                    &opts,
                    0.0,
                    &x0,
                    5926.0,
                    &Output::Times(vec![]),
                    |_, _| std::ops::ControlFlow::Continue(()),
                )
                .unwrap()
            });
        });
    }
    g.finish();
    // A plain wall-clock figure as well (one run each).
    for (name, extra) in [
        ("springs_wheels_control", WHEELS_ONLY),
        ("all_effects", ALL),
    ] {
        let mut sim = scene(extra).simulation().unwrap();
        let x0 = sim.x0().to_vec();
        let opts = Options::new(Method::Rk4).with_fixed_step(0.1);
        let t = Instant::now();
        let st = satsim_integrate::integrate(
            &mut sim,
            &opts,
            0.0,
            &x0,
            5926.0,
            &Output::Times(vec![]),
            |_, _| std::ops::ControlFlow::Continue(()),
        )
        .unwrap();
        let dt = t.elapsed().as_secs_f64();
        println!(
            "one orbit ({name}): {dt:.4} s wall, {} steps, {:.2} us/step, {:.0} ns/rhs",
            st.steps_accepted,
            1e6 * dt / st.steps_accepted as f64,
            1e9 * dt / st.rhs_evals as f64
        );
    }
}

criterion_group!(benches, rhs, one_orbit);
criterion_main!(benches);
