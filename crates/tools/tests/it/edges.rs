//! Small faults at the edges of the library API: a controller with gains for fewer wheels
//! than the scene has, slices of the wrong length given to public functions (an error, never
//! a panic), and output rows or whole runs that allocate.

use crate::common::example;
use satsim_satellite::{PreprintParams, build_model, recognise, state_from_engine};
use satsim_spacecraft::effects::{AttitudeControl, ReactionWheels, Target, Wheel};
use satsim_spacecraft::simulation::Simulation;
use satsim_testkit::alloc::allocations;
use satsim_tools::scene::Scene;
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Body, ModelBuilder};

use satsim_integrate::System;

fn bus() -> satsim_tree::Model {
    ModelBuilder::new(BaseKind::Free)
        .body(Body::new("bus", 100.0, Mat3::identity() * 10.0))
        .build()
        .unwrap()
}

#[test]
fn a_controller_runs_before_the_wheels_it_commands_and_is_refused_without_them() {
    let axes = [Vec3::x(), Vec3::y(), Vec3::z()];
    let wheels: Vec<Wheel> = ["x", "y", "z"]
        .iter()
        .zip(axes)
        .map(|(n, a)| Wheel::new(*n, a, 0.05))
        .collect();
    let control = AttitudeControl::new(Target::Inertial(Default::default()), 1.0, 10.0);
    // Given after the wheels, the controller still runs first (it declares `before`).
    let sim = Simulation::builder(bus())
        .effect(ReactionWheels::new(wheels))
        .effect(control.clone())
        .build()
        .unwrap();
    assert_eq!(sim.effect_names(), ["attitude_control", "reaction_wheels"]);
    let err = Simulation::builder(bus())
        .effect(control)
        .build()
        .err()
        .expect("a controller without wheels must be refused");
    let msg = err.to_string();
    assert!(
        msg.contains("attitude_control") && msg.contains("`reaction_wheels`"),
        "{msg}"
    );
}

#[test]
fn public_functions_refuse_short_slices() {
    let scene = Scene::read(example("scenes/deploy.toml")).unwrap();
    let mut sim = scene.simulation().unwrap();
    let n = sim.layout().len;
    let x = sim.x0().to_vec();
    let short = &x[..n - 1];
    let mut dx = vec![0.0; n];
    let mut row = Vec::new();
    let e = sim.rhs(0.0, short, &mut dx).unwrap_err();
    assert!(e.to_string().contains("rhs: state has length"), "{e}");
    assert!(sim.rhs(0.0, &x, &mut dx[..n - 1]).is_err());
    assert!(sim.row(0.0, short, &mut row).is_err());
    assert!(sim.diagnostics(0.0, short).is_err());
    let mut g = vec![0.0; sim.n_events()];
    assert!(!g.is_empty(), "the default scene has events");
    assert!(sim.events(0.0, short, &mut g).is_err());
    // The full-length state still works.
    sim.rhs(0.0, &x, &mut dx).unwrap();
    sim.events(0.0, &x, &mut g).unwrap();

    let e = state_from_engine(&[0.0; 11], &[0.0; 11], &[0.0; 11]).unwrap_err();
    assert!(e.to_string().contains("q: expected 12"), "{e}");
    assert!(state_from_engine(&[0.0; 12], &[0.0; 10], &[0.0; 11]).is_err());
    assert!(state_from_engine(&[0.0; 12], &[0.0; 11], &[0.0; 11]).is_ok());
    let layout = recognise(&build_model(&PreprintParams::default()).unwrap()).unwrap();
    assert!(layout.body(1).is_some() && layout.body(4).is_some());
    assert_eq!(layout.body(0), None);
    assert_eq!(layout.body(5), None);
}

/// An output row (wheels, controller, orbit, springs, stops: the default scene) allocates
/// nothing once its buffer has grown.
#[test]
fn output_rows_do_not_allocate() {
    let scene = Scene::read(example("scenes/deploy.toml")).unwrap();
    let mut sim = scene.simulation().unwrap();
    let x = sim.x0().to_vec();
    let mut row = Vec::new();
    sim.row(0.0, &x, &mut row).unwrap();
    let before = allocations();
    for k in 0..10 {
        sim.row(0.1 * k as f64, &x, &mut row).unwrap();
    }
    assert_eq!(allocations() - before, 0, "allocations in 10 rows");
}

/// A whole run of the default scene (wheels with friction, controller, orbit, gravity
/// gradient, springs, latching stops: the latches and the wheels' stick-slip are events)
/// allocates nothing per step, for a fixed-step, two explicit adaptive and the implicit
/// method: from the first output row past the start (the first step has grown the buffers)
/// to the last row, the allocations between two rows are counted, and every stretch of steps
/// allocates nothing, those with an event too. The rows go to a sink that copies them into a
/// buffer reserved beforehand, so the count is the integrator loop's, the right-hand side's,
/// the event functions', the events' (their impulse solve, their description in the event
/// log) and the row's.
#[test]
fn a_whole_run_allocates_nothing_per_step() {
    use satsim_integrate::{Method, Options, Output};
    let scene = Scene::read(example("scenes/deploy.toml")).unwrap();
    let methods = [
        Options::new(Method::Rk4).with_fixed_step(0.01),
        Options::new(Method::Dp54).with_tolerances(1e-9, 1e-9),
        Options::new(Method::Dop853).with_tolerances(1e-9, 1e-9),
        Options::new(Method::Radau5).with_tolerances(1e-6, 1e-6),
    ];
    for options in methods {
        let mut sim = scene.simulation().unwrap();
        let mut last_row = Vec::with_capacity(256);
        // (t, allocations since the previous row), from the first row past the start.
        let mut deltas: Vec<(f64, usize)> = Vec::with_capacity(1000);
        let mut previous: Option<usize> = None;
        let stats = sim
            .run(&options, 60.0, &Output::Interval(0.5), |t, row| {
                let now = allocations();
                if let Some(p) = previous {
                    deltas.push((t, now - p));
                }
                if t > 0.0 {
                    previous = Some(now);
                }
                last_row.clear();
                last_row.extend_from_slice(row);
                Ok::<(), std::convert::Infallible>(())
            })
            .unwrap();
        assert!(stats.events.len() >= 2, "the latches are in the run");
        assert!(deltas.len() > 100, "{} rows", deltas.len());
        let mut t_previous = 0.5;
        let (mut quiet, mut at_events) = (0, 0);
        for &(t, n) in &deltas {
            let event = stats
                .events
                .iter()
                .any(|&(te, _)| te > t_previous && te <= t);
            if event {
                at_events += n;
                assert_eq!(
                    n, 0,
                    "{:?}: {n} allocations in ({t_previous}, {t}] s, handling an event",
                    options.method
                );
            } else {
                quiet += n;
                assert_eq!(
                    n, 0,
                    "{:?}: {n} allocations in ({t_previous}, {t}] s",
                    options.method
                );
            }
            t_previous = t;
        }
        println!(
            "{:?}: {} steps, {} events; allocations: {quiet} between events, {at_events} in the \
             stretches with an event",
            options.method,
            stats.steps_accepted,
            stats.events.len()
        );
    }
}
