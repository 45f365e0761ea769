//! The energy budget `energy_budget = T + V − W + D` (kinetic + potential − actuator work +
//! dissipated energy) stays constant: on every example scene, and on a scene for each
//! dissipative or actuated effect. Each effect's scene also runs with that effect's power
//! left out of the budget (the [`Unbooked`] wrapper), and the budget must then drift: the
//! check would catch an effect whose work is forgotten.
//!
//! The bound: over a run, `max |budget(t) − budget(0)|` must be below `RATIO` times the
//! largest term of the budget (the largest magnitude, over the run, of `T`, `V`, `W` and
//! `D`), with `RATIO = 1e-6`. The budget is exact but for the integration error: `W` and `D`
//! are integrated by the same method as the motion, to its order, and the impacts' losses
//! are booked exactly at the events; the integration error of `T + V` is relative to `T + V`
//! itself (a tolerance `rtol` on the states), hence the magnitude rather than the range. At
//! the scenes' tolerances (RK4 at 0.01 s, adaptive methods at `rtol <= 1e-8`) the measured
//! ratios are 3e-8 or smaller (printed by each test; the largest is Radau IIA on the stiff
//! hinges, which damps their unresolved vibration), so 1e-6 leaves a margin of 30, while a
//! left-out work term exceeds it 3e4 times or more (measured ratios 3e-2 to 1.3 with one
//! effect's power left out; each effect's test asserts more than 1e-3).

use nalgebra::UnitQuaternion;
use satsim_integrate::{EventAction, EventDirection, Method, Options, Output, SystemError};
use satsim_spacecraft::effects::orbit::{Elements, R_EARTH};
use satsim_spacecraft::effects::{
    AttitudeControl, Context, Effect, Forces, GravityGradient, GravityModel, HingeControl,
    HingeProfile, HingeSprings, HingeStop, HingeStops, Links, Needs, Orbit, OrbitModel, OrbitState,
    Power, ReactionWheels, Request, Rotor, StopAction, Target, Wheel,
};
use satsim_spacecraft::simulation::Simulation;
use satsim_tools::scene::Scene;
use satsim_tree::spatial::{Force, Vec3};
use satsim_tree::{Model, State};
use std::path::{Path, PathBuf};

/// Largest budget drift, as a fraction of the largest exchanged term (see the module docs).
const RATIO: f64 = 1e-6;

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// The budget's drift and the largest exchanged term over a run, and the final `W`, `D`.
#[derive(Debug)]
struct Budget {
    drift: f64,
    scale: f64,
    work: f64,
    dissipated: f64,
}

impl Budget {
    fn ratio(&self) -> f64 {
        self.drift / self.scale
    }
}

/// Runs `sim` to `t_end`, reading the budget at every accepted step.
fn measure(sim: &mut Simulation, options: &Options, t_end: f64) -> Budget {
    let cols = sim.columns();
    let at = |name: &str| {
        cols.iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name} in {cols:?}"))
    };
    let terms = [
        at("kinetic_energy"),
        at("potential_energy"),
        at("work_actuators"),
        at("energy_dissipated"),
    ];
    let budget = at("energy_budget");
    let mut lo = [f64::INFINITY; 4];
    let mut hi = [f64::NEG_INFINITY; 4];
    let mut first = None;
    let mut drift: f64 = 0.0;
    let mut last = Vec::new();
    sim.run(options, t_end, &Output::Steps, |_, row| {
        for (k, &c) in terms.iter().enumerate() {
            lo[k] = lo[k].min(row[c]);
            hi[k] = hi[k].max(row[c]);
        }
        let b0 = *first.get_or_insert(row[budget]);
        drift = drift.max((row[budget] - b0).abs());
        last = row.to_vec();
        Ok::<(), ()>(())
    })
    .expect("the run completes");
    let scale = (0..4)
        .map(|k| hi[k].abs().max(lo[k].abs()))
        .fold(0.0, f64::max);
    Budget {
        drift,
        scale,
        work: last[terms[2]],
        dissipated: last[terms[3]],
    }
}

fn assert_flat(what: &str, b: &Budget) {
    println!(
        "{what}: drift {:.3e} J of {:.3e} J exchanged (ratio {:.2e}), W {:.4e} J, D {:.4e} J",
        b.drift,
        b.scale,
        b.ratio(),
        b.work,
        b.dissipated
    );
    assert!(b.scale > 0.0, "{what}: nothing exchanged");
    assert!(b.ratio() < RATIO, "{what}: the budget drifts: {b:?}");
}

#[test]
fn every_example_scene_keeps_its_budget() {
    let dir = examples().join("scenes");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("examples/scenes")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        // This scene needs the effect that examples/custom_effect.rs defines and registers.
        .filter(|p| !p.ends_with("magnetic_torquer.toml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 8, "{paths:?}");
    for path in paths {
        let scene = Scene::read(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = scene.simulation().expect("the scene builds");
        let b = measure(&mut sim, &scene.options, scene.duration);
        if b.scale == 0.0 {
            // At rest (deployment_modes.toml is a linearisation point): nothing moves.
            assert_eq!(b.drift, 0.0, "{}", path.display());
            continue;
        }
        assert_flat(&path.display().to_string(), &b);
    }
}

#[test]
fn the_flexible_array_keeps_its_budget() {
    // The deployment with flexible panels (examples/flexible_array.toml): strain energy in
    // `V`, modal damping in `D`, the latches' impacts (at about 4.5 and 9.5 s) exciting the
    // modes; 20 s of it, through both latches. With RK4 at 2 ms, every mode resolved: the
    // scene's own Radau IIA steps over the fastest modes and damps them (its run summary
    // books that as the budget's change), which is the method's, not the model's.
    let scene =
        Scene::read(examples().join("flexible_array.toml")).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.simulation().expect("the scene builds");
    assert_eq!(sim.layout().eta.len(), 9, "three panels of three modes");
    let rk4 = Options::new(Method::Rk4).with_fixed_step(0.002);
    let b = measure(&mut sim, &rk4, 20.0);
    assert_eq!(
        sim.event_records()
            .filter(|(_, e, _)| *e == "hinge_stops")
            .count(),
        2
    );
    assert_flat("flexible_array.toml", &b);
}

#[test]
fn the_budget_leaves_radau_iia_s_steps_and_states_as_they_were() {
    // The works are quadratures (`System::quadratures`): out of the error control and out of
    // Radau IIA's Newton test and Jacobian, so the flexible deployment's first 12 s (both
    // latches, a wheel sticking and breaking free) take the same steps and reach the same
    // state, bit for bit, with the budget and without it. (Counted in the Newton test, the
    // works took 380 steps there where the motion alone takes 370.)
    let mut scene =
        Scene::read(examples().join("flexible_array.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.options.method, Method::Radau5);
    let mut run = |budget: bool| {
        scene.energy_budget = budget;
        let mut sim = scene.simulation().expect("the scene builds");
        let stats = sim
            .run(&scene.options, 12.0, &Output::Times(vec![]), |_, _| {
                Ok::<(), ()>(())
            })
            .expect("the run completes");
        (stats, sim.event_log().to_vec())
    };
    let (with, with_events) = run(true);
    let (without, without_events) = run(false);
    let n = without.x_final.len();
    assert_eq!(with.x_final.len(), n + 2, "the two works");
    assert_eq!(with.x_final[..n], without.x_final[..]);
    assert_eq!(
        (
            with.steps_accepted,
            with.steps_rejected,
            with.jacobian_evals
        ),
        (
            without.steps_accepted,
            without.steps_rejected,
            without.jacobian_evals
        )
    );
    // The first Jacobian differences the two works' columns, to check they are zero.
    assert_eq!(with.rhs_evals, without.rhs_evals + 2);
    assert_eq!(with_events, without_events);
    assert!(with_events.len() >= 5, "{with_events:?}");
}

// ---- one scene per dissipative or actuated effect ----------------------------------------

/// The preprint's satellite (`examples/satellite.toml`: bus, 3-DOF gimbal h1-h3, panels
/// h4, h5), its panels moving.
fn satellite() -> (Model, State) {
    let text = r#"model = "../satellite.toml"
duration = 1.0
[initial]
base = { angular_velocity = [0.01, -0.02, 0.015] }
hinges = { angle = [0.0, 0.1, 0.0, 1.0, -1.0], rate = [0.02, 0.0, -0.01, 0.3, -0.2] }
"#;
    let scene = Scene::parse(text, &examples().join("scenes/test.toml")).expect("scene");
    (scene.model, scene.initial)
}

fn rk4() -> Options {
    Options {
        method: Method::Rk4,
        fixed_step: Some(0.01),
        ..Options::default()
    }
}

fn dp54(rtol: f64) -> Options {
    Options {
        method: Method::Dp54,
        rtol,
        atol: rtol * 1e-3,
        ..Options::default()
    }
}

fn orbit() -> Orbit {
    Orbit::from_elements(
        OrbitModel::Kepler,
        &Elements {
            a: R_EARTH + 500e3,
            e: 0.05,
            i: 0.9,
            raan: 0.3,
            argp: 0.2,
            nu: 0.1,
        },
    )
}

/// An effect with its power left out of the budget (everything else delegated).
struct Unbooked(Box<dyn Effect>);

impl Effect for Unbooked {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn needs(&self) -> Needs {
        self.0.needs()
    }
    fn n_states(&self) -> usize {
        self.0.n_states()
    }
    fn state_names(&self) -> Vec<String> {
        self.0.state_names()
    }
    fn initial_state(&self, own: &mut [f64]) {
        self.0.initial_state(own)
    }
    fn orbit_state(&self, own: &[f64]) -> Option<OrbitState> {
        self.0.orbit_state(own)
    }
    fn rotors(&self) -> Vec<Rotor> {
        self.0.rotors()
    }
    fn commands_rotors(&self) -> bool {
        self.0.commands_rotors()
    }
    fn after(&self) -> &[&str] {
        self.0.after()
    }
    fn before(&self) -> &[&str] {
        self.0.before()
    }
    fn connect(&mut self, links: &Links) {
        self.0.connect(links)
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        own: &[f64],
        own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        self.0.apply(ctx, forces, own, own_dot)
    }
    fn power(&self, _ctx: &Context, _own: &[f64], _applied: f64) -> Power {
        Power::default()
    }
    fn potential_energy(&self, ctx: &Context, own: &[f64]) -> f64 {
        self.0.potential_energy(ctx, own)
    }
    fn start(
        &mut self,
        ctx: &Context,
        forces: &Forces,
        own: &[f64],
        requests: &mut Vec<Request>,
    ) -> Result<(), SystemError> {
        self.0.start(ctx, forces, own, requests)
    }
    fn n_events(&self) -> usize {
        self.0.n_events()
    }
    fn events(&self, ctx: &Context, forces: &Forces, own: &[f64], g: &mut [f64]) {
        self.0.events(ctx, forces, own, g)
    }
    fn event_direction(&self, k: usize) -> EventDirection {
        self.0.event_direction(k)
    }
    fn on_event(
        &mut self,
        k: usize,
        ctx: &Context,
        forces: &Forces,
        own: &mut [f64],
        requests: &mut Vec<Request>,
    ) -> EventAction {
        self.0.on_event(k, ctx, forces, own, requests)
    }
    fn describe_event(&self, k: usize) -> String {
        self.0.describe_event(k)
    }
}

/// Runs the scene made by `effects` twice: as it is (the budget must hold) and with the
/// effect named `knock` [`Unbooked`] (the budget must drift by far more than the bound).
fn check_effect(
    what: &str,
    (model, state): (Model, State),
    effects: impl Fn() -> Vec<Box<dyn Effect>>,
    knock: &str,
    options: &Options,
    t_end: f64,
) -> Budget {
    let build = |knocked: bool| {
        let mut b = Simulation::builder(model.clone()).initial(state.clone());
        for e in effects() {
            b = if knocked && e.name() == knock {
                b.boxed(Box::new(Unbooked(e)))
            } else {
                b.boxed(e)
            };
        }
        b.build().expect("builds")
    };
    let b = measure(&mut build(false), options, t_end);
    assert_flat(what, &b);
    let k = measure(&mut build(true), options, t_end);
    println!("{what} without {knock}'s power: ratio {:.2e}", k.ratio());
    assert!(
        k.ratio() > 1e3 * RATIO,
        "{what}: leaving out {knock}'s power goes unnoticed: {k:?}"
    );
    b
}

#[test]
fn dampers_dissipate() {
    let b = check_effect(
        "hinge springs and dampers",
        satellite(),
        || {
            vec![Box::new(HingeSprings {
                stiffness: vec![50.0, 50.0, 50.0, 2.0, 2.0],
                damping: vec![40.0, 40.0, 40.0, 4.0, 4.0],
                reference: vec![0.0; 5],
            })]
        },
        "hinge_springs",
        &rk4(),
        20.0,
    );
    assert!(b.dissipated > 0.0 && b.work == 0.0, "{b:?}");
}

#[test]
fn hinge_control_does_work() {
    let b = check_effect(
        "hinge control",
        satellite(),
        || {
            vec![Box::new(HingeControl {
                hinges: vec![HingeProfile {
                    hinge: 3,
                    start: 1.0,
                    end: 0.0,
                    t_start: 2.0,
                    duration: 10.0,
                    kp: 40.0,
                    kd: 60.0,
                    torque_limit: 5.0,
                }],
                ..Default::default()
            })]
        },
        "hinge_control",
        &rk4(),
        20.0,
    );
    assert!(b.work != 0.0 && b.dissipated == 0.0, "{b:?}");
}

fn wheel(name: &str, axis: Vec3) -> Wheel {
    Wheel::new(name, axis, 0.05)
}

#[test]
fn wheel_motors_work_and_friction_dissipates() {
    // x: a motor against viscous and Coulomb friction; y: spinning down on Coulomb and
    // Stribeck friction until it sticks (stick/slip events); z: viscous friction only.
    let wheels = || {
        let mut x = wheel("x", Vec3::x());
        x.torque = 0.02;
        x.coulomb = 0.002;
        x.viscous = 1e-3;
        let mut y = wheel("y", Vec3::y());
        y.speed = 6.0;
        y.coulomb = 0.01;
        y.stribeck = 0.005;
        y.stribeck_speed = 0.5;
        y.viscous = 1e-3;
        let mut z = wheel("z", Vec3::z());
        z.speed = -30.0;
        z.viscous = 2e-3;
        vec![Box::new(ReactionWheels::new(vec![x, y, z])) as Box<dyn Effect>]
    };
    let b = check_effect(
        "reaction wheels",
        satellite(),
        wheels,
        "reaction_wheels",
        &rk4(),
        40.0,
    );
    assert!(b.work > 0.0 && b.dissipated > 0.0, "{b:?}");
}

#[test]
fn attitude_control_works_through_the_wheels() {
    let axes = [Vec3::x(), Vec3::y(), Vec3::z()];
    let effects = || {
        let mut wheels = ReactionWheels::new(
            axes.iter()
                .zip(["x", "y", "z"])
                .map(|(a, n)| {
                    let mut w = wheel(n, *a);
                    w.viscous = 1e-4;
                    w
                })
                .collect(),
        );
        wheels.commanded = true;
        let control = AttitudeControl::new(Target::Orbital(UnitQuaternion::identity()), 5.0, 50.0);
        vec![
            Box::new(orbit()) as Box<dyn Effect>,
            Box::new(GravityGradient::new(GravityModel::Full)),
            Box::new(wheels),
            Box::new(control),
        ]
    };
    let b = check_effect(
        "attitude control",
        satellite(),
        effects,
        "reaction_wheels",
        &rk4(),
        60.0,
    );
    assert!(b.work != 0.0 && b.dissipated > 0.0, "{b:?}");
}

/// A rigid body on an eccentric orbit, tumbling slowly under the gravity gradient: the
/// field turns with the orbit and strengthens towards perigee, so it does work.
fn gravity_gradient(model: GravityModel) -> Budget {
    let text = r#"duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 500.0
inertia = [[110.0, 5.0, 0.0], [5.0, 120.0, -3.0], [0.0, -3.0, 60.0]]
[[model.body]]
name = "boom"
mass = 20.0
inertia = [[1.0, 0.0, 0.0], [0.0, 30.0, 0.0], [0.0, 0.0, 30.0]]
com = [3.0, 0.0, 0.0]
[[model.hinge]]
name = "root"
parent = "bus"
child = "boom"
axis = [0.0, 0.0, 1.0]
at = [1.0, 0.0, 0.0]
[initial]
base = { angular_velocity = [0.0005, -0.001, 0.002] }
hinges = { angle = [0.3], rate = [0.0] }
"#;
    let scene = Scene::parse(text, &examples().join("scenes/test.toml")).expect("scene");
    let name = format!("gravity gradient ({model:?})");
    check_effect(
        &name,
        (scene.model, scene.initial),
        || {
            vec![
                Box::new(orbit()) as Box<dyn Effect>,
                Box::new(GravityGradient::new(model)),
                Box::new(HingeSprings::new(vec![0.01])),
            ]
        },
        "gravity_gradient",
        &dp54(1e-10),
        3000.0,
    )
}

#[test]
fn the_gravity_field_does_work_as_the_orbit_turns() {
    for model in [GravityModel::Preprint, GravityModel::Full] {
        let b = gravity_gradient(model);
        assert!(b.work != 0.0 && b.dissipated == 0.0, "{b:?}");
    }
}

#[test]
fn impacts_lose_energy_at_the_event() {
    // No dampers: everything dissipated is lost in the impacts, booked at the events.
    let stops = || {
        vec![
            Box::new(HingeSprings::new(vec![50.0, 50.0, 50.0, 2.0, 2.0])) as Box<dyn Effect>,
            Box::new(HingeStops::new(vec![
                HingeStop {
                    hinge: 3,
                    lower: Some(0.0),
                    upper: None,
                    action: StopAction::Latch,
                    min_rebound_rate: 0.0,
                },
                HingeStop {
                    hinge: 4,
                    lower: None,
                    upper: Some(0.0),
                    action: StopAction::Rebound { restitution: 0.5 },
                    min_rebound_rate: 1e-3,
                },
            ])),
        ]
    };
    let (model, state) = satellite();
    let mut sim = stops()
        .into_iter()
        .fold(Simulation::builder(model).initial(state), |b, e| b.boxed(e))
        .build()
        .expect("builds");
    let b = measure(&mut sim, &rk4(), 20.0);
    assert_flat("hinge stops", &b);
    let impacts = sim
        .event_log()
        .iter()
        .filter(|(_, what)| what.contains("latched") || what.contains("rebounded"))
        .count();
    assert!(impacts >= 2, "{:?}", sim.event_log());
    // Left out, the impacts' losses would be the drift: far beyond the bound.
    assert!(
        b.dissipated > 1e3 * RATIO * b.scale && b.work == 0.0,
        "{b:?}"
    );
}

#[test]
fn constant_hinge_torques_are_actuators() {
    let (model, mut state) = satellite();
    let nb = model.base_nv();
    state.tau[nb + 3] = 0.05;
    state.tau[nb + 1] = -0.02;
    let mut sim = Simulation::builder(model)
        .initial(state)
        .effect(HingeSprings::new(vec![50.0, 50.0, 50.0, 2.0, 2.0]))
        .build()
        .expect("builds");
    let b = measure(&mut sim, &rk4(), 20.0);
    assert_flat("constant hinge torques", &b);
    assert!(b.work.abs() > 1e3 * RATIO * b.scale, "{b:?}");
}

/// A user's effect: a thruster fixed on body `body`, pushing with `force` (body axes) at
/// `at` (body frame). It needs no kinematics, writes a body wrench, and has neither a
/// potential nor a `power` of its own: the default books its measured power as an
/// actuator's.
struct Thruster {
    body: usize,
    force: Vec3,
    at: Vec3,
}

impl Effect for Thruster {
    fn name(&self) -> &str {
        "thruster"
    }
    fn apply(
        &mut self,
        _ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        forces.add_wrench(
            self.body,
            Force::new(self.at.cross(&self.force), self.force),
        );
        Ok(())
    }
}

#[test]
fn a_new_effect_is_booked_without_special_handling() {
    let b = check_effect(
        "thruster",
        satellite(),
        || {
            vec![
                Box::new(Thruster {
                    body: 4,
                    force: Vec3::new(0.0, 0.3, 0.1),
                    at: Vec3::new(0.5, 0.0, 0.2),
                }) as Box<dyn Effect>,
                Box::new(HingeSprings::new(vec![50.0, 50.0, 50.0, 2.0, 2.0])),
            ]
        },
        "thruster",
        &rk4(),
        20.0,
    );
    assert!(b.work > 0.0, "{b:?}");
}

#[test]
fn without_the_budget_the_run_is_unchanged() {
    // W and D stay out of the error control: the adaptive steps and every other state are
    // those of a run without them.
    let (model, state) = satellite();
    let run = |on: bool| {
        let mut sim = Simulation::builder(model.clone())
            .initial(state.clone())
            .effect(HingeSprings {
                stiffness: vec![50.0, 50.0, 50.0, 2.0, 2.0],
                damping: vec![40.0, 40.0, 40.0, 4.0, 4.0],
                reference: vec![0.0; 5],
            })
            .energy_budget(on)
            .build()
            .expect("builds");
        let n = sim.columns().len();
        let mut rows = Vec::new();
        let stats = sim
            .run(&dp54(1e-8), 10.0, &Output::Steps, |_, row| {
                rows.push(row[..n.min(row.len())].to_vec());
                Ok::<(), ()>(())
            })
            .expect("runs");
        (stats.steps_accepted, stats.steps_rejected, rows)
    };
    let (on, off) = (run(true), run(false));
    assert_eq!((on.0, on.1), (off.0, off.1));
    assert_eq!(on.2.len(), off.2.len());
    for (a, b) in on.2.iter().zip(&off.2) {
        assert_eq!(a[..b.len()], b[..], "the shared columns differ");
    }
}

// ---- the environment: solar pressure, drag and the field do work -------------------------

/// A spinning 1 m cube bus with a 2 m x 1 m panel on a sprung hinge, both with their box
/// faces as facets, on an orbit at `altitude` (m) with the scene's epoch, and `extra`.
fn environment_scene(altitude: f64, extra: &str) -> Scene {
    let text = format!(
        r#"epoch = "2026-03-20T12:00:00 UTC"
duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[20.0, 1.0, 0.0], [1.0, 25.0, 0.0], [0.0, 0.0, 15.0]]
shape = {{ box = [1.0, 1.0, 1.0] }}
facets_from_shape = {{ specular = 0.3, diffuse = 0.2, drag = 2.2 }}
[[model.body]]
name = "panel"
mass = 10.0
inertia = [[1.7, 0.0, 0.0], [0.0, 3.4, 0.0], [0.0, 0.0, 5.0]]
com = [0.0, 1.0, 0.0]
shape = {{ box = [2.0, 2.0, 0.02] }}
facets_from_shape = {{ specular = 0.05, diffuse = 0.1, drag = 2.2 }}
[[model.hinge]]
name = "h"
parent = "bus"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.5, 0.0]
[initial]
base = {{ angular_velocity = [0.01, 0.02, -0.015] }}
hinges = {{ angle = [0.3], rate = [0.05] }}
[orbit]
altitude = {altitude}
inclination_deg = 51.6
{extra}
"#
    );
    Scene::parse(&text, &examples().join("scenes/test.toml")).expect("scene")
}

fn environment_budget(altitude: f64, extra: &str, knock: &str) -> Budget {
    let scene = environment_scene(
        altitude,
        &format!("[effects.hinge_springs]\nstiffness = [0.05]\n{extra}"),
    );
    check_effect(
        knock,
        (scene.model.clone(), scene.initial.clone()),
        || scene.effects.to_boxed(),
        knock,
        &dp54(1e-10),
        600.0,
    )
}

#[test]
fn solar_pressure_does_work_on_the_turning_panels() {
    let b = environment_budget(
        500e3,
        "[effects.solar_radiation]\nshadow = \"none\"\n",
        "solar_radiation",
    );
    assert!(b.work != 0.0 && b.dissipated == 0.0, "{b:?}");
}

/// The gravity gradient reads only the poses and works out its own power, so the right-hand
/// side leaves out the bodies' velocities; the magnetic torquer declares no kinematics but
/// adds wrenches whose power the budget must measure, so with both the right-hand side
/// computes the velocities again (`rhs_forces`) and the budget still closes.
#[test]
fn the_gravity_gradient_beside_a_torquer_keeps_the_budget() {
    let b = environment_budget(
        500e3,
        "[effects.gravity_gradient]\nmodel = \"full\"\n[effects.magnetic]\nresidual_dipole = [2.0, -1.0, 3.0]\n[[effects.magnetic.torquer]]\nname = \"x\"\naxis = [1.0, 0.0, 0.0]\nmax_dipole = 10.0\ndipole = 8.0\n",
        "magnetic",
    );
    assert!(b.work != 0.0 && b.dissipated == 0.0, "{b:?}");
}

#[test]
fn drag_does_work_by_the_flow_and_dissipates_by_the_motion() {
    let b = environment_budget(300e3, "[effects.drag]\n", "drag");
    assert!(b.work != 0.0 && b.dissipated > 0.0, "{b:?}");
}

#[test]
fn the_field_does_work_on_a_torquer() {
    let b = environment_budget(
        500e3,
        "[effects.magnetic]\nresidual_dipole = [2.0, -1.0, 3.0]\n[[effects.magnetic.torquer]]\nname = \"x\"\naxis = [1.0, 0.0, 0.0]\nmax_dipole = 10.0\ndipole = 8.0\n",
        "magnetic",
    );
    assert!(b.work != 0.0 && b.dissipated == 0.0, "{b:?}");
}
