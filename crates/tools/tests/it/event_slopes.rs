//! The slope the event functions evaluate at the end of a step, reused by the next step
//! (`crates/spacecraft/src/simulation/ahead.rs`): runs of the deployment campaign (stuck
//! wheels read hold torques at every step; panels latch; wheels break free) give the same
//! rows, outcome and events bit for bit with the reuse on and off, and reuse it at most steps.
//! Radau IIA's step ends take its own slope instead (`System::events_at_step_end`).

use crate::common::example;
use satsim_integrate::{
    EventAction, EventDirection, Output, Stats, System, SystemError, integrate,
};
use satsim_spacecraft::simulation::{RunError, Simulation};
use satsim_tools::campaign::Campaign;
use satsim_tools::scene::Scene;
use std::ops::ControlFlow;

/// A run's outcome (as text), rows (as bits) and events.
type Outcome = (String, Vec<u64>, Vec<(u64, String)>);

fn run(scene: &Scene, reuse: bool) -> (Outcome, Simulation) {
    let (outcome, sim, _) = run_counted(scene, reuse);
    (outcome, sim)
}

/// [`run`], and the steps the integrator accepted.
fn run_counted(scene: &Scene, reuse: bool) -> (Outcome, Simulation, u64) {
    let mut sim = scene.simulation().unwrap();
    sim.reuse_event_slopes(reuse);
    let mut rows = Vec::new();
    let result: Result<Stats, RunError<String>> = sim.run(
        &scene.options,
        sim.t0() + scene.duration,
        &Output::Interval(scene.every),
        |t, row| {
            rows.push(t.to_bits());
            rows.extend(row.iter().map(|v| v.to_bits()));
            Ok(())
        },
    );
    let steps = result.as_ref().map_or(0, |s| s.steps_accepted as u64);
    let result = format!("{:?}", result.map(|s| (s.t_final, s.x_final, s.events)));
    let events = sim
        .event_log()
        .iter()
        .map(|(t, what)| (t.to_bits(), what.clone()))
        .collect();
    ((result, rows, events), sim, steps)
}

#[test]
fn reusing_the_event_functions_slope_changes_no_bit() {
    let path = example("scenes/deploy_campaign.toml");
    let campaign = Campaign::read(&path).unwrap();
    for k in 0..3 {
        let text = campaign.run_text(k, &campaign.draw(k));
        let mut scene = Scene::parse(&text, &path).unwrap();
        scene.duration = 25.0;
        let (on, sim_on) = run(&scene, true);
        let (off, sim_off) = run(&scene, false);
        assert_eq!(on.0, off.0, "run {k}: outcome");
        assert!(on.1 == off.1, "run {k}: rows differ");
        assert_eq!(on.2, off.2, "run {k}: events");
        assert!(on.2.len() >= 2, "run {k}: the panels latch");
        // Every reused slope is one evaluation fewer, and most steps reuse one.
        let (log_on, log_off) = (sim_on.run_log(), sim_off.run_log());
        assert_eq!(log_off.reused_rhs(), 0);
        assert_eq!(
            log_on.rhs_evals() + log_on.reused_rhs(),
            log_off.rhs_evals(),
            "run {k}"
        );
        let steps = (scene.duration / 0.01) as u64;
        assert!(
            log_on.reused_rhs() * 2 > steps,
            "run {k}: {} of {steps} steps reused the slope",
            log_on.reused_rhs()
        );
    }
}

/// The kept slope answers only a right-hand side at the very `(t, x)` where the event
/// functions evaluated it, once.
#[test]
fn the_slope_is_reused_only_at_the_same_state() {
    use satsim_integrate::System;
    let path = example("scenes/deploy.toml");
    let scene = Scene::read(&path).unwrap();
    let mut sim = scene.simulation().unwrap();
    let mut fresh = scene.simulation().unwrap();
    assert!(sim.locked().iter().any(|&l| l), "the wheels start stuck");
    let (t, x) = (sim.t0(), sim.x0().to_vec());
    let n = x.len();
    let mut g = vec![0.0; sim.n_events()];
    let (mut dx, mut want) = (vec![0.0; n], vec![0.0; n]);
    let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let mut other = x.clone();
    other[n - 1] += 1e-3;
    for (tk, xk) in [(t, &other), (t + 1e-3, &x)] {
        sim.events(t, &x, &mut g).unwrap();
        sim.rhs(tk, xk, &mut dx).unwrap();
        fresh.rhs(tk, xk, &mut want).unwrap();
        assert_eq!(bits(&dx), bits(&want));
        assert_eq!(sim.run_log().reused_rhs(), 0);
    }
    sim.events(t, &x, &mut g).unwrap();
    sim.rhs(t, &x, &mut dx).unwrap();
    assert_eq!(sim.run_log().reused_rhs(), 1);
    sim.rhs(t, &x, &mut dx).unwrap();
    assert_eq!(sim.run_log().reused_rhs(), 1, "used once");
    fresh.rhs(t, &x, &mut want).unwrap();
    assert_eq!(bits(&dx), bits(&want));
}

/// The same on the flexible deployment (Radau IIA; its modal panels' accelerations feed the
/// hold torques): where the event functions evaluate the right-hand side (locating a
/// crossing), a step starting there takes it, bit for bit as computed apart. At a step's end
/// they take Radau IIA's own slope instead and evaluate none
/// ([`the_flexible_trees_step_ends_take_the_integrators_slope`]), so few steps reuse one.
#[test]
fn the_flexible_tree_reuses_the_event_functions_slope_too() {
    let path = example("flexible_array.toml");
    let mut scene = Scene::read(&path).unwrap();
    scene.duration = 12.0;
    let (on, sim_on, steps) = run_counted(&scene, true);
    let (off, sim_off) = run(&scene, false);
    assert_eq!(on.0, off.0, "outcome");
    assert!(on.1 == off.1, "rows differ");
    assert_eq!(on.2, off.2, "events");
    assert!(
        on.2.iter()
            .filter(|(_, what)| what.contains("latched"))
            .count()
            == 2,
        "both panels latch: {:?}",
        on.2
    );
    let (log_on, log_off) = (sim_on.run_log(), sim_off.run_log());
    assert_eq!(log_off.reused_rhs(), 0);
    assert_eq!(
        log_on.rhs_evals() + log_on.reused_rhs(),
        log_off.rhs_evals()
    );
    assert!(
        log_on.reused_rhs() > 0 && log_on.reused_rhs() * 4 < steps,
        "{} of {steps} steps reused the slope",
        log_on.reused_rhs()
    );
}

/// At a step's end Radau IIA hands the event functions its collocation slope, and the stuck
/// wheels' hold torques come from it (`System::events_at_step_end`) with no right-hand side
/// evaluated: given `f` itself, the event functions are those that evaluate it, bit for bit;
/// given a slope whose bus angular acceleration about `x` is 1e-3 rad/s² more, wheel `x`'s
/// (stuck: `static − |hold − command|`) moves by its inertia times that, 1e-4 N m, and no
/// other (the wheels on orthogonal axes, the panels' stops).
#[test]
fn the_flexible_trees_step_ends_take_the_integrators_slope() {
    let scene = Scene::read(example("flexible_array.toml")).unwrap();
    let mut sim = scene.simulation().unwrap();
    assert!(sim.locked().iter().any(|&l| l), "the wheels start stuck");
    let (t, x) = (sim.t0(), sim.x0().to_vec());
    let (n, ne) = (x.len(), sim.n_events());
    let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let mut f = vec![0.0; n];
    sim.rhs(t, &x, &mut f).unwrap();
    let (mut g, mut from_f, mut from_other) = (vec![0.0; ne], vec![0.0; ne], vec![0.0; ne]);
    sim.events(t, &x, &mut g).unwrap();
    sim.events_at_step_end(t, &x, Some(&f), &mut from_f)
        .unwrap();
    assert_eq!(bits(&g), bits(&from_f), "{g:?} against {from_f:?}");
    let mut other = f.clone();
    other[sim.layout().omega.start] += 1e-3;
    sim.events_at_step_end(t, &x, Some(&other), &mut from_other)
        .unwrap();
    let moved: Vec<f64> = from_other.iter().zip(&g).map(|(a, b)| a - b).collect();
    let changed: Vec<usize> = (0..ne).filter(|&k| from_other[k] != g[k]).collect();
    assert_eq!(changed.len(), 1, "{moved:?}");
    assert!((moved[changed[0]].abs() - 1e-4).abs() < 1e-12, "{moved:?}");
    // Without a slope (the explicit methods), the event functions as they are.
    sim.events_at_step_end(t, &x, None, &mut from_other)
        .unwrap();
    assert_eq!(bits(&from_other), bits(&g));
}

/// The simulation as the integrator sees it, recording each answer to
/// `jacobian_survives_restart` with the number of events handled by then.
struct Watched<'a> {
    sim: &'a mut Simulation,
    answers: Vec<(usize, bool)>,
}

impl System for Watched<'_> {
    fn dim(&self) -> usize {
        self.sim.dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.sim.rhs(t, x, dx)
    }
    fn project(&mut self, x: &mut [f64]) {
        self.sim.project(x)
    }
    fn error_weights(&self, w: &mut [f64]) {
        self.sim.error_weights(w)
    }
    fn quadratures(&self, q: &mut [bool]) {
        self.sim.quadratures(q)
    }
    fn n_events(&self) -> usize {
        self.sim.n_events()
    }
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        self.sim.events(t, x, g)
    }
    fn event_direction(&self, k: usize) -> EventDirection {
        self.sim.event_direction(k)
    }
    fn on_event(&mut self, k: usize, t: f64, x: &mut [f64]) -> EventAction {
        self.sim.on_event(k, t, x)
    }
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        self.sim.on_events(ks, t, x)
    }
    fn next_stop(&self) -> f64 {
        self.sim.next_stop()
    }
    fn on_stop(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
        self.sim.on_stop(t, x)
    }
    fn jacobian_survives_restart(&mut self) -> bool {
        let answer = self.sim.jacobian_survives_restart();
        self.answers.push((self.sim.event_log().len(), answer));
        answer
    }
}

#[test]
fn the_jacobian_survives_every_event_but_those_that_lock_a_hinge() {
    // The flexible deployment's first 12 s under its Radau IIA: wheel `x` breaks free,
    // sticks and reverses, both panels latch.
    let scene = Scene::read(example("flexible_array.toml")).unwrap();
    let mut sim = scene.simulation().unwrap();
    let (t0, x0) = (sim.t0(), sim.x0().to_vec());
    let mut watched = Watched {
        sim: &mut sim,
        answers: Vec::new(),
    };
    let stats = integrate(
        &mut watched,
        &scene.options,
        t0,
        &x0,
        t0 + 12.0,
        &Output::Times(vec![]),
        |_, _| ControlFlow::Continue(()),
    )
    .unwrap();
    let answers = watched.answers;
    let log = sim.event_log();
    // Asked at the start (nothing kept there) and after each event handled.
    assert_eq!(answers.len(), log.len() + 1, "{answers:?}");
    assert!(!answers[0].1);
    let mut seen = 0;
    for &(upto, answer) in &answers[1..] {
        let handled = &log[seen..upto];
        let locks = handled
            .iter()
            .any(|(_, what)| what.contains("stuck") || what.contains("latched"));
        assert_eq!(answer, !locks, "after {handled:?}");
        seen = upto;
    }
    let kept = answers.iter().filter(|a| a.1).count();
    assert!(kept >= 2 && kept < answers.len() - 2, "{answers:?}");
    assert!(stats.jacobian_evals > 0);
}
