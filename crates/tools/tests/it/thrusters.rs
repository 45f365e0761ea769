//! `[effects.thrusters]`: the impulse of a pulse is `thrust · on-time` to round-off (the
//! switch-off is a time stop), the orbit gains `F t / M`, a thruster off the centre of mass
//! turns the angular momentum by `r × F t`, the minimum impulse bit and the on/off mode, the
//! stepping API's `thrust_<name>` equals the same constant duty bit for bit, the energy
//! budget closes, and bad input is an error naming the file and line, or the input.

use crate::common::{body, z_hinge};
use satsim_tools::api::{Trajectory, run_scene};
use satsim_tools::scene::Scene;
use satsim_tools::stepping::{SceneStepper, StepFailure};
use satsim_tree::spatial::Vec3;
use std::path::Path;

const MASS: f64 = 80.0;
/// The bus' centre of mass in its frame (m): off the origin, so that "through the centre of
/// mass" is not "through the origin".
const COM: [f64; 3] = [0.2, -0.1, 0.05];

/// A one-body scene (diagonal inertia about `COM`), at rest in the identity attitude unless
/// `initial` says otherwise, with `[effects.thrusters]` of period 0.1 s and `thrusters`
/// (`[[effects.thrusters.thruster]]` tables), an orbit when `orbit`, RK4 at 0.01 s.
fn scene_text(orbit: bool, initial: &str, thrusters: &str, duration: f64) -> String {
    let orbit = if orbit {
        "[orbit]\naltitude = 500e3\n"
    } else {
        ""
    };
    let initial = if initial.is_empty() {
        "base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.0, 0.0, 0.0] }"
    } else {
        initial
    };
    format!(
        r#"duration = {duration}
[model]
[[model.body]]
name = "bus"
mass = {MASS}
com = [{}, {}, {}]
inertia = [[6.0, 0.0, 0.0], [0.0, 8.0, 0.0], [0.0, 0.0, 10.0]]
{orbit}
[initial]
{initial}
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.1
plots = false
view = false
[effects.thrusters]
period = 0.1
{thrusters}
"#,
        COM[0], COM[1], COM[2]
    )
}

fn parse(text: &str) -> Scene {
    Scene::parse(text, Path::new("thrusters.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// One thruster table.
fn thruster(name: &str, at: [f64; 3], direction: [f64; 3], extra: &str) -> String {
    format!(
        "[[effects.thrusters.thruster]]\nname = \"{name}\"\nbody = \"bus\"\nat = {at:?}\ndirection = {direction:?}\nthrust = 2.0\n{extra}\n"
    )
}

/// The final linear momentum (N s, inertial) and angular momentum about the centre of mass
/// (N m s) of a run of `scene` to its end.
fn momenta(scene: &Scene) -> (Vec3, Vec3) {
    let mut sim = scene.simulation().expect("the scene builds");
    let (t, x) = sim
        .state_at(&scene.options, scene.duration)
        .expect("the run completes");
    assert_eq!(t, scene.duration);
    let d = sim.diagnostics(t, &x).unwrap();
    (d.p, d.h)
}

fn column(t: &Trajectory, name: &str) -> usize {
    t.columns
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {:?}", t.columns))
}

fn last(t: &Trajectory, name: &str) -> f64 {
    t.rows().last().unwrap()[column(t, name)]
}

fn close(a: Vec3, b: Vec3, tol: f64) -> bool {
    (a - b).norm() <= tol * b.norm().max(1e-300)
}

/// The direction `[1, 2, 2] / 3` (normalised by the reader).
const DIR: [f64; 3] = [1.0, 2.0, 2.0];

fn dir() -> Vec3 {
    Vec3::from(DIR) / 3.0
}

#[test]
fn a_pulse_through_the_centre_of_mass_gives_f_t_and_leaves_the_attitude_alone() {
    // 0.37 of a 0.1 s period, three periods: the switch-offs at 0.037 + k 0.1 fall inside
    // RK4 steps of 0.01 s, which end there.
    let duty = 0.37;
    let th = thruster("x", COM, DIR, &format!("duty = {duty}"));
    let scene = parse(&scene_text(false, "", &th, 0.3));
    let (p, h) = momenta(&scene);
    let impulse = 2.0 * dir() * (3.0 * duty * 0.1);
    println!("p {p:?}, expected {impulse:?}, h {h:?}");
    // Round-off: the velocity is a sum of about 40 steps' increments.
    assert!(close(p, impulse, 1e-13), "{p:?} vs {impulse:?}");
    assert!(h.norm() < 1e-15, "{h:?}");
    let run = run_scene(&scene, || false).unwrap();
    for c in ["omega_x", "omega_y", "omega_z"] {
        assert!(last(&run, c).abs() < 1e-15, "{c}");
    }
    assert!((last(&run, "q_w") - 1.0).abs() < 1e-15);
}

#[test]
fn with_an_orbit_the_net_force_moves_the_orbit_by_f_t_over_m() {
    let duty = 0.37;
    let th = thruster("x", COM, DIR, &format!("duty = {duty}"));
    let off = thruster("x", COM, DIR, "duty = 0.0");
    let pushed = run_scene(&parse(&scene_text(true, "", &th, 0.3)), || false).unwrap();
    let coast = run_scene(&parse(&scene_text(true, "", &off, 0.3)), || false).unwrap();
    let v = |t: &Trajectory| {
        Vec3::new(
            last(t, "orbit_v_x"),
            last(t, "orbit_v_y"),
            last(t, "orbit_v_z"),
        )
    };
    let dv = v(&pushed) - v(&coast);
    let expected = 2.0 * dir() * (3.0 * duty * 0.1) / MASS;
    println!("dv {dv:?}, expected {expected:?}");
    // Not to round-off: the two paths part by ~½ (F/M) t², where gravity differs by its
    // gradient 2μ/r³ (2.5e-6 /s²), which changes Δv by up to ~(μ/r³) t² ~ 1e-7 of the push
    // (measured 5e-8).
    assert!(close(dv, expected, 1e-6), "{dv:?} vs {expected:?}");
    // The attitude: still at rest, and the centre of mass at rest in the falling frame.
    for c in ["omega_x", "omega_y", "omega_z"] {
        assert!(last(&pushed, c).abs() < 1e-15, "{c}");
    }
    let (p, h) = momenta(&parse(&scene_text(true, "", &th, 0.3)));
    assert!(p.norm() < 1e-12 && h.norm() < 1e-14, "{p:?} {h:?}");
}

#[test]
fn a_thruster_off_the_centre_of_mass_turns_the_angular_momentum_by_r_cross_f_t() {
    // r = at − com = (0, 0.5, 0), F = 2 z: r × F = (1, 0, 0) N m, about the principal x
    // axis, so the body turns about x and r × F stays (1, 0, 0) in inertial axes.
    let at = [COM[0], COM[1] + 0.5, COM[2]];
    let duty = 0.61;
    let th = thruster("roll", at, [0.0, 0.0, 3.0], &format!("duty = {duty}"));
    let t_on = 4.0 * duty * 0.1;
    let expected_h = Vec3::new(1.0 * t_on, 0.0, 0.0);
    for orbit in [false, true] {
        let scene = parse(&scene_text(orbit, "", &th, 0.4));
        let (p, h) = momenta(&scene);
        println!("orbit {orbit}: h {h:?}, expected {expected_h:?}, p {p:?}");
        assert!(close(h, expected_h, 1e-13), "{h:?}");
        if orbit {
            // The centre of mass stays at rest in the falling frame.
            assert!(p.norm() < 1e-12, "{p:?}");
        } else {
            // The force turned with the body about x: p lies in the y-z plane, |p| < F t.
            assert!(
                p.x.abs() < 1e-15 && p.norm() < 2.0 * t_on && p.norm() > 0.0,
                "{p:?}"
            );
        }
        // The same from the row's columns.
        let run = run_scene(&scene, || false).unwrap();
        assert!((last(&run, "h_x") - expected_h.x).abs() < 1e-13);
    }
}

#[test]
fn the_minimum_impulse_bit_fires_nothing_below_it_and_everything_above() {
    // 0.01 N s at 2 N: 5 ms, a duty of 0.05 of the 0.1 s period.
    for (duty, fires) in [(0.0499, false), (0.0501, true), (0.05, true)] {
        let th = thruster("x", COM, DIR, &format!("duty = {duty}\nmin_impulse = 0.01"));
        let (p, _) = momenta(&parse(&scene_text(false, "", &th, 0.2)));
        let expected = if fires {
            2.0 * dir() * (2.0 * duty * 0.1)
        } else {
            Vec3::zeros()
        };
        println!("duty {duty}: p {p:?}");
        if fires {
            assert!(close(p, expected, 1e-13), "duty {duty}: {p:?}");
        } else {
            assert_eq!(p, Vec3::zeros(), "duty {duty}");
        }
    }
}

#[test]
fn on_off_mode_fires_whole_periods_from_a_duty_of_one_half() {
    for (duty, fires) in [(0.49, false), (0.5, true), (0.8, true)] {
        let th = thruster("x", COM, DIR, &format!("duty = {duty}\nmode = \"on_off\""));
        let (p, _) = momenta(&parse(&scene_text(false, "", &th, 0.3)));
        let expected = if fires {
            2.0 * dir() * 0.3
        } else {
            Vec3::zeros()
        };
        assert!(
            close(p, expected, 1e-13) || p == expected,
            "duty {duty}: {p:?}"
        );
    }
}

#[test]
fn a_duty_through_the_stepping_api_equals_the_same_constant_duty_bit_for_bit() {
    let at = [0.3, 0.4, -0.2];
    let fixed = thruster("a", at, DIR, "duty = 0.3") + &thruster("b", COM, [0.0, 1.0, 0.0], "");
    let held = thruster("a", at, DIR, "") + &thruster("b", COM, [0.0, 1.0, 0.0], "");
    let initial = "base = { angular_velocity = [0.01, -0.02, 0.03] }";
    for orbit in [false, true] {
        let constant = parse(&scene_text(orbit, initial, &fixed, 1.0));
        let stepped = parse(&scene_text(orbit, initial, &held, 1.0));
        let run = run_scene(&constant, || false).unwrap();
        let mut s = SceneStepper::new(&stepped, None, "test").unwrap();
        assert!(s.inputs().iter().any(|i| i == "thrust_a"));
        s.set_inputs(&[("thrust_a", 0.3)]).unwrap();
        // Pieces of whole steps, across period starts and switch-offs.
        for dt in [0.03, 0.12, 0.25, 0.1, 0.5] {
            s.advance(dt).unwrap();
        }
        assert_eq!(s.trajectory().columns, run.columns);
        assert_eq!(s.trajectory().values, run.values, "orbit {orbit}");
        // `a` fired (for 0.03 s of each 0.1 s period: ten pulses of 0.06 N s, nearly aligned
        // as the bus turns 0.04 rad over the run), `b` never did. The rows fall on the period
        // starts, where a row shows the thrust before that instant's sample (the outputs come
        // before the stop), so the pulses are read off the momentum (without the orbit, which
        // otherwise carries the centre of mass's motion).
        if !orbit {
            let idle =
                thruster("a", at, DIR, "duty = 0.0") + &thruster("b", COM, [0.0, 1.0, 0.0], "");
            let idle = parse(&scene_text(orbit, initial, &idle, 1.0));
            let impulse = momenta(&constant).0 - momenta(&idle).0;
            assert!((impulse.norm() - 0.6).abs() < 1e-2, "{impulse:?}");
        }
        assert!(run.rows().all(|r| r[column(&run, "thrust_b")] == 0.0));
    }
}

#[test]
fn an_input_set_at_a_period_start_acts_from_it_and_one_set_inside_a_period_from_the_next() {
    // r × F = (0.5 m) y × (2 N) z = (1, 0, 0) N m about the principal x axis: h_x is 1 N m
    // times the on-time.
    let at = [COM[0], COM[1] + 0.5, COM[2]];
    let th = thruster("roll", at, [0.0, 0.0, 1.0], "");
    let scene = parse(&scene_text(false, "", &th, 1.0));
    let mut s = SceneStepper::new(&scene, None, "test").unwrap();
    let duties = [0.2, 0.7, 0.0, 1.0, 0.45];
    for d in duties {
        s.set_inputs(&[("thrust_roll", d)]).unwrap();
        s.advance(0.1).unwrap();
    }
    let h = |s: &mut SceneStepper| {
        let row = s.row().unwrap();
        row[s.columns().iter().position(|c| c == "h_x").unwrap()]
    };
    let expected: f64 = duties.iter().map(|d| 1.0 * d * 0.1).sum();
    assert!(
        (h(&mut s) - expected).abs() < 1e-14,
        "{} {expected}",
        h(&mut s)
    );
    // Inside a period: held for it, latched at the next start.
    s.set_inputs(&[("thrust_roll", 0.0)]).unwrap();
    s.advance(0.05).unwrap();
    s.set_inputs(&[("thrust_roll", 0.3)]).unwrap();
    s.advance(0.15).unwrap();
    let expected = expected + 1.0 * 0.3 * 0.1;
    assert!(
        (h(&mut s) - expected).abs() < 1e-14,
        "{} {expected}",
        h(&mut s)
    );
}

#[test]
fn the_energy_budget_closes_with_thrusters_firing() {
    let th = thruster("a", [0.5, 0.4, -0.2], DIR, "duty = 0.43")
        + &thruster("b", [-0.3, 0.0, 0.6], [1.0, 0.0, 0.0], "duty = 1.0")
        + &thruster(
            "c",
            [0.0, -0.5, 0.0],
            [0.0, 0.0, -1.0],
            "duty = 0.2\nmode = \"on_off\"",
        );
    let initial = "base = { angular_velocity = [0.05, -0.02, 0.03] }";
    for orbit in [false, true] {
        let scene = parse(&scene_text(orbit, initial, &th, 3.0));
        let run = run_scene(&scene, || false).unwrap();
        let budget = column(&run, "energy_budget");
        let terms = [
            column(&run, "kinetic_energy"),
            column(&run, "potential_energy"),
            column(&run, "work_actuators"),
            column(&run, "energy_dissipated"),
        ];
        let b0 = run.rows().next().unwrap()[budget];
        let drift = run
            .rows()
            .map(|r| (r[budget] - b0).abs())
            .fold(0.0, f64::max);
        let scale = run
            .rows()
            .flat_map(|r| terms.iter().map(|&c| r[c].abs()).collect::<Vec<_>>())
            .fold(0.0, f64::max);
        let work = last(&run, "work_actuators");
        println!("orbit {orbit}: drift {drift:.3e} J of {scale:.3e} J, W {work:.4e} J");
        assert!(work.abs() > 1e-2, "the thrusters did work");
        // As in tests/it/energy_budget.rs: within 1e-6 of the largest term.
        assert!(drift < 1e-6 * scale, "drift {drift} of {scale}");
    }
}

fn scene_error(text: &str) -> String {
    match Scene::parse(text, Path::new("thrusters.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_thruster_keys_are_errors_naming_file_and_line() {
    let good = thruster("x", COM, DIR, "");
    let cases = [
        (
            "direction = [1.0, 2.0, 2.0]",
            "direction = [0.0, 0.0, 0.0]",
            "direction",
        ),
        ("thrust = 2.0", "thrust = 0.0", "thrust"),
        ("thrust = 2.0", "thrust = -1.0", "thrust"),
        ("body = \"bus\"", "body = \"panel\"", "panel"),
        (
            "thrust = 2.0",
            "thrust = 2.0\nmin_impulse = -0.1",
            "min_impulse",
        ),
        ("thrust = 2.0", "thrust = 2.0\nmode = \"pulse\"", "mode"),
        ("thrust = 2.0", "thrust = 2.0\nduty = 1.5", "duty"),
        ("thrust = 2.0", "thrust = 2.0\nduty = -0.1", "duty"),
        ("thrust = 2.0", "thrust = 2.0\nduty = nan", "duty"),
        ("at = [0.2, -0.1, 0.05]", "at = [0.2, inf, 0.05]", "at"),
    ];
    for (from, to, what) in cases {
        assert!(good.contains(from), "{from}");
        let text = scene_text(false, "", &good.replacen(from, to, 1), 1.0);
        let key = to.lines().last().unwrap();
        let line = text.lines().position(|l| l == key).unwrap() + 1;
        let e = scene_error(&text);
        assert!(
            e.contains("thrusters.toml") && e.contains(&format!(":{line}")) && e.contains(what),
            "{to}: {e}"
        );
    }
    // The period and a repeated name.
    let text = scene_text(false, "", &good, 1.0).replace("period = 0.1", "period = 0.0");
    let line = text.lines().position(|l| l == "period = 0.0").unwrap() + 1;
    let e = scene_error(&text);
    assert!(
        e.contains(&format!(":{line}")) && e.contains("period"),
        "{e}"
    );
    let e = scene_error(&scene_text(false, "", &(good.clone() + &good), 1.0));
    assert!(e.contains("listed twice"), "{e}");
}

#[test]
fn a_duty_input_outside_zero_to_one_is_an_error_naming_it_and_changes_nothing() {
    let th = thruster("x", [0.0, 0.5, 0.0], DIR, "");
    let scene = parse(&scene_text(false, "", &th, 1.0));
    let mut s = SceneStepper::new(&scene, None, "test").unwrap();
    s.set_inputs(&[("thrust_x", 0.25)]).unwrap();
    s.advance(0.15).unwrap();
    let row = s.row().unwrap();
    for bad in [1.5, -0.01, f64::NAN, f64::INFINITY] {
        match s.set_inputs(&[("thrust_x", bad)]) {
            Err(StepFailure::Input(m)) => assert!(m.contains("thrust_x"), "{m}"),
            other => panic!("{bad}: {other:?}"),
        }
    }
    assert_eq!(s.stepping().input_values().last(), Some(&0.25));
    assert_eq!(s.row().unwrap(), row);
    let mut reference = SceneStepper::new(&scene, None, "test").unwrap();
    reference.set_inputs(&[("thrust_x", 0.25)]).unwrap();
    reference.advance(0.15).unwrap();
    reference.advance(0.35).unwrap();
    s.advance(0.35).unwrap();
    assert_eq!(s.row().unwrap(), reference.row().unwrap());
}

#[test]
fn the_pulse_is_a_rectangle_whatever_the_integrator() {
    // A constant force is integrated exactly by every method; only the pulse's edges could
    // spoil it, and they are time stops.
    let duty = 0.37;
    let th = thruster("x", COM, DIR, &format!("duty = {duty}"));
    let text = scene_text(false, "", &th, 0.3);
    for integrator in [
        "method = \"dp54\"\nrtol = 1e-9\natol = 1e-12",
        "method = \"dop853\"\nrtol = 1e-9\natol = 1e-12",
        "method = \"radau5\"\nrtol = 1e-9\natol = 1e-12",
    ] {
        let text = text.replace("method = \"rk4\"\nstep = 0.01", integrator);
        let (p, h) = momenta(&parse(&text));
        let impulse = 2.0 * dir() * (3.0 * duty * 0.1);
        println!("{integrator}: p {p:?}");
        assert!(
            close(p, impulse, 1e-12),
            "{integrator}: {p:?} vs {impulse:?}"
        );
        assert!(h.norm() < 1e-15, "{h:?}");
    }
}

/// A bus (80 kg, centre of mass at its origin) and a 20 kg panel on a hinge about z at
/// (0.5, 0, 0), the panel's origin 1 m beyond: the system's centre of mass is at x = 0.3 m.
/// A thruster on the panel pushes along z at the panel's point (−1.2, 0, 0.7), on the
/// vertical through the system's centre of mass.
fn panel_text(orbit: bool, duty: f64) -> String {
    let orbit = if orbit {
        "[orbit]\naltitude = 500e3\n"
    } else {
        ""
    };
    format!(
        r#"duration = 0.5
[model]
{}{}{}{orbit}
[initial]
base = {{ attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.0, 0.0, 0.0] }}
hinges = {{ angle = [0.0], rate = [0.0] }}
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.1
plots = false
view = false
[effects.thrusters]
period = 0.1
[[effects.thrusters.thruster]]
name = "z"
body = "panel"
at = [-1.2, 0.0, 0.7]
direction = [0.0, 0.0, 1.0]
thrust = 3.0
duty = {duty}
"#,
        body("bus", 80.0, [6.0, 8.0, 10.0]),
        body("panel", 20.0, [1.0, 2.0, 3.0]),
        z_hinge("h", "bus", "panel", 0.5, Some(-1.0))
    )
}

#[test]
fn a_thruster_on_a_panel_through_the_centre_of_mass_translates_the_whole_without_turning_it() {
    // The force has no moment about the system's centre of mass nor about the hinge axis:
    // the rigid translation at F / M satisfies the dynamics with the hinge at rest.
    let duty = 0.55;
    let t_on = 5.0 * duty * 0.1;
    let (p, h) = momenta(&parse(&panel_text(false, duty)));
    println!("panel: p {p:?}, h {h:?}");
    assert!(close(p, Vec3::new(0.0, 0.0, 3.0 * t_on), 1e-13), "{p:?}");
    assert!(h.norm() < 1e-14, "{h:?}");
    for orbit in [false, true] {
        let run = run_scene(&parse(&panel_text(orbit, duty)), || false).unwrap();
        for c in ["omega_x", "omega_y", "omega_z", "rate_h"] {
            assert!(
                last(&run, c).abs() < 1e-14,
                "orbit {orbit}: {c} {}",
                last(&run, c)
            );
        }
    }
    let pushed = run_scene(&parse(&panel_text(true, duty)), || false).unwrap();
    let coast = run_scene(&parse(&panel_text(true, 0.0)), || false).unwrap();
    let dv = last(&pushed, "orbit_v_z") - last(&coast, "orbit_v_z");
    // As in the one-body case: the differential gravity, ~1e-7 of the push.
    assert!((dv - 3.0 * t_on / 100.0).abs() < 1e-6 * dv, "{dv}");
}

/// `satsim linearize` (and `modes`) start where a run does: the duty latched at the start
/// fires in the linear model's state. A thruster of duty 1 at `COM + (0, 0.5, 0)` pushing
/// along x turns the bus about its centre of mass by `r × F = (0, 0, −1)` N m: the linear
/// model's residual (the drift of its initial state) is the run's angular and linear
/// acceleration just after its start, where it was zero before the start's sample was
/// taken.
#[test]
fn a_constant_duty_fires_in_the_linearisation_as_in_the_run() {
    let at = [COM[0], COM[1] + 0.5, COM[2]];
    let th = thruster("x", at, [1.0, 0.0, 0.0], "duty = 1.0");
    let scene = parse(&scene_text(false, "", &th, 1.0));
    let lin = satsim_tools::linearize::linearize(&scene).expect("linearises");
    // The run's derivative just after its start, where the duty has latched.
    let mut sim = scene.simulation().expect("the scene builds");
    let (_, x) = sim.state_at(&scene.options, 1e-9).expect("a first step");
    let mut dx = vec![0.0; x.len()];
    satsim_integrate::System::rhs(&mut sim, 1e-9, &x, &mut dx).expect("rhs");
    let layout = sim.layout().clone();
    let omega = lin.state("omega_x").expect("omega");
    let vel = lin.state("vel_x").expect("vel");
    let mut torque_free = true;
    for k in 0..3 {
        let (r_w, r_v) = (lin.residual[omega + k], lin.residual[vel + k]);
        assert!(
            (r_w - dx[layout.omega.start + k]).abs() < 1e-9,
            "omega {k}: {r_w} against the run's {}",
            dx[layout.omega.start + k]
        );
        assert!(
            (r_v - dx[layout.velocity.start + k]).abs() < 1e-9,
            "vel {k}: {r_v} against the run's {}",
            dx[layout.velocity.start + k]
        );
        torque_free &= r_w == 0.0;
    }
    // The couple is there (before, the start's sample was not taken and this was zero).
    assert!(!torque_free, "{:?}", lin.residual);
    assert!(lin.not_an_equilibrium().is_some());
}
