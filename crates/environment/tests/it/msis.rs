//! NRLMSISE-00 against pymsis 0.13.0 (`version=0`, NRL's Fortran msis00, `gtd7d`) at 300
//! rows over 100-1000 km, pole to pole, all longitudes and times of day, F10.7 70/150/250,
//! Ap 4 to 150 and storm-time Ap histories: fixtures/msis_reference.csv, made by
//! fixtures/msis_reference.py. Then the space-weather file's look-up
//! (fixtures/msis_space_weather.csv, values chosen by hand) and the lattice a run reads the
//! model through.

use satsim_environment::atmosphere::nrlmsise::{Drivers, Msis, MsisTrack, from_geodetic};
use satsim_environment::atmosphere::space_weather::{SpaceWeather, day_number};
use satsim_environment::earth::gcrf_to_itrf;
use satsim_environment::{Epoch, MU_EARTH, Vec3, parse_epoch};
use std::path::Path;
use std::sync::Arc;

const REFERENCE: &str = include_str!("../../fixtures/msis_reference.csv");
const WEATHER: &str = include_str!("../../fixtures/msis_space_weather.csv");

/// The fixture's rows: (epoch, lon, lat, alt km, drivers, pymsis's density).
fn reference_rows() -> Vec<(Epoch, f64, f64, f64, Drivers, f64)> {
    REFERENCE
        .lines()
        .skip(1)
        .map(|line| {
            let c: Vec<&str> = line.split(',').collect();
            let x = |k: usize| c[k].parse::<f64>().unwrap();
            let epoch = parse_epoch(&format!("{} UTC", c[0])).unwrap();
            let (f107, f107a) = (x(4), x(5));
            let drivers = match c[13] {
                "1" => Drivers::Constant {
                    f107,
                    f107a,
                    ap: x(6),
                },
                "-1" => Drivers::History {
                    f107,
                    f107a,
                    ap: [x(6), x(7), x(8), x(9), x(10), x(11), x(12)],
                },
                m => panic!("mode {m}"),
            };
            (epoch, x(1), x(2), x(3), drivers, x(14))
        })
        .collect()
}

#[test]
fn msis_density_is_within_1_percent_of_pymsis() {
    let (mut worst, mut rows, mut storm) = (0.0f64, 0, 0);
    for (epoch, lon, lat, alt, drivers, reference) in reference_rows() {
        storm += usize::from(matches!(drivers, Drivers::History { .. }));
        let rho = Msis::new(epoch, drivers)
            .density_geodetic(0.0, lat, lon, alt)
            .unwrap();
        let err = (rho / reference - 1.0).abs();
        assert!(
            err <= 0.01,
            "{epoch} {lat} {lon} {alt}: {rho} vs {reference}"
        );
        worst = worst.max(err);
        rows += 1;
    }
    println!("{rows} rows ({storm} storm-time): worst relative error {worst:.2e}");
    assert_eq!((rows, storm), (300, 30));
    // pymsis computes in single precision: its own rounding is about 1e-6.
    assert!(worst < 1e-4, "{worst}");
}

fn weather() -> SpaceWeather {
    SpaceWeather::parse(WEATHER, Path::new("msis_space_weather.csv")).unwrap()
}

/// UTC seconds from 1900 of `date` at `h:m:s`.
fn utc(y: i64, mo: i64, d: i64, h: f64, m: f64, s: f64) -> f64 {
    day_number(y, mo, d) as f64 * 86_400.0 + h * 3600.0 + m * 60.0 + s
}

#[test]
fn msis_space_weather_gives_the_previous_days_flux_and_the_ap_history() {
    let w = weather();
    // 2024-05-11 03:00:00, the second 3-hour interval (AP2) of the day: by hand from the
    // fixture's rows of 05-08 to 05-11.
    let d = w.drivers(utc(2024, 5, 11, 3.0, 0.0, 0.0)).unwrap();
    assert_eq!(d.f107, 180.0, "05-10's F10.7_OBS");
    assert_eq!(d.f107a, 170.0, "05-11's F10.7_OBS_CENTER81");
    // Daily Ap; AP2 of 05-11; AP1 of 05-11; AP8 and AP7 of 05-10; the mean of AP6..AP1 of
    // 05-10 and AP8, AP7 of 05-09 (241/8); of AP6..AP1 of 05-09 and AP8, AP7 of 05-08 (100/8).
    assert_eq!(d.ap, [80.0, 207.0, 154.0, 94.0, 48.0, 30.125, 12.5]);
    // A second earlier, the first interval: each entry steps back by three hours.
    let d = w.drivers(utc(2024, 5, 11, 2.0, 59.0, 59.0)).unwrap();
    // AP1 of 05-11; AP8, AP7, AP6 of 05-10; AP5..AP1 of 05-10 and AP8..AP6 of 05-09,
    // (33+15+39+32+27 + 27+22+16)/8 = 211/8; AP5..AP1 of 05-09 and AP8..AP6 of 05-08,
    // (14+9+18+15+12 + 9+7+3)/8 = 87/8.
    assert_eq!(d.ap, [80.0, 154.0, 94.0, 48.0, 46.0, 26.375, 10.875]);
    assert_eq!(d.f107, 180.0);
    // Across midnight the previous day's flux moves on with the day.
    let before = w.drivers(utc(2024, 5, 10, 23.0, 59.0, 59.0)).unwrap();
    assert_eq!(
        (before.f107, before.f107a, before.ap[0]),
        (170.0, 165.0, 42.0)
    );
    assert_eq!(before.ap[1], 94.0, "AP8 of 05-10");
    // 05-11 reads back to 05-08; 05-13's row has no 3-hour ap (a predicted month).
    assert!(
        w.check_days(day_number(2024, 5, 11), day_number(2024, 5, 12))
            .is_ok()
    );
    let early = w
        .check_days(day_number(2024, 5, 10), day_number(2024, 5, 11))
        .unwrap_err();
    assert!(
        early.contains("msis_space_weather.csv") && early.contains("no row for 2024-05-07"),
        "{early}"
    );
    let late = w
        .check_days(day_number(2024, 5, 11), day_number(2024, 5, 13))
        .unwrap_err();
    assert!(
        late.contains("msis_space_weather.csv:7:") && late.contains("`AP_AVG` is ``"),
        "{late}"
    );
}

#[test]
fn msis_space_weather_errors_name_the_file_and_line() {
    let path = Path::new("sw.csv");
    let no_column = SpaceWeather::parse("DATE,F10.7_OBS,AP_AVG\n2024-01-01,1,2\n", path);
    let m = no_column.unwrap_err();
    assert!(
        m.starts_with("sw.csv:1:") && m.contains("F10.7_OBS_CENTER81"),
        "{m}"
    );
    let bad = WEATHER.replace(
        "2024-05-10,2602,3,0,0,0,0,0,0,0,0,0,27,",
        "2024-05-10,2602,3,0,0,0,0,0,0,0,0,0,x7,",
    );
    let w = SpaceWeather::parse(&bad, path).unwrap();
    let m = w.drivers(utc(2024, 5, 11, 12.0, 0.0, 0.0)).unwrap_err();
    assert!(
        m.starts_with("sw.csv:4:") && m.contains("`AP1` is `x7`"),
        "{m}"
    );
    let m = SpaceWeather::parse(&WEATHER.replace("2024-05-09,", "2024-05-32,"), path).unwrap_err();
    assert!(
        m.starts_with("sw.csv:3:") && m.contains("2024-05-32"),
        "{m}"
    );
    let m = SpaceWeather::parse(&WEATHER.replace("2024-05-09,", "2024-05-10,"), path).unwrap_err();
    assert!(
        m.starts_with("sw.csv:4:") && m.contains("second row"),
        "{m}"
    );
    let m = SpaceWeather::read(Path::new("/nonexistent/sw.csv")).unwrap_err();
    assert!(
        m.contains("/nonexistent/sw.csv") && m.contains("cannot be read"),
        "{m}"
    );
}

#[test]
fn msis_space_weather_storm_row_matches_pymsis_with_the_full_ap_history() {
    // The fixture's storm rows at 2024-05-11T03:00 used the history the file gives then.
    let epoch = parse_epoch("2024-05-11T03:00:00 UTC").unwrap();
    let table = Msis::new(epoch, Drivers::Table(Arc::new(weather())));
    let mut rows = 0;
    for (e, lon, lat, alt, drivers, reference) in reference_rows() {
        let Drivers::History { ap, .. } = drivers else {
            continue;
        };
        if e != epoch || ap[1] != 207.0 {
            continue;
        }
        let rho = table.density_geodetic(0.0, lat, lon, alt).unwrap();
        assert!(
            (rho / reference - 1.0).abs() < 1e-4,
            "{alt}: {rho} vs {reference}"
        );
        // And the history matters: the daily Ap alone gives another density.
        let daily = Msis::new(
            epoch,
            Drivers::Constant {
                f107: 180.0,
                f107a: 170.0,
                ap: 80.0,
            },
        )
        .density_geodetic(0.0, lat, lon, alt)
        .unwrap();
        assert!(
            (daily / reference - 1.0).abs() > 0.02,
            "{alt}: {daily} vs {reference}"
        );
        rows += 1;
    }
    assert_eq!(rows, 5);
}

/// A circular orbit at `alt` (m) above the equatorial radius, inclined 51.6°, GCRF.
fn orbit(alt: f64, t: f64) -> Vec3 {
    let a = satsim_environment::R_EARTH + alt;
    let n = (MU_EARTH / a.powi(3)).sqrt();
    let (i, raan) = (51.6f64.to_radians(), 0.7f64);
    let (s, c) = (n * t).sin_cos();
    let p = Vec3::new(raan.cos(), raan.sin(), 0.0);
    let q = Vec3::new(-raan.sin() * i.cos(), raan.cos() * i.cos(), i.sin());
    a * (c * p + s * q)
}

#[test]
fn msis_lattice_follows_the_model_along_an_orbit_in_any_call_order() {
    let epoch = parse_epoch("2026-03-20T06:00:00 UTC").unwrap();
    for (alt, drivers) in [
        (400e3f64, Drivers::default()),
        (
            250e3,
            Drivers::Constant {
                f107: 250.0,
                f107a: 230.0,
                ap: 50.0,
            },
        ),
    ] {
        let msis = Msis::new(epoch, drivers);
        let mut track = MsisTrack::new(msis.clone(), 300.0);
        let period = 2.0
            * std::f64::consts::PI
            * ((satsim_environment::R_EARTH + alt).powi(3) / MU_EARTH).sqrt();
        let (mut worst, mut values) = (0.0f64, Vec::new());
        let n = (period / 0.5) as usize;
        for k in 0..=n {
            let t = k as f64 * 0.5;
            let r = orbit(alt, t);
            let rho = track.density(t, &r).unwrap();
            worst = worst.max((rho / msis.density(t, &r).unwrap() - 1.0).abs());
            values.push(rho);
        }
        println!(
            "{} km: {} calls over one orbit ({period:.0} s), {} evaluations, worst relative error {worst:.2e}",
            alt / 1e3,
            n + 1,
            track.evaluations()
        );
        assert!(worst < 5e-4, "{worst}");
        // About one evaluation a second of orbit, where the calls are 0.5 s apart.
        assert!(
            (track.evaluations() as f64) < 1.1 * period,
            "{}",
            track.evaluations()
        );
        // Backwards, with a fresh lattice: the same bits.
        let mut back = MsisTrack::new(msis.clone(), 300.0);
        for k in (0..=n).rev() {
            let t = k as f64 * 0.5;
            assert_eq!(back.density(t, &orbit(alt, t)).unwrap(), values[k]);
        }
    }
}

#[test]
fn msis_density_varies_as_the_model_says_with_height_activity_and_place() {
    let epoch = parse_epoch("2026-06-21T12:00:00 UTC").unwrap();
    let quiet = Msis::new(epoch, Drivers::default());
    let at = |m: &Msis, lat: f64, lon: f64, h: f64| {
        let r = from_geodetic(lat.to_radians(), lon.to_radians(), h);
        m.density(0.0, &(gcrf_to_itrf(epoch, 0.0).inverse() * r))
            .unwrap()
    };
    // Through the frames: the same as the geodetic call.
    let direct = quiet.density_geodetic(0.0, 30.0, 20.0, 400.0).unwrap();
    assert!((at(&quiet, 30.0, 20.0, 400e3) / direct - 1.0).abs() < 1e-9);
    // Falls with height; a storm and a high flux raise it at 400 km; the day side (noon
    // UT at longitude 0, local 12 h) is denser than the night side (longitude 180).
    assert!(at(&quiet, 0.0, 0.0, 300e3) > 3.0 * at(&quiet, 0.0, 0.0, 400e3));
    let active = Msis::new(
        epoch,
        Drivers::Constant {
            f107: 250.0,
            f107a: 250.0,
            ap: 50.0,
        },
    );
    assert!(at(&active, 0.0, 0.0, 400e3) > 3.0 * at(&quiet, 0.0, 0.0, 400e3));
    assert!(at(&quiet, 0.0, 0.0, 400e3) > 1.5 * at(&quiet, 0.0, 180.0, 400e3));
    // Far above its 1000 km and at the ground the model still answers: positive, finite.
    for h in [0.0, 5e6, 36e6] {
        let rho = at(&quiet, 10.0, 20.0, h);
        assert!(rho > 0.0 && rho.is_finite(), "{h}: {rho}");
    }
    assert!(
        (at(&quiet, 10.0, 20.0, 0.0) / 1.2 - 1.0).abs() < 0.1,
        "the sea-level air"
    );
}

/// The cost of one evaluation of the model and of one call of the lattice along an orbit,
/// 0.1 s apart (a fixed-step attitude run's right-hand sides):
/// `cargo test -p satsim-environment --release --test it -- msis_cost --ignored --nocapture`.
#[test]
#[ignore = "a timing, not a check"]
fn msis_cost() {
    use std::time::Instant;
    let epoch = parse_epoch("2026-03-20T06:00:00 UTC").unwrap();
    let msis = Msis::new(epoch, Drivers::default());
    let n = 200_000;
    let points: Vec<(f64, Vec3)> = (0..n)
        .map(|k| (k as f64 * 0.1, orbit(400e3, k as f64 * 0.1)))
        .collect();
    let start = Instant::now();
    let mut sum = 0.0;
    for (t, r) in points.iter().step_by(20) {
        sum += msis.density(*t, r).unwrap();
    }
    let direct = start.elapsed().as_secs_f64() / (n / 20) as f64;
    let mut track = MsisTrack::new(msis.clone(), 300.0);
    let start = Instant::now();
    for (t, r) in &points {
        sum += track.density(*t, r).unwrap();
    }
    let lattice = start.elapsed().as_secs_f64() / n as f64;
    println!(
        "direct {:.2} us a call; lattice {:.3} us a call over {:.0} s of orbit, {} evaluations ({sum:.3e})",
        direct * 1e6,
        lattice * 1e6,
        n as f64 * 0.1,
        track.evaluations()
    );
}
