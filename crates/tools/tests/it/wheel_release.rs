//! Regression: a reaction wheel released with a motor torque barely above its static friction,
//! on a bus that the deploying array is shaking, must not chatter about zero speed.
//!
//! Comparing the motor torque alone with the static friction let the bus drive such a wheel
//! backwards, so `sgn Ω` flipped inside steps without an event: RK4 fell to first order on
//! the deployment scene and a 1e-13 reference took 35 s instead of 0.02 s. The wheels now
//! hold their slip direction between events and decide on the exact hold torque. The default
//! scene contains that release (at t ≈ 5.6 ms); over its 300 s, RK4 converges at fourth
//! order (the first seconds alone are dominated by the controller's saturation kinks).

use crate::common::example;
use satsim_integrate::{Method, Options};
use satsim_tools::accuracy::{compare, run};
use satsim_tools::scene::Scene;

fn deploy(duration: f64) -> Scene {
    let path = example("scenes/deploy.toml");
    let mut scene = Scene::read(path).expect("the default scene loads");
    scene.duration = duration;
    scene
}

#[test]
fn rk4_keeps_its_fourth_order_through_the_wheel_release() {
    let scene = deploy(300.0);
    let reference = run(
        &scene,
        &Options::new(Method::Dop853).with_tolerances(1e-13, 1e-13),
    )
    .unwrap();
    assert!(
        reference
            .stats
            .events
            .iter()
            .any(|&(t, _)| t > 0.0 && t < 0.01),
        "the wheel release should happen in the first 10 ms: {:?}",
        reference.stats.events
    );
    let layout = scene.simulation().unwrap().layout().clone();
    let errors: Vec<f64> = [1.0 / 16.0, 1.0 / 32.0, 1.0 / 64.0]
        .iter()
        .map(|&h| {
            let r = run(&scene, &Options::new(Method::Rk4).with_fixed_step(h)).unwrap();
            compare(&layout, &reference, &r).unwrap().final_max
        })
        .collect();
    for w in errors.windows(2) {
        // Fourth order divides the error by 16 per halving; first order (the chattering) by 2.
        assert!(w[0] / w[1] > 8.0, "RK4 errors {errors:?}: not fourth order");
    }
}

#[test]
fn the_reference_run_takes_few_steps() {
    let mut scene = deploy(1.0);
    scene.every = 0.25;
    let r = run(
        &scene,
        &Options::new(Method::Dop853).with_tolerances(1e-12, 1e-12),
    )
    .unwrap();
    // With the chattering, DOP853 spent some 43 000 steps in the first 0.03 s at 1e-12.
    assert!(
        r.stats.steps_accepted < 500,
        "{} steps",
        r.stats.steps_accepted
    );
}
