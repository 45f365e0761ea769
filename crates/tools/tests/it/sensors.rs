//! Sensors (`[sensors]`, `satsim_spacecraft::sensors`): without noise the readings are the
//! truth of the same rows bit for bit; the noise has the stated statistics over 10^4
//! samples; the Sun sensor sees the Sun outside the umbra only; seeds reproduce and separate
//! readings, a campaign's runs draw their own; sensors leave the trajectory unchanged to the
//! last bit; bad input is an error naming the file and line.

use crate::common::example;
use satsim_environment::parse_epoch;
use satsim_environment::sun::sun_position;
use satsim_spacecraft::effects::quat_mul;
use satsim_spacecraft::sensors::star_tracker::ARCSEC;
use satsim_tools::api::{Trajectory, run_scene};
use satsim_tools::campaign::Campaign;
use satsim_tools::scene::Scene;
use satsim_tools::stepping::SceneStepper;
use satsim_tree::spatial::Vec3;
use std::path::Path;

const EPOCH: &str = "2026-03-20T12:00:00 UTC";

/// A spinning rigid bus on a 500 km, 51.6° orbit in the dipole field, RK4 at 0.01 s, with
/// `sensors` appended (a `[sensors]` table).
fn orbit_scene_text(duration: f64, every: f64, sensors: &str) -> String {
    format!(
        r#"epoch = "{EPOCH}"
duration = {duration}

[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 12.0, 0.0], [0.0, 0.0, 8.0]]

[initial]
base = {{ attitude = [0.9, 0.1, -0.3, 0.3], angular_velocity = [0.05, -0.02, 0.03] }}

[orbit]
altitude = 500e3
inclination_deg = 51.6

[integrator]
method = "rk4"
step = 0.01

[output]
every = {every}
plots = false
view = false

[effects.magnetic]
field = "dipole"

{sensors}"#
    )
}

fn parse(text: &str) -> Scene {
    Scene::parse(text, Path::new("sensors.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn run(scene: &Scene) -> Trajectory {
    run_scene(scene, || false).unwrap()
}

fn col(t: &Trajectory, name: &str) -> usize {
    t.columns
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column `{name}`"))
}

fn values(t: &Trajectory, names: &[&str], row: &[f64]) -> Vec<f64> {
    names.iter().map(|n| row[col(t, n)]).collect()
}

fn xyz(prefix: &str) -> [String; 3] {
    ["x", "y", "z"].map(|a| format!("{prefix}_{a}"))
}

fn std_dev(x: &[f64]) -> f64 {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

#[test]
fn without_noise_the_readings_are_the_truth_of_their_rows() {
    let sensors = r#"
[sensors]
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.05
bias = [1e-3, 0.0, -2e-3]
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.05
[[sensors.magnetometer]]
name = "mag"
body = "bus"
period = 0.05
"#;
    // Rows every step: the rows between samples hold the reading last taken.
    let t = run(&parse(&orbit_scene_text(2.0, 0.01, sensors)));
    let rows: Vec<&[f64]> = t.rows().collect();
    assert_eq!(rows.len(), 201);
    let omega = xyz("omega");
    let field = xyz("magnetic_field");
    let q = ["q_w", "q_x", "q_y", "q_z"];
    let bias = [1e-3, 0.0, -2e-3];
    for (i, row) in rows.iter().enumerate() {
        // The sample this row holds: the last at or before it (every 5th row).
        let s = rows[i - i % 5];
        for a in 0..3 {
            let truth = s[col(&t, &omega[a])] + bias[a];
            assert_eq!(
                row[col(&t, &xyz("gyro")[a])].to_bits(),
                truth.to_bits(),
                "row {i}"
            );
            let b = s[col(&t, &field[a])];
            assert_eq!(
                row[col(&t, &xyz("mag")[a])].to_bits(),
                b.to_bits(),
                "row {i}"
            );
        }
        // The quaternion with w >= 0 of the row's attitude.
        let truth: Vec<f64> = q.iter().map(|c| s[col(&t, c)]).collect();
        let sign = if truth[0] < 0.0 { -1.0 } else { 1.0 };
        let got = values(&t, &["st_q_w", "st_q_x", "st_q_y", "st_q_z"], row);
        for a in 0..4 {
            assert_eq!(got[a].to_bits(), (sign * truth[a]).to_bits(), "row {i}");
        }
    }
    // The body turns: the held readings differ from the row's truth between samples.
    let r = rows[3];
    assert_ne!(r[col(&t, "gyro_x")], r[col(&t, "omega_x")] + 1e-3);
}

#[test]
fn noise_statistics_over_ten_thousand_samples() {
    let (nd, walk, arcsec, mag_noise, period) = (2e-4, 5e-4, [5.0, 5.0, 40.0], 3e-8, 0.01);
    let sensors = format!(
        r#"
[sensors]
seed = 11
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = {period}
noise_density = {nd}
[[sensors.gyro]]
name = "drift"
body = "bus"
period = {period}
bias_walk = {walk}
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = {period}
noise_arcsec = {arcsec:?}
[[sensors.magnetometer]]
name = "mag"
body = "bus"
period = {period}
noise = {mag_noise}
"#
    );
    let t = run(&parse(&orbit_scene_text(99.99, period, &sensors)));
    let rows: Vec<&[f64]> = t.rows().collect();
    assert_eq!(rows.len(), 10_000);
    let within = |got: f64, want: f64, what: &str| {
        assert!(
            (got / want - 1.0).abs() < 0.05,
            "{what}: std {got}, expected {want}"
        );
    };
    for a in 0..3 {
        let err = |sensor: &str, truth: &str| -> Vec<f64> {
            rows.iter()
                .map(|r| r[col(&t, &xyz(sensor)[a])] - r[col(&t, &xyz(truth)[a])])
                .collect()
        };
        // Gyro white noise: N(0, noise_density / sqrt(period)), zero mean.
        let w = err("gyro", "omega");
        let sigma = nd / period.sqrt();
        within(std_dev(&w), sigma, "gyro white noise");
        assert!(
            mean(&w).abs() < 4.0 * sigma / 100.0,
            "gyro mean {}",
            mean(&w)
        );
        // Bias walk: the per-sample increments are N(0, bias_walk sqrt(period)).
        let b = err("drift", "omega");
        assert_eq!(b[0], 0.0, "the first reading carries the initial bias");
        let steps: Vec<f64> = b.windows(2).map(|p| p[1] - p[0]).collect();
        within(std_dev(&steps), walk * period.sqrt(), "gyro bias walk");
        // Magnetometer: N(0, noise) about the field.
        let m = err("mag", "magnetic_field");
        within(std_dev(&m), mag_noise, "magnetometer noise");
        assert!(mean(&m).abs() < 4.0 * mag_noise / 100.0);
    }
    // Star tracker: the error rotation q_true⁻¹ ⊗ q_measured, about the body's axes.
    let mut err = [Vec::new(), Vec::new(), Vec::new()];
    for r in &rows {
        let q = values(&t, &["q_w", "q_x", "q_y", "q_z"], r);
        let m = values(&t, &["st_q_w", "st_q_x", "st_q_y", "st_q_z"], r);
        assert!(m[0] >= 0.0);
        let d = quat_mul(&[q[0], -q[1], -q[2], -q[3]], &[m[0], m[1], m[2], m[3]]);
        let s = d[0].signum();
        for a in 0..3 {
            err[a].push(2.0 * s * d[a + 1]);
        }
    }
    for a in 0..3 {
        within(std_dev(&err[a]), arcsec[a] * ARCSEC, "star tracker");
    }
}

/// `deploy_in_orbit.toml` cut to `duration`, with `extra` appended.
fn deploy_in_orbit(duration: f64, extra: &str) -> Scene {
    let path = example("scenes/deploy_in_orbit.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("duration = 600.0"));
    let text = text.replacen("duration = 600.0", &format!("duration = {duration}"), 1) + extra;
    Scene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

const DEPLOY_SENSORS: &str = r#"
[sensors]
seed = 3
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.1
noise_density = 1e-5
bias_walk = 1e-7
[[sensors.star_tracker]]
name = "st"
body = "panel1"
period = 0.5
noise_arcsec = [5.0, 5.0, 40.0]
[[sensors.sun_sensor]]
name = "sun"
body = "bus"
period = 0.25
[[sensors.magnetometer]]
name = "mag"
body = "panel3"
period = 0.1
noise = 1e-8
"#;

#[test]
fn sensors_do_not_change_the_trajectory_and_the_sun_sensor_sees_the_sun_outside_the_umbra() {
    let plain = run(&deploy_in_orbit(15.0, ""));
    let with = run(&deploy_in_orbit(15.0, DEPLOY_SENSORS));
    assert_eq!(plain.n_rows(), with.n_rows());
    for (c, name) in plain.columns.iter().enumerate() {
        let k = col(&with, name);
        for (i, (a, b)) in plain.rows().zip(with.rows()).enumerate() {
            assert_eq!(a[c].to_bits(), b[k].to_bits(), "`{name}` at row {i}");
        }
    }
    // The Sun sensor (period 0.25, rows every second: each row holds its own sample).
    let epoch = parse_epoch(EPOCH).unwrap();
    let (mut dark, mut lit) = (0, 0);
    for row in with.rows() {
        let t = row[0];
        let s = Vec3::from_iterator(values(&with, &["sun_x", "sun_y", "sun_z"], row));
        if row[col(&with, "shadow")] == 0.0 {
            assert_eq!(s, Vec3::zeros(), "t = {t}: umbra");
            dark += 1;
            continue;
        }
        lit += 1;
        let r = Vec3::from_iterator(values(
            &with,
            &xyz("orbit_r").each_ref().map(|s| s.as_str()),
            row,
        ));
        let q = values(&with, &["q_w", "q_x", "q_y", "q_z"], row);
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q[0], q[1], q[2], q[3],
        ));
        let want = q.inverse_transform_vector(&(sun_position(epoch, t) - r).normalize());
        assert!((s - want).norm() < 1e-12, "t = {t}: {s} against {want}");
    }
    // The run starts in the umbra (t < 3 s) and ends in sunlight.
    assert!(dark >= 3 && lit >= 4, "{dark} rows dark, {lit} lit");
}

#[test]
fn seeds_reproduce_and_separate_the_readings() {
    let gyro = |seed: &str, more: &str| {
        format!(
            "[sensors]\n{seed}\n[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 0.1\nnoise_density = 1e-4\nbias_walk = 1e-5\n{more}"
        )
    };
    let readings = |text: &str| -> Vec<u64> {
        let t = run(&parse(&orbit_scene_text(2.0, 0.1, text)));
        t.rows()
            .flat_map(|r| xyz("gyro").map(|c| r[col(&t, &c)].to_bits()))
            .collect()
    };
    let a = readings(&gyro("seed = 5", ""));
    assert_eq!(
        a,
        readings(&gyro("seed = 5", "")),
        "same seed, same readings"
    );
    assert_ne!(
        a,
        readings(&gyro("seed = 6", "")),
        "another seed, other readings"
    );
    assert_eq!(
        readings(&gyro("", "")),
        readings(&gyro("seed = 0", "")),
        "default 0"
    );
    // Another sensor after it draws from its own stream: the gyro's readings stay.
    let more =
        "[[sensors.gyro]]\nname = \"other\"\nbody = \"bus\"\nperiod = 0.03\nnoise_density = 1e-3\n";
    assert_eq!(a, readings(&gyro("seed = 5", more)));

    // The stepping API's seed replaces the scene's; measure() is the row's reading.
    let scene = parse(&orbit_scene_text(2.0, 0.1, &gyro("seed = 1", "")));
    let mut s = SceneStepper::with_seed(&scene, None, "t", Some(5)).unwrap();
    let m0 = s.measure().unwrap();
    assert_eq!(m0.len(), 1);
    assert_eq!(m0[0].0, "gyro");
    let got: Vec<u64> = m0[0].1.iter().map(|v| v.to_bits()).collect();
    assert_eq!(got, a[..3], "the first reading, at the start");
    s.advance(0.35).unwrap();
    // At 0.35 s the reading is the one taken at 0.3 s (the fourth).
    let m = s.measure().unwrap();
    let got: Vec<u64> = m[0].1.iter().map(|v| v.to_bits()).collect();
    assert_eq!(got, a[9..12]);
    let row = s.row().unwrap();
    let cols = s.columns().to_vec();
    for (k, c) in xyz("gyro").iter().enumerate() {
        let i = cols.iter().position(|n| n == c).unwrap();
        assert_eq!(row[i].to_bits(), got[k]);
    }
}

#[test]
fn a_campaigns_runs_draw_their_own_noise_and_each_is_its_drawn_scene() {
    let sensors = "[sensors]\nseed = 1\n[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 0.1\nnoise_density = 1e-4\n\n[campaign]\nruns = 3\nseed = 9\n[[campaign.disperse]]\nkey = \"model.body.0.mass\"\nnormal = { sigma = 1.0 }\n";
    let text = orbit_scene_text(1.0, 0.1, sensors);
    let c = Campaign::parse(&text, Path::new("campaign.toml")).unwrap_or_else(|e| panic!("{e}"));
    let g = c.columns.iter().position(|n| n == "gyro_x").unwrap() - 1;
    let (r0, r1) = (c.run_one(0), c.run_one(1));
    let (s0, s1) = (r0.outcome.unwrap(), r1.outcome.unwrap());
    assert_ne!(s0.last[g], s1.last[g], "two runs, two noise streams");
    assert_eq!(
        s0.last,
        c.run_one(0).outcome.unwrap().last,
        "a rerun is the same"
    );
    assert_ne!(c.sensor_seed(0), c.sensor_seed(1));
    // Run 1 is `satsim run` of its drawn scene, whose text carries its seed.
    let drawn = c.run_text(1, &c.draw(1));
    assert!(drawn.contains(&format!("seed = {}", c.sensor_seed(1))));
    let t = run(&parse(&drawn));
    let last = t.rows().last().unwrap();
    assert_eq!(&last[1..], &s1.last[..]);
}

/// Every order of the four sensor kinds in the file gives the same columns, and a campaign's
/// drawn runs (whose scene text is rewritten, tables in another order) the nominal scene's:
/// the columns and noise streams follow the kinds, not the text.
#[test]
fn every_order_of_the_sensor_kinds_gives_one_campaign() {
    let blocks = [
        "[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 0.1\nnoise_density = 1e-4\n",
        "[[sensors.star_tracker]]\nname = \"st\"\nbody = \"bus\"\nperiod = 0.1\nnoise_arcsec = [5.0, 5.0, 40.0]\n",
        "[[sensors.sun_sensor]]\nname = \"sun\"\nbody = \"bus\"\nperiod = 0.1\nnoise = 1e-3\n",
        "[[sensors.magnetometer]]\nname = \"mag\"\nbody = \"bus\"\nperiod = 0.1\nnoise = 1e-8\n",
    ];
    let campaign = "\n[campaign]\nruns = 2\nseed = 4\n[[campaign.disperse]]\nkey = \"model.body.0.mass\"\nnormal = { sigma = 1.0 }\n";
    let mut first: Option<(Vec<String>, Vec<u64>)> = None;
    let mut orders = 0;
    for a in 0..4 {
        for b in 0..4 {
            for c in 0..4 {
                if a == b || a == c || b == c {
                    continue;
                }
                let d = (0..4).find(|x| ![a, b, c].contains(x)).unwrap();
                orders += 1;
                let sensors = format!(
                    "[sensors]\nseed = 1\n{}{}{}{}{campaign}",
                    blocks[a], blocks[b], blocks[c], blocks[d]
                );
                let text = orbit_scene_text(0.3, 0.1, &sensors);
                let cp = Campaign::parse(&text, Path::new("campaign.toml"))
                    .unwrap_or_else(|e| panic!("order {a}{b}{c}{d}: {e}"));
                let mut bits = Vec::new();
                for k in 0..2 {
                    let st = cp
                        .run_one(k)
                        .outcome
                        .unwrap_or_else(|e| panic!("order {a}{b}{c}{d}, run {k}: {e}"));
                    bits.extend(st.last.iter().map(|v| v.to_bits()));
                }
                let cols = cp.columns.clone();
                match &first {
                    None => first = Some((cols, bits)),
                    Some((c0, b0)) => {
                        assert_eq!(&cols, c0, "order {a}{b}{c}{d}: the columns");
                        assert_eq!(&bits, b0, "order {a}{b}{c}{d}: the runs' last rows");
                    }
                }
            }
        }
    }
    assert_eq!(orders, 24);
    let (cols, _) = first.unwrap();
    let at = |n: &str| cols.iter().position(|c| c == n).unwrap();
    assert!(at("gyro_x") < at("st_q_w") && at("st_q_w") < at("sun_x") && at("sun_x") < at("mag_x"));
}

fn error_of(text: &str) -> String {
    match Scene::parse(text, Path::new("bad.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// The 1-based line of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn bad_sensor_input_is_an_error_naming_the_file_and_line() {
    let gyro = "[sensors]\n[[sensors.gyro]]\nname = \"g\"\nbody = \"bus\"\nperiod = 0.1\n";
    let cases: Vec<(String, &str, &str)> = vec![
        (format!("{gyro}colour = 1\n"), "colour", "unknown key"),
        (gyro.replace("\"bus\"", "\"panel\""), "body = ", "unknown body `panel`"),
        (gyro.replace("0.1", "0.0"), "period", "> 0"),
        (gyro.replace("0.1", "nan"), "period", "> 0"),
        (gyro.replace("0.1", "-1.0"), "period", "> 0"),
        (format!("{gyro}noise_density = -1e-5\n"), "noise_density", ">= 0"),
        (format!("{gyro}[[sensors.star_tracker]]\nname = \"g\"\nbody = \"bus\"\nperiod = 1.0\n"), "name = \"g\"", "listed twice"),
        ("[sensors]\nseed = -1\n".into(), "seed", ">= 0"),
        ("[sensors]\n[[sensors.magnetometer]]\nname = \"omega\"\nbody = \"bus\"\nperiod = 1.0\nnoise = -1.0\n".into(), "noise", ">= 0"),
        ("[sensors]\n[[sensors.gyro]]\nname = \"omega\"\nbody = \"bus\"\nperiod = 1.0\n".into(), "\"omega\"", "already has"),
    ];
    for (sensors, at, needle) in cases {
        let text = orbit_scene_text(1.0, 0.1, &sensors);
        let err = error_of(&text);
        // The line of the last `at` (a line of the sensors part).
        let start = text.find("[sensors]").unwrap();
        let at = start + text[start..].rfind(at).unwrap();
        let line = text[..at].matches('\n').count() + 1;
        assert!(err.contains(needle), "`{needle}` not in: {err}");
        assert!(
            err.contains(&format!("bad.toml:{line}")),
            "line {line} not in: {err}"
        );
    }
    // A Sun sensor without an epoch, a magnetometer without the field: at their tables.
    let text = orbit_scene_text(
        1.0,
        0.1,
        "[sensors]\n[[sensors.sun_sensor]]\nname = \"s\"\nbody = \"bus\"\nperiod = 1.0\n",
    )
    .replacen(&format!("epoch = \"{EPOCH}\"\n"), "", 1)
    .replacen("[effects.magnetic]\nfield = \"dipole\"\n", "", 1);
    let err = error_of(&text);
    assert!(err.contains("epoch") && err.contains("bad.toml:"), "{err}");
    let text = orbit_scene_text(
        1.0,
        0.1,
        "[sensors]\n[[sensors.magnetometer]]\nname = \"m\"\nbody = \"bus\"\nperiod = 1.0\n",
    )
    .replacen("[effects.magnetic]\nfield = \"dipole\"\n", "", 1);
    let err = error_of(&text);
    let line = line_of(&text, "name = \"m\"");
    assert!(err.contains("[effects.magnetic]"), "{err}");
    assert!(
        err.contains(&format!("bad.toml:{line}"))
            || err.contains(&format!("bad.toml:{}", line - 1)),
        "{err}"
    );
}
