//! The orbit in the Earth's harmonic field and with third bodies, through the simulation.

use satsim_environment::gravity::{HarmonicField, egm2008};
use satsim_environment::{moon::moon_position, parse_epoch, sun::sun_position};
use satsim_integrate::{Method, Options, Output};
use satsim_spacecraft::effects::orbit::Elements;
use satsim_spacecraft::effects::{Orbit, OrbitModel, ThirdBodies};
use satsim_spacecraft::simulation::Simulation;
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Body, ModelBuilder};
use std::sync::Arc;

fn simulation(orbit: Orbit) -> Simulation {
    let model = ModelBuilder::new(BaseKind::Free)
        .body(Body::new(
            "bus",
            500.0,
            Mat3::from_diagonal(&Vec3::new(10.0, 10.0, 10.0)),
        ))
        .build()
        .unwrap();
    Simulation::builder(model).effect(orbit).build().unwrap()
}

/// The orbit's position after `t_end` s.
fn position_after(orbit: Orbit, t_end: f64) -> Vec3 {
    let mut sim = simulation(orbit);
    let opts = Options::new(Method::Dp54)
        .with_tolerances(1e-12, 1e-9)
        .with_max_steps(10_000_000);
    let x0 = sim.x0().to_vec();
    let mut last = Vec::new();
    satsim_integrate::integrate(
        &mut sim,
        &opts,
        0.0,
        &x0,
        t_end,
        &Output::Times(vec![t_end]),
        |_, x| {
            last = x.to_vec();
            std::ops::ControlFlow::Continue(())
        },
    )
    .unwrap();
    let o = sim.layout().effect("orbit").unwrap();
    Vec3::new(last[o.start], last[o.start + 1], last[o.start + 2])
}

/// A 500 km, 51.6 deg orbit in the J2 field with EGM2008's own GM, radius and J2, or in
/// EGM2008 to `(degree, order)`: the same initial state.
fn leo(harmonics: Option<(usize, usize)>) -> Orbit {
    let egm = egm2008().unwrap();
    let el = Elements {
        a: 6_878e3,
        e: 0.001,
        i: 51.6f64.to_radians(),
        raan: 0.3,
        argp: 0.5,
        nu: 0.0,
    };
    let (r, v) = el.to_cartesian(egm.gm);
    let mut orbit = Orbit::new(OrbitModel::J2, r, v);
    orbit.mu = egm.gm;
    orbit.radius = egm.radius;
    orbit.j2 = -egm.get(2, 0).0 * 5f64.sqrt();
    orbit.epoch = Some(parse_epoch("2026-03-20T12:00:00 UTC").unwrap());
    if let Some((n, m)) = harmonics {
        orbit.harmonics = Some(Arc::new(HarmonicField::new(egm, n, m).unwrap()));
    }
    orbit
}

#[test]
fn a_day_in_egm2008_20x20_drifts_kilometres_from_j2_only() {
    // "J2 only" is EGM2008 to degree 2, order 0 in the same Earth-fixed frame: the
    // difference is then that of the harmonics beyond J2 alone.
    let day = 86_400.0;
    let j2_fixed = position_after(leo(Some((2, 0))), day);
    let h20 = position_after(leo(Some((20, 20))), day);
    let again = position_after(leo(Some((20, 20))), day);
    assert_eq!(h20, again, "not deterministic");
    let d20 = (h20 - j2_fixed).norm();
    // `model = "j2"` puts J2 about the GCRF's z axis, not the pole of date: in 2026 the two
    // are 0.14 deg apart (precession), which alone moves this orbit by kilometres a day.
    let d_pole = (position_after(leo(None), day) - j2_fixed).norm();
    println!(
        "after one day: EGM2008 20x20 vs J2 (Earth-fixed pole) {:.3} km; J2 about the GCRF z axis vs about the pole of date {:.3} km",
        d20 / 1e3,
        d_pole / 1e3
    );
    assert!((300.0..30e3).contains(&d20), "20x20 vs J2: {d20} m");
}

#[test]
fn the_third_bodies_move_a_geostationary_orbit_by_kilometres_a_day() {
    let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let r = Vec3::new(42_164e3, 0.0, 0.0);
    let v = Vec3::new(0.0, (3.986004418e14f64 / 42_164e3).sqrt(), 0.0);
    let mut plain = Orbit::new(OrbitModel::Kepler, r, v);
    plain.epoch = Some(epoch);
    let mut both = plain.clone();
    both.third_bodies = ThirdBodies {
        sun: true,
        moon: true,
    };
    // The effect's perturbation at t is the formula on the tracks' positions.
    let t = 1234.5;
    let a = both.third_body(t, &r).unwrap();
    let (s, m) = (sun_position(epoch, t), moon_position(epoch, t));
    let tide = |mu: f64, b: Vec3| mu * ((b - r) / (b - r).norm().powi(3) - b / b.norm().powi(3));
    let formula = tide(1.3271244e20, s) + tide(4.902800066e12, m);
    assert!(
        (a - formula).norm() < 1e-6 * formula.norm(),
        "{a:?} vs {formula:?}"
    );
    let day = 86_400.0;
    let d = (position_after(both, day) - position_after(plain, day)).norm();
    // ~1e-5 m/s² over a day: ½ a t² ~ 37 km is the bound, the orbit's response is kilometres.
    println!("GEO one day, Sun and Moon vs none: {:.3} km", d / 1e3);
    assert!((1e3..100e3).contains(&d), "{d} m");
}

#[test]
fn without_an_epoch_the_fields_are_an_error() {
    let mut orbit = leo(Some((4, 4)));
    orbit.epoch = None;
    assert!(orbit.gravity(0.0, &orbit.r0).is_err());
    orbit.harmonics = None;
    orbit.third_bodies.moon = true;
    let r0 = orbit.r0;
    assert!(orbit.third_body(0.0, &r0).is_err());
}
