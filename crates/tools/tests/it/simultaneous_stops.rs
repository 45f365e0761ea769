//! Symmetric deployments: mirror-image panels reach their stops at the same instant. Every
//! panel must be stopped there (none swings through its stop), under every integrator, with
//! latching and with rebounding stops, and one impulse solve for the simultaneous impacts
//! keeps a symmetric deployment symmetric. The example scenes never pass a latching stop.

use crate::common::example;
use satsim_integrate::{Method, Options, Output};
use satsim_spacecraft::effects::{HingeSprings, HingeStop, HingeStops, StopAction};
use satsim_spacecraft::simulation::Simulation;
use satsim_tools::scene::Scene;
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Body, Hinge, ModelBuilder, State};

/// A panel: name, hinge point on the bus, its axis, the panel centre from the hinge, the
/// stowed angle, and which side its stop (at 0) is on.
struct Panel {
    name: &'static str,
    at: [f64; 3],
    axis: [f64; 3],
    out: [f64; 3],
    stowed: f64,
}

/// Panels at +y, −y (hinged about x) and +x, −x (hinged about y), each stowed folded up
/// (towards +z), mirror images of each other.
const PANELS: [Panel; 4] = [
    Panel {
        name: "py",
        at: [0.0, 1.0, 0.0],
        axis: [1.0, 0.0, 0.0],
        out: [0.0, 0.75, 0.0],
        stowed: 1.5,
    },
    Panel {
        name: "my",
        at: [0.0, -1.0, 0.0],
        axis: [1.0, 0.0, 0.0],
        out: [0.0, -0.75, 0.0],
        stowed: -1.5,
    },
    Panel {
        name: "px",
        at: [1.0, 0.0, 0.0],
        axis: [0.0, 1.0, 0.0],
        out: [0.75, 0.0, 0.0],
        stowed: -1.5,
    },
    Panel {
        name: "mx",
        at: [-1.0, 0.0, 0.0],
        axis: [0.0, 1.0, 0.0],
        out: [-0.75, 0.0, 0.0],
        stowed: 1.5,
    },
];

/// A bus with the first `n` panels, deployed by springs towards 0.3 rad beyond 0, where a
/// stop of `action` waits (so that rebounding panels come back to it).
fn deployment(n: usize, action: StopAction) -> Simulation {
    let mut b = ModelBuilder::new(BaseKind::Free);
    b.push_body(Body::new("bus", 600.0, Mat3::identity() * 225.0));
    for p in &PANELS[..n] {
        // A 1.0 m by 1.5 m plate of 15 kg, long along `out`.
        let along_y = p.out[1] != 0.0;
        let i = if along_y {
            Mat3::from_diagonal(&Vec3::new(2.81, 1.25, 4.06))
        } else {
            Mat3::from_diagonal(&Vec3::new(1.25, 2.81, 4.06))
        };
        b.push_body(Body::new(p.name, 15.0, i));
        b.push_hinge(
            Hinge::revolute(p.name, "bus", p.name, Vec3::from(p.axis))
                .at(Vec3::from(p.at))
                .child_at(-Vec3::from(p.out)),
        );
    }
    let model = b.build().unwrap();
    let mut state = State::rest(&model);
    let stops = PANELS[..n]
        .iter()
        .enumerate()
        .map(|(k, p)| {
            state.q[model.base_nq() + k] = p.stowed;
            HingeStop {
                hinge: k,
                lower: (p.stowed > 0.0).then_some(0.0),
                upper: (p.stowed < 0.0).then_some(0.0),
                action,
                min_rebound_rate: 0.05,
            }
        })
        .collect();
    let mut springs = HingeSprings::new(vec![3.0; n]);
    springs.reference = PANELS[..n]
        .iter()
        .map(|p| -0.3 * p.stowed.signum())
        .collect();
    Simulation::builder(model)
        .initial(state)
        .effect(springs)
        .effect(HingeStops::new(stops))
        .build()
        .unwrap()
}

fn options(method: Method) -> Options {
    let o = Options::new(method).with_tolerances(1e-9, 1e-12);
    if method == Method::Rk4 {
        o.with_fixed_step(0.002)
    } else {
        o
    }
}

/// Runs and checks: no panel ever beyond its stop, the panels mirror each other, the bus
/// never turns; returns the event log.
fn check(n: usize, action: StopAction, method: Method) -> Vec<(f64, String)> {
    let mut sim = deployment(n, action);
    let l = sim.layout().clone();
    let mut rows = Vec::new();
    sim.run(&options(method), 8.0, &Output::Interval(0.002), |_, r| {
        rows.push(r.to_vec());
        Ok::<(), ()>(())
    })
    .unwrap();
    let what = format!("{n} panels, {action:?}, {method}");
    // Row: t, q (4), ω (3), angles (n), rates (n), ...
    let angle = |r: &[f64], k: usize| r[8 + k];
    for r in &rows {
        for (k, p) in PANELS[..n].iter().enumerate() {
            let beyond = if p.stowed > 0.0 {
                -angle(r, k)
            } else {
                angle(r, k)
            };
            assert!(
                beyond < 1e-6,
                "{what}: hinge {} is {beyond} rad past its stop at t = {}",
                p.name,
                r[0]
            );
        }
        // Mirror images: py = -my, px = -mx.
        for pair in [(0, 1), (2, 3)] {
            if pair.1 < n {
                let (a, b) = (angle(r, pair.0), angle(r, pair.1));
                assert!(
                    (a + b).abs() < 1e-9,
                    "{what}: asymmetric at t = {}: {a} vs {b}",
                    r[0]
                );
            }
        }
        let omega = Vec3::new(r[5], r[6], r[7]);
        assert!(
            omega.norm() < 1e-10,
            "{what}: bus turns at {omega} (t = {})",
            r[0]
        );
    }
    let _ = l;
    sim.event_log().to_vec()
}

#[test]
fn symmetric_panels_all_latch_at_their_stops_under_every_integrator() {
    for n in [2, 4] {
        for method in Method::ALL {
            let log = check(n, StopAction::Latch, method);
            let latches: Vec<_> = log.iter().filter(|(_, m)| m.contains("latched")).collect();
            assert_eq!(latches.len(), n, "{n} panels, {method}: {log:?}");
            // All at the same instant.
            assert!(latches.iter().all(|(t, _)| *t == latches[0].0), "{log:?}");
            for p in &PANELS[..n] {
                assert!(
                    latches
                        .iter()
                        .any(|(_, m)| m.contains(&format!("`{}`", p.name))),
                    "{method}: {} never latched: {log:?}",
                    p.name
                );
            }
        }
    }
}

#[test]
fn symmetric_panels_all_rebound_at_their_stops_under_every_integrator() {
    for n in [2, 4] {
        for method in Method::ALL {
            let log = check(n, StopAction::Rebound { restitution: 0.5 }, method);
            for p in &PANELS[..n] {
                let bounces = log
                    .iter()
                    .filter(|(_, m)| m.contains(&format!("`{}` rebounded", p.name)))
                    .count();
                assert!(
                    bounces >= 2,
                    "{method}: {} bounced {bounces} times: {log:?}",
                    p.name
                );
                let first = log
                    .iter()
                    .filter(|(_, m)| m.contains(&format!("`{}` rebounded", PANELS[0].name)))
                    .count();
                assert_eq!(bounces, first, "{method}: {log:?}");
            }
        }
    }
}

/// Every example scene: no hinge ever passes a latching stop (checked every 10 ms).
#[test]
fn no_example_scene_passes_a_latching_stop() {
    let dir = example("scenes");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        // This scene needs the effect that examples/custom_effect.rs defines and registers.
        if path.ends_with("magnetic_torquer.toml") {
            continue;
        }
        let scene = Scene::read(&path).unwrap();
        let Some(stops) = scene.effects.get::<HingeStops>().cloned() else {
            continue;
        };
        let mut sim = scene.simulation().unwrap();
        let angles = sim.layout().angles.clone();
        let mut worst = (0.0f64, 0.0, String::new());
        let duration = scene.duration.min(60.0);
        // Rows: t, q (4), ω (3), then the angles.
        sim.run(&scene.options, duration, &Output::Interval(0.01), |t, r| {
            for s in stops.stops.iter().filter(|s| s.action == StopAction::Latch) {
                let phi = r[8 + s.hinge];
                let past = s
                    .lower
                    .map_or(0.0, |l| l - phi)
                    .max(s.upper.map_or(0.0, |u| phi - u));
                if past > worst.0 {
                    worst = (past, t, format!("hinge {}", s.hinge));
                }
            }
            Ok::<(), ()>(())
        })
        .unwrap();
        let _ = angles;
        assert!(
            worst.0 < 1e-6,
            "{}: {} is {} rad past its latching stop at t = {}",
            path.display(),
            worst.2,
            worst.0,
            worst.1
        );
        checked += 1;
    }
    assert!(checked >= 2, "only {checked} scenes with stops");
}
