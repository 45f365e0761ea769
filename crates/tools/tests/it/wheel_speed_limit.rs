//! Regression: a reaction wheel's speed limit stalled the adaptive integrators (issue 28).
//!
//! The default scene with wheel `x` limited to 3 rad/s: the controller drives it into the
//! limit. Cutting the motor torque wherever `|Ω| ≥ max_speed` made DP5(4) chatter on the
//! limit (friction slows the wheel, the torque comes back, it speeds up, the torque goes):
//! 100 000 steps reached t = 0.68 s, the default 10 000 000 burnt minutes of CPU. The limit
//! is now a mode held between events and the wheel is held at it while the command drives
//! it outwards. A run that does run out of steps says what it was stepping through.

use crate::common::example;
use satsim_integrate::{Method, Options, Output};
use satsim_tools::accuracy::run;
use satsim_tools::scene::Scene;

fn limited_deploy(duration: f64) -> Scene {
    let path = example("scenes/deploy.toml");
    let text = std::fs::read_to_string(&path).unwrap().replacen(
        "max_speed = 600.0        # rad/s",
        "max_speed = 3.0",
        1,
    );
    assert!(
        text.contains("max_speed = 3.0"),
        "the scene's wheel x changed"
    );
    let mut scene = Scene::parse(&text, &path).expect("valid scene");
    scene.duration = duration;
    scene
}

#[test]
fn dp54_runs_through_a_wheel_held_at_its_speed_limit() {
    let scene = limited_deploy(20.0);
    let dp54 = Options::new(Method::Dp54)
        .with_tolerances(1e-9, 1e-12)
        .with_max_steps(100_000);
    let r = run(&scene, &dp54).expect("the run ends");
    assert!(
        r.stats.steps_accepted + r.stats.steps_rejected < 10_000,
        "{:?}",
        r.stats
    );
    // The wheel never exceeds its limit (by more than the event location's tolerance).
    let sim = scene.simulation().unwrap();
    let i = sim
        .layout()
        .effects
        .iter()
        .find(|(n, _)| n == "reaction_wheels")
        .unwrap()
        .1
        .start;
    for (t, x) in r.times.iter().zip(&r.states) {
        assert!(
            x[i].abs() <= 3.0 * (1.0 + 1e-9),
            "t = {t}: wheel x at {} rad/s",
            x[i]
        );
    }
    // And is held at it: exactly 3 rad/s at several output times.
    let at_limit = r.states.iter().filter(|x| x[i].abs() == 3.0).count();
    assert!(
        at_limit >= 3,
        "{:?}",
        r.states.iter().map(|x| x[i]).collect::<Vec<_>>()
    );
    // RK4 integrates the same model (the same events): the two agree.
    let rk4 = run(
        &scene,
        &Options::new(Method::Rk4).with_fixed_step(1.0 / 64.0),
    )
    .unwrap();
    let (a, b) = (r.states.last().unwrap(), rk4.states.last().unwrap());
    assert!(
        (a[i] - b[i]).abs() < 1e-6,
        "wheel x: {} by DP5(4), {} by RK4",
        a[i],
        b[i]
    );
}

#[test]
fn a_run_out_of_steps_names_the_effect_whose_events_it_was_stepping_through() {
    let scene = limited_deploy(20.0);
    let mut sim = scene.simulation().unwrap();
    let options = Options::new(Method::Dp54)
        .with_tolerances(1e-9, 1e-12)
        .with_max_steps(60);
    let e = sim
        .run(&options, 20.0, &Output::Interval(1.0), |_, _| {
            Ok::<(), String>(())
        })
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("maximum number of steps exceeded at t = "),
        "{e}"
    );
    assert!(
        e.contains("events (t = ") && e.contains("were reaction_wheels "),
        "{e}"
    );
    assert!(e.contains("the last: wheel `x`"), "{e}");
    // Without any event, it says so.
    let mut sim = scene.simulation().unwrap();
    let e = sim
        .run(
            &options.clone().with_max_steps(2),
            20.0,
            &Output::Interval(1.0),
            |_, _| Ok::<(), String>(()),
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("no event fired"), "{e}");
}

#[test]
fn a_fixed_step_run_out_of_steps_does_not_blame_the_dynamics() {
    // 1/64 s steps with a row every 0.01 s: every row cuts a step, so the run takes more
    // steps than its grid's (which fit the budget, so the run is not refused before it
    // starts).
    let scene = limited_deploy(20.0);
    let rk4 = Options::new(Method::Rk4)
        .with_fixed_step(1.0 / 64.0)
        .with_max_steps(2000);
    let run = |t_end: f64, every: f64, options: &Options| {
        let mut sim = scene.simulation().unwrap();
        sim.run(options, t_end, &Output::Interval(every), |_, _| {
            Ok::<(), String>(())
        })
        .unwrap_err()
        .to_string()
    };
    let e = run(20.0, 0.01, &rk4);
    assert!(
        e.starts_with("maximum number of steps exceeded at t = "),
        "{e}"
    );
    assert!(e.contains("; the step is fixed (0.015625 s)"), "{e}");
    assert!(e.contains("events (t = "), "{e}");
    assert!(!e.contains("dynamics themselves"), "{e}");
    // Before any event (one step of the grid cut by 40 rows): the fixed step alone, no word
    // of the dynamics.
    let e = run(0.004, 1e-4, &rk4.clone().with_max_steps(2));
    assert!(e.contains("; the step is fixed (0.015625 s)"), "{e}");
    assert!(!e.contains("no event fired"), "{e}");
}
