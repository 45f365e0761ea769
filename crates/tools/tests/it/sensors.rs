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
    deploy_in_orbit_edited(duration, extra, |text| text)
}

/// [`deploy_in_orbit`] with its text passed through `edit` first.
fn deploy_in_orbit_edited(
    duration: f64,
    extra: &str,
    edit: impl FnOnce(String) -> String,
) -> Scene {
    let path = example("scenes/deploy_in_orbit.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("duration = 600.0"));
    let text = text.replacen("duration = 600.0", &format!("duration = {duration}"), 1);
    let text = edit(text) + extra;
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

/// [`deploy_in_orbit`] on RK4 at 0.01 s, a fixed step that every sample period of
/// [`DEPLOY_SENSORS`] is a whole number of: where a sample leaves the steps as they were
/// (an adaptive method's steps land on the samples, which changes the trajectory within its
/// error, as the guide says).
fn deploy_in_orbit_fixed_step(duration: f64, extra: &str) -> Scene {
    deploy_in_orbit_edited(duration, extra, |text| {
        let adaptive = "method = \"dop853\"\nrtol = 1e-9\natol = 1e-9\n";
        assert!(text.contains(adaptive), "the scene's integrator changed");
        text.replacen(adaptive, "method = \"rk4\"\nstep = 0.01\n", 1)
    })
}

#[test]
fn sensors_do_not_change_the_trajectory_and_the_sun_sensor_sees_the_sun_outside_the_umbra() {
    let plain = run(&deploy_in_orbit_fixed_step(15.0, ""));
    let with = run(&deploy_in_orbit_fixed_step(15.0, DEPLOY_SENSORS));
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
        (format!("{gyro}bias = [0.0, 0.0, 0.0, 1.0]\n"), "bias", "`sensors.gyro.bias`: invalid length 4, expected an array of length 3"),
        (format!("{gyro}bias = [0.0, 0.0]\n"), "bias", "`sensors.gyro.bias`: invalid length 2, expected an array of length 3"),
        ("[sensors]\n[[sensors.coarse_sun]]\nname = \"c\"\nbody = \"bus\"\nperiod = 1.0\nnormal = [1.0, 0.0, 0.0, \"junk\"]\n".into(), "normal", "`sensors.coarse_sun.normal`: invalid length 4, expected an array of length 3"),
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

// ---- Contract section 17: misalignment, scale factor, quantisation, star-tracker exclusion,
// coarse Sun sensors, GPS receivers.

/// Rodrigues' formula (independently of the quaternions the sensors use): the rotation of
/// vector `r` (rad).
fn rodrigues(r: Vec3) -> nalgebra::Matrix3<f64> {
    let angle = r.norm();
    let k = r / angle;
    let kx = nalgebra::Matrix3::new(0.0, -k.z, k.y, k.z, 0.0, -k.x, -k.y, k.x, 0.0);
    nalgebra::Matrix3::identity() * angle.cos()
        + k * k.transpose() * (1.0 - angle.cos())
        + kx * angle.sin()
}

fn vec_of(t: &Trajectory, names: &[String], row: &[f64]) -> Vec3 {
    Vec3::new(
        row[col(t, &names[0])],
        row[col(t, &names[1])],
        row[col(t, &names[2])],
    )
}

fn attitude(t: &Trajectory, row: &[f64]) -> nalgebra::UnitQuaternion<f64> {
    let q = values(t, &["q_w", "q_x", "q_y", "q_z"], row);
    nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// Whether `x` is a whole multiple of `step` (to the rounding of the division).
fn multiple(x: f64, step: f64) -> bool {
    let k = x / step;
    (k - k.round()).abs() < 1e-9
}

#[test]
fn misalignment_scale_factor_and_quantization_appear_in_the_readings() {
    let m = [0.01, -0.02, 0.03];
    let s = [0.01, -0.02, 0.03];
    let sensors = format!(
        r#"
[sensors]
seed = 2
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.05
bias = [1e-3, 0.0, -2e-3]
scale_factor = {s:?}
misalignment = {m:?}
[[sensors.gyro]]
name = "scalar"
body = "bus"
period = 0.05
scale_factor = 0.02
[[sensors.gyro]]
name = "quant"
body = "bus"
period = 0.05
quantization = 1e-3
[[sensors.gyro]]
name = "noisy"
body = "bus"
period = 0.05
noise_density = 1e-3
quantization = 1e-3
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.05
misalignment = [0.0, 0.0, 1.5707963267948966]
[[sensors.star_tracker]]
name = "stq"
body = "bus"
period = 0.05
quantization = 1e-4
[[sensors.magnetometer]]
name = "mag"
body = "bus"
period = 0.05
misalignment = {m:?}
quantization = 1e-9
"#
    );
    let t = run(&parse(&orbit_scene_text(2.0, 0.05, &sensors)));
    let r = rodrigues(Vec3::from(m));
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (mut rounded_up, mut rounded_down) = (0, 0);
    for (i, row) in t.rows().enumerate() {
        let omega = vec_of(&t, &xyz("omega"), row);
        // (1 + s) ∘ (Rᵀ ω) + bias, in the misaligned axes.
        let want = (Vec3::repeat(1.0) + Vec3::from(s)).component_mul(&(r.transpose() * omega))
            + Vec3::new(1e-3, 0.0, -2e-3);
        let got = vec_of(&t, &xyz("gyro"), row);
        assert!((got - want).amax() < 1e-15, "row {i}: {got} against {want}");
        // A scalar scale factor: every axis, to the last bit.
        let got = vec_of(&t, &xyz("scalar"), row);
        for a in 0..3 {
            assert_eq!(got[a].to_bits(), (1.02 * omega[a]).to_bits(), "row {i}");
        }
        // Quantised: the truth rounded to the nearest multiple of the step.
        let got = vec_of(&t, &xyz("quant"), row);
        for a in 0..3 {
            assert!(multiple(got[a], 1e-3), "row {i}: {}", got[a]);
            assert!((got[a] - omega[a]).abs() <= 0.5e-3 + 1e-18, "row {i}");
            assert_eq!(got[a], (omega[a] / 1e-3).round() * 1e-3, "row {i}");
            if got[a].abs() > omega[a].abs() {
                rounded_up += 1;
            } else {
                rounded_down += 1;
            }
            assert!(multiple(vec_of(&t, &xyz("noisy"), row)[a], 1e-3), "row {i}");
        }
        // The star tracker: the attitude of the frame turned a quarter turn about z.
        let q = values(&t, &["q_w", "q_x", "q_y", "q_z"], row);
        let mut want = quat_mul(&[q[0], q[1], q[2], q[3]], &[h, 0.0, 0.0, h]);
        if want[0] < 0.0 {
            want = want.map(|v| -v);
        }
        let got = values(&t, &["st_q_w", "st_q_x", "st_q_y", "st_q_z"], row);
        for a in 0..4 {
            assert!(
                (got[a] - want[a]).abs() < 1e-15,
                "row {i}: {got:?} against {want:?}"
            );
        }
        // Its quantised components: the attitude's, rounded.
        let got = values(&t, &["stq_q_w", "stq_q_x", "stq_q_y", "stq_q_z"], row);
        let sign = if q[0] < 0.0 { -1.0 } else { 1.0 };
        for a in 0..4 {
            assert!(multiple(got[a], 1e-4), "row {i}");
            assert_eq!(got[a], (sign * q[a] / 1e-4).round() * 1e-4, "row {i}");
        }
        // The field in the misaligned axes, quantised to 1 nT.
        let b = vec_of(&t, &xyz("magnetic_field"), row);
        let want = r.transpose() * b;
        let got = vec_of(&t, &xyz("mag"), row);
        for a in 0..3 {
            assert!(multiple(got[a], 1e-9), "row {i}");
            assert!((got[a] - want[a]).abs() <= 0.5e-9 + 1e-20, "row {i}");
        }
    }
    assert!(
        rounded_up > 10 && rounded_down > 10,
        "{rounded_up} up, {rounded_down} down"
    );
}

/// A bus at rest at the epoch, on an orbit through the terminator (its position at a right
/// angle to the Sun), with `attitude` (body to inertial) and `sensors`.
fn pointing_scene(attitude: nalgebra::UnitQuaternion<f64>, sensors: &str) -> Scene {
    let (r, v) = terminator();
    pointing_scene_at(r, v, attitude, sensors)
}

/// [`pointing_scene`] at position `r` (m) and velocity `v` (m/s).
fn pointing_scene_at(
    r: Vec3,
    v: Vec3,
    attitude: nalgebra::UnitQuaternion<f64>,
    sensors: &str,
) -> Scene {
    let q = attitude.quaternion();
    parse(&format!(
        r#"epoch = "{EPOCH}"
duration = 1.0

[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 12.0, 0.0], [0.0, 0.0, 8.0]]

[initial]
base = {{ attitude = [{}, {}, {}, {}], angular_velocity = [0.0, 0.0, 0.0] }}

[orbit]
position = [{}, {}, {}]
velocity = [{}, {}, {}]

[integrator]
method = "rk4"
step = 0.01

[output]
every = 0.1
plots = false
view = false

{sensors}"#,
        q.w, q.i, q.j, q.k, r.x, r.y, r.z, v.x, v.y, v.z
    ))
}

/// The position (m) and velocity (m/s) of [`pointing_scene`]: 500 km up, at a right angle to
/// the Sun, moving towards it.
fn terminator() -> (Vec3, Vec3) {
    let s = sun_position(parse_epoch(EPOCH).unwrap(), 0.0).normalize();
    let r = s.cross(&Vec3::z()).normalize() * (satsim_environment::R_EARTH + 500e3);
    (r, s * (3.986004418e14 / r.norm()).sqrt())
}

fn turn(axis: Vec3, deg: f64) -> nalgebra::UnitQuaternion<f64> {
    nalgebra::UnitQuaternion::from_scaled_axis(axis.normalize() * deg.to_radians())
}

#[test]
fn a_star_tracker_is_flagged_invalid_near_the_sun_and_the_earths_limb() {
    let (r, _) = terminator();
    let to_sun = (sun_position(parse_epoch(EPOCH).unwrap(), 0.0) - r).normalize();
    // The boresight (body +z) on the Sun.
    let q = nalgebra::UnitQuaternion::rotation_between(&Vec3::z(), &to_sun).unwrap();
    // A tracker turned 40° off it, away from the Earth: its misalignment about the body
    // axis that is, inertially, to_sun × r.
    let axis = q.inverse_transform_vector(&to_sun.cross(&r)).normalize();
    let m40 = axis * 40f64.to_radians();
    let sensors = format!(
        r#"
[sensors]
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.1
exclusion_deg = {{ sun = 30.0, earth = 20.0 }}
[[sensors.star_tracker]]
name = "off"
body = "bus"
period = 0.1
misalignment = [{}, {}, {}]
exclusion_deg = {{ sun = 30.0, earth = 20.0 }}
[[sensors.star_tracker]]
name = "earth_only"
body = "bus"
period = 0.1
exclusion_deg = {{ earth = 20.0 }}
[[sensors.star_tracker]]
name = "plain"
body = "bus"
period = 0.1
"#,
        m40.x, m40.y, m40.z
    );
    let scene = pointing_scene(q, &sensors);
    let t = run(&scene);
    let c = &t.columns;
    let at = |n: &str| c.iter().position(|x| x == n);
    // `_valid` after the quaternion, only with exclusion angles.
    assert_eq!(at("st_valid"), at("st_q_z").map(|i| i + 1));
    assert_eq!(at("off_valid"), at("off_q_z").map(|i| i + 1));
    assert!(at("earth_only_valid").is_some() && at("plain_valid").is_none());
    let q40 = quat_mul(&[q.w, q.i, q.j, q.k], &{
        let r = turn(axis, 40.0);
        [r.w, r.i, r.j, r.k]
    });
    for row in t.rows() {
        // On the Sun: invalid from the start, so the held reading is the initial zeros.
        assert_eq!(row[col(&t, "st_valid")], 0.0);
        assert_eq!(
            values(&t, &["st_q_w", "st_q_x", "st_q_y", "st_q_z"], row),
            [0.0; 4]
        );
        // 40° off: valid, the turned frame's attitude.
        assert_eq!(row[col(&t, "off_valid")], 1.0);
        let got = values(&t, &["off_q_w", "off_q_x", "off_q_y", "off_q_z"], row);
        let sign = q40[0].signum();
        for a in 0..4 {
            assert!(
                (got[a] - sign * q40[a]).abs() < 1e-12,
                "{got:?} against {q40:?}"
            );
        }
        // The Sun is 90° from the nadir: the Earth's exclusion alone leaves it valid.
        assert_eq!(row[col(&t, "earth_only_valid")], 1.0);
    }
    // measure(): the validity as an entry after the tracker's; none for `plain`.
    let mut s = SceneStepper::with_seed(&scene, None, "t", None).unwrap();
    s.advance(0.25).unwrap();
    let m = s.measure().unwrap();
    let names: Vec<&str> = m.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "st",
            "st_valid",
            "off",
            "off_valid",
            "earth_only",
            "earth_only_valid",
            "plain"
        ]
    );
    assert_eq!(m[0].1, [0.0; 4]);
    assert_eq!(m[1].1, [0.0]);
    assert_eq!(m[3].1, [1.0]);
    assert_eq!(m[2].1.len(), 4);
    assert_eq!(m[6].1.len(), 4);

    // The Earth's limb: the boresight (ρ + 10)° from the nadir, at a right angle to the Sun
    // (turned about the Sun's direction): excluded by `earth = 20`; turned 20° further by a
    // misalignment, (ρ + 30)°: valid.
    let nadir = -r.normalize();
    let rho = (satsim_environment::R_EARTH / r.norm()).asin().to_degrees();
    let bore = turn(to_sun, rho + 10.0) * nadir;
    // (to_sun is seen from the spacecraft: 5e-5 rad off the perpendicular to the nadir.)
    assert!(bore.dot(&to_sun).abs() < 1e-4);
    let q = nalgebra::UnitQuaternion::rotation_between(&Vec3::z(), &bore).unwrap();
    let m20 = q.inverse_transform_vector(&to_sun).normalize() * 20f64.to_radians();
    let sensors = format!(
        "[sensors]\n[[sensors.star_tracker]]\nname = \"st\"\nbody = \"bus\"\nperiod = 0.1\nexclusion_deg = {{ sun = 30.0, earth = 20.0 }}\n[[sensors.star_tracker]]\nname = \"off\"\nbody = \"bus\"\nperiod = 0.1\nexclusion_deg = {{ sun = 30.0, earth = 20.0 }}\nmisalignment = [{}, {}, {}]\n[[sensors.star_tracker]]\nname = \"near\"\nbody = \"bus\"\nperiod = 0.1\nexclusion_deg = {{ earth = 9.0 }}\n",
        m20.x, m20.y, m20.z
    );
    let t = run(&pointing_scene(q, &sensors));
    for row in t.rows() {
        assert_eq!(row[col(&t, "st_valid")], 0.0, "{}° from the limb", 10.0);
        assert_eq!(row[col(&t, "off_valid")], 1.0, "{}° from the limb", 30.0);
        assert_eq!(
            row[col(&t, "near_valid")],
            1.0,
            "10° from the limb, 9° excluded"
        );
    }
}

#[test]
fn coarse_sun_sensors_follow_the_cosine_in_their_field_of_view_and_see_the_albedo() {
    let normals = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let mut sensors = String::from("[sensors]\n");
    for (k, n) in normals.iter().enumerate() {
        sensors += &format!(
            "[[sensors.coarse_sun]]\nname = \"css{k}\"\nbody = \"bus\"\nperiod = 0.1\nnormal = {n:?}\nfov_deg = 60.0\nscale = 2.0\n[[sensors.coarse_sun]]\nname = \"alb{k}\"\nbody = \"bus\"\nperiod = 0.1\nnormal = {n:?}\nalbedo = true\n"
        );
    }
    // Into the Earth's shadow and out (deploy_in_orbit), and over the day side, 45° from the
    // sub-solar point, the body turned.
    let epoch = parse_epoch(EPOCH).unwrap();
    let s = sun_position(epoch, 0.0).normalize();
    let c = s.cross(&Vec3::z()).normalize();
    let r = (s + c).normalize() * (satsim_environment::R_EARTH + 500e3);
    let v = (c - s).normalize() * (3.986004418e14 / r.norm()).sqrt();
    let q = nalgebra::UnitQuaternion::from_scaled_axis(Vec3::new(0.3, -0.5, 0.7));
    let (mut inside, mut outside, mut dark, mut earth) = (0, 0, 0, 0);
    for t in [
        run(&deploy_in_orbit(15.0, &sensors)),
        run(&pointing_scene_at(r, v, q, &sensors)),
    ] {
        for row in t.rows() {
            let time = row[0];
            let r = vec_of(&t, &xyz("orbit_r"), row);
            let q = attitude(&t, row);
            let sun = sun_position(epoch, time);
            // The scene's conical shadow (its `shadow` column is the last evaluation's, not the
            // row's).
            let lit = satsim_environment::shadow::shadow_fraction(
                satsim_environment::shadow::ShadowModel::Conical,
                &r,
                &sun,
            );
            let s = q.inverse_transform_vector(&(sun - r).normalize());
            let nadir = q.inverse_transform_vector(&(-r.normalize()));
            let day = sun.normalize().dot(&r.normalize()).max(0.0);
            for (k, n) in normals.iter().enumerate() {
                let n = Vec3::from(*n);
                let c = n.dot(&s);
                let got = row[col(&t, &format!("css{k}"))];
                let want = if c >= 60f64.to_radians().cos() {
                    inside += usize::from(lit > 0.0);
                    2.0 * lit * c
                } else {
                    outside += usize::from(lit > 0.0 && c > 0.0);
                    0.0
                };
                assert!(
                    (got - want).abs() < 1e-12,
                    "t = {time}, css{k}: {got} against {want}"
                );
                if lit == 0.0 {
                    assert_eq!(got, 0.0);
                    dark += 1;
                }
                // With the albedo: the whole hemisphere's cosine, plus the Earth's light.
                let albedo = 0.3
                    * day
                    * satsim_spacecraft::sensors::coarse_sun::sphere_view_factor(
                        n.dot(&nadir),
                        r.norm() / satsim_environment::R_EARTH,
                    );
                earth += usize::from(albedo > 0.0);
                let want = lit * c.max(0.0) + albedo;
                let got = row[col(&t, &format!("alb{k}"))];
                assert!(
                    (got - want).abs() < 1e-12,
                    "t = {time}, alb{k}: {got} against {want}"
                );
            }
        }
    }
    assert!(
        inside > 5 && outside > 5 && dark > 5 && earth > 5,
        "{inside} {outside} {dark} {earth}"
    );
}

#[test]
fn a_gps_receiver_reads_the_orbit_with_the_stated_noise() {
    let (sp, sv, period) = (5.0, 0.05, 0.01);
    let sensors = format!(
        "[sensors]\nseed = 4\n[[sensors.gps]]\nname = \"gps\"\nbody = \"bus\"\nperiod = {period}\nnoise_position = {sp}\nnoise_velocity = {sv}\n[[sensors.gps]]\nname = \"exact\"\nbody = \"bus\"\nperiod = {period}\n"
    );
    let t = run(&parse(&orbit_scene_text(99.99, period, &sensors)));
    let rows: Vec<&[f64]> = t.rows().collect();
    let n = rows.len() as f64;
    assert_eq!(rows.len(), 10_000);
    let pos = xyz("orbit_r");
    let vel = xyz("orbit_v");
    let cols = |prefix: &str, v: &str| ["x", "y", "z"].map(|a| format!("{prefix}_{v}{a}"));
    for a in 0..3 {
        for (what, truth, sigma, v) in [("position", &pos, sp, ""), ("velocity", &vel, sv, "v")] {
            let noisy = &cols("gps", v)[a];
            let exact = &cols("exact", v)[a];
            let e: Vec<f64> = rows
                .iter()
                .map(|r| {
                    assert_eq!(r[col(&t, exact)].to_bits(), r[col(&t, &truth[a])].to_bits());
                    r[col(&t, noisy)] - r[col(&t, &truth[a])]
                })
                .collect();
            // Mean 0 and σ within 4 standard errors (σ/√n and σ/√(2n)).
            let (m, s) = (mean(&e), std_dev(&e));
            assert!(m.abs() < 4.0 * sigma / n.sqrt(), "{what} {a}: mean {m}");
            assert!(
                (s / sigma - 1.0).abs() < 4.0 / (2.0 * n).sqrt(),
                "{what} {a}: std {s}, expected {sigma}"
            );
        }
    }
    let m = SceneStepper::with_seed(
        &parse(&orbit_scene_text(1.0, 0.1, &sensors)),
        None,
        "t",
        None,
    )
    .unwrap()
    .measure()
    .unwrap();
    assert_eq!(m[0].0, "gps");
    assert_eq!(m[0].1.len(), 6);
    let at = |n: &str| t.columns.iter().position(|c| c == n).unwrap();
    assert_eq!(
        (at("gps_x") + 1..at("gps_x") + 6)
            .map(|i| t.columns[i].as_str())
            .collect::<Vec<_>>(),
        ["gps_y", "gps_z", "gps_vx", "gps_vy", "gps_vz"]
    );
}

#[test]
fn bad_new_sensor_input_is_an_error_naming_the_file_and_line() {
    let gyro = "[sensors]\n[[sensors.gyro]]\nname = \"g\"\nbody = \"bus\"\nperiod = 0.1\n";
    let st = "[sensors]\n[[sensors.star_tracker]]\nname = \"s\"\nbody = \"bus\"\nperiod = 0.1\n";
    let css = "[sensors]\n[[sensors.coarse_sun]]\nname = \"c\"\nbody = \"bus\"\nperiod = 0.1\n";
    let gps = "[sensors]\n[[sensors.gps]]\nname = \"p\"\nbody = \"bus\"\nperiod = 0.1\n";
    let cases: Vec<(String, &str, &str)> = vec![
        (format!("{gyro}misalignment = [0.1, nan, 0.0]\n"), "misalignment", "rotation vector"),
        (format!("{gyro}misalignment = [4.0, 0.0, 0.0]\n"), "misalignment", "half a turn"),
        (format!("{gyro}quantization = 0.0\n"), "quantization", "> 0"),
        (format!("{gyro}scale_factor = -1.0\n"), "scale_factor", "> -1"),
        (format!("{gyro}scale_factor = [0.1, inf, 0.0]\n"), "scale_factor", "> -1"),
        (format!("{gyro}scale_factor = [0.1, 0.2]\n"), "scale_factor", "array of three"),
        (format!("{st}exclusion_deg = {{ moon = 3.0 }}\n"), "exclusion_deg", "moon"),
        (format!("{st}exclusion_deg = {{}}\n"), "exclusion_deg", "needs `sun` or `earth`"),
        (format!("{st}exclusion_deg = {{ sun = 200.0 }}\n"), "exclusion_deg", "[0, 180]"),
        (format!("{st}exclusion_deg = {{ earth = -1.0 }}\n"), "exclusion_deg", ">= 0"),
        (format!("{st}quantization = -1e-4\n"), "quantization", "> 0"),
        (format!("{css}normal = [0.0, 0.0, 0.0]\n"), "normal", "not all zero"),
        (format!("{css}normal = [0.0, 0.0, 1.0]\nfov_deg = 100.0\n"), "fov_deg", "(0, 90]"),
        (format!("{css}normal = [0.0, 0.0, 1.0]\nscale = 0.0\n"), "scale", "> 0"),
        (format!("{css}normal = [0.0, 0.0, 1.0]\nnoise = -0.1\n"), "noise", ">= 0"),
        (format!("{css}normal = [0.0, 0.0, 1.0]\nalbedo = 0.3\n"), "albedo", "bool"),
        (format!("{gps}noise_position = -1.0\n"), "noise_position", ">= 0"),
        (format!("{gps}noise_velocity = nan\n"), "noise_velocity", ">= 0"),
        (format!("{gps}misalignment = [0.0, 0.0, 0.1]\n"), "misalignment", "unknown"),
        ("[sensors]\n[[sensors.coarse_sun]]\nname = \"omega_x\"\nbody = \"bus\"\nperiod = 1.0\nnormal = [1.0, 0.0, 0.0]\n".into(), "\"omega_x\"", "already has"),
    ];
    for (sensors, at, needle) in cases {
        let text = orbit_scene_text(1.0, 0.1, &sensors);
        let err = error_of(&text);
        let start = text.find("[sensors]").unwrap();
        let at = start + text[start..].rfind(at).unwrap();
        let line = text[..at].matches('\n').count() + 1;
        assert!(err.contains(needle), "`{needle}` not in: {err}");
        assert!(
            err.contains(&format!("bad.toml:{line}")),
            "line {line} not in: {err}"
        );
    }
    // A coarse Sun sensor without its normal; the Sun's exclusion and a coarse Sun sensor
    // without the epoch; a GPS receiver without an orbit.
    let err = error_of(&orbit_scene_text(1.0, 0.1, css));
    assert!(err.contains("normal") && err.contains("bad.toml:"), "{err}");
    let no_epoch = |s: &str| {
        orbit_scene_text(1.0, 0.1, s)
            .replacen(&format!("epoch = \"{EPOCH}\"\n"), "", 1)
            .replacen("[effects.magnetic]\nfield = \"dipole\"\n", "", 1)
    };
    let text = no_epoch(&format!("{st}exclusion_deg = {{ sun = 30.0 }}\n"));
    let err = error_of(&text);
    assert!(err.contains("epoch"), "{err}");
    assert!(
        err.contains(&format!("bad.toml:{}", line_of(&text, "exclusion_deg"))),
        "{err}"
    );
    let err = error_of(&no_epoch(&format!("{css}normal = [0.0, 0.0, 1.0]\n")));
    assert!(err.contains("epoch") && err.contains("coarse_sun"), "{err}");
    let text = orbit_scene_text(1.0, 0.1, gps)
        .replacen("[orbit]\naltitude = 500e3\ninclination_deg = 51.6\n", "", 1)
        .replacen("[effects.magnetic]\nfield = \"dipole\"\n", "", 1);
    let err = error_of(&text);
    assert!(err.contains("[orbit]") && err.contains("gps"), "{err}");
    let text = orbit_scene_text(
        1.0,
        0.1,
        &format!("{st}exclusion_deg = {{ earth = 10.0 }}\n"),
    )
    .replacen("[orbit]\naltitude = 500e3\ninclination_deg = 51.6\n", "", 1)
    .replacen("[effects.magnetic]\nfield = \"dipole\"\n", "", 1);
    let err = error_of(&text);
    assert!(err.contains("[orbit]"), "{err}");
    assert!(
        err.contains(&format!("bad.toml:{}", line_of(&text, "exclusion_deg"))),
        "{err}"
    );
}

#[test]
fn the_estimator_skips_the_readings_of_an_excluded_star_tracker() {
    let (r, _) = terminator();
    let to_sun = (sun_position(parse_epoch(EPOCH).unwrap(), 0.0) - r).normalize();
    let q = nalgebra::UnitQuaternion::rotation_between(&Vec3::z(), &to_sun).unwrap();
    let scene = |exclusion: &str| {
        let sensors = format!(
            "[sensors]\n[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 0.1\nnoise_density = 1e-6\n[[sensors.star_tracker]]\nname = \"st\"\nbody = \"bus\"\nperiod = 0.1\nnoise_arcsec = [5.0, 5.0, 40.0]\n{exclusion}\n[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = \"st\"\n"
        );
        run(&pointing_scene(q, &sensors))
    };
    // The boresight on the Sun: every reading excluded, the filter never starts (no
    // estimate: zeros).
    let t = scene("exclusion_deg = { sun = 30.0 }");
    for row in t.rows() {
        assert_eq!(row[col(&t, "st_valid")], 0.0);
        assert_eq!(
            values(&t, &["est_q_w", "est_q_x", "est_q_y", "est_q_z"], row),
            [0.0; 4]
        );
    }
    // The Earth's exclusion only (the boresight 90° from the nadir): the same readings
    // valid, the filter starts and follows them.
    let t = scene("exclusion_deg = { earth = 20.0 }");
    for row in t.rows() {
        assert_eq!(row[col(&t, "st_valid")], 1.0);
        // Within a milliradian of the truth (the tracker's noise: 40 arc seconds about z).
        let est = values(&t, &["est_q_w", "est_q_x", "est_q_y", "est_q_z"], row);
        let q = values(&t, &["q_w", "q_x", "q_y", "q_z"], row);
        let dot: f64 = est.iter().zip(&q).map(|(a, b)| a * b).sum();
        assert!(dot.abs() > (0.5e-3f64).cos(), "{est:?} against {q:?}");
    }
}
