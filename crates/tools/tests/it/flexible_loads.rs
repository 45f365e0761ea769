//! Loads on the modes: a force at a point of a flexible body bends it through the mode
//! shapes there (`Σ φₖ(p)·f` on mode `k`), not only through its frame. A thruster at a
//! cantilever's tip, firing steadily, holds the tip at the static deflection of a tip load,
//! `F L³ / 3 EI` (Euler-Bernoulli), to the truncation of the modal sum
//! `Σₖ φₖ(L)² F / ωₖ²`, which it equals to the integrator's settling.

use satsim_tools::api::run_scene;
use satsim_tools::scene::Scene;
use satsim_tree::flexible::Beam;
use satsim_tree::spatial::Vec3;
use std::path::Path;

const L: f64 = 2.0;
const EI: f64 = 500.0;
const RHO_A: f64 = 5.0;

fn cantilever_with_a_tip_thruster(thrust: f64) -> String {
    format!(
        r#"duration = 20.0
[model]
[model.base]
kind = "fixed"
[[model.body]]
name = "beam"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = {L}, EI = {EI}, rho_A = {RHO_A}, modes = 3 }}
damping = 0.3
[integrator]
method = "dp54"
rtol = 1e-10
atol = 1e-12
[output]
every = 0.5
plots = false
view = false
[effects.thrusters]
period = 1.0
[[effects.thrusters.thruster]]
name = "tip"
body = "beam"
at = [0.0, {L}, 0.0]
direction = [0.0, 0.0, 1.0]
thrust = {thrust}
duty = 1.0
"#
    )
}

#[test]
fn a_thruster_at_a_cantilevers_tip_bends_it_by_the_static_deflection() {
    let thrust = 1.5;
    let text = cantilever_with_a_tip_thruster(thrust);
    let scene = Scene::parse(&text, Path::new("tip.toml")).unwrap_or_else(|e| panic!("{e}"));
    let run = run_scene(&scene, || false).unwrap();
    let tip = run
        .columns
        .iter()
        .position(|c| c == "tip_beam")
        .expect("a tip column");
    let settled = run.rows().last().unwrap()[tip];
    let beam = Beam {
        root: Vec3::zeros(),
        axis: Vec3::y(),
        bend: Vec3::z(),
        length: L,
        ei: EI,
        rho_a: RHO_A,
        modes: 3,
    };
    let modal: f64 = beam
        .cantilever_modes()
        .iter()
        .enumerate()
        .map(|(k, m)| m.shape(L)[0].powi(2) * thrust / beam.omega(k + 1).powi(2))
        .sum();
    let euler_bernoulli = thrust * L.powi(3) / (3.0 * EI);
    println!("tip {settled:e}, modal sum {modal:e}, F L^3 / 3 EI {euler_bernoulli:e}");
    assert!(
        (settled - modal).abs() < 1e-6 * modal,
        "tip {settled:e}, the modal sum {modal:e}"
    );
    assert!(
        (settled - euler_bernoulli).abs() < 1e-2 * euler_bernoulli,
        "tip {settled:e}, F L^3 / 3 EI = {euler_bernoulli:e}"
    );
    // The energy budget closes: the thruster's work on the modes, `Σ Q_k η̇_k`, is booked.
    let col = |name: &str| run.columns.iter().position(|c| c == name).unwrap();
    let (first, last) = (run.rows().next().unwrap(), run.rows().last().unwrap());
    let work = last[col("work_actuators")];
    let drift = (last[col("energy_budget")] - first[col("energy_budget")]).abs();
    println!("work {work:e}, budget drift {drift:e}");
    assert!(work > 0.5 * thrust * settled, "work {work:e}");
    assert!(
        drift < 1e-8 * work,
        "the budget moved by {drift:e} of {work:e}"
    );
}

/// A strip in sunlight: a flexible cantilever whose one facet covers it, facing the Sun,
/// bends under the light's uniform pressure by the static deflection of a uniform load
/// `q L⁴ / 8 EI` (`q = F / L`, `F` the light's force on the facet), to the truncation of its modal sum `Σ φₖ(L) Qₖ / ωₖ²` with
/// `Qₖ = (F / L) ∫ φₖ dx` (the beam's `S₁ₖ / ρA`), which it equals to its settling.
#[test]
fn a_strip_in_sunlight_bends_by_the_static_deflection_of_a_uniform_load() {
    let epoch = satsim_environment::parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let sun = satsim_environment::sun::sun_position(epoch, 0.0).normalize();
    // The strip along `axis` (normal to the Sun), bending along the Sun's direction; its
    // facet faces the Sun. Its frame is a free root heavy enough (1e9 kg, 1e9 kg m²) to
    // stay put under the light (it turns by 1e-9 rad over the run): the clamp.
    let axis = sun.cross(&Vec3::z()).normalize();
    let (ei, rho_a, len, width) = (2e-3, 0.5, 2.0, 0.5);
    let v = |x: Vec3| format!("[{:?}, {:?}, {:?}]", x[0], x[1], x[2]);
    let centre = axis * (0.5 * len);
    let text = format!(
        r#"duration = 900.0
epoch = "2026-03-20T12:00:00 UTC"
[model]
[[model.body]]
name = "strip"
mass = 1e9
inertia = [[1e9, 0.0, 0.0], [0.0, 1e9, 0.0], [0.0, 0.0, 1e9]]
facets = [ {{ size = [{len}, {width}], edge = {axis}, normal = {sun}, at = {centre} }} ]
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = {axis}, bend = {sun}, length = {len}, EI = {ei}, rho_A = {rho_a}, modes = 4 }}
damping = 0.7
stiffening = false
[orbit]
altitude = 500e3
[effects.solar_radiation]
shadow = "none"
[integrator]
method = "dp54"
rtol = 1e-10
atol = 1e-14
[output]
every = 10.0
plots = false
view = false
"#,
        axis = v(axis),
        sun = v(sun),
        centre = v(centre),
    );
    let scene = Scene::parse(&text, Path::new("strip.toml")).unwrap_or_else(|e| panic!("{e}"));
    let run = run_scene(&scene, || false).unwrap();
    let col = |name: &str| run.columns.iter().position(|c| c == name).unwrap();
    let last = run.rows().last().unwrap();
    let tip = last[col("tip_strip")];
    // The light's force on the absorbing facet at normal incidence: the pressure at the
    // Sun's distance times the area (the orbit's 6 900 km move it by 1e-4 at most).
    let au = satsim_environment::AU;
    let d = satsim_environment::sun::sun_position(epoch, 0.0).norm();
    let force = satsim_environment::SOLAR_PRESSURE_1AU * (au / d).powi(2) * len * width;
    let beam = Beam {
        root: Vec3::zeros(),
        axis,
        bend: sun,
        length: len,
        ei,
        rho_a,
        modes: 4,
    };
    let s1 = beam.stiffening_integrals().s1;
    let shapes = beam.cantilever_modes();
    // Per unit force F: the modal sum, and the uniform load's formula.
    let per_newton: f64 = (0..4)
        .map(|k| shapes[k].shape(len)[0] * (-s1[k] / (rho_a * len)) / beam.omega(k + 1).powi(2))
        .sum();
    let formula = -len.powi(3) / (8.0 * ei);
    println!("tip {tip:e}, modal per N {per_newton:e}, formula per N {formula:e}");
    let modal = force * per_newton;
    assert!(
        (tip - modal).abs() < 5e-4 * modal.abs(),
        "tip {tip:e}, the modal sum {modal:e}"
    );
    let uniform = force * formula;
    assert!(
        (tip - uniform).abs() < 1e-2 * uniform.abs(),
        "tip {tip:e}, q L^4 / 8 EI = {uniform:e}"
    );
}

/// A strip of eight mirror facets, deflected (`[initial] flexible`), in sunlight 45° off its
/// normal: each facet rides the deflected shape, its centroid moved by the mean deflection
/// over it and its normal turned by the mean slope. The light's moment equals that of a rigid
/// strip whose facets are placed by hand where the beam's shape puts them: centroid at the
/// mean of `w(x)` over the facet (Simpson), normal that of the chord, `b − s a` normalised,
/// `s = (w(x₁) − w(x₀)) / Δx` the mean slope (exact). The undeformed strip's moment differs
/// by a fifth of itself, so the test tells the two apart. The strip's frame is a root of
/// 1e12 kg, so that the beam's kilogram moves the centre of mass about which the moment is
/// taken by 1e-12 m only.
#[test]
fn a_deflected_strips_facets_ride_its_shape() {
    let epoch = satsim_environment::parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let sun = satsim_environment::sun::sun_position(epoch, 0.0).normalize();
    let axis = sun.cross(&Vec3::z()).normalize();
    let bend = (sun + sun.cross(&axis)).normalize();
    let (ei, rho_a, len, width, n) = (2e-3, 0.5, 2.0, 0.5, 8);
    let eta = [0.25, -0.04, 0.01, 0.0];
    let beam = Beam {
        root: Vec3::zeros(),
        axis,
        bend,
        length: len,
        ei,
        rho_a,
        modes: 4,
    };
    let shapes = beam.cantilever_modes();
    let w =
        |x: f64, d: usize| -> f64 { shapes.iter().zip(eta).map(|(m, e)| m.shape(x)[d] * e).sum() };
    let v = |x: Vec3| format!("[{:?}, {:?}, {:?}]", x[0], x[1], x[2]);
    let dx = len / n as f64;
    let facet = |at: Vec3, normal: Vec3, edge: Vec3| {
        format!(
            "{{ size = [{dx}, {width}], edge = {}, normal = {}, at = {}, specular = 1.0 }}",
            v(edge),
            v(normal),
            v(at)
        )
    };
    let (mut flat, mut placed) = (Vec::new(), Vec::new());
    for k in 0..n {
        let (x0, x1) = (k as f64 * dx, (k + 1) as f64 * dx);
        flat.push(facet(axis * (0.5 * (x0 + x1)), bend, axis));
        // Simpson's rule on 200 intervals for the mean deflection.
        let m = 200;
        let h = dx / m as f64;
        let mean = (0..=m)
            .map(|j| {
                let c = if j == 0 || j == m {
                    1.0
                } else if j % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                c * w(x0 + j as f64 * h, 0)
            })
            .sum::<f64>()
            * h
            / 3.0
            / dx;
        let s = (w(x1, 0) - w(x0, 0)) / dx;
        let at = axis * (0.5 * (x0 + x1)) + bend * mean;
        placed.push(facet(
            at,
            (bend - axis * s).normalize(),
            (axis + bend * s).normalize(),
        ));
    }
    let scene = |facets: &[String], flexible: bool| {
        let flex = if flexible {
            format!(
                "[model.body.flexible]\nbeam = {{ root = [0.0, 0.0, 0.0], axis = {}, bend = {}, length = {len}, EI = {ei}, rho_A = {rho_a}, modes = 4 }}\nstiffening = false\n",
                v(axis),
                v(bend)
            )
        } else {
            String::new()
        };
        let initial = if flexible {
            format!("[initial]\nflexible = {{ strip = {{ eta = {eta:?} }} }}\n")
        } else {
            String::new()
        };
        let text = format!(
            r#"duration = 0.01
epoch = "2026-03-20T12:00:00 UTC"
{initial}[model]
[[model.body]]
name = "strip"
mass = 1e12
inertia = [[1e12, 0.0, 0.0], [0.0, 1e12, 0.0], [0.0, 0.0, 1e12]]
facets = [ {} ]
{flex}[orbit]
altitude = 500e3
[effects.solar_radiation]
shadow = "none"
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.01
plots = false
view = false
"#,
            facets.join(", ")
        );
        let scene = Scene::parse(&text, Path::new("strip.toml")).unwrap_or_else(|e| panic!("{e}"));
        let run = run_scene(&scene, || false).unwrap();
        let col = |name: &str| run.columns.iter().position(|c| c == name).unwrap();
        let first = run.rows().next().unwrap();
        Vec3::new(
            first[col("srp_torque_x")],
            first[col("srp_torque_y")],
            first[col("srp_torque_z")],
        )
    };
    let riding = scene(&flat, true);
    let by_hand = scene(&placed, false);
    let undeformed = scene(&flat, false);
    println!("riding {riding:?}\nby hand {by_hand:?}\nundeformed {undeformed:?}");
    println!(
        "tip deflection {:.4} m, tip slope {:.4}",
        w(len, 0),
        w(len, 1)
    );
    assert!(
        (riding - by_hand).norm() < 1e-11 * by_hand.norm(),
        "riding {riding:?}, by hand {by_hand:?}"
    );
    assert!((undeformed - by_hand).norm() > 0.1 * by_hand.norm());
    assert!(riding.norm() > 0.0);
}

/// A floppy boom in the gravity gradient: a 10 m beam (first mode 5e-3 rad/s, as slow as
/// the orbit) on a 100 kg bus, 30° off the local vertical, on a circular 500 km orbit, no
/// damping. With `stiffening` the field acts over its deformed mass and on its modes
/// ([`satsim_tree::flexible::FlexModel::linear_field`]): it bends the boom by a good part of
/// its length's hundredth, and the energy budget (kinetic, strain, the field's potential
/// less the work of the field turning with the orbit) closes.
#[test]
fn a_floppy_boom_bends_in_the_gravity_gradient_and_the_energy_budget_closes() {
    let (len, rho_a): (f64, f64) = (10.0, 1.0);
    let omega1: f64 = 5e-3;
    let ei = (omega1 / 1.875_104_068_711_961f64.powi(2)).powi(2) * rho_a * len.powi(4);
    let text = format!(
        r#"duration = 1500.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[20.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 20.0]]
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.5], axis = [0.0, 0.0, 1.0], bend = [1.0, 0.0, 0.0], length = {len}, EI = {ei}, rho_A = {rho_a}, modes = 3 }}
damping = 0.0
stiffening = true
[initial]
base = {{ attitude = [0.9659258262890683, 0.0, 0.25881904510252074, 0.0], angular_velocity = [0.0, 0.0, 0.0] }}
[orbit]
altitude = 500e3
inclination_deg = 0.0
[effects.gravity_gradient]
model = "full"
[integrator]
method = "dp54"
rtol = 1e-11
atol = 1e-13
[output]
every = 50.0
plots = false
view = false
"#
    );
    let scene = Scene::parse(&text, Path::new("boom.toml")).unwrap_or_else(|e| panic!("{e}"));
    let run = run_scene(&scene, || false).unwrap();
    let col = |name: &str| {
        run.columns
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", run.columns))
    };
    let (first, last) = (run.rows().next().unwrap(), run.rows().last().unwrap());
    let tip = run
        .rows()
        .map(|r| r[col("tip_bus")].abs())
        .fold(0.0, f64::max);
    let work = run
        .rows()
        .map(|r| r[col("work_actuators")].abs())
        .fold(0.0, f64::max);
    let drift = (last[col("energy_budget")] - first[col("energy_budget")]).abs();
    println!(
        "largest tip deflection {tip:e} m, largest field work {work:e} J, budget drift {drift:e} J"
    );
    assert!(tip > 1e-2 * len / 10.0, "the boom hardly bends: {tip:e} m");
    assert!(work > 0.0);
    assert!(
        drift < 1e-7 * work,
        "the budget moved by {drift:e} of {work:e}"
    );
}
