//! The Sun's position against astropy's built-in ephemeris (ERFA epv00) at 300 dates over
//! 1900-2100: fixtures/sun_reference.csv, made by fixtures/sun_reference.py.

use satsim_environment::{AU, Vec3, parse_epoch, sun::sun_position};

const REFERENCE: &str = include_str!("../../fixtures/sun_reference.csv");

#[test]
fn sun_position_is_within_0_01_degrees_and_1e_4_of_the_ephemeris() {
    let (mut worst_angle, mut worst_distance, mut rows) = (0.0f64, 0.0f64, 0);
    for line in REFERENCE.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let epoch = parse_epoch(cols[0]).unwrap();
        let reference = Vec3::new(
            cols[1].parse().unwrap(),
            cols[2].parse().unwrap(),
            cols[3].parse().unwrap(),
        );
        let r = sun_position(epoch, 0.0);
        let angle = r.angle(&reference).to_degrees();
        let distance = (r.norm() / reference.norm() - 1.0).abs();
        worst_angle = worst_angle.max(angle);
        worst_distance = worst_distance.max(distance);
        rows += 1;
    }
    println!(
        "{rows} dates: worst direction {:.2} arcsec, worst distance {worst_distance:.2e} relative",
        worst_angle * 3600.0
    );
    assert_eq!(rows, 300);
    assert!(worst_angle < 0.01, "direction off by {worst_angle} deg");
    assert!(worst_distance < 1e-4, "distance off by {worst_distance}");
}

#[test]
fn time_runs_from_the_epoch() {
    // epoch + t and (epoch + t) + 0 are the same instant; the Sun moves ~1 degree a day.
    let e = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let later = parse_epoch("2026-03-21T12:00:00 UTC").unwrap();
    let a = sun_position(e, 86_400.0);
    assert!((a - sun_position(later, 0.0)).norm() < 1.0);
    let daily = sun_position(e, 0.0).angle(&a).to_degrees();
    assert!((daily - 0.9856).abs() < 0.04, "{daily}");
    assert!((a.norm() / AU - 1.0).abs() < 0.02);
}
