//! Built-in flight software (`[fsw]`, `satsim_spacecraft::fsw::Onboard`): the estimator in a
//! scene is the standalone MEKF on the same readings, bit for bit, and its error stays
//! within its 3σ; an estimator alone leaves the truth unchanged to the last bit; the nadir
//! reference is the orbital frame; the closed loop on the sensors (MEKF, guidance, PID on
//! the wheels) points the deploying satellite within the estimator's 3σ plus a small
//! margin, inertially and at nadir, as well as the truth-based controller or better; B-dot
//! on the magnetometer detumbles as fast as the truth-based B-dot; momentum dumping keeps
//! the wheels' momentum bounded where it grows without; bad input is an error naming the
//! file and line.

use crate::common::example;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use satsim_spacecraft::effects::OrbitState;
use satsim_spacecraft::fsw::{GyroModel, Mekf, MekfParams, Pid, attitude_error, gyro_mean};
use satsim_spacecraft::sensors::star_tracker::ARCSEC;
use satsim_spacecraft::sensors::{Kind, Sensors};
use satsim_tools::api::{Trajectory, run_scene};
use satsim_tools::campaign::Campaign;
use satsim_tools::scene::Scene;
use satsim_tools::scene_keys::Override;
use satsim_tools::stepping::SceneStepper;
use std::path::PathBuf;

/// The closed-loop example.
const POINTING: &str = "scenes/fsw_mekf_pointing.toml";

/// After the deployment (the panels latch by 10 s; the bus settles by 120 s).
const SETTLED: f64 = 150.0;

/// The controller's margin over the estimator's 3σ (rad): 10 arc seconds, what the loop adds
/// to the estimate's error (its response to the estimate's noise, the wheels' friction and
/// the gravity gradient).
const MARGIN: f64 = 10.0 * ARCSEC;

fn path_in_examples(name: &str) -> PathBuf {
    example("scenes").join(name)
}

fn parse(text: &str, name: &str) -> Scene {
    Scene::parse(text, &path_in_examples(name)).unwrap_or_else(|e| panic!("{e}"))
}

fn read(path: &str, sets: &[&str]) -> Scene {
    let o: Vec<Override> = sets.iter().map(|s| Override::parse(s).unwrap()).collect();
    Scene::read_with(example(path), &o).unwrap_or_else(|e| panic!("{e}"))
}

fn run(scene: &Scene) -> Trajectory {
    run_scene(scene, || false).unwrap_or_else(|e| panic!("{e}"))
}

fn col(t: &Trajectory, name: &str) -> usize {
    t.columns
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column `{name}`"))
}

fn get<const N: usize>(t: &Trajectory, row: &[f64], names: [&str; N]) -> [f64; N] {
    names.map(|n| row[col(t, n)])
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// fsw_in_the_loop.toml (the deploying satellite held by the truth-based controller, a 10 Hz
/// gyro and star tracker) for 120 s with rows every gyro sample, plus `fsw`.
fn in_the_loop(fsw: &str) -> Scene {
    let text = std::fs::read_to_string(example("scenes/fsw_in_the_loop.toml")).unwrap();
    let text = text
        .replacen("duration = 600.0", "duration = 120.0", 1)
        .replacen("every = 1.0", "every = 0.1", 1);
    parse(&format!("{text}\n{fsw}"), "fsw_in_the_loop.toml")
}

#[test]
fn the_estimator_is_the_standalone_mekf_on_the_same_readings_and_within_its_3_sigma() {
    let scene =
        in_the_loop("[fsw.estimator]\nkind = \"mekf\"\ngyro = \"gyro\"\nstar_tracker = \"st\"\n");
    let t = run(&scene);
    // The filter's noises are the gyro's.
    let sensors = scene.effects.get::<Sensors>().unwrap();
    let Kind::Gyro(g) = sensors.sensors()[0].kind() else {
        panic!("the first sensor is the gyro")
    };
    let Kind::StarTracker(st) = sensors.sensors()[1].kind() else {
        panic!("the second sensor is the star tracker")
    };
    assert_eq!(st.noise, [5.0 * ARCSEC, 5.0 * ARCSEC, 40.0 * ARCSEC]);
    let params = MekfParams {
        sigma_v: g.noise_density,
        sigma_u: g.bias_walk,
        sigma_attitude: 0.01,
        sigma_bias: 1e-4,
    };
    assert_eq!((params.sigma_v, params.sigma_u), (1e-5, 1e-7));
    // Each row is a gyro sample: it holds the readings taken there and the estimate after
    // that sample's update. The standalone filter: start at the first star tracker reading,
    // then update and compare; at each next sample propagate with the mean of the gyro's
    // readings at the period's ends, update, compare, and so on.
    let mut filter: Option<Mekf> = None;
    let mut last_gyro = [0.0; 3];
    let (mut n, mut within, mut within_norm) = (0usize, [0usize; 3], 0usize);
    let mut worst = 0.0f64;
    for row in t.rows() {
        let time = row[0];
        let q_st = get(&t, row, ["st_q_w", "st_q_x", "st_q_y", "st_q_z"]);
        let gyro = get(&t, row, ["gyro_x", "gyro_y", "gyro_z"]);
        let f = match &mut filter {
            Some(f) => {
                f.propagate(gyro_mean(&last_gyro, &gyro), 0.1).unwrap();
                f
            }
            None => filter.insert(
                Mekf::new(params, q_st, [0.0; 3])
                    .unwrap()
                    .with_gyro_model(GyroModel::Sampled),
            ),
        };
        last_gyro = gyro;
        f.update_attitude(q_st, st.noise).unwrap();
        let est = get(&t, row, ["est_q_w", "est_q_x", "est_q_y", "est_q_z"]);
        let bias = get(&t, row, ["est_bias_x", "est_bias_y", "est_bias_z"]);
        let sigma = get(&t, row, ["est_sigma_x", "est_sigma_y", "est_sigma_z"]);
        assert_eq!(est, f.attitude(), "t = {time}");
        assert_eq!(bias, f.bias(), "t = {time}");
        assert_eq!(sigma, f.sigma_attitude(), "t = {time}");
        // The estimate against the truth, over the second half.
        let truth = get(&t, row, ["q_w", "q_x", "q_y", "q_z"]);
        let e = attitude_error(est, truth);
        let est_error = row[col(&t, "est_error")];
        assert!((est_error - norm(e)).abs() < 1e-15, "t = {time}");
        if time >= 60.0 {
            n += 1;
            for a in 0..3 {
                within[a] += usize::from(e[a].abs() <= 3.0 * sigma[a]);
                worst = worst.max(e[a].abs() / sigma[a]);
            }
            within_norm += usize::from(est_error <= 3.0 * norm(sigma));
        }
    }
    assert_eq!(n, 601);
    let share = within.map(|w| w as f64 / n as f64);
    let share_norm = within_norm as f64 / n as f64;
    eprintln!(
        "est_error within 3 sigma over 60..120 s: per axis {share:?}, |error| <= 3 |sigma| {share_norm}; worst |error|/sigma {worst:.2}"
    );
    assert!(share.iter().all(|s| *s > 0.98), "{share:?}");
    assert!(share_norm > 0.98, "{share_norm}");
}

#[test]
fn an_estimator_alone_leaves_the_truth_unchanged_to_the_last_bit() {
    let with = run(&in_the_loop(
        "[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = [\"st\"]\nperiod = 0.1\n[fsw.guidance]\nmode = \"nadir\"\n",
    ));
    let without = run(&in_the_loop(""));
    let fsw = |c: &str| c.starts_with("est_") || c.starts_with("ref_") || c == "pointing_error";
    let kept: Vec<&String> = with.columns.iter().filter(|c| !fsw(c)).collect();
    assert_eq!(kept, without.columns.iter().collect::<Vec<_>>());
    for (a, b) in with.rows().zip(without.rows()) {
        for (i, c) in without.columns.iter().enumerate() {
            assert_eq!(
                a[col(&with, c)].to_bits(),
                b[i].to_bits(),
                "column {c} at t = {}",
                b[0]
            );
        }
    }
}

/// The orbital frame and its rate at a row, from the orbit's columns.
fn orbital(t: &Trajectory, row: &[f64]) -> OrbitState {
    let [rx, ry, rz, vx, vy, vz] = get(
        t,
        row,
        [
            "orbit_r_x",
            "orbit_r_y",
            "orbit_r_z",
            "orbit_v_x",
            "orbit_v_y",
            "orbit_v_z",
        ],
    );
    OrbitState {
        r: Vector3::new(rx, ry, rz),
        v: Vector3::new(vx, vy, vz),
        mu: 3.986004418e14,
    }
}

fn quaternion(q: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_normalize(Quaternion::new(q[0], q[1], q[2], q[3]))
}

#[test]
fn the_nadir_reference_is_the_orbital_frame_at_every_row() {
    let scene = read(
        POINTING,
        &[
            "duration=60.0",
            "output.every=0.5",
            "fsw.guidance.mode=nadir",
            "initial.base.frame=orbital",
        ],
    );
    let t = run(&scene);
    assert_eq!(t.rows().count(), 121);
    let mut worst = (0.0f64, 0.0f64);
    for row in t.rows() {
        let o = orbital(&t, row);
        let frame = o.orbital_frame();
        let q = frame.quaternion();
        let s = if q.w < 0.0 { -1.0 } else { 1.0 };
        let want = [s * q.w, s * q.i, s * q.j, s * q.k];
        let got = get(&t, row, ["ref_q_w", "ref_q_x", "ref_q_y", "ref_q_z"]);
        let dq = (0..4).fold(0.0f64, |m, i| m.max((got[i] - want[i]).abs()));
        // The rate, in the reference's axes: the orbit's r × v / r², (0, −n, 0) on a circle.
        let w = frame.inverse_transform_vector(&o.orbital_rate());
        let got_w = get(&t, row, ["ref_omega_x", "ref_omega_y", "ref_omega_z"]);
        let dw = (0..3).fold(0.0f64, |m, i| m.max((got_w[i] - w[i]).abs()));
        worst = (worst.0.max(dq), worst.1.max(dw));
        // pointing_error: the truth against this frame.
        let truth = quaternion(get(&t, row, ["q_w", "q_x", "q_y", "q_z"]));
        let pe = row[col(&t, "pointing_error")];
        assert!(
            (pe - (frame.inverse() * truth).angle()).abs() < 1e-9,
            "t = {}",
            row[0]
        );
    }
    eprintln!(
        "nadir reference against the orbital frame: |dq| <= {:.1e}, |dw| <= {:.1e} rad/s",
        worst.0, worst.1
    );
    assert!(worst.0 <= 1e-12 && worst.1 <= 1e-18, "{worst:?}");
    // On the circular orbit the reference turns at (0, −n, 0).
    let n = (3.986004418e14 / (6378137.0f64 + 500e3).powi(3)).sqrt();
    let row = t.rows().last().unwrap();
    let w = get(&t, row, ["ref_omega_x", "ref_omega_y", "ref_omega_z"]);
    assert!(
        w[0].abs() < 1e-12 && (w[1] + n).abs() < 1e-9 * n && w[2].abs() < 1e-12,
        "{w:?}"
    );
}

/// Pointing error statistics after [`SETTLED`]: the largest excess over the estimator's
/// 3σ (norm of the three sigmas) plus [`MARGIN`], the largest error and the RMS (rad).
fn pointing(t: &Trajectory) -> (f64, f64, f64) {
    let (mut excess, mut max, mut sum, mut n) = (f64::NEG_INFINITY, 0.0f64, 0.0, 0);
    for row in t.rows().filter(|r| r[0] >= SETTLED) {
        let pe = row[col(t, "pointing_error")];
        let sigma = get(t, row, ["est_sigma_x", "est_sigma_y", "est_sigma_z"]);
        excess = excess.max(pe - (3.0 * norm(sigma) + MARGIN));
        max = max.max(pe);
        sum += pe * pe;
        n += 1;
    }
    assert!(n > 100);
    (excess, max, (sum / n as f64).sqrt())
}

fn closed_loop(extra: &[&str]) {
    let truth_sets = [
        "effects.attitude_control.enabled=true",
        "fsw.control.enabled=false",
    ];
    let with = |more: &[&str]| -> Vec<String> {
        extra
            .iter()
            .chain(more)
            .map(|s| s.to_string())
            .collect::<Vec<_>>()
    };
    let sets = |v: &[String]| read(POINTING, &v.iter().map(|s| s.as_str()).collect::<Vec<_>>());
    let fsw = run(&sets(&with(&[])));
    let fsw_pd = run(&sets(&with(&["fsw.control.ki=[0.0, 0.0, 0.0]"])));
    let truth = run(&sets(&with(&truth_sets)));
    let (excess, max, rms) = pointing(&fsw);
    let (_, max_pd, rms_pd) = pointing(&fsw_pd);
    let (_, max_truth, rms_truth) = pointing(&truth);
    let last = fsw.rows().last().unwrap();
    let sigma3 = 3.0
        * norm(get(
            &fsw,
            last,
            ["est_sigma_x", "est_sigma_y", "est_sigma_z"],
        ));
    let arcsec = |x: f64| x / ARCSEC;
    eprintln!(
        "{extra:?} after {SETTLED} s: fsw PID max {:.1}\" rms {:.1}\"; fsw PD (ki = 0) max {:.1}\" rms {:.1}\"; truth-based PD max {:.1}\" rms {:.1}\"; estimator 3 sigma {:.1}\" + margin {:.0}\"",
        arcsec(max),
        arcsec(rms),
        arcsec(max_pd),
        arcsec(rms_pd),
        arcsec(max_truth),
        arcsec(rms_truth),
        arcsec(sigma3),
        arcsec(MARGIN)
    );
    assert!(
        excess <= 0.0,
        "pointing error {:.1}\" over 3 sigma + margin",
        arcsec(excess)
    );
    // The PID on the estimate points better than the truth-based PD of the same kp and kd
    // (the integral removes the disturbances' offset); without the integral, within the
    // estimator's 3σ of it.
    assert!(rms < rms_truth, "{rms} >= {rms_truth}");
    assert!(
        rms_pd <= rms_truth + sigma3,
        "{rms_pd} > {rms_truth} + {sigma3}"
    );
    // The truth-based run's estimator still runs (observes only): the same readings.
    let first = |t: &Trajectory| t.rows().next().unwrap()[col(t, "st_q_w")];
    assert_eq!(first(&fsw), first(&truth));
}

#[test]
fn the_closed_loop_on_the_sensors_holds_an_inertial_attitude_within_3_sigma_and_margin() {
    closed_loop(&[]);
}

#[test]
fn the_closed_loop_on_the_sensors_points_at_nadir_within_3_sigma_and_margin() {
    closed_loop(&[
        "fsw.guidance.mode=nadir",
        "initial.base.frame=orbital",
        "effects.attitude_control.target=orbital",
    ]);
}

#[test]
fn the_control_commands_only_the_wheels_within_their_limits() {
    // A short run: the held commands are what the wheels get (no larger than max_torque,
    // 1 N m), and the controller's clock is counted among the scene's samplers.
    // A control every 0.05 s (two per gyro sample: the estimate turned on by the gyro's
    // rate in between) makes 401 samples in 20 s, the gyro 201.
    let scene = read(POINTING, &["duration=20.0", "fsw.control.period=0.05"]);
    assert!(
        scene
            .clocks
            .iter()
            .any(|c| c.what == "`fsw.control`" && c.period == 0.05),
        "{:?}",
        scene.clocks
    );
    let err = scene.check_rows(300).unwrap_err().to_string();
    let text = std::fs::read_to_string(example(POINTING)).unwrap();
    let line = text
        .lines()
        .position(|l| l.starts_with("period = 0.1                # s"))
        .unwrap()
        + 1;
    assert!(
        err.contains("`fsw.control`") && err.contains(&format!("fsw_mekf_pointing.toml:{line}")),
        "{err}"
    );
    let t = run(&scene);
    assert!(t.columns.iter().any(|c| c == "pointing_error"));
    let sensors = scene.effects.get::<Sensors>().unwrap();
    assert!(sensors.fsw().unwrap().commands_rotors());
}

#[test]
fn star_trackers_of_a_longer_period_update_only_when_they_sampled() {
    // A second tracker on the bus every 0.3 s, listed after the first: the filter updates
    // with `st` at every gyro sample and with `st3` at every third.
    let st3 = "[[sensors.star_tracker]]\nname = \"st3\"\nbody = \"bus\"\nperiod = 0.3\nnoise_arcsec = [20.0, 20.0, 20.0]\n";
    let scene = in_the_loop(&format!(
        "{st3}\n[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = [\"st\", \"st3\"]\nsigma_attitude = 0.02\nsigma_bias = 1e-3\n"
    ));
    let scene = Scene {
        duration: 30.0,
        ..scene
    };
    let t = run(&scene);
    let params = MekfParams {
        sigma_v: 1e-5,
        sigma_u: 1e-7,
        sigma_attitude: 0.02,
        sigma_bias: 1e-3,
    };
    let (n1, n3) = ([5.0, 5.0, 40.0].map(|a| a * ARCSEC), [20.0 * ARCSEC; 3]);
    let mut f: Option<Mekf> = None;
    let mut last_gyro = [0.0; 3];
    for (k, row) in t.rows().enumerate() {
        let q1 = get(&t, row, ["st_q_w", "st_q_x", "st_q_y", "st_q_z"]);
        let q3 = get(&t, row, ["st3_q_w", "st3_q_x", "st3_q_y", "st3_q_z"]);
        let gyro = get(&t, row, ["gyro_x", "gyro_y", "gyro_z"]);
        let f = match &mut f {
            Some(f) => {
                f.propagate(gyro_mean(&last_gyro, &gyro), 0.1).unwrap();
                f
            }
            None => f.insert(
                Mekf::new(params, q1, [0.0; 3])
                    .unwrap()
                    .with_gyro_model(GyroModel::Sampled),
            ),
        };
        last_gyro = gyro;
        f.update_attitude(q1, n1).unwrap();
        if k % 3 == 0 {
            f.update_attitude(q3, n3).unwrap();
        }
        let est = get(&t, row, ["est_q_w", "est_q_x", "est_q_y", "est_q_z"]);
        let sigma = get(&t, row, ["est_sigma_x", "est_sigma_y", "est_sigma_z"]);
        assert_eq!(
            (est, sigma),
            (f.attitude(), f.sigma_attitude()),
            "t = {}",
            row[0]
        );
    }
    // A tracker whose period is not a whole number of the gyro's is refused.
    let bad = std::fs::read_to_string(example("scenes/fsw_in_the_loop.toml")).unwrap()
        + &st3.replace("0.3", "0.25")
        + "\n[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = [\"st\", \"st3\"]\n";
    let err = error_of(&bad);
    let line = bad
        .lines()
        .position(|l| l.starts_with("star_tracker = ["))
        .unwrap()
        + 1;
    assert!(
        err.contains("not a whole multiple") && err.contains(&format!("bad_fsw.toml:{line}")),
        "{err}"
    );
}

/// The built-in blocks against the same MEKF and PID written outside, in a stepping loop on
/// `measure()`: the same readings at the same instants, the same held commands, so the
/// same trajectory to the last bit.
#[test]
fn the_built_in_blocks_equal_the_same_laws_in_a_stepping_loop_on_the_readings() {
    let short = ["duration=60.0"];
    let builtin = run(&read(POINTING, &short));
    let outside = read(
        POINTING,
        &[
            "duration=60.0",
            "fsw.estimator.enabled=false",
            "fsw.guidance.enabled=false",
            "fsw.control.enabled=false",
        ],
    );
    let mut s = SceneStepper::new(&outside, None, "test").unwrap();
    let params = MekfParams {
        sigma_v: 1e-5,
        sigma_u: 1e-7,
        sigma_attitude: 0.01,
        sigma_bias: 1e-4,
    };
    let noise = [5.0, 5.0, 40.0].map(|a| a * ARCSEC);
    let mut pid = Pid::new([40.0; 3], [2.0; 3], [300.0; 3], None);
    pid.allocate(&[Vector3::x(), Vector3::y(), Vector3::z()], &[1.0; 3]);
    let mut filter: Option<Mekf> = None;
    let mut last_gyro = [0.0; 3];
    while s.t() < 60.0 - 1e-9 {
        let meas = s.measure().unwrap();
        let reading = |name: &str| meas.iter().find(|(n, _)| n == name).unwrap().1.clone();
        let (g, q) = (reading("gyro"), reading("st"));
        let (g, q) = ([g[0], g[1], g[2]], [q[0], q[1], q[2], q[3]]);
        let f = match &mut filter {
            Some(f) => {
                f.propagate(gyro_mean(&last_gyro, &g), 0.1).unwrap();
                f
            }
            None => filter.insert(
                Mekf::new(params, q, [0.0; 3])
                    .unwrap()
                    .with_gyro_model(GyroModel::Sampled),
            ),
        };
        f.update_attitude(q, noise).unwrap();
        last_gyro = g;
        let u = pid.torque(
            &f.unit_attitude(),
            &Vector3::from(f.rate(g)),
            &UnitQuaternion::identity(),
            &Vector3::zeros(),
            0.1,
        );
        let mut c = [0.0; 3];
        pid.commands(&u, &mut c);
        s.set_inputs(&[("wheel_x", c[0]), ("wheel_y", c[1]), ("wheel_z", c[2])])
            .unwrap();
        s.advance(0.1).unwrap();
    }
    let got = s.trajectory();
    assert_eq!(got.n_rows(), builtin.n_rows());
    let mut compared = 0;
    for (c, name) in got.columns.iter().enumerate() {
        let Some(b) = builtin.columns.iter().position(|n| n == name) else {
            continue;
        };
        for (x, y) in got.rows().zip(builtin.rows()) {
            assert_eq!(x[c].to_bits(), y[b].to_bits(), "{name} at t = {}", x[0]);
        }
        compared += 1;
    }
    assert!(compared >= 50, "{compared}");
}

fn error_of(text: &str) -> String {
    match Scene::parse(text, &path_in_examples("bad_fsw.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_fsw_input_is_an_error_naming_the_file_and_line() {
    let base = std::fs::read_to_string(example(POINTING)).unwrap();
    let est = "star_tracker = \"st\"\n";
    let tracker2 = "[[sensors.star_tracker]]\nname = \"st2\"\nbody = \"panel1\"\nperiod = 0.1\n\n[fsw.estimator]";
    let dated = format!("epoch = \"2026-03-20T12:00:00 UTC\"\n{base}");
    let control_on = "[effects.attitude_control]   # the truth-based controller, off: [fsw.control] flies the bus\nenabled = true";
    // (edit, the text of the line the error names, what it says)
    let cases: Vec<(String, &str, &str)> = vec![
        (base.replacen("gyro = \"gyro\"", "gyro = \"gyro9\"", 1), "gyro = \"gyro9\"", "unknown sensor `gyro9`"),
        (base.replacen("gyro = \"gyro\"", "gyro = \"st\"", 1), "gyro = \"st\"", "is a star_tracker, not a gyro"),
        (base.replacen(est, "star_tracker = [\"st\", \"nope\"]\n", 1), "star_tracker = [", "unknown sensor `nope`"),
        (base.replacen(est, "star_tracker = \"st2\"\n", 1).replacen("[fsw.estimator]", tracker2, 1), "star_tracker = \"st2\"", "on body `panel1`"),
        (base.replacen(est, "star_tracker = \"st\"\nperiod = 0.2\n", 1), "period = 0.2", "must be the gyro `gyro`'s period"),
        (base.replacen("sigma_attitude = 0.01", "sigma_attitude = -1.0", 1), "sigma_attitude", "> 0"),
        (base.replacen("kind = \"mekf\"", "kind = \"ukf\"", 1), "kind = \"ukf\"", "unknown kind"),
        (base.replacen("kind = \"mekf\"", "kind = \"mekf\"\nenabled = false", 1), "[fsw.control]", "needs an estimator"),
        (base.replacen("[effects.attitude_control]   # the truth-based controller, off: [fsw.control] flies the bus\nenabled = false", control_on, 1), "[fsw.control]", "would both command the wheels"),
        (base.replacen("mode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]", "mode = \"sun\"\nattitude = [0.6, 0.8, 0.0, 0.0]", 1), "attitude = [0.6", "belongs to mode = \"inertial\" or \"nadir\""),
        (dated.replacen("mode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]", "mode = \"sun\"\naxis = [0.0, 0.0, 1.0]", 1), "mode = \"sun\"", "needs `secondary = [x, y, z]`"),
        (base.replacen("mode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]", "mode = \"sun\"\naxis = [0.0, 0.0, 1.0]\nsecondary = [0.0, 1.0, 0.0]", 1), "mode = \"sun\"", "needs the scene's `epoch`"),
        (dated.replacen("mode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]", "mode = \"sun\"\naxis = [0.0, 0.0, 1.0]\nsecondary = [0.0, 0.0, 2.0]", 1), "secondary = [0.0, 0.0, 2.0]", "parallel"),
        (dated.replacen("mode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]", "mode = \"target\"\nlatitude_deg = 95.0\nlongitude_deg = 0.0", 1), "latitude_deg = 95.0", "within ±90"),
        (dated.replacen("mode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]", "mode = \"target\"\nlongitude_deg = 0.0", 1), "mode = \"target\"", "needs `latitude_deg`"),
        (base.replacen("mode = \"inertial\"", "mode = \"inertial\"\naxis = [0.5, 0.0, 0.0]", 1), "axis = [0.5", "`fsw.guidance.axis` belongs to mode = \"sun\" or \"target\""),
        (base.replacen("mode = \"inertial\"", "mode = \"inertial\"\nmax_rate = -0.02", 1), "max_rate", "`fsw.guidance.max_rate` must be a finite number > 0"),
        (base.replacen("mode = \"inertial\"", "mode = \"inertial\"\nmax_acceleration = 0.0", 1), "max_acceleration", "must be a finite number > 0"),
        (base.replacen("mode = \"inertial\"", "mode = \"spin\"", 1), "mode = \"spin\"", "unknown mode"),
        (base.replacen("attitude = [1.0, 0.0, 0.0, 0.0]\n\n[fsw.control]", "\n[fsw.control]", 1), "mode = \"inertial\"", "needs `attitude"),
        (base.replacen("actuator = \"wheels\"", "actuator = \"torquers\"", 1), "[fsw.control]", "needs `magnetometer`"),
        (base.replacen("actuator = \"wheels\"", "actuator = \"wheels\"\nmagnetometer = \"mag\"", 1), "magnetometer = \"mag\"", "belongs to actuator = \"torquers\""),
        (base.replacen("actuator = \"wheels\"", "actuator = \"torquers\"\nmagnetometer = \"gyro\"", 1), "magnetometer = \"gyro\"", "is a gyro, not a magnetometer"),
        (base.replacen("actuator = \"wheels\"", "actuator = \"ion_engines\"", 1), "actuator = \"ion_engines\"", "unknown actuator"),
        (base.replacen("actuator = \"wheels\"", "actuator = \"thrusters\"", 1), "[fsw.control]", "needs [effects.thrusters]"),
        (base.replacen("kp = [40.0, 40.0, 40.0]", "kp = [40.0, -1.0, 40.0]", 1), "kp = [40.0, -1.0", ">= 0"),
        (base.replacen("actuator = \"wheels\"", "actuator = \"wheels\"\ninertia = [[-20.0, 0.0, 0.0], [0.0, 25.0, 0.0], [0.0, 0.0, 30.0]]", 1), "inertia = [[-20.0", "symmetric positive definite"),
        (base.replacen("actuator = \"wheels\"", "actuator = \"wheels\"\ninertia = [[20.0, 1.0, 0.0], [0.0, 25.0, 0.0], [0.0, 0.0, 30.0]]", 1), "inertia = [[20.0, 1.0", "symmetric positive definite"),
        (base.replacen("period = 0.1                # s\n", "period = 0.0\n", 1), "period = 0.0", "> 0"),
        (format!("{base}\n[fsw.momentum]\ngain = 1e-3\nmagnetometer = \"mag\"\n"), "magnetometer = \"mag\"", "`fsw.momentum.magnetometer`: unknown sensor `mag` (the scene's magnetometer sensors: none)"),
        (format!("{base}\n[fsw.bdot]\nmagnetometer = \"mag\"\ngain = 4e5\n"), "magnetometer = \"mag\"", "`fsw.bdot.magnetometer`: unknown sensor `mag`"),
        (format!("{base}\n[[fsw.mode]]\nname = \"detumble\"\nblocks = [\"bdot\"]\n"), "blocks = [\"bdot\"]", "no [fsw.bdot]"),
        (format!("{base}\n[[fsw.mode]]\nname = \"a\"\nblocks = [\"estimator\"]\n"), "[fsw.guidance]", "runs in no [[fsw.mode]]"),
        (format!("{base}\n[fsw.camera]\n"), "[fsw.camera]", "unknown key `camera`"),
    ];
    for (text, at, needle) in cases {
        assert_error_at(&text, at, needle);
    }
    // Nadir without an orbit; a control without the wheels; guidance without an estimator.
    let no_orbit = base
        .replacen("[orbit]\nmodel = \"kepler\"\naltitude = 500e3          # m, circular\ninclination_deg = 51.6\n", "", 1)
        .replacen("[effects.gravity_gradient]\nmodel = \"full\"\n", "", 1)
        .replacen("mode = \"inertial\"", "mode = \"nadir\"", 1);
    let err = error_of(&no_orbit);
    let line = no_orbit
        .lines()
        .position(|l| l.contains("mode = \"nadir\""))
        .unwrap()
        + 1;
    assert!(
        err.contains("needs an [orbit]") && err.contains(&format!("bad_fsw.toml:{line}")),
        "{err}"
    );
    let no_estimator = "[fsw.guidance]\nmode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]\n";
    let text = std::fs::read_to_string(example("scenes/fsw_in_the_loop.toml")).unwrap();
    let err = error_of(&format!("{text}\n{no_estimator}"));
    assert!(
        err.contains("needs an estimator") && err.contains("bad_fsw.toml:"),
        "{err}"
    );
    // A scene without sensors: the estimator's gyro is unknown.
    let deploy = std::fs::read_to_string(example("scenes/deploy.toml")).unwrap();
    let err = error_of(&format!(
        "{deploy}\n[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = \"st\"\n"
    ));
    assert!(
        err.contains("the scene has no sensors") && err.contains("bad_fsw.toml:"),
        "{err}"
    );
}

/// A small tumbling bus (4.1 deg/s) on an inclined orbit with three torquers (5 A m² each)
/// and a noiseless magnetometer every second, plus `extra`.
fn tumbling(extra: &str) -> Scene {
    parse(&tumbling_text(extra), "tumbling.toml")
}

fn tumbling_text(extra: &str) -> String {
    format!(
        r#"
epoch = "2026-03-20T12:00:00 UTC"
duration = 3000.0
[model]
[[model.body]]
name = "bus"
mass = 20.0
inertia = [[2.0, 0.0, 0.0], [0.0, 2.5, 0.0], [0.0, 0.0, 3.0]]
[initial]
base = {{ attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.04, -0.05, 0.03] }}
[orbit]
altitude = 500e3
inclination_deg = 51.6
[integrator]
method = "rk4"
step = 0.5
[output]
every = 10.0
[effects.magnetic]
[[effects.magnetic.torquer]]
name = "x"
axis = [1.0, 0.0, 0.0]
max_dipole = 5.0
[[effects.magnetic.torquer]]
name = "y"
axis = [0.0, 1.0, 0.0]
max_dipole = 5.0
[[effects.magnetic.torquer]]
name = "z"
axis = [0.0, 0.0, 1.0]
max_dipole = 5.0
[sensors]
seed = 1
[[sensors.magnetometer]]
name = "mag"
body = "bus"
period = 1.0
{extra}
"#
    )
}

/// The first row time at which |omega| falls below each threshold (rad/s).
fn times_below(t: &Trajectory, thresholds: &[f64]) -> Vec<f64> {
    thresholds
        .iter()
        .map(|thr| {
            t.rows()
                .find(|r| norm(get(t, r, ["omega_x", "omega_y", "omega_z"])) < *thr)
                .map_or(f64::INFINITY, |r| r[0])
        })
        .collect()
}

const FSW_BDOT: &str = "[fsw.bdot]\nmagnetometer = \"mag\"\ngain = 1e7\n";

#[test]
fn bdot_on_the_magnetometer_detumbles_as_fast_as_the_truth_based_bdot() {
    // The truth-based law takes Ḃ_b = −ω × B_b (the field's own change along the orbit left
    // out); the finite difference of the readings holds that change too, of order the
    // orbital rate (2n ≈ 0.13 deg/s), so the two agree while the rate is well above it and
    // the magnetometer's law levels off near it.
    let deg = std::f64::consts::PI / 180.0;
    let thr = [2.0 * deg, 1.0 * deg, 0.5 * deg, 0.25 * deg, 0.1 * deg];
    let truth = run(&tumbling("[effects.bdot]\ngain = 1e7\n"));
    let fsw = run(&tumbling(FSW_BDOT));
    let (a, b) = (times_below(&truth, &thr), times_below(&fsw, &thr));
    let last = |t: &Trajectory| {
        norm(get(
            t,
            t.rows().last().unwrap(),
            ["omega_x", "omega_y", "omega_z"],
        )) / deg
    };
    eprintln!(
        "from 4.1 deg/s, times (s) below 2, 1, 0.5, 0.25, 0.1 deg/s: truth-based B-dot {a:?}, B-dot on the magnetometer {b:?}; after 3000 s: {:.3} and {:.3} deg/s",
        last(&truth),
        last(&fsw)
    );
    for k in 0..2 {
        assert!(
            (b[k] - a[k]).abs() <= 0.1 * a[k],
            "below {} deg/s: {} s against {} s",
            thr[k] / deg,
            b[k],
            a[k]
        );
    }
    assert!(b[2] <= 1.25 * a[2] && b[3] <= 2.0 * a[3], "{a:?} {b:?}");
    assert!(last(&fsw) < 0.2, "{}", last(&fsw));
    // The commanded dipole is the law on the readings: −k (B_k − B_{k−1}) / Δt, none at the
    // first sample. The torquers (the body's axes) make it clamped to ±5 A m², held until
    // the next sample (their columns at a row show the dipole held up to it).
    let mut short = tumbling(FSW_BDOT);
    short.duration = 30.0;
    short.every = 1.0;
    let t = run(&short);
    let mut prev: Option<[f64; 3]> = None;
    let mut held = [0.0; 3];
    let mut clamped = 0;
    for row in t.rows() {
        let b = get(&t, row, ["mag_x", "mag_y", "mag_z"]);
        let m = get(&t, row, ["fsw_dipole_x", "fsw_dipole_y", "fsw_dipole_z"]);
        let d = get(&t, row, ["dipole_x", "dipole_y", "dipole_z"]);
        let want = prev.map_or([0.0; 3], |p| [0, 1, 2].map(|i| -1e7 * (b[i] - p[i]) / 1.0));
        for i in 0..3 {
            assert!(
                (m[i] - want[i]).abs() <= 1e-9 * want[i].abs().max(1.0),
                "t = {}: {m:?} against {want:?}",
                row[0]
            );
            assert_eq!(d[i], held[i], "t = {}", row[0]);
            clamped += usize::from(want[i].abs() > 5.0);
        }
        held = m.map(|x| x.clamp(-5.0, 5.0));
        prev = Some(b);
    }
    assert!(clamped > 0);
}

/// A rigid bus held pitched 20 deg off nadir (about y, the orbit normal) by the flight
/// software on the wheels, all at 1 Hz, over 10 orbits: the gravity gradient at that offset
/// is a constant torque about the orbit normal, so the wheels take up momentum without end
/// unless it is dumped. Plus `extra`.
fn held_off_nadir(extra: &str) -> Scene {
    let text = format!(
        r#"
epoch = "2026-03-20T12:00:00 UTC"
duration = 56770.0
[model]
[[model.body]]
name = "bus"
mass = 200.0
inertia = [[30.0, 0.0, 0.0], [0.0, 40.0, 0.0], [0.0, 0.0, 60.0]]
[initial]
base = {{ frame = "orbital", attitude = [0.984807753012208, 0.0, 0.17364817766693033, 0.0] }}
[orbit]
altitude = 500e3
inclination_deg = 51.6
[integrator]
method = "rk4"
step = 0.5
[output]
every = 60.0
[effects.gravity_gradient]
[effects.magnetic]
[[effects.magnetic.torquer]]
name = "x"
axis = [1.0, 0.0, 0.0]
max_dipole = 20.0
[[effects.magnetic.torquer]]
name = "y"
axis = [0.0, 1.0, 0.0]
max_dipole = 20.0
[[effects.magnetic.torquer]]
name = "z"
axis = [0.0, 0.0, 1.0]
max_dipole = 20.0
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "x"
axis = [1.0, 0.0, 0.0]
inertia = 0.05
max_torque = 0.1
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.05
max_torque = 0.1
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.05
max_torque = 0.1
[sensors]
seed = 3
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 1.0
noise_density = 1e-6
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 1.0
noise_arcsec = [5.0, 5.0, 20.0]
[[sensors.magnetometer]]
name = "mag"
body = "bus"
period = 1.0
noise = 1e-7
[fsw.estimator]
gyro = "gyro"
star_tracker = "st"
[fsw.guidance]
mode = "nadir"
attitude = [0.984807753012208, 0.0, 0.17364817766693033, 0.0]
[fsw.control]
kp = [0.3, 0.4, 0.6]
kd = [6.0, 8.0, 12.0]
{extra}
"#
    );
    parse(&text, "held_off_nadir.toml")
}

/// |h| of the wheels (N m s) at each row.
fn wheel_momentum(t: &Trajectory) -> Vec<(f64, f64)> {
    t.rows()
        .map(|r| {
            let w = get(t, r, ["wheel_x_speed", "wheel_y_speed", "wheel_z_speed"]);
            (r[0], 0.05 * norm(w))
        })
        .collect()
}

#[test]
fn momentum_dumping_keeps_the_wheels_momentum_bounded_while_the_control_points() {
    let start = std::time::Instant::now();
    let without = run(&held_off_nadir(""));
    let with = run(&held_off_nadir(
        "[fsw.momentum]\ngain = 2e-3\nmagnetometer = \"mag\"\n",
    ));
    let elapsed = start.elapsed();
    let (h0, h1) = (wheel_momentum(&without), wheel_momentum(&with));
    let at = |h: &[(f64, f64)], orbit: f64| {
        h.iter()
            .rfind(|(t, _)| *t <= orbit * 5677.0)
            .map_or(f64::NAN, |x| x.1)
    };
    let max_after = |h: &[(f64, f64)], t0: f64| {
        h.iter()
            .filter(|(t, _)| *t >= t0)
            .fold(0.0f64, |m, x| m.max(x.1))
    };
    let max_pe = |t: &Trajectory| {
        t.rows()
            .filter(|r| r[0] > 600.0)
            .map(|r| r[col(t, "pointing_error")])
            .fold(0.0f64, f64::max)
    };
    let orbits = [1.0, 2.0, 5.0, 10.0];
    eprintln!(
        "|h| (N m s) after 1, 2, 5, 10 orbits: without dumping {:?}, with {:?} (largest {:.4}); largest pointing error after 600 s {:.2e} and {:.2e} rad ({elapsed:?} for both runs)",
        orbits.map(|o| at(&h0, o)),
        orbits.map(|o| at(&h1, o)),
        max_after(&h1, 0.0),
        max_pe(&without),
        max_pe(&with)
    );
    // Without dumping the wheels take up the gravity gradient's momentum orbit after orbit.
    let (five, ten) = (at(&h0, 5.0), at(&h0, 10.0));
    assert!(ten > 1.0 && ten > 1.8 * five, "{five} then {ten}");
    // With it the momentum stays bounded, far below.
    let final_with = with.rows().last().map(|r| r[0]).unwrap();
    assert!(final_with > 56_000.0);
    assert!(
        at(&h1, 10.0) < 0.05 * ten,
        "{} against {ten}",
        at(&h1, 10.0)
    );
    assert!(
        max_after(&h1, 5.0 * 5677.0) <= max_after(&h1, 0.0) && max_after(&h1, 0.0) < 0.1,
        "{}",
        max_after(&h1, 0.0)
    );
    // The control keeps pointing while the torquers disturb the bus.
    assert!(
        max_pe(&with) < 2.0 * max_pe(&without) && max_pe(&with) < 5e-4,
        "{} against {}",
        max_pe(&with),
        max_pe(&without)
    );
    // The dipole is the law on the rows' readings: k (h × B) / |B|², h from the wheel speeds
    // (0.05 kg m² each, along the bus' axes).
    for row in with.rows().step_by(97) {
        let h = get(
            &with,
            row,
            ["wheel_x_speed", "wheel_y_speed", "wheel_z_speed"],
        )
        .map(|w| 0.05 * w);
        let b = Vector3::from(get(&with, row, ["mag_x", "mag_y", "mag_z"]));
        let want = 2e-3 * Vector3::from(h).cross(&b) / b.norm_squared();
        let m = Vector3::from(get(
            &with,
            row,
            ["fsw_dipole_x", "fsw_dipole_y", "fsw_dipole_z"],
        ));
        assert!(
            (m - want).norm() <= 1e-12 * want.norm().max(1e-3),
            "t = {}: {m} against {want}",
            row[0]
        );
    }
}

#[test]
fn bad_magnetic_blocks_are_errors_at_their_line() {
    let gyro = "[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 1.0\n";
    let wheel = "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"x\"\naxis = [1.0, 0.0, 0.0]\ninertia = 0.05\n";
    let momentum = "[fsw.momentum]\ngain = 1e-3\nmagnetometer = \"mag\"\n";
    let no_torquers = tumbling_text(FSW_BDOT);
    let i = no_torquers.find("[[effects.magnetic.torquer]]").unwrap();
    let j = no_torquers.find("[sensors]").unwrap();
    let no_torquers = format!("{}{}", &no_torquers[..i], &no_torquers[j..]);
    // (scene, the text of the line the error names, what it says)
    let cases: Vec<(String, &str, &str)> = vec![
        (
            tumbling_text("[fsw.bdot]\nmagnetometer = \"mag9\"\ngain = 1e7\n"),
            "magnetometer = \"mag9\"",
            "`fsw.bdot.magnetometer`: unknown sensor `mag9` (the scene's magnetometer sensors: mag)",
        ),
        (
            tumbling_text(&format!(
                "{gyro}[fsw.bdot]\nmagnetometer = \"gyro\"\ngain = 1e7\n"
            )),
            "magnetometer = \"gyro\"",
            "sensor `gyro` is a gyro, not a magnetometer",
        ),
        (
            tumbling_text(&format!(
                "{gyro}{wheel}[fsw.momentum]\ngain = 1e-3\nmagnetometer = \"gyro\"\n"
            )),
            "magnetometer = \"gyro\"",
            "`fsw.momentum.magnetometer`: sensor `gyro` is a gyro",
        ),
        (
            no_torquers,
            "[fsw.bdot]",
            "the scene has none on the root body",
        ),
        (
            tumbling_text(&format!("[effects.bdot]\ngain = 1e7\n{FSW_BDOT}")),
            "[fsw.bdot]",
            "[fsw.bdot] and [effects.bdot] would both command the torquers",
        ),
        (
            tumbling_text(&format!("[effects.bdot]\ngain = 1e7\n{wheel}{momentum}")),
            "[fsw.momentum]",
            "[fsw.momentum] and [effects.bdot] would both",
        ),
        (
            tumbling_text(&format!("{wheel}{FSW_BDOT}{momentum}")),
            "[fsw.momentum]",
            "[fsw.momentum] and [fsw.bdot] would both command the torquers",
        ),
        (
            tumbling_text(momentum),
            "[fsw.momentum]",
            "needs [effects.reaction_wheels]",
        ),
        (
            tumbling_text(&format!("{FSW_BDOT}period = 1.5\n")),
            "period = 1.5",
            "not a whole multiple of the magnetometer `mag`'s period 1 s",
        ),
        (
            tumbling_text("[fsw.bdot]\nmagnetometer = \"mag\"\ngain = -1.0\n"),
            "gain = -1.0",
            "`fsw.bdot.gain` must be a finite number > 0",
        ),
        (
            tumbling_text(&format!("{wheel}{momentum}period = 0.0\n")),
            "period = 0.0",
            "`fsw.momentum.period` must be a finite number > 0",
        ),
    ];
    for (text, at, needle) in cases {
        assert_error_at(&text, at, needle);
    }
    // Switched off, the truth-based B-dot leaves the torquers to [fsw.bdot]; a period of
    // three magnetometer samples is accepted; `enabled = false` leaves a block out.
    let both = tumbling_text(&format!(
        "[effects.bdot]\ngain = 1e7\nenabled = false\n{FSW_BDOT}period = 3.0\n"
    ));
    let scene = parse(&both, "tumbling.toml");
    let set = scene.effects.get::<Sensors>().unwrap();
    assert!(set.fsw().unwrap().commands_dipoles());
    // Every third reading: the difference over 3 s, held in between.
    let mut short = scene;
    short.duration = 12.0;
    short.every = 1.0;
    let t = run(&short);
    let rows: Vec<&[f64]> = t.rows().collect();
    for (k, row) in rows.iter().enumerate() {
        let m = get(&t, row, ["fsw_dipole_x", "fsw_dipole_y", "fsw_dipole_z"]);
        let at = k - k % 3;
        let want = if at == 0 {
            [0.0; 3]
        } else {
            let (b, p) = (
                get(&t, rows[at], ["mag_x", "mag_y", "mag_z"]),
                get(&t, rows[at - 3], ["mag_x", "mag_y", "mag_z"]),
            );
            [0, 1, 2].map(|i| -1e7 * (b[i] - p[i]) / 3.0)
        };
        for i in 0..3 {
            assert!(
                (m[i] - want[i]).abs() <= 1e-9 * want[i].abs().max(1.0),
                "t = {}: {m:?} against {want:?}",
                row[0]
            );
        }
    }
    let off = parse(
        &tumbling_text(&format!("{FSW_BDOT}enabled = false\n")),
        "tumbling.toml",
    );
    assert!(off.effects.get::<Sensors>().unwrap().fsw().is_none());
}

/// The scene `text` is refused with a message holding `needle` and the line of the first
/// line that starts with `at`.
fn assert_error_at(text: &str, at: &str, needle: &str) {
    let err = error_of(text);
    let line = text
        .lines()
        .position(|l| l.trim_start().starts_with(at))
        .unwrap_or_else(|| panic!("no `{at}`"))
        + 1;
    assert!(err.contains(needle), "`{needle}` not in: {err}");
    assert!(
        err.contains(&format!("bad_fsw.toml:{line}")),
        "line {line} (`{at}`) not in: {err}"
    );
}

/// A run's rows and its event log.
fn run_logged(scene: &Scene) -> (Trajectory, Vec<(f64, String)>) {
    let mut sim = scene.simulation().unwrap_or_else(|e| panic!("{e}"));
    let mut out = Trajectory {
        columns: sim.columns(),
        values: Vec::new(),
    };
    let t_end = sim.t0() + scene.duration;
    sim.run(
        &scene.options,
        t_end,
        &satsim_integrate::Output::Interval(scene.every),
        |_, row| -> Result<(), std::convert::Infallible> {
            out.values.extend_from_slice(row);
            Ok(())
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    (out, sim.event_log().to_vec())
}

/// A small bus with a gyro and a star tracker at 1 Hz, a B-dot block and an estimator, run
/// in the modes `modes`.
fn moded(modes: &str) -> Scene {
    let sensors = "[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 1.0\nnoise_density = 1e-6\n[[sensors.star_tracker]]\nname = \"st\"\nbody = \"bus\"\nperiod = 1.0\nnoise_arcsec = [5.0, 5.0, 20.0]\n";
    let blocks = "[fsw.bdot]\nmagnetometer = \"mag\"\ngain = 1e7\n[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = \"st\"\n";
    let mut s = parse(
        &tumbling_text(&format!("{sensors}{blocks}{modes}")),
        "moded.toml",
    );
    s.duration = 40.0;
    s.every = 1.0;
    s
}

#[test]
fn modes_switch_on_their_conditions_log_each_switch_and_start_their_blocks_afresh() {
    // `time > x` counts from the mode's start; it is checked at every sample instant (1 s);
    // `hold` asks the condition to hold that long first.
    let (t, log) = run_logged(&moded(
        "[[fsw.mode]]\nname = \"a\"\nblocks = [\"bdot\", \"estimator\"]\nuntil = \"time > 10\"\n\
         [[fsw.mode]]\nname = \"b\"\nblocks = [\"estimator\"]\nuntil = \"time > 2\"\nhold = 3.0\n\
         [[fsw.mode]]\nname = \"c\"\nblocks = [\"bdot\"]\nuntil = \"time > 5\"\n\
         [[fsw.mode]]\nname = \"d\"\nblocks = [\"estimator\"]\n",
    ));
    let times: Vec<f64> = log.iter().map(|e| e.0).collect();
    // a: 11 > 10; b: 14 − 11 = 3 > 2 first at 14, held 3 s to 17; c: 23 − 17 > 5; d lasts.
    assert_eq!(times, [11.0, 17.0, 23.0], "{log:?}");
    assert!(
        log[0].1.contains("fsw mode 1 `b` after `a`: time > 10"),
        "{}",
        log[0].1
    );
    let mode: Vec<f64> = t.rows().map(|r| r[col(&t, "fsw_mode")]).collect();
    for (k, m) in mode.iter().enumerate() {
        let want = match k {
            0..=10 => 0.0,
            11..=16 => 1.0,
            17..=22 => 2.0,
            _ => 3.0,
        };
        assert_eq!(*m, want, "row {k}");
    }
    let rows: Vec<&[f64]> = t.rows().collect();
    let bias = |k: usize| norm(get(&t, rows[k], ["est_bias_x", "est_bias_y", "est_bias_z"]));
    let dipole = |k: usize| {
        norm(get(
            &t,
            rows[k],
            ["fsw_dipole_x", "fsw_dipole_y", "fsw_dipole_z"],
        ))
    };
    let est = |k: usize| &rows[k][col(&t, "est_q_w")..=col(&t, "est_error")];
    // A fresh filter starts with bias 0 and its first update leaves it there (no
    // correlation yet); the estimator runs on from a to b, so its bias estimate is not 0.
    assert_eq!(bias(0), 0.0);
    assert!(bias(12) > 0.0);
    // In c it does not run: all its columns zero; B-dot commands.
    assert!(est(20).iter().all(|v| *v == 0.0));
    assert!(dipole(20) > 0.0 && dipole(14) == 0.0);
    // B-dot starts afresh in c (from 17): no command at its first sample (no difference).
    assert!(dipole(17) == 0.0 && dipole(18) == 0.0 && dipole(19) > 0.0);
    // Back in d (from 23) the estimator starts again at its next gyro sample: a fresh
    // filter, the same as at t = 0 after its first update.
    assert!(est(23).iter().all(|v| *v == 0.0));
    assert_eq!(bias(24), 0.0);
    assert_eq!(
        rows[24][col(&t, "est_sigma_x")],
        rows[0][col(&t, "est_sigma_x")]
    );
}

#[test]
fn bad_modes_are_errors_at_their_line() {
    let two = "[[fsw.mode]]\nname = \"a\"\nblocks = [\"bdot\"]\nuntil = \"rate < 0.01\"\n[[fsw.mode]]\nname = \"b\"\nblocks = [\"estimator\"]\n";
    let cases: Vec<(String, &str, &str)> = vec![
        (
            two.replacen("rate < 0.01", "speed < 1", 1),
            "until = \"speed",
            "unknown condition `speed < 1`",
        ),
        (
            two.replacen("rate < 0.01", "time < 5", 1),
            "until = \"time",
            "unknown condition",
        ),
        (
            two.replacen("rate < 0.01", "error < -1", 1),
            "until = \"error",
            "not a finite number >= 0",
        ),
        (
            two.replacen("[\"bdot\"]", "[\"bdot\", \"camera\"]", 1),
            "blocks = [\"bdot\", \"camera\"]",
            "unknown block `camera`",
        ),
        (
            two.replacen("[\"bdot\"]", "[\"bdot\", \"bdot\"]", 1),
            "blocks = [\"bdot\", \"bdot\"]",
            "lists `bdot` twice",
        ),
        (
            two.replacen("[\"bdot\"]", "[\"guidance\", \"estimator\"]", 1),
            "blocks = [\"guidance\"",
            "no [fsw.guidance]",
        ),
        (
            two.replacen("name = \"b\"", "name = \"a\"  # again", 1),
            "name = \"a\"  # again",
            "two modes are called `a`",
        ),
        (
            format!("{two}until = \"time > 1\"\n"),
            "until = \"time > 1\"",
            "the last mode `b` has no mode to switch to",
        ),
        (
            two.replacen("until = \"rate < 0.01\"\n", "", 1),
            "[[fsw.mode]]",
            "mode `a` needs `until`",
        ),
        (
            two.replacen(
                "until = \"rate < 0.01\"",
                "until = \"rate < 0.01\"\nhold = -1.0",
                1,
            ),
            "hold = -1.0",
            ">= 0",
        ),
        (
            format!("{two}[fsw.mode.guidance]\nmode = \"nadir\"\n"),
            "[fsw.mode.guidance]",
            "do not list \"guidance\"",
        ),
    ];
    for (modes, at, needle) in cases {
        let sensors = "[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 1.0\n[[sensors.star_tracker]]\nname = \"st\"\nbody = \"bus\"\nperiod = 1.0\n";
        let blocks = "[fsw.bdot]\nmagnetometer = \"mag\"\ngain = 1e7\n[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = \"st\"\n";
        let text = tumbling_text(&format!("{sensors}{blocks}{modes}"));
        assert_error_at(&text, at, needle);
    }
}

/// The angle (rad) between two unit vectors.
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (Vector3::from(a), Vector3::from(b));
    a.cross(&b).norm().atan2(a.dot(&b))
}

#[test]
#[allow(clippy::needless_range_loop)] // rows are read by index next to their neighbours
fn the_full_adcs_example_detumbles_acquires_the_sun_then_points_at_nadir_and_dumps() {
    let scene = read("scenes/adcs_full.toml", &[]);
    let (t, log) = run_logged(&scene);
    let rows: Vec<&[f64]> = t.rows().collect();
    let at = |time: f64| {
        rows.iter()
            .position(|r| r[0] >= time)
            .unwrap_or_else(|| panic!("no row at {time}"))
    };
    // Two switches, in order, each on its condition.
    assert_eq!(log.len(), 2, "{log:?}");
    assert!(
        log[0]
            .1
            .contains("`sun_acquisition` after `detumble`: rate < 0.005")
    );
    assert!(
        log[1]
            .1
            .contains("`nadir` after `sun_acquisition`: error < 0.02")
    );
    let (t1, t2) = (log[0].0, log[1].0);
    assert!(t1 < 2000.0 && t2 > t1 + 120.0 && t2 < 4000.0, "{t1} {t2}");
    let gyro = |k: usize| norm(get(&t, rows[k], ["gyro_x", "gyro_y", "gyro_z"]));
    let mode = |k: usize| rows[k][col(&t, "fsw_mode")];
    // Detumble: B-dot commands, the rate falls from 1.5 deg/s; the gyro reads below 0.005
    // rad/s for the minute before the switch.
    assert!(gyro(0) > 0.025);
    for k in at(t1 - 60.0)..at(t1) {
        assert!(gyro(k) < 0.005 && mode(k) == 0.0, "t = {}", rows[k][0]);
    }
    // Sun acquisition: the Sun and field estimate within 3 sigma (the norms) once started,
    // through the slew and the braking (measured: 1.3 sigma at most), and the Sun sensor
    // sees the Sun on the arrays' normal (-z) at the switch.
    for k in at(t1 + 60.0)..at(t2) {
        let s = norm(get(
            &t,
            rows[k],
            ["est_sigma_x", "est_sigma_y", "est_sigma_z"],
        ));
        let e = rows[k][col(&t, "est_error")];
        assert!(e < 3.0 * s, "t = {}: {e} against 3 x {s}", rows[k][0]);
    }
    let sun = get(&t, rows[at(t2)], ["sun_x", "sun_y", "sun_z"]);
    assert!(angle(sun, [0.0, 0.0, -1.0]) < 0.03, "{sun:?}");
    // Nadir: after the slew and the dumping's transient, the pointing error stays within
    // the star tracker MEKF's 3 sigma plus 20 arc seconds.
    for k in at(t2 + 1500.0)..rows.len() {
        let s = norm(get(
            &t,
            rows[k],
            ["est_sigma_x", "est_sigma_y", "est_sigma_z"],
        ));
        let p = rows[k][col(&t, "pointing_error")];
        assert!(p < 3.0 * s + 20.0 * ARCSEC, "t = {}: {p}", rows[k][0]);
        assert_eq!(mode(k), 2.0);
    }
    // The wheels' momentum is dumped: from its value at the switch to nearly nothing.
    let h = |k: usize| {
        0.05 * norm(get(
            &t,
            rows[k],
            ["wheel_x_speed", "wheel_y_speed", "wheel_z_speed"],
        ))
    };
    let h_end = (at(10000.0)..rows.len()).map(h).fold(0.0, f64::max);
    assert!(
        h(at(t2)) > 0.1 && h_end < 0.01 * h(at(t2)),
        "{} {h_end}",
        h(at(t2))
    );
}

#[test]
fn a_rate_damping_control_on_the_torquers_slows_the_bus_as_bdot_does() {
    // kp = 0: the PID damps the estimated rate through the torquers, m = (B x u)/|B|^2.
    let sensors = "[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 1.0\nnoise_density = 1e-6\n[[sensors.star_tracker]]\nname = \"st\"\nbody = \"bus\"\nperiod = 1.0\nnoise_arcsec = [5.0, 5.0, 20.0]\n";
    let fsw = "[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = \"st\"\n[fsw.guidance]\nmode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]\n[fsw.control]\nkp = [0.0, 0.0, 0.0]\nkd = [0.05, 0.05, 0.05]\nactuator = \"torquers\"\nmagnetometer = \"mag\"\n";
    let free = run(&tumbling(sensors));
    let damped = run(&tumbling(&format!("{sensors}{fsw}")));
    let rate = |t: &Trajectory| -> Vec<f64> {
        t.rows()
            .map(|r| norm(get(t, r, ["omega_x", "omega_y", "omega_z"])))
            .collect()
    };
    let (w0, w1) = (rate(&free), rate(&damped));
    let last = w0.len() - 1;
    // Without it the tumble keeps its rate (gravity gradient only); with it the rate falls
    // to under a third in 3000 s.
    assert!(
        (w0[last] - w0[0]).abs() < 0.1 * w0[0],
        "{} {}",
        w0[0],
        w0[last]
    );
    assert!(w1[last] < w0[0] / 3.0, "{} {}", w1[0], w1[last]);
    // The torquers get the commands, within their 5 A m^2.
    let dipoles: Vec<f64> = damped
        .rows()
        .flat_map(|r| get(&damped, r, ["dipole_x", "dipole_y", "dipole_z"]))
        .collect();
    assert!(dipoles.iter().any(|d| d.abs() > 1.0));
    assert!(dipoles.iter().all(|d| d.abs() <= 5.0 + 1e-12));
}

#[test]
#[allow(clippy::needless_range_loop)] // each row against the one before
fn sun_pointing_slews_within_its_limits_and_points_the_axis_at_the_sun() {
    let base = std::fs::read_to_string(example(POINTING)).unwrap();
    let text = format!("epoch = \"2026-03-20T12:00:00 UTC\"\n{base}")
        .replacen("duration = 300.0", "duration = 600.0", 1)
        .replacen(
            "mode = \"inertial\"\nattitude = [1.0, 0.0, 0.0, 0.0]",
            "mode = \"sun\"\naxis = [1.0, 0.0, 0.0]\nsecondary = [0.0, 0.0, 1.0]\nmax_rate = 0.01\nmax_acceleration = 2e-4",
            1,
        )
        + "[[sensors.sun_sensor]]\nname = \"sun\"\nbody = \"bus\"\nperiod = 0.1\n";
    let mut scene = parse(&text, "sun_pointing.toml");
    scene.every = 0.1;
    let t = run(&scene);
    let rows: Vec<&[f64]> = t.rows().collect();
    // Rows at every control sample: the reference's rate within max_rate and its change
    // within max_acceleration x period (the Sun's own apparent motion, ~1e-6 rad/s, on top).
    let w = |k: usize| {
        Vector3::from(get(
            &t,
            rows[k],
            ["ref_omega_x", "ref_omega_y", "ref_omega_z"],
        ))
    };
    let mut peak: f64 = 0.0;
    for k in 1..rows.len() {
        peak = peak.max(w(k).norm());
        assert!(
            w(k).norm() <= 0.01 + 2e-6,
            "t = {}: {}",
            rows[k][0],
            w(k).norm()
        );
        assert!(
            (w(k) - w(k - 1)).norm() <= 2e-4 * 0.1 + 2e-7,
            "t = {}",
            rows[k][0]
        );
    }
    assert!(peak > 0.009, "the slew reached {peak}");
    // After the slew (about 1.6 rad at 0.01 rad/s) the Sun sensor sees the Sun on +x.
    let end = rows[rows.len() - 1];
    let sun = get(&t, end, ["sun_x", "sun_y", "sun_z"]);
    assert!(angle(sun, [1.0, 0.0, 0.0]) < 1e-3, "{sun:?}");
    assert!(end[col(&t, "pointing_error")] < 1e-3);
}

/// Twelve thrusters of `thrust` N in couples on the tumbling bus (`period` s PWM): about
/// each body axis, each way, two pushing in opposite directions 0.5 m either side of the
/// centre of mass, so that they make torque and no net force.
fn thruster_couples(thrust: f64, period: f64) -> String {
    let mut s = format!("[effects.thrusters]\nperiod = {period}\n");
    let e = |i: usize, v: f64| {
        let mut a = [0.0; 3];
        a[i] = v;
        format!("[{:?}, {:?}, {:?}]", a[0], a[1], a[2])
    };
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        for (sign, way) in [(1.0, "p"), (-1.0, "m")] {
            for (n, side) in [(1, 1.0), (2, -1.0)] {
                s += &format!(
                    "[[effects.thrusters.thruster]]\nname = \"{axis}{way}{n}\"\nat = {}\ndirection = {}\nthrust = {thrust}\n",
                    e(j, 0.5 * side),
                    e(k, sign * side)
                );
            }
        }
    }
    s
}

const THRUSTER_NAMES: [&str; 12] = [
    "thrust_xp1",
    "thrust_xp2",
    "thrust_xm1",
    "thrust_xm2",
    "thrust_yp1",
    "thrust_yp2",
    "thrust_ym1",
    "thrust_ym2",
    "thrust_zp1",
    "thrust_zp2",
    "thrust_zm1",
    "thrust_zm2",
];

/// The tumbling bus with a 10 Hz gyro and star tracker, the twelve thrusters of 0.5 N
/// (10 Hz PWM) and the estimator, an inertial guidance and a PID on the thrusters (5 Hz),
/// plus `extra`, for `duration` s with rows every `every` s (a row at a period start shows
/// the thrust just before it: rows between them see the pulses).
fn on_thrusters(control: &str, extra: &str, duration: f64, every: f64) -> Scene {
    let mut s = parse(&on_thrusters_text(control, extra), "thrusters.toml");
    s.duration = duration;
    s.every = every;
    s
}

fn on_thrusters_text(control: &str, extra: &str) -> String {
    let sensors = "[[sensors.gyro]]\nname = \"gyro\"\nbody = \"bus\"\nperiod = 0.1\nnoise_density = 1e-5\n[[sensors.star_tracker]]\nname = \"st\"\nbody = \"bus\"\nperiod = 0.1\nnoise_arcsec = [5.0, 5.0, 20.0]\n";
    let fsw = format!(
        "[fsw.estimator]\ngyro = \"gyro\"\nstar_tracker = \"st\"\n[fsw.guidance]\nmode = \"inertial\"\nattitude = [0.5, 0.5, 0.5, 0.5]\n[fsw.control]\n{control}actuator = \"thrusters\"\nperiod = 0.2\n"
    );
    tumbling_text(&format!(
        "{sensors}{}{fsw}{extra}",
        thruster_couples(THRUST, 0.1)
    ))
}

/// The thrusters' force (N): 0.2 N m about each axis at most.
const THRUST: f64 = 0.2;

/// Every thrust column is 0 or the thrust (the PWM's two values), and some fire.
fn thrust_columns_are_pwm(t: &Trajectory, thrust: f64) -> usize {
    let mut on = 0;
    for r in t.rows() {
        for v in get(t, r, THRUSTER_NAMES) {
            assert!(v == 0.0 || v == thrust, "{v}");
            on += usize::from(v == thrust);
        }
    }
    on
}

#[test]
fn a_rate_damping_control_on_the_thrusters_stops_the_tumble() {
    // kp = 0: the PID damps the estimated rate (4.1 deg/s) through the thrusters' couples,
    // 0.5 N m about each axis at most: the momentum (0.19 N m s) is gone within seconds.
    let t = run(&on_thrusters(
        "kp = [0.0, 0.0, 0.0]\nkd = [2.0, 2.0, 2.0]\n",
        "",
        60.0,
        0.01,
    ));
    let rate: Vec<f64> = t
        .rows()
        .map(|r| norm(get(&t, r, ["omega_x", "omega_y", "omega_z"])))
        .collect();
    assert!(rate[0] > 0.07, "{}", rate[0]);
    let last = *rate.last().unwrap();
    assert!(last < 1e-4, "{last}");
    // The loop's time constant is J / kd, about 1.25 s: well under 1e-3 rad/s by 10 s.
    assert!(rate[1000] < 1e-3, "{}", rate[1000]);
    assert!(thrust_columns_are_pwm(&t, THRUST) > 10);
}

#[test]
fn an_inertial_hold_on_the_thrusters_converges_from_two_radians_to_a_milliradian() {
    let t = run(&on_thrusters(
        "kp = [0.1, 0.1, 0.1]\nkd = [1.0, 1.0, 1.0]\n",
        "",
        150.0,
        0.5,
    ));
    let pointing: Vec<f64> = t
        .rows()
        .map(|r| get(&t, r, ["pointing_error"])[0])
        .collect();
    assert!(pointing[0] > 1.0, "{}", pointing[0]);
    // From 2.1 rad to within 1e-3 rad by 100 s (the loop's time constant is about 10 s),
    // at rest. The estimate's error (1e-4 rad here, over its 1σ of 1e-5) comes mostly from
    // the gyro sampling the rate at instants while the PWM's torque changes it within the
    // period (the estimator integrates the samples' mean); the pointing error is that and
    // the PD's response to the noise.
    for r in t.rows().filter(|r| r[0] >= 100.0) {
        let [p, e] = get(&t, r, ["pointing_error", "est_error"]);
        assert!(
            p < 1e-3 && e < 3e-4,
            "t = {}: pointing {p}, estimate {e}",
            r[0]
        );
        let w = norm(get(&t, r, ["omega_x", "omega_y", "omega_z"]));
        assert!(w < 1e-4, "t = {}: {w}", r[0]);
    }
}

#[test]
fn a_mode_without_the_control_stops_the_thrusters_from_their_next_period() {
    let modes = "[[fsw.mode]]\nname = \"hold\"\nblocks = [\"estimator\", \"guidance\", \"control\"]\nuntil = \"time > 20\"\n[[fsw.mode]]\nname = \"coast\"\nblocks = [\"estimator\"]\n";
    let t = run(&on_thrusters(
        "kp = [0.1, 0.1, 0.1]\nkd = [1.0, 1.0, 1.0]\n",
        modes,
        30.0,
        0.01,
    ));
    let fired = |r: &[f64]| get(&t, r, THRUSTER_NAMES).iter().any(|&v| v > 0.0);
    // Still acquiring at 20 s: they fire up to the switch at the 20.1 s sample (a period
    // start, whose duties the switch zeroes), then never again.
    assert!(t.rows().filter(|r| r[0] < 20.0).any(fired));
    assert!(t.rows().filter(|r| r[0] >= 20.5).all(|r| !fired(r)));
    let modes: Vec<f64> = t.rows().map(|r| get(&t, r, ["fsw_mode"])[0]).collect();
    assert_eq!((modes[0], *modes.last().unwrap()), (0.0, 1.0));
}

#[test]
fn bad_thruster_controls_are_errors_at_their_line() {
    let base = std::fs::read_to_string(example(POINTING)).unwrap();
    let to_thrusters =
        |text: &str| text.replacen("actuator = \"wheels\"", "actuator = \"thrusters\"", 1);
    // (No [effects.thrusters]: in bad_fsw_input_is_an_error_naming_the_file_and_line.)
    // Thrusters, none on the root body.
    let on_panel = "[effects.thrusters]\nperiod = 0.1\n[[effects.thrusters.thruster]]\nname = \"a\"\nbody = \"panel1\"\nat = [0.0, 0.0, 0.0]\ndirection = [1.0, 0.0, 0.0]\nthrust = 1.0\n";
    assert_error_at(
        &format!("{}\n{on_panel}", to_thrusters(&base)),
        "[fsw.control]",
        "needs thrusters on the root body",
    );
    // A control period that is not a whole multiple of the thrusters' period: at the
    // control's `period`, or at the table when it takes the estimator's.
    let ok = on_thrusters_text("kp = [0.1, 0.1, 0.1]\nkd = [1.0, 1.0, 1.0]\n", "");
    let text = ok.replacen("period = 0.2\n", "period = 0.25\n", 1);
    parse(
        &ok.replacen("period = 0.2\n", "period = 0.3\n", 1),
        "ok.toml",
    );
    assert_error_at(
        &text,
        "period = 0.25",
        "must be a whole multiple of [effects.thrusters] `period` (0.1 s)",
    );
    let slow = text.replacen("period = 0.25\n", "", 1).replacen(
        "[effects.thrusters]\nperiod = 0.1",
        "[effects.thrusters]\nperiod = 0.3",
        1,
    );
    assert_error_at(
        &slow,
        "[fsw.control]",
        "(0.1 s, the estimator's) must be a whole multiple",
    );
    // A disabled [effects.thrusters] has no thrusters.
    let disabled = text.replacen(
        "[effects.thrusters]\nperiod = 0.1",
        "[effects.thrusters]\nperiod = 0.1\nenabled = false",
        1,
    );
    assert_error_at(&disabled, "[fsw.control]", "needs [effects.thrusters]");
}

/// The closed-loop example's PID at a period its loop is unstable at is a warning at the
/// `[fsw.control]` line, with its gains and the longest stable period; at its own period,
/// none. The runs agree, the MEKF in the loop: from the deployed state (the stops off, so
/// that it stays) the check's boundary is 3.55 s; over 300 s at a period of 3.3 s the
/// attitude stays within 4.4e-4 rad of its target, at 3.8 s it chatters at 6.3e-3 rad
/// inside the wheels' torque limits.
#[test]
fn a_pid_unstable_at_its_period_is_a_warning_at_its_table() {
    let warned = |s: &Scene| {
        s.warnings
            .iter()
            .find(|w| w.contains("the sampled law is unstable"))
            .cloned()
    };
    assert_eq!(warned(&read(POINTING, &[])), None);
    let w = warned(&read(POINTING, &["fsw.control.period=20"])).expect("a warning");
    assert!(
        w.contains("fsw_mekf_pointing.toml:121 (with --set): [fsw.control]: the sampled law is unstable at `period` = 20 s")
            && w.contains("kp = [40, 40, 40] N m/rad, ki = [2, 2, 2] N m/(rad s), kd = [300, 300, 300] N m s/rad")
            && w.contains("it is stable at periods up to 5.1147e0 s"),
        "{w}"
    );
    let deployed = |period: &str| {
        let p = format!("fsw.control.period={period}");
        let sets = [
            "initial.hinges.angle=[0.0, 0.0, 0.0, 0.0, 0.0]",
            "effects.hinge_stops.enabled=false",
            "duration=300",
            &p,
        ];
        read(POINTING, &sets)
    };
    let below = deployed("3.3");
    let w = warned(&deployed("3.8")).expect("a warning");
    assert!(w.contains("stable at periods up to 3.5492e0 s"), "{w}");
    assert_eq!(warned(&below), None);
    // The largest rotation from the target (the identity) over the run.
    let largest = |s: &Scene| {
        let t = run(s);
        t.rows()
            .map(|r| {
                let [x, y, z] = get(&t, r, ["q_x", "q_y", "q_z"]);
                2.0 * (x * x + y * y + z * z).sqrt().min(1.0).asin()
            })
            .fold(0.0, f64::max)
    };
    let (stable, unstable) = (largest(&below), largest(&deployed("3.8")));
    assert!(stable < 1e-3 && unstable > 5e-3, "{stable} {unstable}");
}

/// A 100 kg bus on three wheels, a gyro and a star tracker, the MEKF, an inertial guidance
/// to `attitude` and the PID on the wheels, for `duration` s, plus `extra`.
fn bus_text(attitude: &str, duration: f64, extra: &str) -> String {
    format!(
        r#"duration = {duration}

[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[20.0, 0.0, 0.0], [0.0, 25.0, 0.0], [0.0, 0.0, 30.0]]

[initial]
base = {{ attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.001, -0.002, 0.0015] }}

[integrator]
method = "rk4"
step = 0.05

[output]
every = 1.0
plots = false
view = false

[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "x"
axis = [1.0, 0.0, 0.0]
inertia = 0.05
max_torque = 0.2
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.05
max_torque = 0.2
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.05
max_torque = 0.2

[sensors]
seed = 3
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.1
noise_density = 1e-5
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.1
noise_arcsec = [5.0, 5.0, 40.0]

[fsw.estimator]
kind = "mekf"
gyro = "gyro"
star_tracker = "st"
period = 0.1

[fsw.guidance]
mode = "inertial"
attitude = {attitude}

[fsw.control]
kind = "pid"
kp = [2.0, 2.0, 2.0]
kd = [20.0, 20.0, 20.0]
actuator = "wheels"
period = 0.1
{extra}"#
    )
}

/// The inertial guidance's reference attitude in `scene`.
fn guidance_attitude(scene: &Scene) -> [f64; 4] {
    let onboard = scene.effects.get::<Sensors>().unwrap().fsw().unwrap();
    let q = onboard.reference_at(0.0, None).unwrap().attitude;
    [q.w, q.i, q.j, q.k]
}

#[test]
fn a_quaternion_within_1e_3_of_unit_is_normalised_with_a_warning_and_refused_beyond() {
    let line_of = |text: &str, at: &str| {
        text.lines()
            .position(|l| l.trim_start().starts_with(at))
            .unwrap()
            + 1
    };
    // Five digits (norm 1 + 4.6e-6): normalised, a warning at its line.
    let text = bus_text("[0.70711, 0.0, 0.0, 0.70711]", 1.0, "");
    let scene = parse(&text, "bad_fsw.toml");
    let q = guidance_attitude(&scene);
    // The written components in the same ratio, on unit norm.
    assert!(
        (q[0] - q[3]).abs() < 1e-15 && q[1] == 0.0 && q[2] == 0.0,
        "{q:?}"
    );
    assert!((q[0] * q[0] + q[3] * q[3] - 1.0).abs() < 1e-15, "{q:?}");
    let line = line_of(&text, "attitude = [0.70711");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains(&format!("bad_fsw.toml:{line}:"))
                && w.contains("`fsw.guidance.attitude`: quaternion norm 1.00000455")
                && w.contains("normalised")),
        "{:?}",
        scene.warnings
    );
    // Rounding only: no warning.
    let scene = parse(
        &bus_text("[1.0000000001, 0.0, 0.0, 0.0]", 1.0, ""),
        "ok.toml",
    );
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Beyond 1e-3: refused, the tolerance stated.
    let text = bus_text("[1.0, 0.05, 0.0, 0.0]", 1.0, "");
    assert_error_at(
        &text,
        "attitude = [1.0, 0.05",
        "within 1e-3 of 1 it is normalised",
    );
    assert_error_at(&text, "attitude = [1.0, 0.05", "quaternion norm 1.00124");

    // The truth-based controller's target, by the same rule.
    let control = |q: &str| {
        let deploy = std::fs::read_to_string(example("scenes/fsw_in_the_loop.toml")).unwrap();
        let (head, tail) = deploy.split_once("[effects.attitude_control]").unwrap();
        let tail = tail.replacen(
            "attitude = [1.0, 0.0, 0.0, 0.0]",
            &format!("attitude = {q}"),
            1,
        );
        assert!(tail.contains(&format!("attitude = {q}")));
        format!("{head}[effects.attitude_control]{tail}")
    };
    let text = control("[1.0, 0.01, 0.0, 0.0]");
    let scene = parse(&text, "bad_fsw.toml");
    let line = line_of(&text, "attitude = [1.0, 0.01");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains(&format!("bad_fsw.toml:{line}:"))
                && w.contains("`effects.attitude_control.attitude`: quaternion norm 1.00004999")
                && w.contains("normalised")),
        "{:?}",
        scene.warnings
    );
    use satsim_spacecraft::effects::{AttitudeControl, Target};
    let Target::Inertial(q) = scene.effects.get::<AttitudeControl>().unwrap().target else {
        panic!("an inertial target")
    };
    let n = 1.0001f64.sqrt();
    assert!((q.w - 1.0 / n).abs() < 1e-15 && (q.i - 0.01 / n).abs() < 1e-15);
    let text = control("[1.0, 0.1, 0.0, 0.0]");
    assert_error_at(
        &text,
        "attitude = [1.0, 0.1",
        "within 1e-3 of 1 it is normalised",
    );
}

/// A campaign that disperses one component of the guidance's quaternion by more than the
/// scene's 1e-3 normalises the drawn quaternion: every run finishes, on the attitude the
/// drawn quaternion points at, and `runs.csv` keeps the component as drawn.
#[test]
fn a_campaign_dispersing_a_quaternion_component_normalises_each_drawn_quaternion() {
    let campaign = "\n[campaign]\nruns = 8\nseed = 5\n[[campaign.disperse]]\n\
        key = \"fsw.guidance.attitude\"\nindex = 1\nnormal = { sigma = 0.1 }\n";
    let text = bus_text("[1.0, 0.0, 0.0, 0.0]", 2.0, campaign);
    let c =
        Campaign::parse(&text, std::path::Path::new("bus.toml")).unwrap_or_else(|e| panic!("{e}"));
    let ref_x = c.columns.iter().position(|n| n == "ref_q_x").unwrap() - 1;
    let mut beyond = 0;
    for k in 0..8 {
        let r = c.run_one(k);
        let x = r.values[0];
        let stats = r
            .outcome
            .as_ref()
            .unwrap_or_else(|e| panic!("run {k}: {e}"));
        beyond += usize::from((1.0 + x * x).sqrt() - 1.0 > 1e-3);
        // The reference is the drawn quaternion normalised.
        let want = x / (1.0 + x * x).sqrt();
        assert!((stats.last[ref_x] - want).abs() < 1e-12, "run {k}: {x}");
        let scene = Scene::parse(&c.run_text(k, &r.values), std::path::Path::new("bus.toml"))
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }
    assert!(
        beyond >= 2,
        "{beyond} of the draws moved the norm by more than 1e-3"
    );
}

/// A noiseless gyro (with a bias) and star tracker: the MEKF's updates take the least 1σ
/// (`MIN_SIGMA`, 1e-6 rad) and stay well posed; the estimate follows the truth within it and
/// finds the gyro's bias.
#[test]
fn the_mekf_on_a_noiseless_gyro_and_star_tracker_runs_and_follows_the_truth() {
    let text = bus_text("[1.0, 0.0, 0.0, 0.0]", 60.0, "")
        .replacen("noise_density = 1e-5", "bias = [1e-5, -1e-5, 2e-5]", 1)
        .replacen(
            "noise_arcsec = [5.0, 5.0, 40.0]",
            "noise_arcsec = [0.0, 0.0, 0.0]",
            1,
        );
    assert!(text.contains("noise_arcsec = [0.0, 0.0, 0.0]") && !text.contains("noise_density"));
    let t = run(&parse(&text, "noiseless.toml"));
    let mut rows = 0;
    for row in t.rows().filter(|r| r[0] >= 1.0) {
        let [error] = get(&t, row, ["est_error"]);
        assert!(error < 1e-6, "t = {}: est_error {error}", row[0]);
        if row[0] >= 10.0 {
            let b = get(&t, row, ["est_bias_x", "est_bias_y", "est_bias_z"]);
            let off = norm([b[0] - 1e-5, b[1] + 1e-5, b[2] - 2e-5]);
            assert!(off < 1e-8, "t = {}: bias {b:?}", row[0]);
        }
        rows += 1;
    }
    assert!(rows >= 60, "{rows}");
}

/// `[fsw.control]` on the wheels allocates to the root body's wheels: two of them reach two
/// axes, a warning at the table names the third; three reach every axis, no warning.
#[test]
fn a_control_on_root_wheels_that_span_two_axes_is_warned_of_naming_the_third() {
    let y_wheel = "[[effects.reaction_wheels.wheel]]\nname = \"y\"\naxis = [0.0, 1.0, 0.0]\ninertia = 0.05\nmax_torque = 0.2\n";
    let full = bus_text("[1.0, 0.0, 0.0, 0.0]", 1.0, "");
    assert!(full.contains(y_wheel));
    let scene = parse(&full, "bus.toml");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let text = full.replacen(y_wheel, "", 1);
    let scene = parse(&text, "bus.toml");
    let line = text.lines().position(|l| l == "[fsw.control]").unwrap() + 1;
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains(&format!("bus.toml:{line}:"))
                && w.contains("span 2 of the 3 axes")
                && w.contains("about [0, 1, 0] (body axes)")),
        "{:?}",
        scene.warnings
    );
}
