//! The Moon's position against astropy's built-in Moon (ERFA moon98) at 24 dates over
//! 1950-2100: fixtures/moon_reference.csv, made by fixtures/moon_reference.py.

use satsim_environment::moon::{MoonTrack, moon_position};
use satsim_environment::{Vec3, parse_epoch};

const REFERENCE: &str = include_str!("../../fixtures/moon_reference.csv");

#[test]
fn moon_position_is_within_0_01_degrees_of_astropy() {
    let (mut worst_angle, mut worst_distance, mut rows) = (0.0f64, 0.0f64, 0);
    for line in REFERENCE.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let epoch = parse_epoch(cols[0]).unwrap();
        let reference = Vec3::new(
            cols[1].parse().unwrap(),
            cols[2].parse().unwrap(),
            cols[3].parse().unwrap(),
        );
        let r = moon_position(epoch, 0.0);
        worst_angle = worst_angle.max(r.angle(&reference).to_degrees());
        worst_distance = worst_distance.max((r.norm() - reference.norm()).abs());
        rows += 1;
    }
    println!(
        "{rows} dates: worst direction {:.2} arcsec, worst distance {:.3} km",
        worst_angle * 3600.0,
        worst_distance / 1e3
    );
    assert_eq!(rows, 24);
    assert!(worst_angle < 0.01, "direction off by {worst_angle} deg");
    assert!(worst_distance < 10e3, "distance off by {worst_distance} m");
}

#[test]
fn the_track_follows_the_series_in_any_call_order() {
    let epoch = parse_epoch("2026-07-04T00:00:00 UTC").unwrap();
    let mut track = MoonTrack::new(epoch);
    let mut worst: f64 = 0.0;
    for k in 0..2000 {
        let t = -3600.0 + 97.3 * k as f64;
        worst = worst.max((track.position(t) - moon_position(epoch, t)).norm());
    }
    assert!(worst < 150.0, "worst {worst} m");
    let mut fresh = MoonTrack::new(epoch);
    for t in [5000.0, 123.0, 599.999, 600.0, -1.0] {
        assert_eq!(fresh.position(t), track.position(t));
    }
}
