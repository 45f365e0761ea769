//! The integrators on simulations: the attitude quaternion stays on the unit sphere, and a
//! hinge stop is located on the dense output at its known crossing time, then latches or
//! rebounds and the run restarts cleanly.

use satsim_integrate::{Method, Options, Output, StopReason};
use satsim_satellite::{Deployment, PreprintParams, build_model};
use satsim_spacecraft::effects::{HingeSprings, HingeStop, HingeStops, StopAction};
use satsim_spacecraft::simulation::{Simulation, attitude_norm_error};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Body, Hinge, Model, ModelBuilder, State};
use std::ops::ControlFlow;

/// RK4 at a fixed step, the adaptive methods at `tol`.
fn options(method: Method, tol: f64) -> Options {
    let o = Options::new(method)
        .with_tolerances(tol, tol)
        .with_max_steps(10_000_000);
    if method == Method::Rk4 {
        o.with_fixed_step(0.01)
    } else {
        o
    }
}

#[test]
fn the_attitude_quaternion_stays_within_1e_12_of_unit_norm() {
    // The preprint satellite, tumbling with its panels swinging on springs.
    let model = build_model(&PreprintParams::default()).unwrap();
    let mut state = State::rest(&model);
    state.q[7..12].copy_from_slice(&Deployment::HalfDeployed.angles());
    state.v[..3].copy_from_slice(&[0.3, -0.5, 0.2]);
    state.v[6..11].copy_from_slice(&[0.05, -0.04, 0.03, 0.4, -0.3]);
    for method in Method::ALL {
        let mut sim = Simulation::builder(model.clone())
            .initial(state.clone())
            .effect(HingeSprings::new(vec![30.0, 30.0, 30.0, 2.0, 3.0]))
            .build()
            .unwrap();
        let x0 = sim.x0().to_vec();
        let layout = sim.layout().clone();
        let mut worst: f64 = 0.0;
        let mut n = 0;
        // Output::Steps: the state at the end of every accepted step, after projection.
        let stats = satsim_integrate::integrate(
            &mut sim,
            &options(method, 1e-6),
            0.0,
            &x0,
            20.0,
            &Output::Steps,
            |_, x| {
                worst = worst.max(attitude_norm_error(&layout, x));
                n += 1;
                ControlFlow::Continue(())
            },
        )
        .unwrap();
        assert_eq!(stats.stop, StopReason::Finished);
        assert!(n > 10, "{method}: {n} steps");
        assert!(worst <= 1e-12, "{method}: |‖q‖ − 1| reached {worst:e}");
    }
}

/// A single arm on a fixed base, hinged about z through its centre of mass, driven from rest
/// by a constant hinge torque `tau` towards an upper stop at `phi_stop`: `φ(t) = τ t² / 2I`,
/// so it reaches the stop at `t* = sqrt(2 φ_stop I / τ)` with rate `τ t* / I`.
const I: f64 = 2.5;
const TAU: f64 = 0.4;
const PHI_STOP: f64 = 0.7;

fn arm(action: StopAction) -> Simulation {
    let model: Model = ModelBuilder::new(BaseKind::Fixed)
        .body(Body::new(
            "ground",
            10.0,
            Mat3::from_diagonal(&Vec3::new(1.0, 1.0, 1.0)),
        ))
        .body(Body::new(
            "arm",
            3.0,
            Mat3::from_diagonal(&Vec3::new(1.0, 2.0, I)),
        ))
        .hinge(Hinge::revolute("h", "ground", "arm", Vec3::z()))
        .build()
        .unwrap();
    let mut state = State::rest(&model);
    state.tau[0] = TAU;
    Simulation::builder(model)
        .initial(state)
        .effect(HingeStops::new(vec![HingeStop {
            hinge: 0,
            lower: None,
            upper: Some(PHI_STOP),
            action,
            min_rebound_rate: 1e-3,
        }]))
        .build()
        .unwrap()
}

fn t_star() -> f64 {
    (2.0 * PHI_STOP * I / TAU).sqrt()
}

#[test]
fn a_stop_is_located_at_its_known_crossing_time_then_latches() {
    let t_star = t_star();
    for method in Method::ALL {
        let mut sim = arm(StopAction::Latch);
        let x0 = sim.x0().to_vec();
        let l = sim.layout().clone();
        let mut rows = Vec::new();
        let stats = satsim_integrate::integrate(
            &mut sim,
            &options(method, 1e-10),
            0.0,
            &x0,
            6.0,
            &Output::Interval(0.25),
            |t, x| {
                rows.push((t, x.to_vec()));
                ControlFlow::Continue(())
            },
        )
        .unwrap();
        assert_eq!(stats.events.len(), 1, "{method}: {:?}", stats.events);
        let t_ev = stats.events[0].0;
        // Located on the dense output to the event tolerance, 1e-10 s.
        assert!(
            (t_ev - t_star).abs() <= 1e-10 + 1e-13,
            "{method}: event at {t_ev}, expected {t_star} (off by {:e})",
            t_ev - t_star
        );
        assert!(sim.event_log()[0].1.contains("latched"));
        // Before: the analytic motion; after: held at the stop, at rest.
        for (t, x) in &rows {
            let (phi, rate) = (x[l.angles.start], x[l.rates.start]);
            if *t < t_ev {
                assert!(
                    (phi - TAU * t * t / (2.0 * I)).abs() < 1e-9,
                    "{method} t={t}"
                );
                assert!((rate - TAU * t / I).abs() < 1e-9, "{method} t={t}");
            } else {
                assert!((phi - PHI_STOP).abs() < 1e-9, "{method} t={t}: {phi}");
                assert_eq!(rate, 0.0, "{method} t={t}");
            }
        }
        assert_eq!(stats.stop, StopReason::Finished);
        assert_eq!(stats.t_final, 6.0);
    }
}

#[test]
fn a_rebounding_stop_restarts_cleanly_and_hits_again_when_expected() {
    // Restitution e: each impact reverses the rate to −e v, the torque brings the arm back
    // after 2 e v I / τ, so the impacts are at t*, t* (1 + 2e), t* (1 + 2e + 2e²), …
    let e = 0.5;
    let t_star = t_star();
    let expected = [
        t_star,
        t_star * (1.0 + 2.0 * e),
        t_star * (1.0 + 2.0 * e + 2.0 * e * e),
    ];
    for method in Method::ALL {
        let mut sim = arm(StopAction::Rebound { restitution: e });
        let x0 = sim.x0().to_vec();
        let stats = satsim_integrate::integrate(
            &mut sim,
            &options(method, 1e-10),
            0.0,
            &x0,
            expected[2] + 0.1,
            &Output::Times(vec![]),
            |_, _| ControlFlow::Continue(()),
        )
        .unwrap();
        assert_eq!(stats.events.len(), 3, "{method}: {:?}", stats.events);
        for (k, ((t, _), t_exp)) in stats.events.iter().zip(expected).enumerate() {
            // Each location is within 1e-10 s; the restart from a state 1e-10 s past the
            // stop shifts the next impact by a few times that.
            let tol = 1e-10 * (1.0 + 4.0 * k as f64);
            assert!(
                (t - t_exp).abs() <= tol,
                "{method}: impact {k} at {t}, expected {t_exp} (off by {:e})",
                t - t_exp
            );
        }
        assert!(sim.event_log().iter().all(|(_, w)| w.contains("rebounded")));
        // Just after the last impact the arm moves away at e³ times the first impact rate.
        let rate = stats.x_final[sim.layout().rates.start];
        let v3 = -e.powi(3) * TAU * t_star / I + TAU * (stats.t_final - expected[2]) / I;
        assert!(
            (rate - v3).abs() < 1e-8,
            "{method}: rate {rate}, expected {v3}"
        );
    }
}
