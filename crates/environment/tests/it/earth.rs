//! The Earth's orientation against astropy's GCRS -> ITRS (IAU 2006/2000A with nutation and
//! polar motion, UT1 = UTC) at 40 dates over 1972-2050: fixtures/earth_reference.csv, made
//! by fixtures/earth_reference.py.

use nalgebra::{Matrix3, Rotation3};
use satsim_environment::earth::{earth_rotation_gcrf, gcrf_to_itrf};
use satsim_environment::{OMEGA_EARTH, Vec3, parse_epoch};

const REFERENCE: &str = include_str!("../../fixtures/earth_reference.csv");

/// What the model leaves out, as an angle (arcsec): nutation moves the pole by at most
/// sqrt((Δψ sin ε)² + Δε²) with |Δψ| <= 17.2 + 1.32 + 0.23 + 0.21 = 19.0 and |Δε| <= 9.20 +
/// 0.57 + 0.10 + 0.09 = 10.0 (the largest terms of IAU 1980), i.e. 12.5; the equation of the
/// equinoxes turns the equator back by what nutation turns it along the pole, so the two
/// cancel about the pole; polar motion adds at most 0.6; the frame bias, the precession
/// models' difference and GMST-82 against the Earth rotation angle under 0.1.
const LEFT_OUT_ARCSEC: f64 = 12.5 + 0.6 + 0.1;

fn rows() -> Vec<(String, Rotation3<f64>, Rotation3<f64>)> {
    REFERENCE
        .lines()
        .skip(1)
        .map(|line| {
            let cols: Vec<&str> = line.split(',').collect();
            let num: Vec<f64> = cols[1..].iter().map(|x| x.parse().unwrap()).collect();
            let m = |k: usize| {
                Rotation3::from_matrix_eps(
                    &Matrix3::from_row_slice(&num[k..k + 9]),
                    1e-15,
                    100,
                    Rotation3::identity(),
                )
            };
            (cols[0].to_string(), m(0), m(9))
        })
        .collect()
}

#[test]
fn gcrf_to_itrf_is_within_the_left_out_terms_of_astropy() {
    let (mut worst, mut worst_lon, mut worst_lat) = (0.0f64, 0.0f64, 0.0f64);
    let points = [
        Vec3::new(7e6, 0.0, 0.0),
        Vec3::new(0.0, 7e6, 0.0),
        Vec3::new(3e6, -4e6, 5e6),
        Vec3::new(-2e6, 1e6, -6.5e6),
    ];
    let table = rows();
    assert_eq!(table.len(), 40);
    for (date, reference, _) in &table {
        let r = gcrf_to_itrf(parse_epoch(date).unwrap(), 0.0);
        // The angle of the rotation between the two bounds every point's separation.
        worst = worst.max((r * reference.inverse()).angle().to_degrees() * 3600.0);
        for p in &points {
            let (a, b) = (r * p, reference * p);
            let lon = |v: Vec3| v.y.atan2(v.x);
            let lat = |v: Vec3| (v.z / v.norm()).asin();
            let d_lon = (lon(a) - lon(b) + 3.0 * std::f64::consts::PI)
                .rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            worst_lon = worst_lon.max(d_lon.abs().to_degrees() * 3600.0 * lat(b).cos());
            worst_lat = worst_lat.max((lat(a) - lat(b)).abs().to_degrees() * 3600.0);
        }
    }
    println!(
        "worst rotation error {worst:.2} arcsec (bound {LEFT_OUT_ARCSEC}); points: east {worst_lon:.2}, north {worst_lat:.2} arcsec"
    );
    assert!(worst < LEFT_OUT_ARCSEC, "{worst} arcsec");
}

#[test]
fn the_earth_turns_at_its_rate_about_the_pole_of_date() {
    let (mut worst_vec, mut worst_rate, mut worst_own) = (0.0f64, 0.0f64, 0.0f64);
    for (date, m, n) in rows() {
        let epoch = parse_epoch(&date).unwrap();
        let omega = earth_rotation_gcrf(epoch, 0.0);
        // Earth-fixed coordinates turn by −ω: n = exp(−[ω_itrf]× 60 s) m.
        let reference = m.inverse() * (-(n * m.inverse()).scaled_axis() / 60.0);
        worst_vec = worst_vec.max((omega - reference).norm() / reference.norm());
        worst_rate = worst_rate.max((reference.norm() / OMEGA_EARTH - 1.0).abs());
        // The model's own turn over 60 s, against its stated rate.
        let (a, b) = (gcrf_to_itrf(epoch, 0.0), gcrf_to_itrf(epoch, 60.0));
        let own = a.inverse() * (-(b * a.inverse()).scaled_axis() / 60.0);
        worst_own = worst_own.max((own - omega).norm() / OMEGA_EARTH);
    }
    println!(
        "ω against astropy: {worst_vec:.2e} (direction and rate), |ω| {worst_rate:.2e}; against gcrf_to_itrf's own turn {worst_own:.2e}"
    );
    // The direction: the pole of date within the nutation and polar motion bound.
    assert!(
        worst_vec < (LEFT_OUT_ARCSEC / 3600.0).to_radians(),
        "{worst_vec}"
    );
    // The rate: the nutation terms' rates (fortnightly 0.2" and semiannual 1.3" terms) change
    // it by under 1.2e-7.
    assert!(worst_rate < 1.2e-7, "{worst_rate}");
    // GMST turns 1.0027379 times a solar day less the precession in right ascension:
    // the Earth rotation angle's rate, 7.2921151e-5 rad/s, 2e-9 from OMEGA_EARTH, and the
    // precession's turn of the pole, 5e-8 of it.
    assert!(worst_own < 1e-7, "{worst_own}");
}
