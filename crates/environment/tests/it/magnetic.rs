//! The geomagnetic field: IGRF-14 against ppigrf (fixtures/igrf_reference.csv, made by
//! fixtures/igrf_reference.py), the dipole against its closed-form magnitudes from the
//! coefficient table, the two frames' routes, the poles, and the span.

use satsim_environment::earth::gcrf_to_itrf;
use satsim_environment::magnetic::{FieldModel, GeoField};
use satsim_environment::{Vec3, parse_epoch};

const REFERENCE: &str = include_str!("../../fixtures/igrf_reference.csv");
const TABLE: &str = include_str!("../../data/igrf14coeffs.txt");
/// IGRF's reference radius (m).
const A: f64 = 6_371_200.0;

/// The unit vectors r̂, θ̂ (south), φ̂ (east) at colatitude `th`, longitude `ph` (rad).
fn basis(th: f64, ph: f64) -> [Vec3; 3] {
    let (st, ct) = th.sin_cos();
    let (sp, cp) = ph.sin_cos();
    [
        Vec3::new(st * cp, st * sp, ct),
        Vec3::new(ct * cp, ct * sp, -st),
        Vec3::new(-sp, cp, 0.0),
    ]
}

#[test]
fn igrf14_matches_ppigrf_everywhere_including_the_poles() {
    let mut worst = 0.0f64;
    let mut rows = 0;
    for line in REFERENCE.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        let num: Vec<f64> = c[1..].iter().map(|x| x.parse().unwrap()).collect();
        let (r, th, ph) = (num[0] * 1e3, num[1].to_radians(), num[2].to_radians());
        let field = GeoField::new(FieldModel::Igrf14, parse_epoch(c[0]).unwrap()).unwrap();
        let e = basis(th, ph);
        // On the axis exactly (sin θ = 0), as the fixture's poles are.
        let pos = if num[1] == 0.0 || num[1] == 180.0 {
            Vec3::new(0.0, 0.0, r * th.cos())
        } else {
            e[0] * r
        };
        let b = field.field_itrf(0.0, &pos) * 1e9;
        for k in 0..3 {
            worst = worst.max((b.dot(&e[k]) - num[3 + k]).abs());
        }
        rows += 1;
    }
    println!("{rows} points: worst component difference {worst:.2e} nT");
    assert_eq!(rows, 24);
    // The same model and the same dates: only rounding is left (the fixture's 1e-6 nT).
    assert!(worst < 1e-3, "{worst} nT");
}

#[test]
fn the_poles_are_ordinary_points() {
    let e = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let field = GeoField::new(FieldModel::Igrf14, e).unwrap();
    for z in [7.0e6, -7.0e6] {
        let at_pole = field.field_itrf(0.0, &Vec3::new(0.0, 0.0, z));
        assert!(at_pole.iter().all(|x| x.is_finite()));
        // 1 mm off the axis in eight directions: the same field to 1e-9 of it.
        for k in 0..8 {
            let phi = k as f64 * std::f64::consts::FRAC_PI_4;
            let near = field.field_itrf(0.0, &Vec3::new(1e-3 * phi.cos(), 1e-3 * phi.sin(), z));
            assert!(
                (near - at_pole).norm() < 1e-9 * at_pole.norm(),
                "{near} vs {at_pole}"
            );
        }
    }
}

/// The table's (g10, g11, h11) in the column of `year` (1900.0, …, 2025.0), read here apart
/// from the crate's parser.
fn degree_one(year: f64) -> Vec3 {
    let col = 3 + ((year - 1900.0) / 5.0) as usize;
    let get = |gh: &str, n: &str, m: &str| -> f64 {
        let line = TABLE
            .lines()
            .find(|l| {
                let c: Vec<&str> = l.split_whitespace().collect();
                c.len() > 3 && c[0] == gh && c[1] == n && c[2] == m
            })
            .unwrap();
        line.split_whitespace().nth(col).unwrap().parse().unwrap()
    };
    Vec3::new(get("g", "1", "0"), get("g", "1", "1"), get("h", "1", "1"))
}

#[test]
fn the_dipole_is_b0_at_its_equator_and_twice_that_at_its_poles() {
    // 2022.5 (2 July 2022, 12:00): halfway between the 2020 and 2025 models.
    for (date, coeffs) in [
        ("2025-01-01T00:00:00 UTC", degree_one(2025.0)),
        (
            "2022-07-02T12:00:00 UTC",
            (degree_one(2020.0) + degree_one(2025.0)) / 2.0,
        ),
    ] {
        let field = GeoField::new(FieldModel::Dipole, parse_epoch(date).unwrap()).unwrap();
        let (g10, g11, h11) = (coeffs.x, coeffs.y, coeffs.z);
        let m = Vec3::new(g11, h11, g10); // the dipole's axis in Earth-fixed axes
        let b0 = coeffs.norm() * 1e-9;
        for r in [A, 7.0e6, 4.2e7] {
            let scale = (A / r).powi(3);
            let pole = m.normalize() * r;
            let equator = m.cross(&Vec3::z()).normalize() * r;
            let bp = field.field_itrf(0.0, &pole);
            let be = field.field_itrf(0.0, &equator);
            assert!(
                (bp.norm() / (2.0 * b0 * scale) - 1.0).abs() < 1e-12,
                "{date} {r}"
            );
            assert!((be.norm() / (b0 * scale) - 1.0).abs() < 1e-12, "{date} {r}");
            // Along the axis at the pole; against it at the equator (north is −m's way).
            assert!(bp.normalize().dot(&m.normalize()) > 1.0 - 1e-12);
            assert!(be.normalize().dot(&m.normalize()) < -1.0 + 1e-12);
        }
    }
}

#[test]
fn far_away_igrf14_tends_to_its_dipole() {
    let e = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let igrf = GeoField::new(FieldModel::Igrf14, e).unwrap();
    let dipole = GeoField::new(FieldModel::Dipole, e).unwrap();
    let dir = Vec3::new(0.3, -0.5, 0.8).normalize();
    let rel = |r: f64| {
        let (a, b) = (
            igrf.field_itrf(0.0, &(dir * r)),
            dipole.field_itrf(0.0, &(dir * r)),
        );
        (a - b).norm() / b.norm()
    };
    // The quadrupole falls one power of r faster than the dipole: the difference halves as
    // r doubles (to the octupole's share), and is small far out.
    let (near, far) = (rel(100.0 * A), rel(200.0 * A));
    assert!(near < 1e-2, "{near}");
    assert!((far / near - 0.5).abs() < 0.01, "{far} / {near}");
}

#[test]
fn the_gcrf_and_itrf_routes_agree() {
    let e = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    for model in [FieldModel::Igrf14, FieldModel::Dipole] {
        let field = GeoField::new(model, e).unwrap();
        for t in [0.0, 3.3e5] {
            let r = Vec3::new(4.1e6, -3.3e6, 4.4e6);
            let rot = gcrf_to_itrf(e, t);
            let direct = field.field_gcrf(t, &r);
            let via = rot.inverse() * field.field_itrf(t, &(rot * r));
            assert!((direct - via).norm() < 1e-12 * direct.norm());
            // And the Earth's turn matters: the ITRF field at the GCRF position differs.
            assert!((field.field_itrf(t, &r) - direct).norm() > 1e-3 * direct.norm());
        }
    }
}

#[test]
fn epochs_outside_1900_to_2030_are_refused_with_the_span_named() {
    for date in [
        "1899-12-31T23:59:00 UTC",
        "2030-01-01T00:01:00 UTC",
        "1850-06-01T00:00:00 UTC",
    ] {
        let err = GeoField::new(FieldModel::Igrf14, parse_epoch(date).unwrap()).unwrap_err();
        assert!(err.contains("1900") && err.contains("2030"), "{err}");
    }
    for date in ["1900-01-01T00:00:00 UTC", "2030-01-01T00:00:00 UTC"] {
        assert!(GeoField::new(FieldModel::Dipole, parse_epoch(date).unwrap()).is_ok());
    }
    assert_eq!(FieldModel::from_name("igrf14"), Some(FieldModel::Igrf14));
    assert_eq!(FieldModel::from_name("dipole"), Some(FieldModel::Dipole));
    assert_eq!(FieldModel::from_name("igrf13"), None);
    for m in [FieldModel::Igrf14, FieldModel::Dipole] {
        assert_eq!(FieldModel::from_name(m.name()), Some(m));
    }
}
