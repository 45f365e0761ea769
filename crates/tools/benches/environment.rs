//! Cost of one right-hand side with each environment effect, on the preprint satellite with
//! the 24 facets of `examples/satellite.toml` (the bus' and the three panels' box faces),
//! panels half open (so that they shade each other and the bus), on a 500 km orbit in
//! sunlight: the orbit alone, then each effect added to it alone, solar pressure with and
//! without self-shadowing at 4, 8 and 16 rays per facet side, and everything together; then
//! every effect with the simple models of the world and with the flight-fidelity ones.
//!
//! Then the world models' calls of one such right-hand side alone (`environment_world`): what
//! the flight models cost of it.
//!
//! `cargo bench -p satsim-tools --bench environment`

use criterion::{Criterion, criterion_group, criterion_main};
use satsim_integrate::System;
use satsim_tools::scene::Scene;
use std::hint::black_box;
use std::path::Path;

const BASE: &str = r#"model = "../satellite.toml"
epoch = "2026-03-20T12:00:00 UTC"
duration = 600.0
[initial]
hinges = { angle = [0.0, 0.0, 0.0, 1.2, -1.0], rate = [0.01, 0.0, 0.0, 0.05, -0.04] }
base = { attitude = [0.9, 0.1, 0.3, 0.3], angular_velocity = [0.001, -0.002, 0.0015] }
[orbit]
altitude = 500e3
inclination_deg = 51.6
true_anomaly_deg = 0.0
"#;

fn srp(self_shadowing: bool, resolution: usize) -> String {
    format!(
        "[effects.solar_radiation]\nshadow = \"conical\"\nself_shadowing = {self_shadowing}\nresolution = {resolution}\n"
    )
}

const DRAG: &str = "[effects.drag]\n";
const IGRF: &str = "[effects.magnetic]\nfield = \"igrf14\"\nresidual_dipole = [0.5, 0.5, 1.0]\n";
const DIPOLE: &str = "[effects.magnetic]\nfield = \"dipole\"\nresidual_dipole = [0.5, 0.5, 1.0]\n";
const GG: &str = "[effects.gravity_gradient]\nmodel = \"full\"\n";

/// Gravity gradient, solar pressure, drag and the field with the simple models: the orbit's
/// point-mass gravity, the exponential atmosphere, the dipole, no Earth light.
fn simple_models() -> String {
    format!("{GG}{}{DRAG}{DIPOLE}", srp(false, 8))
}

/// The same effects with the flight-fidelity models: EGM2008 to degree and order 20, the
/// Sun's and the Moon's pull, NRLMSISE-00, IGRF-14, the Earth's reflected and emitted light.
fn flight_models() -> String {
    format!(
        "{GG}{}albedo = true\n[effects.drag]\natmosphere = \"nrlmsise00\"\n{IGRF}",
        srp(false, 8)
    )
}

/// The orbit's table for [`flight_models`].
const FLIGHT_ORBIT: &str = "gravity = { model = \"egm2008\", degree = 20, order = 20 }\nthird_body = [\"sun\", \"moon\"]\n";

fn scene(extra: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/bench.toml");
    // The orbit's keys go in its table, which `BASE` ends with.
    let orbit = if extra.contains("albedo") && extra.contains("nrlmsise00") {
        FLIGHT_ORBIT
    } else {
        ""
    };
    Scene::parse(&format!("{BASE}{orbit}{extra}"), &path).expect("bench scene")
}

fn rhs(c: &mut Criterion) {
    let mut g = c.benchmark_group("environment_rhs");
    let all = format!("{GG}{}{DRAG}{IGRF}", srp(true, 8));
    let cases: Vec<(&str, String)> = vec![
        ("orbit_only", String::new()),
        ("gravity_gradient_full", GG.into()),
        ("srp", srp(false, 8)),
        ("srp_self_shadowing_4", srp(true, 4)),
        ("srp_self_shadowing_8", srp(true, 8)),
        ("srp_self_shadowing_16", srp(true, 16)),
        ("drag", DRAG.into()),
        ("magnetic_igrf14", IGRF.into()),
        ("magnetic_dipole", DIPOLE.into()),
        ("all", all),
        // Every effect on without self-shadowing (the facets' geometry is no model of the
        // world), with the simple models, then with the flight-fidelity ones: their
        // difference is what the models of the world cost in a right-hand side.
        // Each flight-fidelity model alone, beside the simple one it replaces.
        ("gravity_egm2008_20", String::new()),
        ("third_body_sun_moon", String::new()),
        (
            "drag_nrlmsise00",
            "[effects.drag]\natmosphere = \"nrlmsise00\"\n".into(),
        ),
        ("srp_albedo", format!("{}albedo = true\n", srp(false, 8))),
        ("all_simple_models", simple_models()),
        ("all_flight_models", flight_models()),
    ];
    for (name, extra) in cases {
        let orbit = match name {
            "gravity_egm2008_20" => "gravity = { model = \"egm2008\", degree = 20, order = 20 }\n",
            "third_body_sun_moon" => "third_body = [\"sun\", \"moon\"]\n",
            _ => "",
        };
        let mut sim = scene(&format!("{orbit}{extra}")).simulation().unwrap();
        let x = sim.x0().to_vec();
        let mut dx = vec![0.0; x.len()];
        g.bench_function(name, |b| {
            b.iter(|| sim.rhs(0.0, black_box(&x), &mut dx).unwrap());
        });
    }
    g.finish();
}

/// The world models' calls of one right-hand side with every flight model on (what
/// `all_flight_models` asks of `satsim-environment`), timed alone: the harmonic gravity on
/// its lattice, the Sun and the Moon on their tracks and their pulls, NRLMSISE-00 on its
/// lattice, IGRF-14 on its lattice, the Earth's rotation for the co-rotating air, the
/// shadow, the Earth's exitance and the cap's moments of the 24 facets. `at_rest`: at the
/// benchmark state's place and time, as `environment_rhs` evaluates them (every lattice
/// cell made); `along_the_orbit`: marching 0.2 s a call along the orbit, its cells made as
/// it goes, at the rate a run meets them.
fn world(c: &mut Criterion) {
    use satsim_environment::atmosphere::nrlmsise::{Drivers, Msis, MsisTrack};
    use satsim_environment::earth::earth_rotation_gcrf;
    use satsim_environment::earth_radiation::{CapTable, EarthRadiation};
    use satsim_environment::gravity::{
        HarmonicField, HarmonicLattice, LATTICE_DEG, MU_MOON, MU_SUN, egm2008,
        third_body_acceleration,
    };
    use satsim_environment::magnetic::{FieldModel, GeoField};
    use satsim_environment::moon::MoonTrack;
    use satsim_environment::shadow::{ShadowModel, shadow_fraction};
    use satsim_environment::sun::SunTrack;
    use satsim_environment::{R_EARTH, Vec3, parse_epoch};
    use std::sync::Arc;

    let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let field = Arc::new(HarmonicField::new(egm2008().unwrap(), 20, 20).unwrap());
    let mut gravity = HarmonicLattice::new(field, LATTICE_DEG).unwrap();
    let (mut sun, mut moon) = (SunTrack::new(epoch), MoonTrack::new(epoch));
    let mut air = MsisTrack::new(Msis::new(epoch, Drivers::default()), 300.0);
    let magnetic = GeoField::new(FieldModel::Igrf14, epoch)
        .unwrap()
        .with_lattice(satsim_environment::magnetic::LATTICE_DEG);
    let light = EarthRadiation::default();
    // The 24 facets' normals: the six faces of four boxes, turned apart.
    let normals: Vec<Vec3> = (0..4)
        .flat_map(|b| {
            let turn = nalgebra::Rotation3::new(Vec3::new(0.3 * b as f64, 0.7, -0.2 * b as f64));
            [
                Vec3::x(),
                -Vec3::x(),
                Vec3::y(),
                -Vec3::y(),
                Vec3::z(),
                -Vec3::z(),
            ]
            .map(|n| turn * n)
        })
        .collect();
    let (a, n_rate, inc) = (R_EARTH + 500e3, 1.1e-3, 51.6f64.to_radians());
    let place = |t: f64| {
        let u = n_rate * t;
        Vec3::new(u.cos(), u.sin() * inc.cos(), u.sin() * inc.sin()) * a
    };
    let mut calls = |t: f64, r: &Vec3| {
        let mut acc = gravity.acceleration_gcrf(epoch, t, r);
        let (r_sun, r_moon) = (sun.position(t), moon.position(t));
        acc += third_body_acceleration(MU_SUN, &r_sun, r);
        acc += third_body_acceleration(MU_MOON, &r_moon, r);
        let rho = air.density(t, r).unwrap();
        let b = magnetic.field_gcrf(t, r);
        let w = earth_rotation_gcrf(epoch, t);
        let shadow = shadow_fraction(ShadowModel::Conical, r, &r_sun);
        let m = light.exitance(r, &r_sun).total();
        let cap = CapTable::shared().at_altitude(r.norm() / R_EARTH);
        let nadir = -r.normalize();
        let mut sum = 0.0;
        for n in &normals {
            sum += cap.moments(n, &nadir).irradiance;
        }
        acc.x + rho + b.x + w.z + shadow + m + sum
    };
    let mut g = c.benchmark_group("environment_world");
    let r0 = place(0.0);
    g.bench_function("flight_models_at_rest", |b| {
        b.iter(|| calls(0.0, black_box(&r0)))
    });
    let mut t = 0.0;
    g.bench_function("flight_models_along_the_orbit", |b| {
        b.iter(|| {
            t += 0.2;
            calls(t, black_box(&place(t)))
        })
    });
    g.finish();
}

criterion_group!(benches, rhs, world);
criterion_main!(benches);
