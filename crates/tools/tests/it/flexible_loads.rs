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
