use super::*;
use nalgebra::{UnitQuaternion, Vector3};
use satsim_integrate::{Method, Stats};
use satsim_spacecraft::simulation::StateLayout;

#[test]
fn attitude_angle_of_a_rotation_is_its_angle() {
    let base = UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0);
    for (axis, angle) in [
        (Vector3::new(1.0, 2.0, -0.5), 1e-9),
        (Vector3::new(0.0, 0.0, 1.0), 0.25),
        (Vector3::new(-3.0, 1.0, 1.0), 3.0),
    ] {
        let d = UnitQuaternion::from_scaled_axis(axis.normalize() * angle);
        let q = base * d;
        let c = |u: UnitQuaternion<f64>| [u.w, u.i, u.j, u.k];
        let e = attitude_angle(&c(base), &c(q));
        assert!((e - angle).abs() < 1e-15 + 1e-13 * angle, "{e} vs {angle}");
        // q and −q are the same attitude.
        let neg = c(q).map(|v| -v);
        assert!((attitude_angle(&c(base), &neg) - angle).abs() < 1e-15 + 1e-13 * angle);
        // The error is the same measured in either order.
        assert!((attitude_angle(&c(q), &c(base)) - angle).abs() < 1e-15 + 1e-13 * angle);
    }
}

fn layout_free_2() -> StateLayout {
    // q (4), angles (2), ω (3), v (3), rates (2)
    StateLayout {
        free: true,
        n_hinges: 2,
        attitude: 0..4,
        angles: 4..6,
        omega: 6..9,
        velocity: 9..12,
        rates: 12..14,
        eta: 14..14,
        etadot: 14..14,
        effects: vec![],
        len: 14,
    }
}

fn traj(times: &[f64], states: Vec<Vec<f64>>) -> Trajectory {
    Trajectory {
        times: times.to_vec(),
        states,
        stats: Stats {
            rhs_evals: 0,
            steps_accepted: 0,
            steps_rejected: 0,
            jacobian_evals: 0,
            jacobian_updates: 0,
            lu_decompositions: 0,
            steps_capped: 0,
            capped_span: 0.0,
            events: vec![],
            t_final: *times.last().unwrap(),
            x_final: vec![],
            stop: satsim_integrate::StopReason::Finished,
        },
        seconds: 0.0,
    }
}

#[test]
fn metrics_on_a_synthetic_case() {
    let l = layout_free_2();
    let mut x = vec![0.0; 14];
    x[0] = 1.0;
    let reference = traj(&[0.0, 1.0], vec![x.clone(), x.clone()]);
    // At t = 1: rotated by 2e-6 rad, hinge angle off by 3e-7, velocity (not compared)
    // off by 1, bus rate off by 4e-6 (the largest), hinge rate off by 1e-6.
    let mut y = x.clone();
    let (s, c) = (1e-6f64.sin(), 1e-6f64.cos());
    y[..4].copy_from_slice(&[c, 0.0, s, 0.0]);
    y[5] = 3e-7;
    y[10] = 1.0;
    y[7] = -4e-6;
    y[13] = 1e-6;
    let run = traj(&[0.0, 1.0], vec![x.clone(), y]);
    let m = compare(&l, &reference, &run).unwrap();
    assert!((m.at_end.attitude - 2e-6).abs() < 1e-18);
    assert_eq!(m.at_end.angles, 3e-7);
    assert_eq!(m.at_end.rates, 4e-6);
    assert_eq!(m.final_max, 4e-6);
    assert_eq!(m.max_over_time, 4e-6);
    // RMS over the two saved times: sqrt((0 + (4e-6)²) / 2).
    assert!((m.rms - 4e-6 / 2f64.sqrt()).abs() < 1e-20);
    // Mismatched saved times are an error.
    let short = traj(&[0.0], vec![x]);
    assert!(compare(&l, &reference, &short).is_err());
}

#[test]
fn reach_interpolates_in_log_log() {
    let m = |e: f64, t: f64| Measured {
        errors: ErrorMetrics {
            final_max: e,
            ..Default::default()
        },
        seconds: t,
        rhs_evals: (t * 1e6) as usize,
        steps: 1,
        rejected: 0,
        events: 0,
    };
    let p = |tol: f64, e: f64, t: f64| Point {
        method: Method::Dp54,
        setting: Setting::Tolerance(tol),
        result: Ok(m(e, t)),
    };
    let report = Report {
        scene: "x".into(),
        duration: 1.0,
        every: 1.0,
        state_len: 1,
        sweep: Sweep {
            methods: vec![Method::Dp54],
            tolerances: vec![],
            rk4_steps: vec![],
            atol_scale: 1.0,
            repeats: 1,
            reference: (Method::Dop853, 1e-13),
            cross_reference: (Method::Dp54, 1e-13),
        },
        reference: ReferenceRun {
            method: Method::Dop853,
            tol: 1e-13,
            seconds: 0.0,
            rhs_evals: 0,
            steps: 0,
        },
        cross_reference: ReferenceRun {
            method: Method::Dp54,
            tol: 1e-13,
            seconds: 0.0,
            rhs_evals: 0,
            steps: 0,
        },
        floor: ErrorMetrics::default(),
        points: vec![p(1e-4, 1e-6, 0.01), p(1e-6, 1e-10, 0.1)],
    };
    let r = report.to_reach(Method::Dp54, 1e-8, Cost::Seconds);
    assert!((r.interpolated.unwrap() - 10f64.powf(-1.5)).abs() < 1e-12);
    assert_eq!(r.cheapest.unwrap().0, Setting::Tolerance(1e-6));
    let svg = report.svg(Cost::Seconds);
    assert!(svg.starts_with("<svg") && svg.contains("polyline") && svg.contains("DP5(4)"));
    assert_eq!(report.csv().lines().count(), 3);
    assert!(report.markdown().contains("| DP5(4) | tol 1e-6 |"));
}

/// On a flexible scene, an RK4 step beyond the stability limit of its highest mode is not
/// run (it would blow up): the sweep says why, with the limit, and runs the stable steps.
#[test]
fn rk4_steps_beyond_the_modes_stability_limit_are_not_run() {
    let text = r#"duration = 0.5
[model]
[model.base]
kind = "fixed"
[[model.body]]
name = "beam"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[model.body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = 2.0, EI = 500.0, rho_A = 5.0, modes = 2 }
[initial]
flexible = { beam = { eta = [0.01, 0.0] } }
[integrator]
method = "dp54"
[output]
every = 0.25
plots = false
view = false
"#;
    let scene = crate::scene::Scene::parse(text, std::path::Path::new("beam.toml")).unwrap();
    use crate::scene::step_limit::{HingeGains, rk4_limit, rk4_stable_step};
    let (stable, what) = rk4_stable_step(&scene).unwrap();
    assert!(what.starts_with("body `beam`'s mode 2 ("), "{what}");
    let flex = scene.flexible.as_ref().unwrap();
    let limit = rk4_limit(
        flex,
        &scene.initial_q(),
        &scene.initial_v(),
        &HingeGains::none(0),
    )
    .unwrap();
    assert_eq!(limit.step, stable);
    let hz = limit.omega / std::f64::consts::TAU;
    // The second clamped mode: (4.694)² √(EI / ρA L⁴) / 2π.
    let expected = 4.694091f64.powi(2) * (500.0f64 / (5.0 * 16.0)).sqrt() / std::f64::consts::TAU;
    assert!(
        (hz - expected).abs() < 1e-4 * expected,
        "{hz} Hz, expected {expected}"
    );
    let sweep = Sweep {
        methods: vec![Method::Rk4],
        tolerances: vec![],
        rk4_steps: vec![4.0 * stable, 0.5 * stable],
        atol_scale: 1.0,
        repeats: 1,
        reference: (Method::Dop853, 1e-10),
        cross_reference: (Method::Dp54, 1e-10),
    };
    let report = sweep::sweep(&scene, &sweep, |_| {}).unwrap();
    let beyond = report.points[0].result.as_ref().unwrap_err();
    assert!(
        beyond.starts_with("not run: h = ")
            && beyond.contains("beyond rk4's stability limit for body `beam`'s mode 2"),
        "{beyond}"
    );
    assert!(
        report.points[1].result.is_ok(),
        "{:?}",
        report.points[1].result
    );
}

/// `elastic_error = false` is Radau IIA's: the sweep runs the other methods with the elastic
/// coordinates in their error (an explicit method's steps would go past the modes' stability
/// limit), so a scene with it gives them the same runs as one without it.
#[test]
fn explicit_methods_count_the_elastic_coordinates_whatever_the_scene_says() {
    let text = r#"duration = 1.0
[model]
[model.base]
kind = "fixed"
[[model.body]]
name = "hub"
mass = 10.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[model.body]]
name = "arm"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[model.body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = 2.0, EI = 500.0, rho_A = 5.0, modes = 2 }
[[model.hinge]]
name = "h"
parent = "hub"
child = "arm"
axis = [1.0, 0.0, 0.0]
[initial]
hinges = { angle = [0.3], rate = [0.0] }
[effects.hinge_springs]
stiffness = [20.0]
damping = [0.5]
reference = [0.0]
[integrator]
method = "radau5"
elastic_error = false
[output]
every = 0.25
plots = false
view = false
"#;
    let path = std::path::Path::new("arm.toml");
    let rigid_only = crate::scene::Scene::parse(text, path).unwrap();
    let every_state = crate::scene::Scene::parse(&text.replace("false", "true"), path).unwrap();
    assert!(!rigid_only.elastic_error && every_state.elastic_error);
    let sweep = Sweep {
        methods: vec![Method::Dp54, Method::Radau5],
        tolerances: vec![1e-6],
        rk4_steps: vec![],
        atol_scale: 1.0,
        repeats: 1,
        reference: (Method::Dop853, 1e-10),
        cross_reference: (Method::Dp54, 1e-10),
    };
    let rhs = |scene: &crate::scene::Scene| -> Vec<usize> {
        let report = sweep::sweep(scene, &sweep, |_| {}).unwrap();
        report
            .points
            .iter()
            .map(|p| p.result.as_ref().unwrap().rhs_evals)
            .collect()
    };
    let (a, b) = (rhs(&rigid_only), rhs(&every_state));
    assert_eq!(a[0], b[0], "dp54: {a:?} against {b:?}");
    // Radau IIA takes the scene's setting: fewer steps with the modes out of its error.
    assert!(a[1] < b[1], "radau5: {a:?} against {b:?}");
}
