//! The Earth's reflected and emitted light on the facets (`[effects.solar_radiation]
//! albedo = true`), through `satsim_tools::environment`: a plate facing the nadir against
//! the closed form, night and eclipse, plates facing away, the keys' errors, and the example
//! deployment with it on.

use satsim_environment::earth_radiation::{EARTH_IR, SPEED_OF_LIGHT, solar_flux};
use satsim_environment::sun::sun_position;
use satsim_environment::{R_EARTH, parse_epoch};
use satsim_tools::environment::{EffectReport, Environment, environment};
use satsim_tools::scene::Scene;
use satsim_tree::spatial::Vec3;
use std::path::Path;

const EPOCH: &str = "2026-03-20T12:00:00 UTC";

fn scene(text: &str) -> Scene {
    Scene::parse(text, Path::new("earth.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn find<'a>(env: &'a Environment, name: &str) -> Option<&'a EffectReport> {
    env.effects.iter().find(|e| e.name == name)
}

/// The Sun's direction from the Earth's centre at the epoch.
fn sun_dir() -> Vec3 {
    sun_position(parse_epoch(EPOCH).unwrap(), 0.0).normalize()
}

/// One body at `r` (m, GCRF) on a circular orbit, its x axis turned onto `x_axis`, carrying
/// one facet of area 2 m² with normal body x and centroid (0, 0.5, 0), optical fractions
/// `specular`, `diffuse`; `keys`: the rest of `[effects.solar_radiation]`.
fn plate(r: Vec3, x_axis: Vec3, specular: f64, diffuse: f64, keys: &str) -> String {
    let q = nalgebra::UnitQuaternion::rotation_between(&Vec3::x(), &x_axis)
        .unwrap_or_else(|| nalgebra::UnitQuaternion::from_axis_angle(&Vec3::z_axis(), 3.0));
    let v = Vec3::z().cross(&r).normalize() * (3.986004418e14 / r.norm()).sqrt();
    format!(
        r#"
epoch = "{EPOCH}"
duration = 10.0
[model]
[[model.body]]
name = "plate"
mass = 50.0
inertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]
facets = [{{ area = 2.0, normal = [1.0, 0.0, 0.0], at = [0.0, 0.5, 0.0], specular = {specular:?}, diffuse = {diffuse:?} }}]
[initial]
base = {{ attitude = [{:?}, {:?}, {:?}, {:?}] }}
[orbit]
position = [{:?}, {:?}, {:?}]
velocity = [{:?}, {:?}, {:?}]
[effects.solar_radiation]
{keys}
"#,
        q.w, q.i, q.j, q.k, r.x, r.y, r.z, v.x, v.y, v.z
    )
}

/// The Sun from the Earth's centre as the effect saw it: the orbit's position plus the
/// reported direction times the distance.
fn r_sun(env: &Environment) -> Vec3 {
    let (s, d) = env.sun.unwrap();
    env.orbit.unwrap().0 + s * d
}

#[test]
fn a_plate_facing_the_nadir_under_the_sun_follows_the_closed_form() {
    let r = sun_dir() * (R_EARTH + 500e3);
    for (specular, diffuse, keys, albedo, ir) in [
        (0.0, 0.0, "albedo = true", 0.3, EARTH_IR),
        (0.6, 0.0, "albedo = true", 0.3, EARTH_IR),
        (
            0.2,
            0.5,
            "albedo = true\nalbedo_coefficient = 0.25\nearth_ir = 220.0",
            0.25,
            220.0,
        ),
    ] {
        let env = environment(
            &scene(&plate(r, -r.normalize(), specular, diffuse, keys)),
            0.0,
        )
        .unwrap();
        assert_eq!(env.shadow, Some(1.0));
        let rs = r_sun(&env);
        let pos = env.orbit.unwrap().0;
        // The closed form: exitance M = a S cos z + M_ir, view factor (R/r)², and summed
        // over the cap of half-angle α (sin α = R/r) the force
        // (M/c) A [(1 + ρs)(2/3)(1 − cos³ α) + (2/3) ρd (R/r)²] away from the Earth (body −x),
        // at (0, 0.5, 0).
        let f_view = (R_EARTH / pos.norm()).powi(2);
        let cos_alpha = (1.0 - f_view).sqrt();
        let cap = 2.0 / 3.0 * (1.0 - cos_alpha.powi(3));
        let cos_zenith = rs.normalize().dot(&pos.normalize());
        assert!(cos_zenith > 1.0 - 1e-9, "{cos_zenith}");
        let m = albedo * solar_flux(rs.norm()) * cos_zenith + ir;
        let e = m * f_view;
        let f = -m / SPEED_OF_LIGHT
            * 2.0
            * ((1.0 + specular) * cap + 2.0 / 3.0 * diffuse * f_view)
            * Vec3::x();
        let earth = find(&env, "earth_radiation").expect("earth_radiation reported");
        let got = &earth.bodies[0];
        println!(
            "ρs {specular}, ρd {diffuse}: {:.3e} N, closed form off by {:.1e} relative",
            f.norm(),
            (got.force - f).norm() / f.norm()
        );
        assert!(
            (got.force - f).norm() <= 1e-12 * f.norm(),
            "ρs {specular}, ρd {diffuse}: {} against {f}",
            got.force
        );
        let tau = Vec3::new(0.0, 0.5, 0.0).cross(&f);
        assert!((got.torque - tau).norm() <= 1e-12 * tau.norm());
        // 0.3 S (R/r)² + 237 (R/r)² ≈ 560 W/m² at 500 km.
        assert!(e > 450.0 && e < 650.0, "{e} W/m²");
        // The Sun is at the zenith, behind the plate: no solar pressure on it.
        assert!(find(&env, "solar_radiation").is_none(), "{:?}", env.effects);
        // Without `albedo = true`, no Earth light.
        let off = environment(
            &scene(&plate(r, -r.normalize(), specular, diffuse, "")),
            0.0,
        )
        .unwrap();
        assert!(find(&off, "earth_radiation").is_none());
    }
}

#[test]
fn the_albedo_is_off_at_night_the_infrared_stays_and_the_cap_reaches_past_the_horizon() {
    let r = sun_dir() * (R_EARTH + 500e3);
    let load = |pos: Vec3, x_axis: Vec3, keys: &str| {
        let env = environment(&scene(&plate(pos, x_axis, 0.0, 0.0, keys)), 0.0).unwrap();
        let f = find(&env, "earth_radiation").map_or(Vec3::zeros(), |e| e.bodies[0].force);
        (env, f)
    };
    // At midnight, in the umbra: the infrared alone, (237/c) A (2/3)(1 − cos³ α) on the
    // black plate.
    let (env, night) = load(-r, r.normalize(), "albedo = true");
    assert_eq!(env.shadow, Some(0.0));
    assert!(find(&env, "solar_radiation").is_none());
    let f_view = (R_EARTH / r.norm()).powi(2);
    let cos_alpha = (1.0 - f_view).sqrt();
    let ir = EARTH_IR * 2.0 / 3.0 * (1.0 - cos_alpha.powi(3)) / SPEED_OF_LIGHT * 2.0;
    assert!((night + ir * Vec3::x()).norm() <= 1e-12 * ir, "{night}");
    // With the shadow off the Sun shines at midnight, but the night side reflects nothing.
    let (env, night) = load(-r, r.normalize(), "albedo = true\nshadow = \"none\"");
    assert_eq!(env.shadow, Some(1.0));
    assert!((night + ir * Vec3::x()).norm() <= 1e-12 * ir);
    // At noon the albedo adds 0.3 S / 237 ≈ 1.73 times the infrared.
    let (_, noon) = load(r, -r.normalize(), "albedo = true");
    let ratio = noon.norm() / ir;
    assert!((ratio - 2.73).abs() < 0.03, "noon / night = {ratio}");
    // A plate facing the zenith gets nothing; one tilted 95° from the nadir still sees the
    // Earth's edge (its limb is 68° from the nadir) and is pushed, less than one facing it;
    // past 90° + 68° nothing. Through 90° (a box's side face on a nadir-pointing
    // spacecraft) the force is continuous.
    let (_, up) = load(r, r.normalize(), "albedo = true");
    assert_eq!(up, Vec3::zeros());
    let side = Vec3::z().cross(&r).normalize();
    let at = |deg: f64| {
        let t = deg.to_radians();
        load(
            r,
            -r.normalize() * t.cos() + side * t.sin(),
            "albedo = true",
        )
        .1
    };
    let (_, facing) = load(r, -r.normalize(), "albedo = true");
    let past = at(95.0);
    assert!(
        past.norm() > 0.01 * facing.norm() && past.norm() < facing.norm(),
        "{past}"
    );
    // Along the normal (body x), the push is the plate's own: −(M/c) A W < 0.
    assert!(past.x < 0.0, "{past}");
    assert_eq!(at(90.0 + 68.2), Vec3::zeros());
    let (below, above) = (at(90.0 - 1e-7), at(90.0 + 1e-7));
    assert!(
        (below - above).norm() < 1e-6 * below.norm(),
        "{below} {above}"
    );
    // Tilted 15° from the nadir (the plate's horizon cuts the Earth from 22° on): the whole
    // cap seen, in closed form: with Ω = 2π(1 − cos α), b = 2π(1 − cos³ α)/3,
    // a = (Ω − b)/2, a black plate is pushed by (M/c) A (a n + (b − a) cos β d)/π, d the
    // nadir; along its normal by (M/c) A (a + (b − a) cos² β)/π.
    let tilt = 15f64.to_radians();
    let tilted = -r.normalize() * tilt.cos() + side * tilt.sin();
    let (env, f) = load(r, tilted, "albedo = true");
    let rs = r_sun(&env);
    let m = (0.3 * solar_flux(rs.norm()) + EARTH_IR) / SPEED_OF_LIGHT * 2.0;
    let pi = std::f64::consts::PI;
    let omega = 2.0 * pi * (1.0 - cos_alpha);
    let b = 2.0 * pi * (1.0 - cos_alpha.powi(3)) / 3.0;
    let a = 0.5 * (omega - b);
    let cb = tilt.cos();
    let along = m * (a + (b - a) * cb * cb) / pi;
    let norm = m * (a * a + 2.0 * a * (b - a) * cb * cb + (b - a).powi(2) * cb * cb).sqrt() / pi;
    assert!(
        (f.norm() - norm).abs() < 1e-12 * norm,
        "{} vs {norm}",
        f.norm()
    );
    assert!((f.x + along).abs() < 1e-12 * norm, "{f} vs {along}");
}

#[test]
fn the_earth_light_keys_are_checked_at_their_line() {
    let r = sun_dir() * (R_EARTH + 500e3);
    for (keys, needle) in [
        (
            "albedo = true\nalbedo_coefficient = 1.5",
            "albedo_coefficient` must be between 0 and 1",
        ),
        (
            "albedo = true\nearth_ir = -3.0",
            "earth_ir` must be between 0 and 1000",
        ),
        ("earth_ir = 240.0", "applies only with `albedo = true`"),
        (
            "albedo = false\nalbedo_coefficient = 0.3",
            "applies only with `albedo = true`",
        ),
        ("albedo = \"yes\"", "albedo"),
    ] {
        let text = plate(r, -r.normalize(), 0.0, 0.0, keys);
        let e = Scene::parse(&text, Path::new("earth.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(needle) && e.contains("earth.toml:"),
            "{keys}: {e}"
        );
    }
}

/// The example deployment (`examples/scenes/deploy_in_orbit.toml`) with the Earth's light,
/// at its start in the umbra and moved under the Sun.
fn deployment(extra: &str) -> Scene {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/deploy_in_orbit.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replace("resolution = 8\n", "resolution = 8\nalbedo = true\n");
    let text = text.replace("true_anomaly_deg = 247.15", extra);
    Scene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_example_deployment_feels_the_earth_light_of_the_expected_order() {
    let sum = |e: &EffectReport| e.bodies.iter().map(|b| b.force).sum::<Vec3>();
    // In the umbra at the start: the infrared alone, no Sun.
    let scene = deployment("true_anomaly_deg = 247.15");
    let env = environment(&scene, 0.0).unwrap();
    assert_eq!(env.shadow, Some(0.0));
    let earth = find(&env, "earth_radiation").expect("earth_radiation reported");
    let f = sum(earth).norm();
    // Bounded by every facet facing the nadir head-on: (237/c)(R/r)² Σ A (1 + ρs + 2/3 ρd).
    let r = env.orbit.unwrap().0.norm();
    let bound_per_area = EARTH_IR * (R_EARTH / r).powi(2) / SPEED_OF_LIGHT * 2.0;
    assert!(f > 1e-9 && f < bound_per_area * 30.0, "{f} N");
    // The run's columns carry the Earth light's torque, finite after a few steps.
    let sim = scene.simulation().unwrap();
    let names = sim
        .effect("solar_radiation")
        .unwrap()
        .output_columns()
        .join(",");
    assert!(names.ends_with("earth_radiation_torque_z"), "{names}");
    let later = environment(&scene, 0.5).unwrap();
    let f_later = sum(find(&later, "earth_radiation").unwrap());
    assert!(f_later.iter().all(|x| x.is_finite()) && f_later.norm() > 0.0);

    // Near the sub-solar point (the orbit's node at the March equinox, true anomaly 0): the
    // Earth light next to the Sun's. On a black plate facing the nadir it is
    // (0.3 S + 237)(2/3)(1 − cos³ α) against S, 0.30 of it; the spacecraft's facets face
    // both at other angles.
    let env = environment(&deployment("true_anomaly_deg = 0.0"), 0.0).unwrap();
    assert_eq!(env.shadow, Some(1.0));
    let zenith = env.orbit.unwrap().0.normalize().dot(&env.sun.unwrap().0);
    assert!(zenith > 0.95, "cos of the Sun's zenith angle {zenith}");
    let sun = sum(find(&env, "solar_radiation").unwrap()).norm();
    let earth = sum(find(&env, "earth_radiation").unwrap()).norm();
    let ratio = earth / sun;
    println!("Earth light / sunlight on the deployment near the sub-solar point: {ratio:.3}");
    assert!(
        ratio > 0.1 && ratio < 1.0,
        "{earth} N against {sun} N: {ratio}"
    );
}

#[test]
fn the_two_lights_add_up_to_what_the_run_applies() {
    // The Sun 60° from the zenith; the plate's normal halfway between the Sun and the
    // nadir: lit by both.
    let s = sun_dir();
    let p = Vec3::z().cross(&s).normalize();
    let up = s * 0.5 + p * 0.75f64.sqrt();
    let r = up * (R_EARTH + 500e3);
    let n = (s - up).normalize();
    let text = plate(r, n, 0.3, 0.2, "albedo = true");
    let scene = scene(&text);
    let env = environment(&scene, 0.0).unwrap();
    let sun = find(&env, "solar_radiation").unwrap();
    let earth = find(&env, "earth_radiation").unwrap();
    let mut sim = scene.simulation().unwrap();
    let x0 = sim.x0().to_vec();
    let all = sim.loads(0.0, &x0).unwrap();
    let all = all.iter().find(|l| l.name == "solar_radiation").unwrap();
    let total = all.wrenches[0].lin;
    let split = sun.bodies[0].force + earth.bodies[0].force;
    assert!(sun.bodies[0].force.norm() > 0.0 && earth.bodies[0].force.norm() > 0.0);
    assert!(
        (total - split).norm() <= 1e-15 * total.norm(),
        "{total} vs {split}"
    );
    for (a, (s, e)) in all
        .generalized
        .iter()
        .zip(sun.generalized_forces.iter().zip(&earth.generalized_forces))
    {
        assert!((a - (s + e)).abs() <= 1e-15 * total.norm() + 1e-30);
    }
}

#[test]
fn with_self_shadowing_a_facet_shades_another_from_the_earth_light() {
    // Two 2 m² plates facing the nadir, one 0.5 m below the other: from the nadir the lower
    // hides the upper entirely, so with self-shadowing the Earth pushes one plate, without
    // it both.
    let r = sun_dir() * (R_EARTH + 500e3);
    let one = "facets = [{ area = 2.0, normal = [1.0, 0.0, 0.0], at = [0.0, 0.5, 0.0], specular = 0.0, diffuse = 0.0 }]";
    let two = "facets = [{ area = 2.0, normal = [1.0, 0.0, 0.0], at = [0.0, 0.5, 0.0] }, \
               { area = 2.0, normal = [1.0, 0.0, 0.0], at = [0.5, 0.5, 0.0] }]";
    let force = |keys: &str| {
        let text = plate(r, -r.normalize(), 0.0, 0.0, keys).replace(one, two);
        assert!(text.contains(two));
        let env = environment(&scene(&text), 0.0).unwrap();
        find(&env, "earth_radiation").unwrap().bodies[0].force
    };
    let shaded = force("albedo = true\nself_shadowing = true");
    let both = force("albedo = true");
    assert!(shaded.norm() > 0.0);
    assert!(
        (both - 2.0 * shaded).norm() < 1e-12 * both.norm(),
        "{both} {shaded}"
    );
}
