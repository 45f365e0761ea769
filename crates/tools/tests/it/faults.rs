//! `[[faults]]`: each kind against a closed form or the unfaulted run (a wheel switched off
//! keeps the speed it had, `τ (1/I_w + 1/I_b) t_f`; a seized wheel's impulse conserves the
//! angular momentum and leaves the rigid body of the closed form; a thruster stuck on or off
//! gives the impulse of its on-time; a stuck sensor repeats its last reading, a biased one
//! the unfaulted reading plus the bias), each logged at its time, bad input refused at its
//! line, and a campaign over the fault's time.

use satsim_integrate::Output;
use satsim_tools::api::Trajectory;
use satsim_tools::campaign::{Campaign, Quiet, RunOptions, Shard, run_campaign};
use satsim_tools::scene::Scene;
use std::path::Path;

/// The bus's inertia about z and the wheel's axial inertia (kg m²).
const I_BUS: f64 = 8.0;
const I_WHEEL: f64 = 0.05;

/// A free bus (diagonal inertia [10, 12, `I_BUS`]) with wheel `rw1` on z (`wheel` more keys
/// of its table), `initial` its `[initial]` keys, RK4 at 0.01 s, rows every 0.1 s, then
/// `extra` (faults, sensors, a campaign).
fn wheel_scene(duration: f64, initial: &str, wheel: &str, extra: &str) -> String {
    format!(
        r#"duration = {duration}
[model]
[[model.body]]
name = "bus"
mass = 50.0
inertia = [[10.0, 0.0, 0.0], [0.0, 12.0, 0.0], [0.0, 0.0, {I_BUS:?}]]
[initial]
{initial}
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.1
plots = false
view = false
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "rw1"
axis = [0.0, 0.0, 1.0]
inertia = {I_WHEEL:?}
{wheel}
{extra}
"#
    )
}

fn parse(text: &str) -> Scene {
    Scene::parse(text, Path::new("faults.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// The error of `text`, which must be refused.
fn refused(text: &str) -> String {
    match Scene::parse(text, Path::new("faults.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A run of `scene`: its rows and its events `(t, effect, what)`.
fn run(scene: &Scene) -> (Trajectory, Vec<(f64, String, String)>) {
    let mut sim = scene.simulation().unwrap_or_else(|e| panic!("{e}"));
    let mut out = Trajectory {
        columns: sim.columns(),
        values: Vec::new(),
    };
    let t_end = sim.t0() + scene.duration;
    sim.run(
        &scene.options,
        t_end,
        &Output::Interval(scene.every),
        |_, row| -> Result<(), std::convert::Infallible> {
            out.values.extend_from_slice(row);
            Ok(())
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let events = sim
        .event_records()
        .map(|(t, e, w)| (t, e.to_owned(), w.to_owned()))
        .collect();
    (out, events)
}

fn col(t: &Trajectory, name: &str) -> usize {
    t.columns
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {:?}", t.columns))
}

/// `(t, value)` of column `name` over the rows.
fn series(t: &Trajectory, name: &str) -> Vec<(f64, f64)> {
    let c = col(t, name);
    t.rows().map(|r| (r[0], r[c])).collect()
}

const AT_REST: &str =
    "base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.0, 0.0, 0.0] }";

#[test]
fn a_wheel_switched_off_keeps_the_speed_its_torque_gave_it_and_the_momentum_stays_zero() {
    let tau = 0.01;
    let at = 3.0;
    let fault = format!("[[faults]]\nat = {at:?}\nkind = \"wheel_off\"\ntarget = \"rw1\"\n");
    let scene = parse(&wheel_scene(
        6.0,
        AT_REST,
        &format!("torque = {tau}"),
        &fault,
    ));
    let (t, events) = run(&scene);
    // Bus and wheel about z: I_b ω̇ = −τ, I_w (ω̇ + Ω̇) = τ, so Ω̇ = τ (1/I_w + 1/I_b).
    let rate = tau * (1.0 / I_WHEEL + 1.0 / I_BUS);
    let torque = col(&t, "wheel_rw1_torque");
    for ((time, speed), row) in series(&t, "wheel_rw1_speed").into_iter().zip(t.rows()) {
        let want = rate * time.min(at);
        assert!(
            (speed - want).abs() <= 1e-13 * want.abs().max(1.0),
            "t {time}: {speed} against {want}"
        );
        // A row at the fault is written before it.
        let motor = if time <= at { tau } else { 0.0 };
        assert_eq!(row[torque], motor, "t {time}");
    }
    // The motor's torque is internal: the momentum stays zero.
    for (time, h) in series(&t, "h_norm") {
        assert!(h <= 1e-15, "t {time}: |h| = {h}");
    }
    assert_eq!(
        events,
        [(
            at,
            "reaction_wheels".to_owned(),
            "fault: wheel `rw1` off (its motor gives no torque)".to_owned()
        )]
    );
}

#[test]
fn a_seized_wheel_shares_its_momentum_with_the_bus_in_the_closed_form() {
    // Bus and wheel spinning about z (a principal axis): every rate is constant but at the
    // fault, where the rigid body takes the z momentum `I_b ω + I_w (ω + Ω)`.
    let (omega, speed, at) = (0.02, 120.0, 2.5);
    let initial = format!(
        "base = {{ attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.0, 0.0, {omega:?}] }}"
    );
    let fault = format!("[[faults]]\nat = {at:?}\nkind = \"wheel_stuck\"\ntarget = \"rw1\"\n");
    let text = wheel_scene(5.0, &initial, &format!("speed = {speed:?}"), &fault);
    // A fixed step and an adaptive method alike land on the fault.
    for method in ["rk4", "dp54"] {
        let scene = parse(&text.replace("\"rk4\"", &format!("\"{method}\"")));
        seized_in_closed_form(&scene, omega, speed, at);
    }
}

/// The run of `scene` (bus and wheel at `omega` and `speed` about z, the wheel seized at
/// `at`) against the closed form.
fn seized_in_closed_form(scene: &Scene, omega: f64, speed: f64, at: f64) {
    let (t, events) = run(scene);
    let h = I_BUS * omega + I_WHEEL * (omega + speed);
    let after = h / (I_BUS + I_WHEEL);
    let energy = |w: f64, s: f64| 0.5 * I_BUS * w * w + 0.5 * I_WHEEL * (w + s) * (w + s);
    let (wz, sp, hz, ke) = (
        col(&t, "omega_z"),
        col(&t, "wheel_rw1_speed"),
        col(&t, "h_z"),
        col(&t, "kinetic_energy"),
    );
    for r in t.rows() {
        let (w, s, e) = if r[0] <= at {
            (omega, speed, energy(omega, speed))
        } else {
            (after, 0.0, energy(after, 0.0))
        };
        assert!(
            (r[wz] - w).abs() <= 1e-14 * w,
            "t {}: ω {} against {w}",
            r[0],
            r[wz]
        );
        assert!(
            (r[sp] - s).abs() <= 1e-12 * speed,
            "t {}: Ω {}",
            r[0],
            r[sp]
        );
        assert!(
            (r[hz] - h).abs() <= 1e-14 * h,
            "t {}: h {} against {h}",
            r[0],
            r[hz]
        );
        assert!(
            (r[ke] - e).abs() <= 1e-13 * e,
            "t {}: T {} against {e}",
            r[0],
            r[ke]
        );
    }
    assert!(energy(after, 0.0) < 0.5 * energy(omega, speed));
    // The energy the seizure takes is booked as dissipated: the budget stays closed.
    let e0 = energy(omega, speed);
    for (time, b) in series(&t, "energy_budget") {
        assert!(
            (b - e0).abs() <= 1e-13 * e0,
            "t {time}: budget {b} against {e0}"
        );
    }
    let lost = series(&t, "energy_dissipated").last().unwrap().1;
    let want = e0 - energy(after, 0.0);
    assert!((lost - want).abs() <= 1e-12 * want, "{lost} against {want}");
    assert_eq!(events.len(), 1, "{events:?}");
    assert_eq!(events[0].0, at);
    assert_eq!(
        events[0].2,
        format!("fault: wheel `rw1` stuck (speed {speed} rad/s lost)")
    );
}

#[test]
fn a_seizure_in_a_tumble_conserves_the_angular_momentum_and_leaves_no_relative_speed() {
    // A tilted, off-centre wheel of 1 kg in a tumble, seized at the start: the state the
    // fault leaves against the one before it.
    let wheel = "speed = 150.0\nmass = 1.0\nat = [0.1, -0.05, 0.02]\ntransverse = 0.03";
    let initial =
        "base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.01, -0.02, 0.03] }";
    let fault = "[[faults]]\nat = 0.0\nkind = \"wheel_stuck\"\ntarget = \"rw1\"\n";
    let text = wheel_scene(1.0, initial, wheel, fault)
        .replace("axis = [0.0, 0.0, 1.0]", "axis = [1.0, 2.0, 2.0]");
    let scene = parse(&text);
    let mut sim = scene.simulation().unwrap();
    let (t0, x0) = (sim.t0(), sim.x0().to_vec());
    let before = sim.diagnostics(t0, &x0).unwrap();
    let (t, x) = sim.state_at(&scene.options, t0).unwrap();
    assert_eq!(t, t0);
    let after = sim.diagnostics(t, &x).unwrap();
    let dh = (after.h - before.h).norm();
    assert!(
        dh <= 1e-12 * before.h.norm(),
        "Δh {dh} of {}",
        before.h.norm()
    );
    assert!(after.kinetic < before.kinetic);
    let mut row = Vec::new();
    sim.row(t, &x, &mut row).unwrap();
    let speed = row[sim
        .columns()
        .iter()
        .position(|c| c == "wheel_rw1_speed")
        .unwrap()];
    assert!(speed.abs() <= 1e-12 * 150.0, "Ω {speed}");
    // Seized for good: a whole run ends with the wheel turning with the bus.
    let (t, events) = run(&scene);
    let last = series(&t, "wheel_rw1_speed").last().unwrap().1;
    assert!(last.abs() <= 1e-12 * 150.0, "Ω {last}");
    assert!(
        events[0]
            .2
            .starts_with("fault: wheel `rw1` stuck (speed 150")
    );
}

/// A bus of 80 kg with its centre of mass at its origin and thruster `x` along x through it
/// (2 N, PWM period 0.1 s) at `duty`, with `faults`.
fn thruster_scene(duty: f64, faults: &str) -> Scene {
    parse(&format!(
        r#"duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 80.0
inertia = [[6.0, 0.0, 0.0], [0.0, 8.0, 0.0], [0.0, 0.0, 10.0]]
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.05
plots = false
view = false
[effects.thrusters]
period = 0.1
[[effects.thrusters.thruster]]
name = "x"
at = [0.0, 0.0, 0.0]
direction = [1.0, 0.0, 0.0]
thrust = 2.0
duty = {duty:?}
{faults}
"#
    ))
}

/// The linear momentum along x at the end of a run of `scene` (N s).
fn momentum(scene: &Scene) -> f64 {
    let mut sim = scene.simulation().unwrap();
    let (t, x) = sim.state_at(&scene.options, scene.duration).unwrap();
    assert_eq!(t, scene.duration);
    sim.diagnostics(t, &x).unwrap().p.x
}

#[test]
fn a_thruster_stuck_on_or_off_gives_the_impulse_of_its_on_time() {
    let fault = |kind: &str, at: f64| {
        format!("[[faults]]\nat = {at:?}\nkind = \"{kind}\"\ntarget = \"x\"\n")
    };
    // (duty, fault, on-time over the second): pulses of duty × 0.1 s from each period start.
    let cases = [
        // Never commanded, stuck on at 0.35: 0.65 s.
        (0.0, fault("thruster_stuck_on", 0.35), 0.65),
        // 0.3 duty: four whole pulses of 0.03 s, then on from 0.35.
        (0.3, fault("thruster_stuck_on", 0.35), 4.0 * 0.03 + 0.65),
        // Full duty, off at 0.35.
        (1.0, fault("thruster_off", 0.35), 0.35),
        // Half duty, off in the middle of the pulse from 0.3: three pulses and 0.02 s.
        (0.5, fault("thruster_off", 0.32), 3.0 * 0.05 + 0.02),
    ];
    for (duty, f, on) in cases {
        let scene = thruster_scene(duty, &f);
        let p = momentum(&scene);
        let want = 2.0 * on;
        assert!((p - want).abs() <= 1e-13, "{f}: p {p} against {want}");
        let (t, events) = run(&scene);
        let at: f64 = if f.contains("0.32") { 0.32 } else { 0.35 };
        let stuck = f.contains("stuck_on");
        for (time, thrust) in series(&t, "thrust_x") {
            if time > at {
                assert_eq!(thrust, if stuck { 2.0 } else { 0.0 }, "{f}: t {time}");
            }
        }
        let what = if stuck {
            "fault: thruster `x` stuck on (full thrust)"
        } else {
            "fault: thruster `x` off (fires no more)"
        };
        assert_eq!(
            events,
            [(at, "thrusters".to_owned(), what.to_owned())],
            "{f}"
        );
    }
}

/// A tumbling bus with a noisy, biased gyro `g` and a star tracker `st` sampled every 0.1 s
/// (seed 5), rows every 0.05 s, with `faults`.
fn sensor_scene(faults: &str) -> Scene {
    let initial = "base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.1, -0.2, 0.3] }";
    let sensors = r#"[sensors]
seed = 5
[[sensors.gyro]]
name = "g"
body = "bus"
period = 0.1
noise_density = 1e-4
bias_walk = 1e-5
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.1
noise_arcsec = [5.0, 5.0, 20.0]
"#;
    let text = wheel_scene(1.0, initial, "", &format!("{sensors}\n{faults}"))
        .replace("every = 0.1", "every = 0.05");
    parse(&text)
}

#[test]
fn a_biased_sensor_reads_the_unfaulted_reading_plus_the_bias_and_a_stuck_one_its_last() {
    let bias = [1e-3, -2e-3, 3e-3];
    let faults = format!(
        "[[faults]]\nat = 0.5\nkind = \"sensor_bias\"\ntarget = \"g\"\nvalue = {bias:?}\n\
         [[faults]]\nat = 0.55\nkind = \"sensor_stuck\"\ntarget = \"st\"\n"
    );
    let (nominal, none) = run(&sensor_scene(""));
    assert!(none.is_empty());
    let (faulty, events) = run(&sensor_scene(&faults));
    assert_eq!(nominal.columns, faulty.columns);
    let names = &nominal.columns;
    let st = col(&nominal, "st_q_w");
    let mut held = None;
    for (a, b) in nominal.rows().zip(faulty.rows()) {
        let t = a[0];
        assert_eq!(t, b[0]);
        for (c, name) in names.iter().enumerate() {
            if let Some(axis) = ["g_x", "g_y", "g_z"].iter().position(|n| n == name)
                && t >= 0.5
            {
                let want = a[c] + bias[axis];
                assert!(
                    (b[c] - want).abs() <= 1e-18,
                    "t {t} {name}: {} against {want}",
                    b[c]
                );
            } else if name.starts_with("st_") && t >= 0.55 {
                continue;
            } else {
                // The fault's stops are observations only: every other value bit for bit.
                assert_eq!(a[c].to_bits(), b[c].to_bits(), "t {t} {name}");
            }
        }
        // The tracker's reading of the sample at 0.5 s, the last before 0.55 s, for good.
        if (t - 0.5).abs() < 1e-12 {
            held = Some(a[st..st + 4].to_vec());
        }
        if t >= 0.55 {
            assert_eq!(&b[st..st + 4], &held.clone().unwrap()[..], "t {t}");
        }
    }
    let held = held.unwrap();
    let show = |v: &[f64]| {
        let s: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
        format!("[{}]", s.join(", "))
    };
    assert_eq!(
        events,
        [
            (
                0.5,
                "sensors".to_owned(),
                "fault: sensor `g` biased by [0.001, -0.002, 0.003]".to_owned()
            ),
            (
                0.55,
                "sensors".to_owned(),
                format!("fault: sensor `st` stuck (reading held at {})", show(&held))
            ),
        ]
    );
}

#[test]
fn bad_faults_are_refused_at_their_line() {
    let scene = |fault: &str| wheel_scene(1.0, AT_REST, "", &format!("[[faults]]\n{fault}"));
    // The line of `key` in the last `[[faults]]` table.
    let line = |text: &str, key: &str| {
        let lines: Vec<&str> = text.lines().collect();
        let table = lines.iter().rposition(|l| *l == "[[faults]]").unwrap();
        1 + table
            + lines[table..]
                .iter()
                .position(|l| l.starts_with(key))
                .unwrap()
    };
    let cases = [
        (
            "at = -1.0\nkind = \"wheel_off\"\ntarget = \"rw1\"",
            "at",
            "`faults.at` must be a finite time >= 0 (s), got -1",
        ),
        (
            "at = nan\nkind = \"wheel_off\"\ntarget = \"rw1\"",
            "at",
            "`faults.at` must be a finite time >= 0 (s), got NaN",
        ),
        (
            "at = 1.0\nkind = \"wheel_jammed\"\ntarget = \"rw1\"",
            "kind",
            "unknown kind `wheel_jammed` (known: wheel_stuck, wheel_off, thruster_stuck_on, thruster_off, sensor_stuck, sensor_bias)",
        ),
        (
            "at = 1.0\nkind = \"wheel_off\"\ntarget = \"rw9\"",
            "target",
            "no wheel `rw9` in the scene (its wheels: rw1)",
        ),
        (
            "at = 1.0\nkind = \"thruster_off\"\ntarget = \"rw1\"",
            "target",
            "a `thruster_off` fault needs thrusters, and the scene has none ([effects.thrusters])",
        ),
        (
            "at = 1.0\nkind = \"sensor_stuck\"\ntarget = \"rw1\"",
            "target",
            "a `sensor_stuck` fault needs sensors, and the scene has none ([sensors])",
        ),
        (
            "at = 1.0\nkind = \"wheel_stuck\"\ntarget = \"rw1\"\nvalue = 2.0",
            "value",
            "a `wheel_stuck` fault takes no value",
        ),
    ];
    for (fault, key, message) in cases {
        let text = scene(fault);
        let e = refused(&text);
        let want = format!("faults.toml:{}:", line(&text, key));
        assert!(e.contains(&want), "{e}: not at {want}");
        assert!(e.contains(message), "{e}: not {message}");
    }
    // A missing key is the schema's error at the table.
    let e = refused(&scene("at = 1.0\nkind = \"wheel_off\""));
    assert!(e.contains("faults.toml:") && e.contains("target"), "{e}");
    // A bias: missing, of the wrong shape, of the wrong length.
    let with_gyro = |fault: &str| {
        wheel_scene(
            1.0,
            AT_REST,
            "",
            &format!(
                "[sensors]\n[[sensors.gyro]]\nname = \"g\"\nbody = \"bus\"\nperiod = 0.1\n[[faults]]\n{fault}"
            ),
        )
    };
    for (fault, key, message) in [
        (
            "at = 1.0\nkind = \"sensor_bias\"\ntarget = \"g\"",
            "kind",
            "needs the bias",
        ),
        (
            "at = 1.0\nkind = \"sensor_bias\"\ntarget = \"g\"\nvalue = \"big\"",
            "value",
            "must be a finite number or an array of finite numbers",
        ),
        (
            "at = 1.0\nkind = \"sensor_bias\"\ntarget = \"g\"\nvalue = 1e-3",
            "value",
            "a `sensor_bias` of gyro `g` needs 3 finite numbers (one per component of its reading, its units), got [0.001]",
        ),
        // The second of two faults is refused at its own `kind`.
        (
            "at = 1.0\nkind = \"sensor_stuck\"\ntarget = \"g\"\n[[faults]]\nat = 2.0\nkind = \"sensor_stuck\"\ntarget = \"g\"",
            "kind",
            "sensor `g` has two `sensor_stuck` faults",
        ),
    ] {
        let text = with_gyro(fault);
        let e = refused(&text);
        let want = format!("faults.toml:{}:", line(&text, key));
        assert!(e.contains(&want), "{e}: not at {want}");
        assert!(e.contains(message), "{e}: not {message}");
    }
}

#[test]
fn a_campaign_over_the_fault_time_gives_each_run_its_own() {
    let tau = 0.01;
    let campaign = "[[faults]]\nat = 3.0\nkind = \"wheel_off\"\ntarget = \"rw1\"\n\n\
        [campaign]\nruns = 4\nseed = 3\n[[campaign.disperse]]\nkey = \"faults.0.at\"\n\
        uniform = { low = -2.0, high = 2.0 }\n";
    let text = wheel_scene(6.0, AT_REST, &format!("torque = {tau}"), campaign);
    let c = Campaign::parse(&text, Path::new("faults.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        c.header().iter().any(|h| h == "faults.0.at"),
        "{:?}",
        c.header()
    );
    let speed = c
        .columns
        .iter()
        .position(|n| n == "wheel_rw1_speed")
        .unwrap()
        - 1;
    let rate = tau * (1.0 / I_WHEEL + 1.0 / I_BUS);
    let mut times = Vec::new();
    for k in 0..4 {
        let r = c.run_one(k);
        let at = r.values[0];
        assert!((1.0..5.0).contains(&at), "run {k}: {at}");
        // The run's wheel stopped gaining speed at its own fault time.
        let last = r.outcome.as_ref().unwrap().last[speed];
        assert!(
            (last - rate * at).abs() <= 1e-12,
            "run {k}: {last} against {}",
            rate * at
        );
        assert!(
            c.csv_row(&r).contains(&format!("{at}")),
            "{}",
            c.csv_row(&r)
        );
        // Its drawn scene logs the fault at that time.
        let (_, events) = run(&parse(&c.run_text(k, &r.values)));
        assert_eq!(events.len(), 1);
        assert_eq!(events[0].0, at, "run {k}");
        times.push(at);
    }
    times.dedup();
    assert_eq!(times.len(), 4, "{times:?}");
    // The campaign's folder, its runs in SIMD lanes: `runs.csv` holds each run's fault time
    // and the speed it left the wheel at.
    let dir = satsim_testkit::temp_dir("faults-campaign");
    let opts = RunOptions {
        threads: Some(2),
        shard: Shard::ALL,
        resume: false,
        lanes: true,
    };
    run_campaign(&c, &dir, &opts, &Quiet).unwrap_or_else(|e| panic!("{e}"));
    let csv = std::fs::read_to_string(dir.join("runs.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at_col = header.iter().position(|h| *h == "faults.0.at").unwrap();
    let final_col = header
        .iter()
        .position(|h| *h == "final_wheel_rw1_speed")
        .unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4);
    for (r, &at) in rows.iter().zip(&times) {
        assert_eq!(r[at_col].parse::<f64>().unwrap(), at);
        let last: f64 = r[final_col].parse().unwrap();
        assert!(
            (last - rate * at).abs() <= 1e-12,
            "{last} against {}",
            rate * at
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn faults_in_a_campaign_in_lanes_give_the_runs_alone() {
    // The deployment campaign (the preprint's tree: its runs take SIMD lanes), 10 s, with a
    // wheel seized at a dispersed time and another switched off.
    let path = crate::common::example("scenes/deploy_campaign.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("duration = 60.0", "duration = 10.0")
        .replace("runs = 64", "runs = 6")
        + "\n[[faults]]\nat = 4.0\nkind = \"wheel_stuck\"\ntarget = \"x\"\n\
           [[faults]]\nat = 6.0\nkind = \"wheel_off\"\ntarget = \"y\"\n\
           [[campaign.disperse]]\nkey = \"faults.0.at\"\nuniform = { low = -1.0, high = 1.0 }\n";
    let c = Campaign::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    let mut csv = Vec::new();
    for lanes in [false, true] {
        let dir = satsim_testkit::temp_dir(&format!("faults-lanes-{lanes}"));
        let opts = RunOptions {
            threads: Some(1),
            shard: Shard::ALL,
            resume: false,
            lanes,
        };
        let report = run_campaign(&c, &dir, &opts, &Quiet).unwrap_or_else(|e| panic!("{e}"));
        if lanes {
            let used = report.lanes.expect("the runs take lanes");
            assert!(used.in_lanes > 0, "{used:?}");
        }
        csv.push(std::fs::read_to_string(dir.join("runs.csv")).unwrap());
        let _ = std::fs::remove_dir_all(&dir);
    }
    assert!(csv[0].lines().all(|l| !l.contains("failed")), "{}", csv[0]);
    assert_eq!(csv[0], csv[1], "runs.csv in lanes and alone");
}

#[test]
fn a_stepped_run_reports_the_fault_when_it_happens_and_ignores_the_dead_wheels_input() {
    let at = 2.5;
    let fault = format!("[[faults]]\nat = {at:?}\nkind = \"wheel_off\"\ntarget = \"rw1\"\n");
    let scene = parse(&wheel_scene(5.0, AT_REST, "", &fault));
    let mut s = satsim_tools::stepping::SceneStepper::new(&scene, None, "test").unwrap();
    let tau = 0.01;
    s.set_inputs(&[("wheel_rw1", tau)]).unwrap();
    let mut seen = Vec::new();
    for k in 1..=5 {
        let events = s.advance(1.0).unwrap();
        seen.push((k, events));
    }
    for (k, events) in &seen {
        if *k == 3 {
            assert_eq!(events.len(), 1, "{events:?}");
            let (t, effect, what) = &events[0];
            assert_eq!((*t, effect.as_str()), (at, "reaction_wheels"));
            assert!(what.starts_with("fault: wheel `rw1` off"), "{what}");
        } else {
            assert!(events.is_empty(), "advance {k}: {events:?}");
        }
    }
    // The input drove the wheel until the fault, and nothing after.
    let rate = tau * (1.0 / I_WHEEL + 1.0 / I_BUS);
    for (time, speed) in series(s.trajectory(), "wheel_rw1_speed") {
        let want = rate * time.min(at);
        assert!(
            (speed - want).abs() <= 1e-13,
            "t {time}: {speed} against {want}"
        );
    }
}

#[test]
fn the_example_loses_its_wheel_mid_slew_and_keeps_its_momentum() {
    // examples/scenes/faults.toml: the y wheel's motor dies at 60 s, the gyro is biased at
    // 150 s; the wheels' torques are internal and nothing else acts.
    let scene = Scene::read(crate::common::example("scenes/faults.toml")).unwrap();
    let (t, events) = run(&scene);
    let when: Vec<(f64, &str)> = events.iter().map(|e| (e.0, e.1.as_str())).collect();
    assert_eq!(when, [(60.0, "reaction_wheels"), (150.0, "sensors")]);
    for (time, h) in series(&t, "h_norm") {
        assert!(h <= 1e-12, "t {time}: |h| = {h}");
    }
    let torque = series(&t, "wheel_y_torque");
    assert!(torque.iter().any(|&(time, m)| time < 60.0 && m != 0.0));
    assert!(torque.iter().all(|&(time, m)| time <= 60.0 || m == 0.0));
    // The slew's rate about y stays, and so the pointing error grows.
    let w = series(&t, "omega_y");
    let at = |s: f64| w.iter().find(|(time, _)| *time == s).unwrap().1;
    assert!(at(100.0) > 0.005 && (at(200.0) / at(100.0) - 1.0).abs() < 0.01);
    let error = series(&t, "pointing_error").last().unwrap().1;
    assert!(error > 0.5, "{error}");
}
