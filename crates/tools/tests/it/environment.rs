//! The environment effects (solar radiation pressure, drag, the geomagnetic field) checked
//! against hand computations through `satsim_tools::environment`, which reports each
//! effect's loads on every body and as generalised forces at a state.

use crate::common::{body, z_hinge};
use satsim_environment::sun::sun_position;
use satsim_environment::{AU, SOLAR_PRESSURE_1AU, parse_epoch};
use satsim_spacecraft::effects::drag::plate_force as drag_plate;
use satsim_spacecraft::effects::solar_radiation::plate_force as srp_plate;
use satsim_tools::environment::{EffectReport, Environment, environment};
use satsim_tools::scene::Scene;
use satsim_tree::spatial::Vec3;
use std::path::Path;

const EPOCH: &str = "2026-03-20T12:00:00 UTC";
/// The identity attitude.
const ID: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

fn scene(text: &str) -> Scene {
    Scene::parse(text, Path::new("env.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn effect<'a>(env: &'a Environment, name: &str) -> &'a EffectReport {
    env.effects
        .iter()
        .find(|e| e.name == name)
        .unwrap_or_else(|| panic!("no `{name}` in {:?}", env.effects))
}

/// The Sun's direction from the Earth's centre at the epoch (the spacecraft's, to 1e-4 rad).
fn sun_dir() -> Vec3 {
    sun_position(parse_epoch(EPOCH).unwrap(), 0.0).normalize()
}

/// An attitude quaternion `[w, x, y, z]` turning body x onto `d` (unit).
fn x_onto(d: Vec3) -> [f64; 4] {
    let q = nalgebra::UnitQuaternion::rotation_between(&Vec3::x(), &d).unwrap();
    [q.w, q.i, q.j, q.k]
}

/// A bus (no facets) and a 2 m x 1 m panel hinged about the bus' z at `[1, 0, 0]`; the
/// panel's one facet (area 2, black) has its centroid 1 m out along the panel's y and faces
/// the panel's x.
fn offset_panel(angle: f64, attitude: [f64; 4]) -> String {
    format!(
        r#"
epoch = "{EPOCH}"
duration = 10.0
[model]
{}{}facets = [{{ area = 2.0, normal = [1.0, 0.0, 0.0], at = [0.0, 1.0, 0.0] }}]
{}[initial]
base = {{ attitude = {attitude:?} }}
hinges = {{ angle = [{angle}], rate = [0.0] }}
[orbit]
altitude = 500e3
[effects.solar_radiation]
shadow = "none"
"#,
        body("bus", 500.0, [100.0; 3]),
        body("panel", 10.0, [1.0; 3]),
        z_hinge("h", "bus", "panel", 1.0, None)
    )
}

#[test]
fn a_panel_turned_on_an_offset_hinge_carries_its_centre_of_pressure() {
    // Light on the panel's facet at 90 degrees: bus x towards the Sun turned by -90 degrees
    // about z, so that the panel (turned +90 degrees) faces it.
    let s = sun_dir();
    let angle = std::f64::consts::FRAC_PI_2;
    // Attitude: bus y onto the Sun (the facet's normal, panel x, is bus y at 90 degrees).
    let q = nalgebra::UnitQuaternion::rotation_between(&Vec3::y(), &s).unwrap();
    let text = offset_panel(angle, [q.w, q.i, q.j, q.k]);
    let env = environment(&scene(&text), 0.0).unwrap();
    let srp = effect(&env, "solar_radiation");
    let (s_env, dist) = env.sun.unwrap();
    // By hand, bus axes: the normal is bus y, the Sun along bus y (to the parallax), the
    // centroid at the hinge point plus the panel's y turned by 90 degrees about z: (-1, 0, 0)
    // from the hinge.
    let s_bus = q.inverse_transform_vector(&s_env);
    let p = SOLAR_PRESSURE_1AU * (AU / dist).powi(2);
    let f = srp_plate(&s_bus, &Vec3::y(), 2.0, 0.0, 0.0, p);
    let arm = Vec3::new(-1.0, 0.0, 0.0);
    let tau_hinge = arm.cross(&f).z;
    let g = &srp.generalized_forces;
    assert_eq!(g.len(), 7);
    assert!(
        (g[6] - tau_hinge).abs() < 1e-9 * tau_hinge.abs(),
        "hinge torque {} vs {tau_hinge} by hand",
        g[6]
    );
    // Basilisk's #1533: the normal turned but the centroid left where it was at zero angle
    // ((0, 1, 0) from the hinge) gives another torque altogether.
    let stale = Vec3::new(0.0, 1.0, 0.0).cross(&f).z;
    assert!((stale - tau_hinge).abs() > 0.5 * tau_hinge.abs());
    // The panel's own wrench: the force in its axes (its x is bus y) and the moment about
    // its origin (the hinge point) of the force at (0, 1, 0).
    let panel = &srp.bodies[1];
    let f_panel = Vec3::new(f.y, -f.x, f.z);
    assert!((panel.force - f_panel).norm() < 1e-12 * f.norm());
    assert!((panel.torque - Vec3::y().cross(&f_panel)).norm() < 1e-12 * f.norm());
    // The bus has no facet.
    assert_eq!(srp.bodies[0].force, Vec3::zeros());
}

#[test]
fn plates_follow_the_closed_forms_and_are_dark_from_behind() {
    let p = 4.56e-6;
    for deg in [0.0f64, 30.0, 60.0, 89.0] {
        let th = deg.to_radians();
        let n = Vec3::z();
        let s = Vec3::new(th.sin(), 0.0, th.cos());
        let c = th.cos();
        // Absorbing: pushed along -s by P A cos.
        let f = srp_plate(&s, &n, 1.5, 0.0, 0.0, p);
        assert!((f + p * 1.5 * c * s).norm() < 1e-20);
        // Specular: 2 P A cos^2 along -n.
        let f = srp_plate(&s, &n, 1.5, 1.0, 0.0, p);
        assert!((f + 2.0 * p * 1.5 * c * c * n).norm() < 1e-20);
        // Diffuse (Lambertian): P A cos (s + 2/3 n).
        let f = srp_plate(&s, &n, 1.5, 0.0, 1.0, p);
        assert!((f + p * 1.5 * c * (s + 2.0 / 3.0 * n)).norm() < 1e-20);
        // Behind: nothing.
        assert_eq!(srp_plate(&-s, &n, 1.5, 0.3, 0.3, p), Vec3::zeros());
        // Drag: the flow meets the facet on its normal's side when v.n > 0.
        let v = 7600.0 * s;
        let f = drag_plate(&v, &n, 1.5, 2.2, 1e-12);
        assert!((f + 0.5 * 1e-12 * 7600.0f64.powi(2) * 2.2 * 1.5 * c * s).norm() < 1e-18);
        assert_eq!(drag_plate(&-v, &n, 1.5, 2.2, 1e-12), Vec3::zeros());
    }
}

/// A 1 m cube bus with its six faces as facets, centred on its centre of mass.
fn cube(extra: &str, attitude: [f64; 4]) -> String {
    format!(
        r#"
epoch = "{EPOCH}"
duration = 10.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[20.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 20.0]]
shape = {{ box = [1.0, 1.0, 1.0] }}
facets_from_shape = {{ specular = 0.3, diffuse = 0.2, drag = 2.2 }}
[initial]
base = {{ attitude = {attitude:?} }}
[orbit]
altitude = 400e3
inclination_deg = 51.6
{extra}
"#
    )
}

#[test]
fn a_symmetric_spacecraft_facing_the_sun_or_the_flow_feels_no_torque() {
    // Face +x towards the Sun: the lit faces' centroids are symmetric about the force line.
    let text = cube(
        "[effects.solar_radiation]\nshadow = \"none\"\nself_shadowing = true\n",
        x_onto(sun_dir()),
    );
    let env = environment(&scene(&text), 0.0).unwrap();
    let srp = effect(&env, "solar_radiation");
    let f = srp.bodies[0].force;
    assert!(f.norm() > 1e-6, "{f}");
    assert!(srp.bodies[0].torque.norm() < 1e-12 * f.norm(), "{srp:?}");
    // Face +x into the flow (atmosphere at rest: the flow is the orbit's velocity).
    let probe = scene(&cube("", ID));
    let v0 = environment(&probe, 0.0).unwrap().orbit.unwrap().1;
    let text = cube(
        "[effects.drag]\nco_rotating = false\n",
        x_onto(v0.normalize()),
    );
    let env = environment(&scene(&text), 0.0).unwrap();
    let drag = effect(&env, "drag");
    let f = drag.bodies[0].force;
    // Only the +x face meets the flow: -1/2 rho v^2 C_D A along the flow.
    let rho = env.density.unwrap();
    let expect = 0.5 * rho * v0.norm_squared() * 2.2 * 1.0;
    assert!(
        (f.norm() - expect).abs() < 1e-9 * expect,
        "{} vs {expect}",
        f.norm()
    );
    assert!(drag.bodies[0].torque.norm() < 1e-12 * f.norm(), "{drag:?}");
}

#[test]
fn effects_that_need_a_date_or_an_orbit_say_what_to_add() {
    let no_epoch =
        cube("[effects.solar_radiation]\n", ID).replace(&format!("epoch = \"{EPOCH}\""), "");
    let e = Scene::parse(&no_epoch, Path::new("env.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("epoch") && e.contains("env.toml:"), "{e}");
    let bad_epoch = cube("", ID).replace(EPOCH, "2026-03-40T12:00:00 UTC");
    let e = Scene::parse(&bad_epoch, Path::new("env.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("env.toml:2") && e.contains("epoch"), "{e}");
    let no_orbit = cube("[effects.drag]\n", ID)
        .replace("[orbit]\naltitude = 400e3\ninclination_deg = 51.6\n", "");
    let e = Scene::parse(&no_orbit, Path::new("env.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("[orbit]"), "{e}");
    let no_facets = offset_panel(0.0, ID).replace(
        "facets = [{ area = 2.0, normal = [1.0, 0.0, 0.0], at = [0.0, 1.0, 0.0] }]",
        "",
    );
    let e = Scene::parse(&no_facets, Path::new("env.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("needs facets"), "{e}");
    let far = cube("[effects.magnetic]\n", ID).replace(EPOCH, "2041-01-01T00:00:00 UTC");
    let e = Scene::parse(&far, Path::new("env.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("epoch"), "{e}");
    // The field's lattice: a spacing from 0 to 10 degrees, refused outside at its key.
    for bad in ["-1.0", "11.0"] {
        let text = cube(&format!("[effects.magnetic]\nlattice_deg = {bad}\n"), ID);
        let e = Scene::parse(&text, Path::new("env.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("env.toml:") && e.contains("effects.magnetic.lattice_deg"),
            "{bad}: {e}"
        );
    }
    for good in ["0.0", "2.0"] {
        let text = cube(&format!("[effects.magnetic]\nlattice_deg = {good}\n"), ID);
        Scene::parse(&text, Path::new("env.toml")).unwrap_or_else(|e| panic!("{good}: {e}"));
    }
}

#[test]
fn a_torquer_feels_m_cross_b_and_bdot_takes_energy_out() {
    let text = cube(
        r#"[effects.magnetic]
field = "igrf14"
[[effects.magnetic.torquer]]
name = "x"
axis = [1.0, 0.0, 0.0]
max_dipole = 10.0
dipole = 7.0
"#,
        ID,
    );
    let env = environment(&scene(&text), 0.0).unwrap();
    let b = env.magnetic_field.unwrap();
    // Attitude identity: bus axes are GCRF axes.
    assert!(b.norm() > 1e-5 && b.norm() < 7e-5, "|B| = {}", b.norm());
    let mag = effect(&env, "magnetic");
    let expect = (7.0 * Vec3::x()).cross(&b);
    assert!((mag.bodies[0].torque - expect).norm() < 1e-15, "{mag:?}");
    assert_eq!(&mag.generalized_forces[..3], expect.as_slice());

    // B-dot on a tumbling cube: the rotational energy only falls.
    let text = cube(
        r#"[effects.magnetic]
[[effects.magnetic.torquer]]
name = "x"
axis = [1.0, 0.0, 0.0]
max_dipole = 50.0
[[effects.magnetic.torquer]]
name = "y"
axis = [0.0, 1.0, 0.0]
max_dipole = 50.0
[[effects.magnetic.torquer]]
name = "z"
axis = [0.0, 0.0, 1.0]
max_dipole = 50.0
[effects.bdot]
gain = 1e8
[integrator]
method = "rk4"
step = 0.5
"#,
        ID,
    )
    .replace("duration = 10.0", "duration = 600.0")
    .replace(
        "base = { attitude = [1.0, 0.0, 0.0, 0.0] }",
        "base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.05, -0.03, 0.02] }",
    );
    let sc = scene(&text);
    let traj = satsim_tools::api::run_scene(&sc, || false).unwrap();
    let col = |n: &str| traj.columns.iter().position(|c| c == n).unwrap();
    let (wx, wy, wz) = (col("omega_x"), col("omega_y"), col("omega_z"));
    let energy: Vec<f64> = traj
        .rows()
        .map(|r| 10.0 * (r[wx] * r[wx] + r[wy] * r[wy] + r[wz] * r[wz]))
        .collect();
    for w in energy.windows(2) {
        assert!(w[1] <= w[0] * (1.0 + 1e-12), "{} then {}", w[0], w[1]);
    }
    let (first, last) = (energy[0], *energy.last().unwrap());
    assert!(
        last < 0.9 * first,
        "B-dot removed too little: {first} -> {last}"
    );
}

#[test]
fn the_net_force_moves_the_orbit_and_not_the_attitude_frame() {
    // A cube facing the Sun: over 100 s the orbit's velocity changes by F/M t more than
    // without the pressure, and the bus does not start moving in the falling frame.
    let srp = "[effects.solar_radiation]\nshadow = \"none\"\n[integrator]\nmethod = \"rk4\"\nstep = 1.0\n";
    let with = cube(srp, x_onto(sun_dir())).replace("duration = 10.0", "duration = 100.0");
    let without = with.replace("[effects.solar_radiation]\nshadow = \"none\"\n", "");
    let last = |text: &str| {
        let sc = scene(text);
        let tr = satsim_tools::api::run_scene(&sc, || false).unwrap();
        let row = tr.rows().last().unwrap().to_vec();
        (tr.columns.clone(), row)
    };
    let (cols, a) = last(&with);
    let (_, b) = last(&without);
    let at = |n: &str| cols.iter().position(|c| c == n).unwrap();
    let dv = Vec3::new(
        a[at("orbit_v_x")] - b[at("orbit_v_x")],
        a[at("orbit_v_y")] - b[at("orbit_v_y")],
        a[at("orbit_v_z")] - b[at("orbit_v_z")],
    );
    let env = environment(&scene(&with), 0.0).unwrap();
    let f = effect(&env, "solar_radiation").bodies[0].force.norm();
    let expect = f / 100.0 * 100.0;
    assert!(
        (dv.norm() - expect).abs() < 0.02 * expect,
        "|dv| = {} vs F/M t = {expect}",
        dv.norm()
    );
    // Had the tree been pushed, it would move at F/M t in the falling frame: kinetic
    // energy 1/2 F^2 t^2 / M (1e-13 J). What is left is the slow turn by the Sun's
    // direction drifting off the cube's axis (below 1e-18 J).
    let pushed = 0.5 * (f * 100.0).powi(2) / 100.0;
    let t_kin = a[at("kinetic_energy")];
    assert!(t_kin < 1e-4 * pushed, "T = {t_kin} J, {pushed} J if pushed");
}

#[test]
fn the_shadow_column_goes_dark_once_an_orbit() {
    let text = cube("[effects.solar_radiation]\nshadow = \"conical\"\n", ID)
        .replace("duration = 10.0", "duration = 5600.0")
        .replace("inclination_deg = 51.6", "inclination_deg = 0.0")
        + "[output]\nevery = 10.0\n[integrator]\nmethod = \"rk4\"\nstep = 10.0\n";
    let sc = scene(&text);
    let tr = satsim_tools::api::run_scene(&sc, || false).unwrap();
    let k = tr.columns.iter().position(|c| c == "shadow").unwrap();
    let nu: Vec<f64> = tr.rows().map(|r| r[k]).collect();
    let dark = nu.iter().filter(|v| **v == 0.0).count() as f64 * 10.0;
    let lit = nu.iter().filter(|v| **v == 1.0).count() as f64 * 10.0;
    // At 400 km near the equinox, umbra lasts about 36 minutes of the 92.6-minute orbit.
    assert!(dark > 1800.0 && dark < 2400.0, "dark {dark} s");
    assert!(lit > 3000.0, "lit {lit} s");
    // Penumbra: a few rows strictly between.
    assert!(nu.iter().any(|v| *v > 0.0 && *v < 1.0));
}

#[test]
fn the_gravity_gradient_column_is_the_couple_about_the_centre_of_mass() {
    let text = r#"
duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[20.0, 1.0, 0.5], [1.0, 25.0, -2.0], [0.5, -2.0, 15.0]]
[initial]
base = { attitude = [0.9, 0.1, 0.3, 0.3] }
[orbit]
altitude = 500e3
inclination_deg = 30.0
true_anomaly_deg = 40.0
[effects.gravity_gradient]
"#;
    let sc = scene(text);
    let tr = satsim_tools::api::run_scene(&sc, || false).unwrap();
    let row = tr.rows().next().unwrap().to_vec();
    let col = |n: &str| row[tr.columns.iter().position(|c| c == n).unwrap()];
    let r = Vec3::new(col("orbit_r_x"), col("orbit_r_y"), col("orbit_r_z"));
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        col("q_w"),
        col("q_x"),
        col("q_y"),
        col("q_z"),
    ));
    let e = q.inverse_transform_vector(&r.normalize());
    let inertia = nalgebra::Matrix3::new(20.0, 1.0, 0.5, 1.0, 25.0, -2.0, 0.5, -2.0, 15.0);
    let k = 3.986004418e14 / r.norm().powi(3);
    let expect = 3.0 * k * e.cross(&(inertia * e));
    let got = Vec3::new(col("gg_torque_x"), col("gg_torque_y"), col("gg_torque_z"));
    assert!(
        (got - expect).norm() < 1e-12 * expect.norm(),
        "{got} vs {expect}"
    );
}

#[test]
fn a_torquer_dipole_held_through_the_stepping_inputs_equals_its_constant_command() {
    let torquer = |dipole: f64| {
        cube(
            &format!(
                "[effects.magnetic]\n[[effects.magnetic.torquer]]\nname = \"x\"\naxis = [1.0, 0.0, 0.0]\nmax_dipole = 10.0\ndipole = {dipole}\n[integrator]\nmethod = \"rk4\"\nstep = 0.5\n"
            ),
            ID,
        )
    };
    let run = satsim_tools::api::run_scene(&scene(&torquer(6.0)), || false).unwrap();
    let mut stepper =
        satsim_tools::stepping::SceneStepper::new(&scene(&torquer(0.0)), None, "t").unwrap();
    assert!(stepper.inputs().iter().any(|i| i == "dipole_x"));
    stepper.set_inputs(&[("dipole_x", 6.0)]).unwrap();
    stepper.advance(10.0).unwrap();
    let stepped = stepper.trajectory();
    let (a, b) = (run.rows().last().unwrap(), stepped.rows().last().unwrap());
    assert_eq!(a, b);
}

/// A flexible strip's modes are degrees of freedom of `satsim dynamics` and take their own
/// generalised forces: sunlight on a facet covering the whole strip, a uniform load `F / L`,
/// loads mode `k` with `(F / L) ∫φₖ`, where the cantilever's `∫₀ᴸ φₖ = 2σₖ / (βₖ √(ρA L))`
/// (`σₖ = (sinh βL − sin βL) / (cosh βL + cos βL)`) against its tip's `φₖ(L) = ±2 / √(ρA L)`.
#[test]
fn a_flexible_strip_in_sunlight_takes_generalised_forces_on_its_modes() {
    let (length, rho_a): (f64, f64) = (2.0, 5.0);
    let text = format!(
        r#"
epoch = "{EPOCH}"
duration = 10.0
[model]
{}{}facets = [{{ size = [0.2, 2.0], normal = [1.0, 0.0, 0.0], at = [0.0, 1.0, 0.0], edge = [0.0, 0.0, 1.0] }}]
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [1.0, 0.0, 0.0], length = {length}, EI = 500.0, rho_A = {rho_a}, modes = 3 }}
{}[initial]
base = {{ attitude = {:?} }}
hinges = {{ angle = [0.0], rate = [0.0] }}
[orbit]
altitude = 500e3
[effects.solar_radiation]
shadow = "none"
"#,
        body("bus", 500.0, [100.0; 3]),
        body("panel", 1.0, [0.1; 3]),
        z_hinge("h", "bus", "panel", 1.0, None),
        x_onto(sun_dir()),
    );
    let s = scene(&text);
    let env = environment(&s, 0.0).unwrap();
    let srp = effect(&env, "solar_radiation");
    let g = &srp.generalized_forces;
    // A free base's 6, the hinge, the three modes (`satsim dynamics`'s 10).
    assert_eq!(g.len(), 10, "{g:?}");
    let force = srp.bodies[1].force.x;
    assert!(force < 0.0, "the light pushes the strip along -x: {force}");
    let flex = s.flexible.as_ref().unwrap();
    let beta_l: [f64; 3] = [
        1.875_104_068_711_961,
        4.694_091_132_974_175,
        7.854_757_438_237_613,
    ];
    let root = (rho_a * length).sqrt();
    for (k, bl) in beta_l.iter().enumerate() {
        let sigma = (bl.sinh() - bl.sin()) / (bl.cosh() + bl.cos());
        let integral = 2.0 * sigma / (bl / length * root);
        let tip = if k % 2 == 0 { 2.0 } else { -2.0 } / root;
        let mut unit = vec![0.0; 3];
        unit[k] = 1.0;
        // The modes' sign is the program's: compare the products with the tip.
        let code_tip = flex.tip_of(1, &unit).unwrap();
        assert!(
            (code_tip.abs() - tip.abs()).abs() < 1e-9,
            "{code_tip} vs {tip}"
        );
        let expected = force / length * integral * tip;
        let got = g[7 + k] * code_tip;
        assert!(
            (got - expected).abs() < 1e-6 * expected.abs(),
            "mode {}: {got} vs {expected}",
            k + 1
        );
    }
}
