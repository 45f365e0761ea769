//! Dense output, event location (reset / continue / stop) and observer break.

use crate::common;

use std::ops::ControlFlow;

use common::{Ball, Smooth, collect, max_err};
use satsim_integrate::{
    EventAction, EventDirection, Method, Options, Output, StopReason, System, SystemError,
    integrate,
};

#[test]
fn dense_output_matches_exact_solution() {
    // Outputs far denser than the steps, so nearly all come from interpolation.
    let times: Vec<f64> = (0..=400).map(|i| i as f64 * 0.025).collect();
    for (method, tol, bound) in [
        (Method::Dp54, 1e-9, 1e-7),
        (Method::Dop853, 1e-11, 1e-9),
        (Method::Radau5, 1e-9, 1e-7),
    ] {
        let opts = Options::new(method).with_tolerances(tol, tol);
        let (r, rows) = collect(
            &mut Smooth,
            &opts,
            &Smooth::X0,
            10.0,
            &Output::Times(times.clone()),
        );
        let stats = r.unwrap();
        assert!(
            stats.steps_accepted < 200,
            "{method}: {} steps",
            stats.steps_accepted
        );
        assert_eq!(rows.len(), times.len());
        let worst = rows
            .iter()
            .map(|(t, x)| max_err(x, &Smooth::exact(*t)))
            .fold(0.0, f64::max);
        println!(
            "{method}: {} steps, worst dense error {worst:e}",
            stats.steps_accepted
        );
        assert!(worst < bound, "{method}: dense error {worst}");
        for (row, t) in rows.iter().zip(&times) {
            assert_eq!(row.0, *t, "outputs at exactly the requested times");
        }
    }
}

#[test]
fn rk4_lands_steps_on_output_times() {
    let opts = Options::new(Method::Rk4).with_fixed_step(0.3);
    let (r, rows) = collect(
        &mut Smooth,
        &opts,
        &Smooth::X0,
        1.0,
        &Output::Interval(0.25),
    );
    let stats = r.unwrap();
    let ts: Vec<f64> = rows.iter().map(|r| r.0).collect();
    assert_eq!(ts, [0.0, 0.25, 0.5, 0.75, 1.0]);
    // Steps land on each output time and keep the grid 0.3 n: 0.25, 0.3, 0.5, 0.6, 0.75,
    // 0.9, 1.0.
    assert_eq!(stats.steps_accepted, 7);
    for (t, x) in &rows {
        assert!(max_err(x, &Smooth::exact(*t)) < 1e-4);
    }
}

#[test]
fn interval_output_ends_at_t_end() {
    let opts = Options::new(Method::Dp54);
    let (_, rows) = collect(
        &mut Smooth,
        &opts,
        &Smooth::X0,
        1.05,
        &Output::Interval(0.5),
    );
    let ts: Vec<f64> = rows.iter().map(|r| r.0).collect();
    assert_eq!(ts, [0.0, 0.5, 1.0, 1.05]);
    let (_, rows) = collect(&mut Smooth, &opts, &Smooth::X0, 1.0, &Output::Interval(0.1));
    assert_eq!(rows.len(), 11);
    assert_eq!(rows.last().unwrap().0, 1.0);
}

const H: f64 = 10.0;
const E: f64 = 0.8;

fn ball_options(method: Method) -> Options {
    let opts = Options::new(method).with_tolerances(1e-10, 1e-12);
    if method == Method::Rk4 {
        opts.with_fixed_step(0.05)
    } else {
        opts
    }
}

#[test]
fn bouncing_ball_impacts_at_analytic_times() {
    let expected = Ball::new(H, E, EventAction::Reset).expected(4);
    let t_end = expected[3] + 0.1;
    for method in Method::ALL {
        let mut ball = Ball::new(H, E, EventAction::Reset);
        let (r, rows) = collect(
            &mut ball,
            &ball_options(method),
            &[H, 0.0],
            t_end,
            &Output::Interval(0.1),
        );
        let stats = r.unwrap();
        assert_eq!(stats.stop, StopReason::Finished);
        let got: Vec<f64> = stats.events.iter().map(|e| e.0).collect();
        assert_eq!(got.len(), 4, "{method}: events {got:?}");
        for (g, e) in got.iter().zip(&expected) {
            assert!(
                (g - e).abs() < 1e-9,
                "{method}: impact at {g}, expected {e}"
            );
        }
        // Outputs stay monotone and complete across resets.
        assert!(rows.windows(2).all(|w| w[1].0 > w[0].0));
        assert_eq!(rows.last().unwrap().0, t_end);
        assert!(
            rows.iter().all(|(_, x)| x[0] > -1e-6),
            "{method}: ball below ground"
        );
    }
}

#[test]
fn stop_action_ends_at_event() {
    let t1 = Ball::new(H, E, EventAction::Stop).expected(1)[0];
    for method in Method::ALL {
        let mut ball = Ball::new(H, E, EventAction::Stop);
        let (r, rows) = collect(
            &mut ball,
            &ball_options(method),
            &[H, 0.0],
            10.0,
            &Output::Interval(0.5),
        );
        let stats = r.unwrap();
        assert_eq!(stats.stop, StopReason::Event { k: 0 });
        assert!((stats.t_final - t1).abs() < 1e-9);
        assert!(stats.x_final[0].abs() < 1e-8);
        // Outputs before the event were all emitted, none after.
        let ts: Vec<f64> = rows.iter().map(|r| r.0).collect();
        assert_eq!(ts, [0.0, 0.5, 1.0]);
    }
}

/// Continue: events are recorded and integration proceeds unchanged.
#[test]
fn continue_action_records_all_crossings() {
    struct ZeroCrossings;
    impl System for ZeroCrossings {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            dx[0] = x[1];
            dx[1] = -x[0];
            Ok(())
        }
        fn n_events(&self) -> usize {
            2
        }
        fn events(&mut self, _t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
            g[0] = x[0]; // cos t: zero at pi/2 + k pi
            g[1] = x[1]; // -sin t: zero at k pi
            Ok(())
        }
        fn event_direction(&self, k: usize) -> EventDirection {
            if k == 0 {
                EventDirection::Both
            } else {
                EventDirection::Rising
            }
        }
        fn on_event(&mut self, _k: usize, _t: f64, x: &mut [f64]) -> EventAction {
            x[0] = 1e9; // ignored under Continue
            EventAction::Continue
        }
    }
    let opts = Options::new(Method::Dop853)
        .with_tolerances(1e-12, 1e-12)
        .with_h_max(10.0);
    let (r, _) = collect(
        &mut ZeroCrossings,
        &opts,
        &[1.0, 0.0],
        10.0,
        &Output::Times(vec![]),
    );
    let stats = r.unwrap();
    let pi = std::f64::consts::PI;
    // cos zeros at pi/2, 3pi/2, 5pi/2; -sin t rising at pi, 3pi.
    let expected = [
        (0.5 * pi, 0),
        (pi, 1),
        (1.5 * pi, 0),
        (2.5 * pi, 0),
        (3.0 * pi, 1),
    ];
    assert_eq!(stats.events.len(), expected.len(), "{:?}", stats.events);
    for ((t, k), (te, ke)) in stats.events.iter().zip(expected) {
        assert_eq!(*k, ke);
        assert!((t - te).abs() < 1e-9, "event {k} at {t}, expected {te}");
    }
    assert!((stats.x_final[0] - 10f64.cos()).abs() < 1e-9);
}

#[test]
fn observer_break_stops_cleanly() {
    for method in Method::ALL {
        let mut opts = Options::new(method);
        if method == Method::Rk4 {
            opts = opts.with_fixed_step(0.01);
        }
        let mut seen = Vec::new();
        let stats = integrate(
            &mut Smooth,
            &opts,
            0.0,
            &Smooth::X0,
            10.0,
            &Output::Interval(0.1),
            |t, x| {
                seen.push((t, x[0]));
                if seen.len() == 3 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
        )
        .unwrap();
        assert_eq!(stats.stop, StopReason::Observer);
        assert_eq!(seen.len(), 3);
        assert_eq!(stats.t_final, 0.2);
        assert_eq!(stats.x_final[0], seen[2].1);
        assert!(stats.steps_accepted < 50, "{method} stopped promptly");
    }
}

#[test]
fn steps_output_reports_every_step() {
    let opts = Options::new(Method::Dp54);
    let (r, rows) = collect(&mut Smooth, &opts, &Smooth::X0, 5.0, &Output::Steps);
    let stats = r.unwrap();
    assert_eq!(rows.len(), stats.steps_accepted + 1);
    assert_eq!(rows[0].0, 0.0);
    assert_eq!(rows.last().unwrap().0, 5.0);
}
