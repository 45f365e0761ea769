//! Building a scene in code and running it: the preprint's satellite (from its typed
//! parameters), stowed, deploying on hinge springs while three reaction wheels hold the bus,
//! on a circular orbit under the full gravity-gradient model.
//!
//! `cargo run --release --example build_scene`

use satsim::integrate::{Method, Options, Output};
use satsim::satellite::{Deployment, PreprintParams, build_model};
use satsim::spacecraft::effects::{
    AttitudeControl, Elements, GravityGradient, GravityModel, HingeSprings, Orbit, OrbitModel,
    ReactionWheels, Target, Wheel,
};
use satsim::tools::scene::Scene;
use satsim::tree::State;
use satsim::tree::spatial::Vec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = build_model(&PreprintParams::default())?;
    let mut initial = State::rest(&model);
    initial.q[7..12].copy_from_slice(&Deployment::Stowed.angles());

    let mut scene = Scene::new(model, initial, 120.0);
    scene.options = Options::new(Method::Rk4).with_fixed_step(0.01);
    scene.every = 10.0;
    let orbit = Orbit::from_elements(
        OrbitModel::J2,
        &Elements::circular(6_878_137.0, 97.4f64.to_radians()),
    );
    let wheels: Vec<Wheel> = (0..3)
        .map(|j| {
            let mut w = Wheel::new(["x", "y", "z"][j], Vec3::ith(j, 1.0), 0.1);
            w.max_torque = 1.0;
            w.viscous = 1e-5;
            w
        })
        .collect();
    let mut springs = HingeSprings::new(vec![50.0, 50.0, 50.0, 2.0, 2.0]);
    springs.damping = vec![40.0, 40.0, 40.0, 4.0, 4.0];
    scene.effects.insert(orbit);
    scene
        .effects
        .insert(GravityGradient::new(GravityModel::Full));
    scene.effects.insert(springs);
    scene.effects.insert(ReactionWheels::new(wheels));
    // The controller commands the wheels (every rotor of the tree, in their order).
    scene.effects.insert(AttitudeControl::new(
        Target::Inertial(Default::default()),
        9.0,
        150.0,
    ));

    let mut sim = scene.simulation()?;
    println!(
        "effects: {}; state length {}",
        sim.effect_names().join(", "),
        sim.layout().len
    );
    let columns = sim.columns();
    let col = |name: &str| columns.iter().position(|c| c == name).unwrap();
    let (h4, h5, ke, wx) = (
        col("angle_h4"),
        col("angle_h5"),
        col("kinetic_energy"),
        col("wheel_x_speed"),
    );
    println!(
        "{:>6} {:>10} {:>10} {:>12} {:>12}",
        "t", "h4", "h5", "T (J)", "wheel x"
    );
    let stats = sim.run(
        &scene.options,
        scene.duration,
        &Output::Interval(scene.every),
        |t, row| {
            println!(
                "{t:6.1} {:10.5} {:10.5} {:12.5} {:12.4}",
                row[h4], row[h5], row[ke], row[wx]
            );
            Ok::<(), std::convert::Infallible>(())
        },
    )?;
    println!(
        "{} steps, {} rhs evaluations",
        stats.steps_accepted, stats.rhs_evals
    );
    Ok(())
}
