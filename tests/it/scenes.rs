//! The example scenes (`examples/scenes/*.toml`) run to their end and obey the physics they
//! were written to show: conservation laws, analytic periods and rates, latched hinges that
//! stay latched, the order of events, and the rest they end in. Nothing here freezes a
//! computed number: every expected value is derived from the scene's parameters (or from the
//! run's own initial state), so a correct change of integrator or step passes and a wrong
//! force, sign or impulse fails.

use satsim::integrate::Output;
use satsim::tools::scene::Scene;
use std::path::{Path, PathBuf};

/// A finished run: the columns, every output row and the event log.
struct Run {
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
    events: Vec<(f64, String)>,
}

impl Run {
    fn col(&self, name: &str) -> usize {
        self.columns
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    }
    /// `(t, value)` of one column over the run.
    fn series(&self, name: &str) -> Vec<(f64, f64)> {
        let i = self.col(name);
        self.rows.iter().map(|r| (r[0], r[i])).collect()
    }
    fn last(&self, name: &str) -> f64 {
        self.rows.last().unwrap()[self.col(name)]
    }
    fn vec3(&self, row: &[f64], prefix: &str) -> [f64; 3] {
        ["x", "y", "z"].map(|a| row[self.col(&format!("{prefix}_{a}"))])
    }
    /// The events whose text contains `what`, with their times.
    fn events_with(&self, what: &str) -> Vec<f64> {
        self.events
            .iter()
            .filter(|(_, e)| e.contains(what))
            .map(|(t, _)| *t)
            .collect()
    }
}

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/scenes/{name}.toml"))
}

fn run_scene(scene: &Scene) -> Run {
    let mut sim = scene.simulation().unwrap_or_else(|e| panic!("{e}"));
    let columns = sim.columns();
    let mut rows: Vec<Vec<f64>> = Vec::new();
    sim.run(
        &scene.options,
        scene.duration,
        &Output::Interval(scene.every),
        |_, row| {
            rows.push(row.to_vec());
            Ok::<(), ()>(())
        },
    )
    .unwrap();
    assert!(
        (rows.last().unwrap()[0] - scene.duration).abs() < 1e-9,
        "the run did not reach its end"
    );
    for r in &rows {
        assert!(
            r.iter().all(|x| x.is_finite()),
            "non-finite output at t = {}",
            r[0]
        );
    }
    // Every scene run here keeps its flexible beams within their modal model (each tip
    // within a tenth of its length at every accepted step) and closes its energy budget.
    let warnings = sim.run_warnings();
    assert!(warnings.is_empty(), "{warnings:?}");
    Run {
        columns,
        rows,
        events: sim.event_log().to_vec(),
    }
}

fn run(name: &str) -> Run {
    run_scene(&Scene::read(scene_path(name)).unwrap_or_else(|e| panic!("{e}")))
}

/// The same scene file with some of its text removed (each piece must be there).
fn run_without(name: &str, pieces: &[&str]) -> Run {
    let path = scene_path(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    for p in pieces {
        assert!(text.contains(p), "{name}: no {p:?} to remove");
        text = text.replace(p, "");
    }
    run_scene(&Scene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}")))
}

/// After `t_latch`, the hinge's rate is exactly zero and its angle exactly constant, at the
/// stop (0 in these scenes) to within the event location's precision.
fn assert_latched(r: &Run, hinge: &str, t_latch: f64) {
    let (a, w) = (
        r.col(&format!("angle_{hinge}")),
        r.col(&format!("rate_{hinge}")),
    );
    let after: Vec<&Vec<f64>> = r.rows.iter().filter(|row| row[0] > t_latch).collect();
    assert!(!after.is_empty());
    let held = after[0][a];
    assert!(
        held.abs() < 1e-9,
        "{hinge} latched at {held}, not at its stop"
    );
    for row in after {
        assert_eq!(row[w], 0.0, "{hinge} moves at t = {}", row[0]);
        assert_eq!(row[a], held, "{hinge} moved at t = {}", row[0]);
    }
}

fn norm(v: [f64; 3]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]])
}

/// Times where a sampled series changes sign, by linear interpolation.
fn sign_changes(s: &[(f64, f64)]) -> Vec<f64> {
    s.windows(2)
        .filter(|w| w[0].1 * w[1].1 < 0.0)
        .map(|w| w[0].0 - w[0].1 * (w[1].0 - w[0].0) / (w[1].1 - w[0].1))
        .collect()
}

/// Complete elliptic integral of the first kind `K(k)`, given `k' ^ 2 = 1 - k ^ 2`
/// (arithmetic-geometric mean).
fn elliptic_k(kc2: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, kc2.sqrt());
    // Quadratic convergence: 30 iterations are far more than double precision needs.
    for _ in 0..30 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

/// Torque-free rigid body spun near its intermediate axis: kinetic energy and angular
/// momentum constant, and the spin axis flips with the period of Euler's equations
/// (Landau & Lifshitz §37: `omega_y` is proportional to `sn(lambda t, k)`, so it changes sign
/// every `2 K(k) / lambda`).
#[test]
fn tumbling_conserves_energy_and_momentum_and_flips_on_time() {
    let r = run("tumbling");
    // Principal moments of examples/scenes/tumbling.toml (x, y, z).
    let inertia = [900.0, 800.0, 600.0];
    let t0 = r.rows[0][r.col("kinetic_energy")];
    let h0 = r.vec3(&r.rows[0], "h");
    let (mut de, mut dh, mut dt_own) = (0.0f64, 0.0f64, 0.0f64);
    for row in &r.rows {
        let w = r.vec3(row, "omega");
        let t = row[r.col("kinetic_energy")];
        // The kinetic energy from the body rates and the principal moments, by hand.
        let own = 0.5 * (0..3).map(|i| inertia[i] * w[i] * w[i]).sum::<f64>();
        de = de.max((t - t0).abs() / t0);
        dh = dh.max(dist(r.vec3(row, "h"), h0) / norm(h0));
        dt_own = dt_own.max((own - t).abs() / t);
    }
    assert!(de < 1e-10, "kinetic energy drifts by {de:e} (relative)");
    assert!(dh < 1e-10, "angular momentum drifts by {dh:e} (relative)");
    assert!(
        dt_own < 1e-12,
        "kinetic energy column against 1/2 w.Iw: {dt_own:e}"
    );

    // Landau's formulas with I1 < I2 < I3; here M^2 < 2 E I2, so I1 and I3 swap roles.
    let w0 = r.vec3(&r.rows[0], "omega");
    let m2: f64 = (0..3).map(|i| (inertia[i] * w0[i]).powi(2)).sum();
    let e2: f64 = (0..3).map(|i| inertia[i] * w0[i] * w0[i]).sum();
    let (i1, i2, i3) = (inertia[0], inertia[1], inertia[2]);
    assert!(m2 < e2 * i2);
    let lambda = ((i3 - i2) * (m2 - e2 * i1) / (i1 * i2 * i3)).sqrt();
    let denom = (i3 - i2) * (m2 - e2 * i1);
    let kc2 = (denom - (i2 - i1) * (e2 * i3 - m2)) / denom;
    let half_period = 2.0 * elliptic_k(kc2) / lambda;
    let flips = sign_changes(&r.series("omega_y"));
    assert!(
        flips.len() >= 2,
        "the spin axis should flip over and back: {flips:?}"
    );
    for w in flips.windows(2) {
        let got = w[1] - w[0];
        assert!(
            (got - half_period).abs() < 1e-4 * half_period,
            "time between flips {got} s, Euler's equations {half_period} s"
        );
    }
}

/// Gravity-gradient pitch libration on a circular orbit: with the pitch `theta` measured from
/// the orbital frame, `theta'' = -(3 n^2 (Ix - Iz) / Iy) sin theta cos theta`, a pendulum in
/// `2 theta` of period `4 K(sin theta0) / w0`; the pitch rate is `omega_y + n` (the body's y
/// axis is opposite to the orbit normal) and peaks at `w0 sin theta0`; roll and yaw stay zero.
#[test]
fn libration_has_the_pendulum_period_and_amplitude() {
    let r = run("libration");
    let (ix, iy, iz) = (110.0f64, 120.0f64, 20.0f64);
    let theta0 = 0.1f64;
    // Mean motion of the 500 km circular orbit (the scene's own initial rate is -n).
    let n = -r.rows[0][r.col("omega_y")];
    let mu = 3.986004418e14;
    let radius = r.rows[0][r.col("orbit_radius")];
    assert!(
        (n - (mu / radius.powi(3)).sqrt()).abs() < 1e-9 * n,
        "the scene's initial rate is not the orbit's mean motion"
    );
    let w0 = n * (3.0 * (ix - iz) / iy).sqrt();
    let k = theta0.sin(); // modulus for the pendulum in 2 theta of amplitude 2 theta0
    let period = 4.0 * elliptic_k(1.0 - k * k) / w0;

    let rate: Vec<(f64, f64)> = r
        .series("omega_y")
        .iter()
        .map(|&(t, w)| (t, w + n))
        .collect();
    let turns = sign_changes(&rate);
    assert!(turns.len() >= 5, "expected several librations: {turns:?}");
    for w in turns.windows(2) {
        let got = 2.0 * (w[1] - w[0]);
        assert!(
            (got - period).abs() < 1e-4 * period,
            "libration period {got} s, pendulum {period} s"
        );
    }
    let peak = rate.iter().fold(0.0f64, |m, &(_, w)| m.max(w.abs()));
    let expected = w0 * theta0.sin();
    assert!(
        (peak - expected).abs() < 1e-3 * expected,
        "peak pitch rate {peak}, pendulum {expected}"
    );
    let off_plane = r.rows.iter().fold(0.0f64, |m, row| {
        m.max(row[r.col("omega_x")].abs())
            .max(row[r.col("omega_z")].abs())
    });
    assert!(
        off_plane < 1e-12,
        "roll/yaw rate {off_plane:e}: the motion left the orbit plane"
    );
    for (_, rad) in r.series("orbit_radius") {
        assert!(
            (rad - radius).abs() < 1e-6 * radius,
            "circular orbit radius {rad}"
        );
    }
}

/// Wheel spin-down on a free bus: friction is internal, so the angular momentum is constant;
/// the wheel stops at the time the friction law gives (relative rate obeys
/// `dOmega/dt = -f(Omega) (1/Iw + 1/Ib)`, integrated here by quadrature), sticks and stays
/// stuck, and the bus ends up turning at `h / (Ib + Iw)`.
#[test]
fn spin_down_stops_on_time_and_hands_its_momentum_to_the_bus() {
    let r = run("spin_down");
    // examples/scenes/spin_down.toml
    let (ib, iw, omega_start) = (40.0, 0.1, 300.0);
    let (a0, a1, omega0, a2) = (0.02, 0.01, 20.0, 5e-5);
    let friction = |w: f64| a0 + a1 * (-(w / omega0) * (w / omega0)).exp() + a2 * w;

    let h0 = r.vec3(&r.rows[0], "h");
    assert!(
        (norm(h0) - iw * omega_start).abs() < 1e-12 * iw * omega_start,
        "initial momentum {h0:?}"
    );
    let mut dh = 0.0f64;
    let mut last_ke = f64::INFINITY;
    for row in &r.rows {
        dh = dh.max(dist(r.vec3(row, "h"), h0) / norm(h0));
        let ke = row[r.col("kinetic_energy")];
        assert!(
            ke <= last_ke + 1e-12,
            "friction gave energy at t = {}",
            row[0]
        );
        last_ke = ke;
    }
    assert!(dh < 1e-10, "angular momentum drifts by {dh:e} (relative)");

    // Simpson's rule for t_stop = integral of dOmega / (f(Omega) (1/Iw + 1/Ib)).
    let m = 200_000;
    let step = omega_start / m as f64;
    let g = |w: f64| 1.0 / (friction(w) * (1.0 / iw + 1.0 / ib));
    let mut sum = g(0.0) + g(omega_start);
    for i in 1..m {
        sum += g(i as f64 * step) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    let t_stop = sum * step / 3.0;
    let stuck = r.events_with("stopped and stuck");
    assert_eq!(stuck.len(), 1, "events: {:?}", r.events);
    assert!(
        (stuck[0] - t_stop).abs() < 1e-6 * t_stop,
        "the wheel stopped at {} s, the friction law says {t_stop} s",
        stuck[0]
    );
    assert!(
        r.events_with("broke free").is_empty(),
        "events: {:?}",
        r.events
    );
    for (t, w) in r.series("wheel_z_speed") {
        if t > stuck[0] {
            assert_eq!(w, 0.0, "the stuck wheel moved at t = {t}");
        }
    }
    let spin = r.last("omega_z");
    let expected = norm(h0) / (ib + iw);
    assert!(
        (spin - expected).abs() < 1e-9 * expected,
        "final bus rate {spin}, momentum / inertia {expected}"
    );
    assert!(r.last("omega_x").abs() < 1e-12 && r.last("omega_y").abs() < 1e-12);
}

/// The control-moment gyro (`examples/scenes/cmg.toml`): a frictionless wheel on a gimbal
/// body keeps its absolute spin, and the bus receives the gyroscopic torque of its momentum
/// `h` turned by the gimbal, `τ = h × δ̇ ẑ − ω × h` in bus axes (`ḣ = δ̇ ẑ × h` relative to
/// the bus). The torque the bus receives is measured from its own motion, `J ω̇ + ω × J ω`
/// (`ω̇` by central differences of the rows); the gimbal's and the rotor's transverse inertia
/// (6e-3 kg m², which the law leaves out) bound the difference. A wheel carried by the bus
/// instead would give the bus no torque at all; total momentum is conserved.
#[test]
fn a_wheel_on_a_gimbal_gives_the_bus_h_cross_the_gimbal_rate() {
    let r = run("cmg");
    let j = [1000.0, 800.0, 600.0];
    let (iw, omega0) = (0.01, 600.0);
    let h0 = r.vec3(&r.rows[0], "h");
    let mut dh = 0.0f64;
    for row in &r.rows {
        dh = dh.max(dist(r.vec3(row, "h"), h0) / norm(h0));
    }
    assert!(dh < 1e-9, "angular momentum drifts by {dh:e} (relative)");
    assert!((norm(h0) - iw * omega0).abs() < 1e-12, "{h0:?}");
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (mut worst, mut peak) = (0.0f64, 0.0f64);
    for k in 1..r.rows.len() - 1 {
        let (a, row, b) = (&r.rows[k - 1], &r.rows[k], &r.rows[k + 1]);
        let dt = b[0] - a[0];
        let w = r.vec3(row, "omega");
        let (wa, wb) = (r.vec3(a, "omega"), r.vec3(b, "omega"));
        let jw = [j[0] * w[0], j[1] * w[1], j[2] * w[2]];
        let gyro = cross(w, jw);
        let felt: [f64; 3] = std::array::from_fn(|i| j[i] * (wb[i] - wa[i]) / dt + gyro[i]);
        // The wheel's absolute axial momentum along its axis (turned by the gimbal angle).
        let delta = row[r.col("angle_gimbal")];
        let rate = row[r.col("rate_gimbal")];
        let axis = [delta.cos(), delta.sin(), 0.0];
        let spin = row[r.col("wheel_cmg_speed")] + w[0] * axis[0] + w[1] * axis[1];
        let h = axis.map(|x| iw * spin * x);
        let turned = cross(h, [0.0, 0.0, rate]);
        let carried = cross(w, h);
        let law: [f64; 3] = std::array::from_fn(|i| turned[i] - carried[i]);
        worst = worst.max(dist(felt, law));
        peak = peak.max(norm(law));
    }
    // Peak h δ̇ ≈ 6 N m s × 0.12 rad/s.
    assert!(
        peak > 0.5,
        "the gimbal hardly turned: peak torque {peak} N m"
    );
    assert!(
        worst < 2e-3 * peak,
        "the bus felt {worst:e} N m away from h x gimbal rate (peak {peak} N m)"
    );
    // The momentum the wheel handed over: from +x to +y of the bus, so the bus turns about
    // +x and −y at about h / J.
    let w = r.vec3(r.rows.last().unwrap(), "omega");
    assert!((w[0] - 6.0 / j[0]).abs() < 0.05 * 6.0 / j[0], "{w:?}");
    assert!((w[1] + 6.0 / j[1]).abs() < 0.05 * 6.0 / j[1], "{w:?}");
}

/// The energy sink (`examples/scenes/spinning_booms.toml`): spinning about its axis of least
/// inertia with two damped flexible booms, the spacecraft keeps its angular momentum while the
/// booms' bending dissipates energy, and ends near the flat spin about its axis of greatest
/// inertia, the least energy `H² / 2 I_max` at that momentum; without the damping, the same
/// spin stays put. `I_max` from the scene's numbers: the bus's 8 kg m² about y and two
/// uniform 0.5 kg booms from 0.4 m to 2.4 m, `ρA (2.4³ − 0.4³) / 3` each. The booms stay
/// within a few per cent of their length (the scene's stiffness is chosen for it):
/// no deflection warning.
#[test]
fn spinning_booms_sink_the_spins_energy_into_a_flat_spin() {
    let boom = 2.0 * 0.25 * (2.4f64.powi(3) - 0.4f64.powi(3)) / 3.0;
    let i_max = 8.0 + boom;
    // The initial momentum's angle from z: `atan(I_x ω_x / (I_z ω_z))`, the booms adding
    // nothing about their own axis x.
    let tilt0 = (8.0 * 0.2 / ((5.0 + boom) * 2.0)).atan().to_degrees();
    let r = run("spinning_booms");
    let h0 = r.vec3(&r.rows[0], "h");
    let flat = norm(h0).powi(2) / (2.0 * i_max);
    let (mut dh, mut last) = (0.0f64, f64::INFINITY);
    for row in &r.rows {
        dh = dh.max(dist(r.vec3(row, "h"), h0) / norm(h0));
        let e = row[r.col("total_energy")];
        assert!(e <= last + 1e-9, "energy rose at t = {}", row[0]);
        last = e;
    }
    assert!(dh < 1e-9, "angular momentum drifts by {dh:e}");
    let (first, end) = (&r.rows[0], r.rows.last().unwrap());
    let budget = (end[r.col("energy_budget")] - first[r.col("energy_budget")]).abs();
    assert!(
        budget < 1e-8 * first[r.col("total_energy")],
        "budget {budget:e}"
    );
    let e_end = end[r.col("kinetic_energy")];
    assert!(
        e_end < 1.03 * flat && e_end > (1.0 - 1e-3) * flat,
        "final energy {e_end} J, flat spin {flat} J (from {} J)",
        first[r.col("kinetic_energy")]
    );
    // The momentum's angle from the bus's z axis (its spin axis at the start), from the
    // attitude: h is inertial.
    let tilt = |run: &Run, row: &[f64], axis: usize| {
        let q = ["q_w", "q_x", "q_y", "q_z"].map(|c| row[run.col(c)]);
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q[0], q[1], q[2], q[3],
        ));
        let h = nalgebra::Vector3::from(run.vec3(row, "h"));
        let body = q.inverse_transform_vector(&h) / h.norm();
        body[axis].abs().acos().to_degrees()
    };
    assert!((tilt(&r, &r.rows[0], 2) - tilt0).abs() < 1e-6, "{tilt0}");
    assert!(
        tilt(&r, end, 1) < 18.0,
        "the spin ended {} deg from y",
        tilt(&r, end, 1)
    );
    let at_1500 = r.rows.iter().find(|row| row[0] >= 1500.0).unwrap();
    assert!(tilt(&r, at_1500, 2) > 30.0, "{}", tilt(&r, at_1500, 2));
    // The booms within their modal model: `run_scene` asserts that no tip passed a tenth of
    // its length at any step (8.9 cm of 2 m measured at the output times).
    // Without the booms' damping: no sink, the spin stays about z.
    let path = scene_path("spinning_booms");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("damping = 0.6", "damping = 0.0")
        .replace("duration = 10000.0", "duration = 1000.0");
    assert!(!text.contains("damping = 0.6") && text.contains("duration = 1000.0"));
    let undamped = run_scene(&Scene::parse(&text, &path).unwrap());
    let worst = undamped
        .rows
        .iter()
        .map(|row| tilt(&undamped, row, 2))
        .fold(0.0, f64::max);
    // 6.41 deg measured, from 6.26 at the start.
    assert!(
        worst < tilt0 + 0.5,
        "without damping the spin tilted by {worst} deg (from {tilt0})"
    );
    let e = |row: &[f64]| row[undamped.col("total_energy")];
    let e0 = e(&undamped.rows[0]);
    assert!((e(undamped.rows.last().unwrap()) - e0).abs() < 1e-8 * e0);
}

/// The deployment: each folded panel latches once at its deployed stop (the outer hinge h5
/// first, then h4) and stays exactly there; the controller brings the bus back to rest at its target
/// attitude, and the gimbal springs the gimbal back to zero.
#[test]
fn deploy_latches_both_panels_and_ends_at_rest() {
    let r = run("deploy");
    let h5 = r.events_with("hinge `h5` latched at its upper stop");
    let h4 = r.events_with("hinge `h4` latched at its lower stop");
    assert_eq!((h5.len(), h4.len()), (1, 1), "events: {:?}", r.events);
    assert!(h5[0] < h4[0], "events: {:?}", r.events);
    let hinge_events = r.events_with("hinge `");
    assert_eq!(hinge_events.len(), 2, "events: {:?}", r.events);
    for (hinge, t_latch) in [("h4", h4[0]), ("h5", h5[0])] {
        assert_latched(&r, hinge, t_latch);
    }
    // Final rest: the bus at its (identity) target, the gimbal at zero.
    let last = r.rows.last().unwrap();
    let q_vec = [r.last("q_x"), r.last("q_y"), r.last("q_z")];
    assert!(2.0 * norm(q_vec) < 1e-3, "attitude error {q_vec:?}");
    assert!(norm(r.vec3(last, "omega")) < 1e-4, "bus still turning");
    for h in ["h1", "h2", "h3"] {
        assert!(
            r.last(&format!("angle_{h}")).abs() < 1e-4,
            "gimbal {h} not back"
        );
        assert!(
            r.last(&format!("rate_{h}")).abs() < 1e-5,
            "gimbal {h} moving"
        );
    }
}

/// The deployment with no external torque (no orbit, no gravity gradient): springs, dampers,
/// latches (impulses), wheel friction and motor torques are all internal, so the angular
/// momentum, zero at the start, stays zero through every event.
#[test]
fn deploy_without_gravity_conserves_angular_momentum() {
    let r = run_without(
        "deploy",
        &[
            "[orbit]\nmodel = \"kepler\"\naltitude = 500e3          # m, circular\ninclination_deg = 51.6\n",
            "[effects.gravity_gradient]\nmodel = \"full\"\n",
        ],
    );
    assert!(r.columns.iter().all(|c| c != "orbit_radius"));
    // Scale: the largest wheel momentum of the run.
    let scale = ["x", "y", "z"]
        .iter()
        .flat_map(|w| r.series(&format!("wheel_{w}_speed")))
        .fold(0.0f64, |m, (_, s)| m.max(0.1 * s.abs()));
    assert!(scale > 1.0, "the wheels should work hard: {scale}");
    let worst = r
        .rows
        .iter()
        .fold(0.0f64, |m, row| m.max(norm(r.vec3(row, "h"))));
    assert!(
        worst < 1e-9 * scale,
        "angular momentum reached {worst:e} N m s (wheel momentum {scale} N m s)"
    );
    assert_eq!(r.events_with("latched").len(), 2, "events: {:?}", r.events);
}

/// Two wings and a boom, torque-free from rest: the angular momentum stays zero; both wing
/// roots latch once and stay latched; the elbow rebounds off its stop; the boom follows its
/// profile to 0; everything ends at rest.
#[test]
fn two_wings_latch_rebound_and_settle_with_zero_momentum() {
    let r = run("two_wings");
    // Scale: the momentum the bus (225 kg m^2 about every axis) takes in reaction to the
    // wings and the boom, which theirs must cancel.
    let scale = r
        .rows
        .iter()
        .fold(0.0f64, |m, row| m.max(225.0 * norm(r.vec3(row, "omega"))));
    let worst = r
        .rows
        .iter()
        .fold(0.0f64, |m, row| m.max(norm(r.vec3(row, "h"))));
    assert!(scale > 0.1, "the bus should react: {scale}");
    assert!(
        worst < 1e-8 * scale,
        "angular momentum reached {worst:e} N m s (bus momentum {scale} N m s)"
    );
    for (hinge, side) in [("left_root", "lower"), ("right_root", "upper")] {
        let t = r.events_with(&format!("hinge `{hinge}` latched at its {side} stop"));
        assert_eq!(t.len(), 1, "{hinge}: events {:?}", r.events);
        assert_latched(&r, hinge, t[0]);
    }
    assert!(
        !r.events_with("hinge `boom_elbow` rebounded at its upper stop")
            .is_empty(),
        "events: {:?}",
        r.events
    );
    // The boom root's profile ends at 0 at t = 80 s; at 200 s everything is at rest.
    assert!(r.last("angle_boom_root").abs() < 1e-3);
    let last = r.rows.last().unwrap();
    for c in r.columns.iter().filter(|c| c.starts_with("rate_")) {
        assert!(last[r.col(c)].abs() < 1e-3, "{c} = {}", last[r.col(c)]);
    }
    assert!(norm(r.vec3(last, "omega")) < 1e-4);
}

/// The boom elbow's stop holds: the angle never goes past it. It used to creep through after
/// the run of ever smaller rebounds near t = 7.09 s: a rebound of a few mrad/s left the stop
/// and came back within one step, so the event function had the same sign at both ends of
/// that step (crates/integrate/src/driver.rs now probes the dense output of a step that
/// starts on a handled event; crates/integrate/tests/it/short_rebounds.rs).
#[test]
fn two_wings_boom_elbow_never_passes_its_stop() {
    let r = run("two_wings");
    for (t, a) in r.series("angle_boom_elbow") {
        assert!(a <= 1e-9, "boom elbow at {a} past its stop at t = {t}");
    }
}

/// What a user reads first in every example scene, frozen with insta: the output columns and
/// the sequence of events (effect and what happened, in order). Only discrete, robust facts
/// are snapshotted, never chaotic numbers; the event times are checked above, against values
/// derived from each scene's parameters.
#[test]
fn example_scene_columns_and_event_sequences() {
    for name in ["deploy", "libration", "spin_down", "tumbling", "two_wings"] {
        let r = run(name);
        let mut text = format!("columns: {}\nevents:\n", r.columns.join(", "));
        // Each event's words without the numbers in brackets; a run of the same event (the
        // tiny rebounds of a hinge settling on its stop) is one line, since how many such
        // rebounds fit above the rest threshold is not a fact worth freezing.
        let mut last = String::new();
        for (_, e) in &r.events {
            let words = e.split(" (").next().unwrap_or(e).trim().to_owned();
            if words == last {
                continue;
            }
            text.push_str(&format!("  {words}\n"));
            last = words;
        }
        insta::assert_snapshot!(format!("scene_{name}"), text);
    }
}
