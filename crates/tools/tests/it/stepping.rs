//! Stepping a scene from the caller's code (`satsim_tools::stepping`): pieces reproduce a
//! run, held inputs act as the initial state's constants, the zero-order hold is exact, the
//! built-in discrete controller equals the same law in a loop over the stepping API, and bad
//! input changes nothing.

use crate::common::{example, fixed_panel_model};
use satsim_tools::api::{Trajectory, run_scene};
use satsim_tools::scene::Scene;
use satsim_tools::stepping::{SceneStepper, StepFailure};
use std::path::{Path, PathBuf};

fn deploy_path() -> PathBuf {
    example("scenes/deploy.toml")
}

/// `deploy.toml` with `edit` applied to its text (anchored at its own folder).
fn deploy(edit: impl Fn(String) -> String) -> Scene {
    let path = deploy_path();
    let text = std::fs::read_to_string(&path).unwrap();
    Scene::parse(&edit(text), &path).expect("valid scene")
}

fn replace(text: String, from: &str, to: &str) -> String {
    assert!(text.contains(from), "`{from}` not in the scene");
    text.replacen(from, to, 1)
}

/// A small deterministic generator (no dependency).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) % n
    }
}

fn stepper(scene: &Scene) -> SceneStepper {
    SceneStepper::new(scene, None, "test").unwrap()
}

/// Steps to the scene's end in pieces of `piece()` seconds (the last one cut at the end).
fn step_to_end(s: &mut SceneStepper, t_end: f64, mut piece: impl FnMut() -> f64) -> usize {
    let mut events = 0;
    while s.t() < t_end {
        let dt = piece().min(t_end - s.t());
        events += s.advance(dt).unwrap().len();
    }
    events
}

fn column(t: &Trajectory, name: &str) -> usize {
    t.columns.iter().position(|c| c == name).unwrap()
}

#[test]
fn rk4_in_random_whole_step_pieces_reproduces_the_run_bit_for_bit() {
    let scene = deploy(|t| replace(t, "duration = 300.0", "duration = 120.0"));
    let run = run_scene(&scene, || false).unwrap();
    let mut s = stepper(&scene);
    let mut rng = Lcg(7);
    let events = step_to_end(&mut s, 120.0, || (1 + rng.next(250)) as f64 * 0.01);
    // Both panels latch on their stops inside the run.
    assert!(events >= 2, "{events} events");
    assert!(
        s.stepping()
            .simulation()
            .event_records()
            .filter(|(_, e, _)| *e == "hinge_stops")
            .count()
            >= 2
    );
    let got = s.trajectory();
    assert_eq!(got.columns, run.columns);
    assert_eq!(got.n_rows(), run.n_rows());
    for (a, b) in got.rows().zip(run.rows()) {
        for (c, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                x.to_bits() == y.to_bits(),
                "t = {}: {} {x} vs {y}",
                a[0],
                run.columns[c]
            );
        }
    }
}

#[test]
fn dp54_in_arbitrary_pieces_reproduces_the_run_within_the_tolerance() {
    let scene = deploy(|t| {
        let t = replace(t, "duration = 300.0", "duration = 60.0");
        replace(
            t,
            "method = \"rk4\"\nstep = 0.01",
            "method = \"dp54\"\nrtol = 1e-10\natol = 1e-12",
        )
    });
    let run = run_scene(&scene, || false).unwrap();
    let mut s = stepper(&scene);
    let mut rng = Lcg(11);
    step_to_end(&mut s, 60.0, || 0.05 + rng.next(1000) as f64 * 1.234e-3);
    let got = s.trajectory();
    assert_eq!(got.n_rows(), run.n_rows());
    let mut worst: f64 = 0.0;
    for name in [
        "q_x", "q_y", "q_z", "angle_h4", "angle_h5", "rate_h4", "omega_x",
    ] {
        let c = column(&run, name);
        for (a, b) in got.rows().zip(run.rows()) {
            assert_eq!(a[0], b[0]);
            worst = worst.max((a[c] - b[c]).abs());
        }
    }
    // Restarting at every piece changes the steps: the rows differ by the integration
    // error the tolerances allow (a few thousand times 1e-10 over the run), not more.
    assert!(worst > 0.0 && worst < 1e-6, "worst difference {worst}");
}

#[test]
fn a_hinge_torque_held_as_an_input_equals_the_same_torque_in_the_initial_state() {
    let edit = |torque: &str| {
        let torque = torque.to_string();
        move |t: String| {
            let t = replace(t, "duration = 300.0", "duration = 40.0");
            replace(
                t,
                "rate = [0.0, 0.0, 0.0, 0.0, 0.0] }",
                &format!("rate = [0.0, 0.0, 0.0, 0.0, 0.0], torque = {torque} }}"),
            )
        }
    };
    let constant = deploy(edit("[0.0, 0.0, 0.0, 0.03, 0.0]"));
    let run = run_scene(&constant, || false).unwrap();
    let plain = deploy(edit("[0.0, 0.0, 0.0, 0.0, 0.0]"));
    let mut s = stepper(&plain);
    assert!(s.inputs().iter().any(|i| i == "torque_h4"));
    s.set_inputs(&[("torque_h4", 0.03)]).unwrap();
    let mut rng = Lcg(3);
    step_to_end(&mut s, 40.0, || (1 + rng.next(300)) as f64 * 0.01);
    assert_eq!(s.trajectory(), &run);
}

/// One panel on a fixed base (a single hinge about z), no effects: `I θ̈ = τ`.
fn one_hinge(step: f64) -> (Scene, f64) {
    let (m, j, d) = (20.0, 1.5, 1.2);
    let text = one_hinge_text(step, "");
    let scene = Scene::parse(&text, Path::new("one_hinge.toml")).unwrap();
    (scene, j + m * d * d)
}

/// The scene of [`one_hinge`], with `integrator` keys replacing RK4 at `step` when given.
fn one_hinge_text(step: f64, integrator: &str) -> String {
    let (m, j, d) = (20.0, 1.5, 1.2);
    let integrator = if integrator.is_empty() {
        format!("method = \"rk4\"\nstep = {step}\n")
    } else {
        integrator.to_string()
    };
    format!(
        r#"
duration = 5.0
{}[initial]
hinges = {{ angle = [0.4], rate = [-0.1] }}
[integrator]
{integrator}
[output]
every = 0.5
"#,
        fixed_panel_model(m, j, d)
    )
}

#[test]
fn a_discrete_law_through_set_inputs_is_held_exactly_between_samples() {
    let (k, damping, h) = (30.0, 8.0, 0.1);
    for step in [0.01, 0.025, 0.1] {
        let (scene, inertia) = one_hinge(step);
        let mut s = stepper(&scene);
        let (ia, ir) = (
            column(s.trajectory(), "angle_h"),
            column(s.trajectory(), "rate_h"),
        );
        let (mut theta, mut omega) = (0.4f64, -0.1f64);
        for sample in 0..40 {
            let row = s.row().unwrap();
            let scale = theta.abs().max(omega.abs());
            assert!(
                (row[ia] - theta).abs() <= 1e-12 * scale
                    && (row[ir] - omega).abs() <= 1e-12 * scale,
                "step {step}, sample {sample}: ({}, {}) vs the closed form ({theta}, {omega})",
                row[ia],
                row[ir]
            );
            let tau = -k * row[ia] - damping * row[ir];
            s.set_inputs(&[("torque_h", tau)]).unwrap();
            s.advance(h).unwrap();
            let tau = -k * theta - damping * omega;
            theta += omega * h + tau * h * h / (2.0 * inertia);
            omega += tau * h / inertia;
        }
        assert!((s.t() - 4.0).abs() < 1e-12);
    }
}

/// `deploy.toml`'s attitude law (inertial target at the identity, three wheels along the
/// bus axes) mirrored from outside: `u = −kp 2 sgn(q_w) q_xyz − kd ω`, wheel commands `−u`.
#[test]
fn the_built_in_discrete_controller_equals_the_same_law_in_a_stepping_loop() {
    let shorten = |t: String| replace(t, "duration = 300.0", "duration = 60.0");
    let builtin = deploy(|t| {
        replace(
            shorten(t),
            "kd = 150.0               # N m s/rad",
            "kd = 150.0\nperiod = 0.1",
        )
    });
    let run = run_scene(&builtin, || false).unwrap();
    let outside = deploy(|t| {
        replace(
            shorten(t),
            "kd = 150.0               # N m s/rad",
            "kd = 150.0\nenabled = false",
        )
    });
    let mut s = stepper(&outside);
    let col = |n: &str| column(s.trajectory(), n);
    let (q, w) = (
        [col("q_w"), col("q_x"), col("q_y"), col("q_z")],
        [col("omega_x"), col("omega_y"), col("omega_z")],
    );
    let (kp, kd) = (9.0, 150.0);
    while s.t() < 60.0 - 1e-9 {
        let row = s.row().unwrap();
        let sgn = if row[q[0]] < 0.0 { -1.0 } else { 1.0 };
        let u: Vec<f64> = (0..3)
            .map(|i| -kp * 2.0 * sgn * row[q[i + 1]] - kd * row[w[i]])
            .collect();
        s.set_inputs(&[("wheel_x", -u[0]), ("wheel_y", -u[1]), ("wheel_z", -u[2])])
            .unwrap();
        s.advance(0.1).unwrap();
    }
    let got = s.trajectory();
    assert_eq!(got.n_rows(), run.n_rows());
    let mut compared = 0;
    for (c, name) in got.columns.iter().enumerate() {
        let Some(r) = run.columns.iter().position(|n| n == name) else {
            continue;
        };
        compared += 1;
        for (a, b) in got.rows().zip(run.rows()) {
            assert!(
                (a[c] - b[r]).abs() <= 1e-12 * b[r].abs().max(1.0),
                "t = {}: {name} {} vs {}",
                a[0],
                a[c],
                b[r]
            );
        }
    }
    assert!(compared > 20);
    // The held law is not the continuous one: the discrete run differs from it.
    let continuous = run_scene(&deploy(shorten), || false).unwrap();
    let c = column(&run, "omega_x");
    assert!(
        run.rows()
            .zip(continuous.rows())
            .any(|(a, b)| (a[c] - b[c]).abs() > 1e-9)
    );
}

#[test]
fn bad_input_is_an_error_naming_it_and_changes_nothing() {
    let scene = deploy(|t| replace(t, "duration = 300.0", "duration = 10.0"));
    let mut s = stepper(&scene);
    s.set_inputs(&[("wheel_x", 0.01)]).unwrap();
    s.advance(0.5).unwrap();
    let (t, row, n) = (s.t(), s.row().unwrap(), s.trajectory().n_rows());
    let expect_input = |r: Result<(), StepFailure>, what: &str| match r {
        Err(StepFailure::Input(m)) => assert!(m.contains(what), "{m}"),
        other => panic!("{what}: {other:?}"),
    };
    expect_input(s.set_inputs(&[("wheel_q", 1.0)]), "wheel_q");
    expect_input(s.set_inputs(&[("torque_nope", 1.0)]), "torque_nope");
    // A bad value among good ones sets none of them.
    expect_input(
        s.set_inputs(&[("wheel_y", 0.5), ("wheel_x", f64::NAN)]),
        "wheel_x",
    );
    expect_input(s.set_inputs(&[("torque_h4", f64::INFINITY)]), "torque_h4");
    for dt in [0.0, -0.1, f64::NAN, f64::INFINITY] {
        expect_input(s.advance(dt).map(|_| ()), "dt");
    }
    assert_eq!(s.t(), t);
    assert_eq!(s.row().unwrap(), row);
    assert_eq!(s.trajectory().n_rows(), n);
    assert_eq!(
        s.stepping().input_values()[s.inputs().iter().position(|i| i == "wheel_y").unwrap()],
        0.0
    );
    // And it goes on as if nothing had been asked.
    let mut reference = stepper(&scene);
    reference.set_inputs(&[("wheel_x", 0.01)]).unwrap();
    reference.advance(0.5).unwrap();
    reference.advance(0.7).unwrap();
    s.advance(0.7).unwrap();
    assert_eq!(s.row().unwrap(), reference.row().unwrap());
}

#[test]
fn a_period_that_is_not_a_positive_number_is_an_error_naming_file_and_line() {
    for bad in ["0.0", "-0.1", "nan", "inf"] {
        let path = deploy_path();
        let text = replace(
            std::fs::read_to_string(&path).unwrap(),
            "kd = 150.0               # N m s/rad",
            &format!("kd = 150.0\nperiod = {bad}"),
        );
        let line = text.lines().position(|l| l.starts_with("period")).unwrap() + 1;
        let e = match Scene::parse(&text, &path) {
            Ok(_) => panic!("period = {bad} was accepted"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains("deploy.toml") && e.contains(&line.to_string()) && e.contains("period"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn the_output_folder_gets_what_satsim_run_writes() {
    let scene = deploy(|t| replace(t, "duration = 300.0", "duration = 5.0"));
    let dir = std::env::temp_dir().join(format!("satsim-stepping-{}", std::process::id()));
    let mut s = SceneStepper::new(&scene, Some(&dir), "deploy.toml").unwrap();
    while s.t() < 5.0 {
        s.advance(0.25).unwrap();
    }
    let written = s.close().unwrap();
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + s.trajectory().n_rows());
    assert_eq!(s.trajectory().n_rows(), 6);
    assert!(dir.join("events.csv").exists());
    assert!(
        written.iter().any(|p| p.ends_with("view.html")),
        "{written:?}"
    );
    assert!(matches!(s.advance(0.1), Err(StepFailure::Input(_))));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The discrete hinge controller (`period` on `[effects.hinge_control]`) against the same law
/// fed through `torque_h` between `advance(0.1)` calls, with RK4 and with DP54.
#[test]
fn the_built_in_discrete_hinge_controller_equals_the_same_law_in_a_stepping_loop() {
    let (kp, kd, limit) = (40.0, 15.0, 6.0);
    let profile = satsim_spacecraft::effects::HingeProfile {
        hinge: 0,
        start: 0.4,
        end: -0.3,
        t_start: 0.5,
        duration: 2.0,
        kp,
        kd,
        torque_limit: limit,
    };
    for integrator in ["", "method = \"dp54\"\nrtol = 1e-10\natol = 1e-12\n"] {
        let edit = |extra: &str| {
            let base = one_hinge_text(0.025, integrator);
            Scene::parse(&format!("{base}{extra}"), Path::new("one_hinge.toml")).unwrap()
        };
        let builtin = edit(&format!(
            "[effects.hinge_control]\nperiod = 0.1\n[[effects.hinge_control.hinge]]\nname = \"h\"\n\
             start = 0.4\nend = -0.3\nt_start = 0.5\nduration = 2.0\nkp = {kp}\nkd = {kd}\n\
             torque_limit = {limit}\n"
        ));
        let run = run_scene(&builtin, || false).unwrap();
        let mut s = stepper(&edit(""));
        let (ia, ir) = (
            column(s.trajectory(), "angle_h"),
            column(s.trajectory(), "rate_h"),
        );
        while s.t() < 5.0 - 1e-9 {
            let row = s.row().unwrap();
            let (reference, rate) = profile.reference(row[0]);
            let u = (kp * (reference - row[ia]) + kd * (rate - row[ir])).clamp(-limit, limit);
            s.set_inputs(&[("torque_h", u)]).unwrap();
            s.advance(0.1).unwrap();
        }
        let got = s.trajectory();
        assert_eq!(got.columns, run.columns);
        assert_eq!(got.n_rows(), run.n_rows());
        for (a, b) in got.rows().zip(run.rows()) {
            for (c, (x, y)) in a.iter().zip(b).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-12 * y.abs().max(1.0),
                    "{integrator}t = {}: {} {x} vs {y}",
                    a[0],
                    run.columns[c]
                );
            }
        }
        // The law did act: the hinge left 0.4 for the profile's end, -0.3.
        let last = run.rows().last().unwrap()[ia];
        assert!(last < 0.0, "{integrator}the hinge ended at {last}");
    }
}

/// `deploy.toml` for 30 s with every kind of effect state a run changes: the discrete
/// attitude controller's held output, the sensors' noise streams (their readings are
/// columns), a thruster's period, and the hinge stops' latches (events).
fn stateful_deploy() -> Scene {
    deploy(|t| {
        let t = replace(t, "duration = 300.0", "duration = 30.0");
        let t = replace(
            t,
            "kd = 150.0               # N m s/rad",
            "kd = 150.0\nperiod = 0.3",
        );
        t + r#"
[sensors]
seed = 11
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.1
noise_density = 1e-4
bias_walk = 1e-6
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.2
noise_arcsec = [5.0, 5.0, 40.0]
[effects.thrusters]
period = 0.5
[[effects.thrusters.thruster]]
name = "roll"
body = "bus"
at = [0.0, 0.5, 0.0]
direction = [0.0, 0.0, 1.0]
thrust = 0.2
duty = 0.3
"#
    })
}

fn run_rows(
    sim: &mut satsim_spacecraft::simulation::Simulation,
    scene: &Scene,
) -> (Vec<u64>, Vec<(f64, String)>) {
    let mut bits = Vec::new();
    sim.run(
        &scene.options,
        scene.duration,
        &satsim_integrate::Output::Interval(0.5),
        |t, row| {
            bits.push(t.to_bits());
            bits.extend(row.iter().map(|v| v.to_bits()));
            Ok::<(), ()>(())
        },
    )
    .unwrap();
    (bits, sim.event_log().to_vec())
}

#[test]
fn a_second_run_of_one_simulation_gives_the_first_runs_bits() {
    let scene = stateful_deploy();
    let mut sim = scene.simulation().unwrap();
    let (first, events) = run_rows(&mut sim, &scene);
    // The panels latch (events), and the sensors and the controller sampled on the way.
    assert!(events.len() >= 2, "{events:?}");
    let evals = sim.rhs_evals();
    let (second, events2) = run_rows(&mut sim, &scene);
    assert_eq!(
        events2, events,
        "the second run's events (not appended to the first's)"
    );
    assert_eq!(sim.rhs_evals(), evals, "the run log starts again");
    assert!(first == second, "a second run differs from the first");
    // A fresh simulation gives the same, and a simulation that ran, stepped, starts again.
    let (fresh, _) = run_rows(&mut scene.simulation().unwrap(), &scene);
    assert!(fresh == first);
    let grid = satsim_spacecraft::simulation::OutputGrid {
        t0: 0.0,
        every: 0.5,
        t_end: 30.0,
    };
    let rows = |sim| {
        let mut st = satsim_spacecraft::simulation::Stepping::new(sim, grid);
        let mut bits = Vec::new();
        st.advance(&scene.options, 30.0, |t, row| {
            bits.push(t.to_bits());
            bits.extend(row.iter().map(|v: &f64| v.to_bits()));
            Ok::<(), String>(())
        })
        .unwrap();
        bits
    };
    let stepped_fresh = rows(scene.simulation().unwrap());
    assert!(rows(sim) == stepped_fresh, "stepping a simulation that ran");
}

#[test]
fn a_simulation_with_an_effect_given_without_a_copy_refuses_a_second_run() {
    let scene = stateful_deploy();
    let mut b = satsim_spacecraft::simulation::Simulation::builder(scene.model.clone())
        .initial(scene.initial.clone());
    for e in scene.effects.to_boxed() {
        b = b.boxed(e);
    }
    let mut sim = b.build().unwrap();
    let opts = &scene.options;
    let output = satsim_integrate::Output::Interval(1.0);
    sim.run(opts, 2.0, &output, |_, _| Ok::<(), String>(()))
        .unwrap();
    let e = sim
        .run(opts, 2.0, &output, |_, _| Ok::<(), String>(()))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "was added without a copy (`SimulationBuilder::boxed`), so the simulation runs once"
        ),
        "{e}"
    );
}

#[test]
fn an_advance_that_would_keep_more_than_max_rows_is_refused_before_it_integrates() {
    let scene = deploy(|t| replace(t, "duration = 300.0", "duration = 2.0"));
    let every = scene.every;
    let mut s = stepper(&scene);
    assert_eq!(s.max_rows(), satsim_tools::scene::DEFAULT_MAX_ROWS);
    // 1e9 s: about 1e9 / every rows, refused at once (no output time listed, no row kept).
    let Err(StepFailure::Input(m)) = s.advance(1e9) else {
        panic!("advance(1e9) was not refused")
    };
    let rows = format!("would record about {:.0} rows", (1e9 / every).floor());
    assert!(m.contains(&rows) && m.contains("`max_rows`"), "{m}");
    assert_eq!((s.t(), s.trajectory().n_rows()), (0.0, 1));
    // A limit of 3 rows: two more intervals fit, a third does not; a piece with no output
    // time in it still goes.
    s.set_max_rows(3);
    s.advance(2.0 * every).unwrap();
    assert_eq!(s.trajectory().n_rows(), 3);
    let Err(StepFailure::Input(m)) = s.advance(every) else {
        panic!("the fourth row was kept")
    };
    assert!(
        m.contains("more than the 0 left of the limit of 3 rows kept"),
        "{m}"
    );
    s.advance(0.25 * every).unwrap();
    assert_eq!(s.trajectory().n_rows(), 3);
    // Past the scene's end, the rows go on on the same grid.
    let mut s = stepper(&scene);
    s.advance(2.0 + 2.0 * every).unwrap();
    let t = s.trajectory();
    let last = t.rows().last().unwrap()[0];
    assert!((last - (2.0 + 2.0 * every)).abs() < 1e-12, "{last}");
}

/// `stiff_hinge.toml` under DP5(4) for 10 s: its hinge modes hold the steps at the method's
/// stability limit (about 7 ms), as `satsim run` warns.
fn stiff_under_dp54() -> Scene {
    let path = example("scenes/stiff_hinge.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = replace(text, "duration = 100.0", "duration = 10.0");
    let text = replace(text, "method = \"radau5\"", "method = \"dp54\"");
    Scene::parse(&text, &path).expect("valid scene")
}

/// A stepped simulation warns of steps held by a stiff motion as `satsim run` does, over
/// the steps the integrator set, not those cut to end a piece; pieces shorter than about the
/// limit are the caller's steps, and no warning comes of them.
#[test]
fn steps_held_by_a_stiff_motion_are_warned_of_over_pieces_longer_than_the_limit() {
    use satsim_integrate::Method;
    use satsim_tools::scene::step_limit::stable_step;
    let scene = stiff_under_dp54();
    let (limit, _) = stable_step(&scene, Method::Dp54).unwrap();
    assert!(limit > 5e-3 && limit < 1e-2, "{limit}");
    // The run's warning, for comparison.
    let (_, said) = satsim_tools::api::run_scene_warned(&scene, || false).unwrap();
    assert!(
        said.iter().any(|w| w.contains("held the steps")),
        "{said:?}"
    );

    let mut s = stepper(&scene);
    step_to_end(&mut s, 10.0, || 1.0);
    let steps = s.stepping().steps();
    // Ten pieces, each ending in a step cut to land on it.
    assert!(
        (steps.span - 10.0).abs() < 1e-9 && steps.capped == 10 && steps.accepted >= 1000,
        "{steps:?}"
    );
    let said = s.warnings();
    let held: Vec<_> = said
        .iter()
        .filter(|w| w.contains("held the steps"))
        .collect();
    assert_eq!(held.len(), 1, "{said:?}");
    assert!(
        held[0].contains("`integrator.method = \"radau5\"` (implicit) steps over it"),
        "{}",
        held[0]
    );

    // Pieces of 1/1.2 of the limit, more than a thousand: counted as steps they would be
    // held (their mean within a factor 1.5 of it). Each ends in a step cut to land on it,
    // and they come more often than 1.5 times the limit: the pieces, not the motion, bound
    // the steps.
    let piece = limit / 1.2;
    let mut s = stepper(&scene);
    let mut pieces = 0;
    step_to_end(&mut s, 10.0, || {
        pieces += 1;
        piece
    });
    assert!(pieces >= 1000, "{pieces}");
    let steps = s.stepping().steps();
    assert_eq!(steps.capped, pieces, "{steps:?}");
    // (`span` sums the pieces: round-off of a part in 1e12.)
    let spacing = steps.mean_capped_spacing();
    assert!(spacing <= piece * (1.0 + 1e-9), "{steps:?}");
    assert!(
        !s.warnings().iter().any(|w| w.contains("held the steps")),
        "{:?}",
        s.warnings()
    );
}

/// The flexible deployment (Radau IIA, its modes left out of the error) stepped at 10 Hz, as
/// a flight-software loop steps it: each piece goes on from the last with its step and
/// Jacobian, so the loop takes a new Jacobian only where the run does (a latch), not one a
/// piece, and its hinge angles stay within the scene's accuracy (1e-4 rad) of the run's.
#[test]
fn a_flexible_scene_stepped_at_10_hz_keeps_its_jacobian_and_the_runs_accuracy() {
    let path = example("flexible_array.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let scene = Scene::parse(&replace(text, "duration = 300.0", "duration = 30.0"), &path)
        .expect("valid scene");
    let run = run_scene(&scene, || false).unwrap();
    let mut s = stepper(&scene);
    let mut pieces = 0;
    step_to_end(&mut s, 30.0, || {
        pieces += 1;
        0.1
    });
    // 15 Jacobians for the 300 pieces (5 509 right-hand sides, 632 steps), as the one run
    // of these 30 s takes (4 085 right-hand sides, 413 steps); afresh, a piece took one
    // each.
    let work = s.stepping().work();
    assert!(
        work.jacobian_evals * 10 < pieces,
        "{work:?} over {pieces} pieces"
    );
    let got = s.trajectory();
    let mut worst: f64 = 0.0;
    for h in ["angle_h1", "angle_h2", "angle_h3", "angle_h4", "angle_h5"] {
        let c = column(&run, h);
        for (a, b) in got.rows().zip(run.rows()) {
            worst = worst.max((a[c] - b[c]).abs());
        }
    }
    // 3.3e-5 rad: the run's own error against a converged reference is 6.7e-5 rad.
    assert!(worst < 1e-4, "{worst}");
}
