//! Linearisation and modes against analytic results, a second algorithm (the CRBA mass
//! matrix) and nonlinear runs. Each test would fail for a wrong Jacobian, a wrong attitude
//! error convention or a wrong eigen-analysis.

use crate::common::{body, example, fixed_panel_model, z_hinge};
use satsim_integrate::{Method, Options, Output};
use satsim_tools::linearize::linearize;
use satsim_tools::modes::{Along, modes, sweep};
use satsim_tools::scene::Scene;
use satsim_tree::{Data, crba};
use std::f64::consts::PI;
use std::path::Path;

fn scene(text: &str) -> Scene {
    Scene::parse(text, Path::new("test.toml")).expect("valid scene")
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// A panel (mass m, inertia j about its centre, centre at distance d from the hinge) on a
/// fixed base, hinged about z, with a spring k and a damper c.
fn fixed_panel(m: f64, j: f64, d: f64, k: f64, c: f64) -> String {
    format!(
        r#"
duration = 1.0
{}[effects.hinge_springs]
stiffness = [{k}]
damping = [{c}]
"#,
        fixed_panel_model(m, j, d)
    )
}

#[test]
fn fixed_base_panel_frequency_is_sqrt_k_over_hinge_inertia() {
    let (m, j, d, k) = (20.0, 1.5, 1.2, 40.0);
    let s = scene(&fixed_panel(m, j, d, k, 0.0));
    let lin = linearize(&s).unwrap();
    assert_eq!(lin.states, ["angle_h", "rate_h"]);
    assert_eq!(lin.inputs, ["torque_h"]);
    let i_hinge = j + m * d * d;
    assert!(rel(-lin.a[(1, 0)], k / i_hinge) < 1e-9, "{}", lin.a);
    assert!(rel(lin.b[(1, 0)], 1.0 / i_hinge) < 1e-9);
    let md = modes(&s).unwrap();
    assert_eq!(md.frequencies_hz.len(), 1);
    assert_eq!(md.rigid_modes, 0);
    let f = (k / i_hinge).sqrt() / (2.0 * PI);
    assert!(rel(md.frequencies_hz[0], f) < 1e-9, "{md:?}");
    assert!(md.damping_ratios[0].abs() < 1e-9);
    // The shape is normalised on the hinge angle; the rate entry is i·ω times it.
    let mode = &md.modes[0];
    assert_eq!(mode.shape[0], ("angle_h".to_string(), 1.0));
    assert!(rel(mode.shape_imag[1].1, 2.0 * PI * f) < 1e-8, "{mode:?}");
}

#[test]
fn damping_ratio_is_c_over_two_sqrt_k_i() {
    let (m, j, d, k, c) = (20.0, 1.5, 1.2, 40.0, 9.0);
    let s = scene(&fixed_panel(m, j, d, k, c));
    let md = modes(&s).unwrap();
    let i_hinge = j + m * d * d;
    let zeta = c / (2.0 * (k * i_hinge).sqrt());
    let wn = (k / i_hinge).sqrt();
    assert!(rel(md.damping_ratios[0], zeta) < 1e-8, "{md:?}");
    // Damped frequency ω_n sqrt(1 − ζ²).
    let fd = wn * (1.0 - zeta * zeta).sqrt() / (2.0 * PI);
    assert!(rel(md.frequencies_hz[0], fd) < 1e-8);
    // Overdamped: no oscillatory mode, two real eigenvalues.
    let s = scene(&fixed_panel(m, j, d, k, 20.0 * c));
    let md = modes(&s).unwrap();
    assert!(md.frequencies_hz.is_empty());
    assert_eq!(md.real_eigenvalues.len(), 2);
}

/// A bus (mass mb, inertia jb about z) with a panel hinged at `a` along x, free-floating.
fn free_bus_panel(extra: &str) -> String {
    format!(
        r#"
duration = 1.0
[model]
{}{}{}[effects.hinge_springs]
stiffness = [30.0]
{extra}
"#,
        body("bus", 300.0, [50.0, 60.0, 70.0]),
        body("panel", 25.0, [2.0, 8.0, 9.0]),
        z_hinge("h", "bus", "panel", 0.8, Some(-1.1))
    )
}

#[test]
fn panel_on_a_free_bus_has_the_two_body_frequency() {
    let s = scene(&free_bus_panel(""));
    let lin = linearize(&s).unwrap();
    let names: Vec<&str> = lin.states.iter().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "att_x", "att_y", "att_z", "omega_x", "omega_y", "omega_z", "vel_x", "vel_y", "vel_z",
            "angle_h", "rate_h"
        ]
    );
    // Planar two-body problem, translation eliminated: reduced mass μ, bus-centre to
    // panel-centre distance a + d; M = [[μ(a+d)² + Jb + Jp, μ(a+d)d + Jp], [·, μd² + Jp]];
    // the bus angle is cyclic, so ω² = k / (M22 − M12²/M11).
    let (mb, jb, mp, jp, a, d, k): (f64, f64, f64, f64, f64, f64, f64) =
        (300.0, 70.0, 25.0, 9.0, 0.8, 1.1, 30.0);
    let mu = mb * mp / (mb + mp);
    let m11 = mu * (a + d) * (a + d) + jb + jp;
    let m12 = mu * (a + d) * d + jp;
    let m22 = mu * d * d + jp;
    let i_eff = m22 - m12 * m12 / m11;
    let f = (k / i_eff).sqrt() / (2.0 * PI);
    let md = modes(&s).unwrap();
    assert_eq!(md.frequencies_hz.len(), 1, "{md:?}");
    assert!(
        rel(md.frequencies_hz[0], f) < 1e-8,
        "{} vs {f}",
        md.frequencies_hz[0]
    );
    // Three double zeros (attitude, angular velocity) and three single (velocity).
    assert_eq!(md.rigid_modes, 9);
    // The mode turns the bus the other way round (att_z and angle_h of opposite signs).
    let shape = &md.modes[0].shape;
    let att_z = shape.iter().find(|(n, _)| n == "att_z").unwrap().1;
    assert!(att_z < 0.0 && att_z > -1.0, "{shape:?}");
}

#[test]
fn finite_differences_match_the_mass_matrix_jacobian() {
    // The preprint's satellite with springs, away from the neutral pose, at rest at its
    // springs' reference (an equilibrium): the accelerations' Jacobian is −M⁻¹ [0; K] by the
    // mass matrix of CRBA (a second algorithm), and B's is M⁻¹ [0; I].
    let text = r#"
duration = 1.0
model = "../../../examples/satellite.toml"
[initial]
hinges = { angle = [0.1, -0.2, 0.15, 1.2, -0.7], rate = [0.0, 0.0, 0.0, 0.0, 0.0] }
[effects.hinge_springs]
stiffness = [50.0, 40.0, 30.0, 2.0, 3.0]
reference = [0.1, -0.2, 0.15, 1.2, -0.7]
"#;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scene.toml");
    let s = Scene::parse(text, &path).unwrap();
    let lin = linearize(&s).unwrap();
    let model = &s.model;
    let mut data = Data::new(model);
    let m = crba(model, &mut data, &s.initial.q).unwrap().clone();
    let minv = m.try_inverse().unwrap();
    let stiff = [50.0, 40.0, 30.0, 2.0, 3.0];
    let nv = model.nv(); // 6 + 5
    // Rows of the accelerations in z: omega (3..6), vel (6..9), rates (14..19).
    let acc_row = |i: usize| if i < 6 { 3 + i } else { 14 + (i - 6) };
    let mut worst: f64 = 0.0;
    let scale = minv.abs().max() * 50.0;
    for i in 0..nv {
        for h in 0..5 {
            // d(acc_i)/d(angle_h) = −(M⁻¹)_{i, 6+h} k_h
            let exact = -minv[(i, 6 + h)] * stiff[h];
            worst = worst.max((lin.a[(acc_row(i), 9 + h)] - exact).abs() / scale);
            let exact_b = minv[(i, 6 + h)];
            worst = worst.max((lin.b[(acc_row(i), h)] - exact_b).abs() / minv.abs().max());
        }
        // At rest the accelerations depend on no velocity and not on the attitude.
        for c in (0..9).chain(14..19) {
            assert!(lin.a[(acc_row(i), c)].abs() < 1e-9, "{} {c}", acc_row(i));
        }
    }
    assert!(worst < 1e-9, "worst relative difference {worst}");
    // Kinematic rows: att' = omega, angle' = rate, exactly.
    for r in 0..3 {
        assert!((lin.a[(r, 3 + r)] - 1.0).abs() < 1e-12);
    }
    for h in 0..5 {
        assert!((lin.a[(9 + h, 14 + h)] - 1.0).abs() < 1e-12);
    }
    assert!(lin.error_estimate < 1e-6, "{}", lin.error_estimate);
}

/// A rotor (inertias It, It, J) on a two-axis gimbal (x then y, springs k) on a fixed base,
/// spinning about z at `spin` rad/s.
fn gimbal_rotor(spin: f64) -> String {
    format!(
        r#"
duration = 1.0
[model]
base = {{ kind = "fixed" }}
[[model.body]]
name = "base"
mass = 10.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[model.body]]
name = "ring1"
mass = 0.0
[[model.body]]
name = "ring2"
mass = 0.0
[[model.body]]
name = "rotor"
mass = 5.0
inertia = [[0.4, 0.0, 0.0], [0.0, 0.4, 0.0], [0.0, 0.0, 0.6]]
[[model.hinge]]
name = "gx"
parent = "base"
child = "ring1"
axis = [1.0, 0.0, 0.0]
[[model.hinge]]
name = "gy"
parent = "ring1"
child = "ring2"
axis = [0.0, 1.0, 0.0]
[[model.hinge]]
name = "spin"
parent = "ring2"
child = "rotor"
axis = [0.0, 0.0, 1.0]
[initial]
hinges = {{ angle = [0.0, 0.0, 0.0], rate = [0.0, 0.0, {spin}] }}
[effects.hinge_springs]
stiffness = [8.0, 8.0, 0.0]
"#
    )
}

#[test]
fn spin_splits_the_gimbal_modes_gyroscopically() {
    let (it, j, k): (f64, f64, f64) = (0.4, 0.6, 8.0);
    let still = modes(&scene(&gimbal_rotor(0.0))).unwrap();
    let f0 = (k / it).sqrt() / (2.0 * PI);
    assert_eq!(still.frequencies_hz.len(), 2);
    for f in &still.frequencies_hz {
        assert!(rel(*f, f0) < 1e-7, "{still:?}");
    }
    // It ω² ∓ h ω − k = 0: nutation and precession.
    let spin = 20.0;
    let h = j * spin;
    let root = (h * h + 4.0 * it * k).sqrt();
    let slow = (root - h) / (2.0 * it) / (2.0 * PI);
    let fast = (root + h) / (2.0 * it) / (2.0 * PI);
    let spun = modes(&scene(&gimbal_rotor(spin))).unwrap();
    assert_eq!(spun.frequencies_hz.len(), 2, "{spun:?}");
    assert!(
        rel(spun.frequencies_hz[0], slow) < 1e-7,
        "{spun:?} vs {slow}"
    );
    assert!(
        rel(spun.frequencies_hz[1], fast) < 1e-7,
        "{spun:?} vs {fast}"
    );
    // The spin hinge's angle and rate are neutral.
    assert_eq!(spun.rigid_modes, 2);
}

#[test]
fn reaction_wheel_momentum_gives_the_free_bus_nutation() {
    // A free bus with one spinning wheel along z: I_t ω̇ + ω × h = 0 in x and y gives the
    // nutation frequency h / sqrt(Ix Iy), the transverse inertias including the rotor's.
    let text = r#"
duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[30.0, 0.0, 0.0], [0.0, 45.0, 0.0], [0.0, 0.0, 50.0]]
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.2
transverse = 0.1
speed = 300.0
"#;
    let s = scene(text);
    let lin = linearize(&s).unwrap();
    assert_eq!(lin.inputs, ["wheel_z"]);
    assert_eq!(lin.states.last().unwrap(), "wheel_z_speed");
    let md = modes(&s).unwrap();
    let h = 0.2 * 300.0;
    let f = h / ((30.0f64 + 0.1) * (45.0 + 0.1)).sqrt() / (2.0 * PI);
    assert_eq!(md.frequencies_hz.len(), 1, "{md:?}");
    assert!(rel(md.frequencies_hz[0], f) < 1e-7, "{md:?} vs {f}");
    // A motor torque spins the wheel up (1/J_axial relative to the bus, the bus having
    // inertia Iz about z) and the bus the other way.
    let w = lin.state("wheel_z_speed").unwrap();
    let oz = lin.state("omega_z").unwrap();
    let (jw, iz) = (0.2, 50.0);
    assert!(rel(lin.b[(oz, 0)], -1.0 / iz) < 1e-8, "{}", lin.b);
    assert!(rel(lin.b[(w, 0)], 1.0 / jw + 1.0 / iz) < 1e-8, "{}", lin.b);
}

#[test]
fn a_tumbling_bus_linearises_to_its_spin_and_its_intermediate_axis_instability() {
    // The guide's example of a linear model about a motion (docs/src/guide/modes.md): the
    // tumbling scene spins the bus at Ω = 0.2 rad/s about y, its intermediate axis
    // (Ix 900, Iy 800, Iz 600). Its Euler equations linearised there give the growth rate
    // Ω √((Iy − Iz)(Ix − Iy)/(Ix Iz)) in x and z; the attitude error turns with the body at Ω.
    let s = Scene::read(example("scenes/tumbling.toml")).unwrap();
    let md = modes(&s).unwrap();
    let spin = 0.2_f64;
    let rate = spin * ((800.0 - 600.0) * (900.0 - 800.0) / (900.0 * 600.0_f64)).sqrt();
    let grows = md.real_eigenvalues.iter().cloned().fold(f64::MIN, f64::max);
    let decays = md.real_eigenvalues.iter().cloned().fold(f64::MAX, f64::min);
    // The small x and z rates (1e-3 and 2e-3 rad/s) move them by about 1e-4 of the rate.
    assert!(rel(grows, rate) < 1e-3, "{md:?} vs {rate}");
    assert!(rel(-decays, rate) < 1e-3, "{md:?} vs {rate}");
    assert!(!md.frequencies_hz.is_empty(), "{md:?}");
    for f in &md.frequencies_hz {
        assert!(rel(*f, spin / (2.0 * PI)) < 1e-3, "{md:?}");
    }
}

fn libration(offset_body_rate: f64) -> String {
    format!(
        r#"
duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 500.0
inertia = [[110.0, 0.0, 0.0], [0.0, 120.0, 0.0], [0.0, 0.0, 20.0]]
[initial.base]
attitude = [0.5, -0.5, -0.5, 0.5]
angular_velocity = [0.0, {offset_body_rate}, 0.0]
[orbit]
altitude = 500e3
[effects.gravity_gradient]
model = "preprint"
"#
    )
}

#[test]
fn gravity_gradient_pitch_and_roll_yaw_librations() {
    // The libration example's satellite aligned with the orbital frame (x along-track, y
    // opposite to the orbit normal, z to the Earth), turning with it at −n about y.
    let mu: f64 = 3.986004418e14;
    let r: f64 = 6378137.0 + 500e3;
    let n = (mu / (r * r * r)).sqrt();
    let s = scene(&libration(-n));
    let md = modes(&s).unwrap();
    let (ix, iy, iz): (f64, f64, f64) = (110.0, 120.0, 20.0);
    let pitch = n * (3.0 * (ix - iz) / iy).sqrt() / (2.0 * PI);
    // Roll-yaw: s⁴ + s² n² (1 + 3 k1 + k1 k3) + 4 n⁴ k1 k3 = 0, k1 = (Iy − Iz)/Ix,
    // k3 = (Iy − Ix)/Iz (pitch axis y).
    let k1 = (iy - iz) / ix;
    let k3 = (iy - ix) / iz;
    let b = n * n * (1.0 + 3.0 * k1 + k1 * k3);
    let c = 4.0 * n.powi(4) * k1 * k3;
    let disc = (b * b - 4.0 * c).sqrt();
    let w1 = ((b - disc) / 2.0).sqrt() / (2.0 * PI);
    let w2 = ((b + disc) / 2.0).sqrt() / (2.0 * PI);
    let has = |f: f64| md.frequencies_hz.iter().any(|g| rel(*g, f) < 1e-6);
    assert!(has(pitch), "pitch {pitch} not in {:?}", md.frequencies_hz);
    assert!(has(w1), "roll-yaw {w1} not in {:?}", md.frequencies_hz);
    assert!(has(w2), "roll-yaw {w2} not in {:?}", md.frequencies_hz);
    // The pitch mode moves att_y only.
    let m = md
        .modes
        .iter()
        .find(|m| rel(m.frequency_hz, pitch) < 1e-6)
        .unwrap();
    let get = |k: &str| m.shape.iter().find(|(s, _)| s == k).unwrap().1;
    assert_eq!(get("att_y"), 1.0);
    assert!(get("att_x").abs() < 1e-6 && get("att_z").abs() < 1e-6);
}

#[test]
fn linear_frequencies_match_a_small_amplitude_nonlinear_run() {
    // The preprint's satellite on undamped springs: start it in each of two mode shapes at
    // small amplitude, run the nonlinear model and count the zero crossings of the largest
    // hinge angle; the period must be that of the mode.
    let text = r#"
duration = 1.0
model = "../../../examples/satellite.toml"
[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
"#;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scene.toml");
    let s = Scene::parse(text, &path).unwrap();
    let md = modes(&s).unwrap();
    assert!(md.frequencies_hz.len() >= 5, "{md:?}");
    for which in [0, md.frequencies_hz.len() - 1] {
        let mode = &md.modes[which];
        let f = mode.frequency_hz;
        let mut sc = s.clone();
        let nq0 = sc.model.base_nq();
        let amplitude = 1e-4;
        let mut pivot = 0;
        for k in 0..5 {
            let name = format!("angle_h{}", k + 1);
            let v = mode.shape.iter().find(|(n, _)| *n == name).unwrap().1;
            if v == 1.0 {
                pivot = k;
            }
            sc.initial.q[nq0 + k] = amplitude * v;
        }
        // The attitude part of the shape as well, so that only this mode is excited.
        let att: Vec<f64> = ["att_x", "att_y", "att_z"]
            .iter()
            .map(|n| mode.shape.iter().find(|(s, _)| s == n).unwrap().1 * amplitude)
            .collect();
        let q = nalgebra::UnitQuaternion::from_scaled_axis(nalgebra::Vector3::new(
            att[0], att[1], att[2],
        ));
        sc.initial.q[..4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
        let periods = 6.0;
        let t_end = periods / f;
        let every = 1.0 / f / 200.0;
        let mut sim = sc.simulation().unwrap();
        let col = 8 + pivot; // t, q (4), omega (3), then the hinge angles
        let mut series: Vec<(f64, f64)> = Vec::new();
        let opts = Options::new(Method::Dop853).with_tolerances(1e-11, 1e-14);
        sim.run(&opts, t_end, &Output::Interval(every), |t, row| {
            series.push((t, row[col]));
            Ok::<(), ()>(())
        })
        .unwrap();
        // Zero crossings (linear interpolation), after the first.
        let mut crossings = Vec::new();
        for w in series.windows(2) {
            let ((t0, a), (t1, b)) = (w[0], w[1]);
            if a != 0.0 && a.signum() != b.signum() {
                crossings.push(t0 + (t1 - t0) * a / (a - b));
            }
        }
        assert!(crossings.len() >= 10, "{}", crossings.len());
        let half = (crossings.last().unwrap() - crossings[0]) / (crossings.len() - 1) as f64;
        let f_run = 1.0 / (2.0 * half);
        assert!(
            rel(f_run, f) < 1e-6,
            "mode {which}: run {f_run} Hz vs linear {f} Hz"
        );
    }
}

#[test]
fn sweep_moves_the_hinges_and_rejects_an_unknown_one() {
    let s = scene(&fixed_panel(20.0, 1.5, 1.2, 40.0, 0.0));
    let along = [Along::parse("h=0:1").unwrap()];
    let pts = sweep(&s, &along, 3).unwrap();
    assert_eq!(pts.len(), 3);
    assert_eq!(pts[1].angles, [0.5]);
    // One hinge on a fixed base: the frequency does not depend on the angle.
    assert!(
        rel(
            pts[0].modes.frequencies_hz[0],
            pts[2].modes.frequencies_hz[0]
        ) < 1e-9
    );
    let bad = [Along::parse("nope=0:1").unwrap()];
    assert!(sweep(&s, &bad, 3).unwrap_err().to_string().contains("nope"));
    assert!(Along::parse("h=0").is_err());
    assert!(Along::parse("h=a:1").is_err());
    // The spring's reference moves with the hinge: every configuration is an equilibrium
    // (on a free bus, a deflected spring would make the linearisation that of the start of
    // a motion; held, the two-body mode stays oscillatory and undamped).
    let s = scene(&free_bus_panel(""));
    let pts = sweep(&s, &[Along::parse("h=0:2").unwrap()], 3).unwrap();
    for p in &pts {
        assert_eq!(p.modes.frequencies_hz.len(), 1, "{p:?}");
        assert!(p.modes.damping_ratios[0].abs() < 1e-9, "{p:?}");
        assert!(p.modes.real_eigenvalues.is_empty(), "{p:?}");
    }
}

#[test]
fn attitude_controller_through_stuck_wheels_is_in_the_linear_model() {
    // A bus held by a PD controller through three wheels with static friction, all at rest:
    // the wheels start stuck, are released for the linearisation, and each axis is the
    // closed loop I ω² = kp with damping ratio kd / (2 sqrt(kp I)). The effective inertia
    // about x is the bus's plus the transverse inertias of the y and z rotors (the x rotor's
    // axial inertia spins freely relative to the bus, transmitting only the motor torque).
    let text = r#"
duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[30.0, 0.0, 0.0], [0.0, 40.0, 0.0], [0.0, 0.0, 50.0]]
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "x"
axis = [1.0, 0.0, 0.0]
inertia = 0.2
coulomb = 0.002
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.2
coulomb = 0.002
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.2
coulomb = 0.002
[effects.attitude_control]
kp = 2.0
kd = 6.0
"#;
    let s = scene(text);
    let md = modes(&s).unwrap();
    assert_eq!(md.released, ["wheel_x", "wheel_y", "wheel_z"]);
    assert!(md.locked.is_empty());
    let (kp, kd) = (2.0f64, 6.0f64);
    for (axis, ib) in [("x", 30.0), ("y", 40.0), ("z", 50.0)] {
        let i = ib + 2.0 * 0.1;
        let wn = (kp / i).sqrt();
        let zeta = kd / (2.0 * (kp * i).sqrt());
        let f = wn * (1.0 - zeta * zeta).sqrt() / (2.0 * PI);
        let found = md
            .modes
            .iter()
            .any(|m| rel(m.frequency_hz, f) < 1e-7 && rel(m.damping_ratio, zeta) < 1e-7);
        assert!(found, "axis {axis}: {f} Hz, zeta {zeta} not in {md:?}");
    }
    // Velocity (3) and the wheel speeds (3) are free integrators.
    assert_eq!(md.rigid_modes, 6);
}

#[test]
fn a_hinge_latched_at_the_start_is_rigid() {
    // Two panels in a chain on a fixed base; the first starts on its latching stop.
    let text = r#"
duration = 1.0
[model]
base = { kind = "fixed" }
[[model.body]]
name = "base"
mass = 10.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[model.body]]
name = "p1"
mass = 2.0
inertia = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]]
[[model.body]]
name = "p2"
mass = 3.0
inertia = [[0.7, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 0.7]]
[[model.hinge]]
name = "a"
parent = "base"
child = "p1"
axis = [0.0, 0.0, 1.0]
child_at = [-0.5, 0.0, 0.0]
[[model.hinge]]
name = "b"
parent = "p1"
child = "p2"
axis = [0.0, 0.0, 1.0]
at = [0.5, 0.0, 0.0]
child_at = [-0.4, 0.0, 0.0]
[effects.hinge_springs]
stiffness = [5.0, 6.0]
[effects.hinge_stops]
[[effects.hinge_stops.stop]]
hinge = "a"
lower = 0.0
action = "latch"
"#;
    let s = scene(text);
    let lin = linearize(&s).unwrap();
    assert_eq!(lin.locked, ["a"]);
    let (ia, ra) = (lin.state("angle_a").unwrap(), lin.state("rate_a").unwrap());
    for k in 0..4 {
        assert_eq!(lin.a[(ia, k)], 0.0);
        assert_eq!(lin.a[(ra, k)], 0.0);
        assert_eq!(lin.a[(k, ra)], 0.0);
    }
    // Hinge a rigid, p2 swings about b alone: I = Ic + m d².
    let md = modes(&s).unwrap();
    let i: f64 = 0.7 + 3.0 * 0.4 * 0.4;
    assert_eq!(md.frequencies_hz.len(), 1, "{md:?}");
    assert!(rel(md.frequencies_hz[0], (6.0 / i).sqrt() / (2.0 * PI)) < 1e-8);
    // The locked angle and rate are two zero eigenvalues of the printed A.
    assert_eq!(md.rigid_modes, 2);
    assert_eq!(md.locked, ["a"]);
}

/// The example satellite of `deployment_modes.toml` with the gimbal springs (h1, h2, h3)
/// set to `k`.
fn satellite_with_gimbal_stiffness(k: &str) -> Scene {
    let path = example("scenes/deployment_modes.toml");
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "stiffness = [50.0, 50.0, 50.0,",
        &format!("stiffness = [{k}, {k}, {k},"),
    );
    assert!(text.contains(k), "the scene's stiffness line changed");
    Scene::parse(&text, &path).expect("valid scene")
}

#[test]
fn a_stiff_gimbal_does_not_hide_the_panel_modes() {
    // With the gimbal springs at 1e6 and at 1e12 N m/rad the gimbal is rigid to the panels
    // either way: the same panel modes below 1 Hz, the same 9 rigid modes of a free body.
    // A rigid tolerance relative to the largest eigenvalue (1e5 1/s at 1e12) took the
    // lower panel mode for a rigid one.
    let soft = |m: &satsim_tools::modes::Modes| -> Vec<f64> {
        m.frequencies_hz
            .iter()
            .copied()
            .filter(|f| *f < 1.0)
            .collect()
    };
    let stiff = modes(&satellite_with_gimbal_stiffness("1e6")).unwrap();
    let stiffer = modes(&satellite_with_gimbal_stiffness("1e12")).unwrap();
    assert_eq!(stiff.rigid_modes, 9, "{stiff:?}");
    assert_eq!(stiffer.rigid_modes, 9, "{stiffer:?}");
    let (a, b) = (soft(&stiff), soft(&stiffer));
    assert_eq!(a.len(), 2, "{a:?}");
    assert_eq!(b.len(), a.len(), "{a:?} against {b:?}");
    for (x, y) in a.iter().zip(&b) {
        assert!(rel(*y, *x) < 1e-3, "{a:?} against {b:?}");
    }
}

#[test]
fn a_spring_beyond_the_range_of_f64_products_is_an_error() {
    // A spring of 1e308 gave eigenvalues of 1e298 (they are 1e153) and negative damping
    // ratios, exit status 0.
    let s = satellite_with_gimbal_stiffness("1e308");
    let e = linearize(&s).unwrap_err();
    assert!(
        matches!(e, satsim_tools::linearize::LinearizeError::OutOfRange { value, .. } if value.abs() > 1e300),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.contains("out of range") && text.contains("/d(angle_h"),
        "{text}"
    );
    let e = modes(&s).unwrap_err().to_string();
    assert!(e.contains("out of range"), "{e}");
    // A stiff but representable spring is not.
    assert!(linearize(&satellite_with_gimbal_stiffness("1e12")).is_ok());
}

/// A flexible body's modal columns against the mass matrix of the flexible CRBA (a second
/// algorithm): at rest at `η = 0` the accelerations' Jacobian in `η` is `−M⁻¹ [0; K]`,
/// `K = diag(ωₖ²)`. Two beams whose modal coordinate, in `√kg m`, is far from their size:
/// a 0.4 g strip of 0.2 m (bent past its length by `η = 2e-3`) and twelve modes of a 2 m
/// beam (the twelfth turns its tip by a radian at `η = 0.09`), both on a 1 kg body hinged to
/// a 10 kg bus. Steps of `η = 1e-3` took them out of the linear range: the linearisation was
/// refused as inaccurate.
#[test]
fn light_and_high_modes_are_linearised_against_the_flexible_mass_matrix() {
    use satsim_tree::flexible::{FlexData, crba as flex_crba};
    for (length, ei, rho_a, modes) in [(0.2, 0.002, 0.002, 3), (2.0, 500.0, 5.0, 12)] {
        let s = scene(&format!(
            r#"
duration = 1.0
[output]
view = false
[model]
{}
{}
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = {length}, EI = {ei}, rho_A = {rho_a}, modes = {modes} }}
{}
"#,
            body("bus", 10.0, [1.0; 3]),
            body("p", 1.0, [0.1; 3]),
            z_hinge("h", "bus", "p", 0.5, None),
        ));
        let lin = linearize(&s).unwrap_or_else(|e| panic!("{modes} modes, L = {length}: {e}"));
        let flex = s.flexible.as_ref().unwrap();
        let mut q = s.initial.q.clone();
        q.extend(std::iter::repeat_n(0.0, modes));
        let mut data = FlexData::new(flex);
        let minv = flex_crba(flex, &mut data, &q)
            .unwrap()
            .clone()
            .try_inverse()
            .unwrap();
        let k = flex.stiffness();
        // States: att 0..3, omega 3..6, vel 6..9, angle 9, rate 10, eta 11.., etadot ...
        let (eta, etadot) = (11, 11 + modes);
        let acc_row = |i: usize| match i {
            0..6 => 3 + i,
            6 => 10,
            _ => etadot + (i - 7),
        };
        let scale = (0..minv.nrows())
            .map(|i| {
                (0..modes)
                    .map(|m| (minv[(i, 7 + m)] * k[m]).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        let mut worst: f64 = 0.0;
        for i in 0..minv.nrows() {
            for m in 0..modes {
                let exact = -minv[(i, 7 + m)] * k[m];
                worst = worst.max((lin.a[(acc_row(i), eta + m)] - exact).abs() / scale);
            }
        }
        assert!(worst < 1e-8, "{modes} modes, L = {length}: {worst}");
        // The plain differences' own error, which the refusal weighs at 1e-3 of the largest
        // entry: 1.8e-3 for the twelfth mode with steps of 1e-3.
        assert!(
            lin.error_estimate < 1e-4 * scale,
            "{modes} modes: {} against {scale}",
            lin.error_estimate
        );
    }
}
