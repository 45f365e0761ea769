//! Time stops ([`System::next_stop`], [`System::on_stop`]) and the fixed-step grid
//! ([`Options::grid_origin`]).

use crate::common::Smooth;
use satsim_integrate::{
    EventAction, EventDirection, IntegrateError, Method, Options, Output, Stats, System,
    SystemError, integrate,
};
use std::ops::ControlFlow;

/// `θ'' = u`, with `u = −K θ(t_k) − D ω(t_k)` sampled every `period` and held.
struct Sampled {
    period: f64,
    k: f64,
    d: f64,
    u: f64,
    next: f64,
    samples: Vec<(f64, f64, f64)>,
}

impl Sampled {
    fn new(period: f64) -> Self {
        Self {
            period,
            k: 3.0,
            d: 0.7,
            u: 0.0,
            next: 0.0,
            samples: Vec::new(),
        }
    }
}

impl System for Sampled {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = self.u;
        Ok(())
    }
    fn next_stop(&self) -> f64 {
        self.next
    }
    fn on_stop(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
        self.samples.push((t, x[0], x[1]));
        self.u = -self.k * x[0] - self.d * x[1];
        let k = (t / self.period + 1e-9).floor() + 1.0;
        self.next = k * self.period;
        Ok(true)
    }
}

fn options(method: Method) -> Options {
    let o = Options::new(method).with_tolerances(1e-6, 1e-9);
    match method {
        Method::Rk4 => o.with_fixed_step(0.03),
        _ => o,
    }
}

/// [`Sampled`] at 0.1 s from `[1, 0]` over `0..t_end` under `method`, no output rows.
fn sampled_run(method: Method, t_end: f64) -> (Sampled, Stats) {
    let mut sys = Sampled::new(0.1);
    let stats = integrate(
        &mut sys,
        &options(method),
        0.0,
        &[1.0, 0.0],
        t_end,
        &Output::Times(vec![]),
        |_, _| ControlFlow::Continue(()),
    )
    .unwrap();
    (sys, stats)
}

/// A held input makes the motion a parabola on each interval, which every method of order
/// two or more integrates exactly: the samples match the closed form to round-off, so the
/// steps landed on the sample instants and the held value was constant between them.
#[test]
fn a_held_input_sampled_at_time_stops_is_exact_for_every_method() {
    for method in Method::ALL {
        let (sys, stats) = sampled_run(method, 2.0);
        assert_eq!(stats.t_final, 2.0);
        // Samples at 0, 0.1, ..., 2.0 (the one at t_end included).
        assert_eq!(sys.samples.len(), 21, "{method}");
        let (mut th, mut om) = (1.0f64, 0.0f64);
        for (i, &(t, a, w)) in sys.samples.iter().enumerate() {
            // At k · 0.1, or at a grid point within round-off of it (where the stop is due).
            assert!(
                (t - i as f64 * 0.1).abs() <= 1e-15,
                "{method}: sample {i} at {t}"
            );
            let scale = th.abs().max(om.abs()).max(1.0);
            assert!(
                (a - th).abs() <= 1e-13 * scale && (w - om).abs() <= 1e-13 * scale,
                "{method}: sample {i}: ({a}, {w}) vs closed form ({th}, {om})"
            );
            let (h, u) = (0.1, -sys.k * th - sys.d * om);
            th += om * h + u * h * h / 2.0;
            om += u * h;
        }
    }
}

#[test]
fn a_stop_that_does_not_move_on_is_an_error_not_a_loop() {
    struct Stuck;
    impl System for Stuck {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, _x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            dx[0] = 1.0;
            Ok(())
        }
        fn next_stop(&self) -> f64 {
            0.5
        }
    }
    let e = integrate(
        &mut Stuck,
        &Options::new(Method::Dp54),
        0.0,
        &[0.0],
        1.0,
        &Output::Times(vec![]),
        |_, _| ControlFlow::Continue(()),
    )
    .unwrap_err();
    assert!(
        matches!(&e, IntegrateError::System { t, .. } if *t == 0.5)
            && e.to_string().contains("did not move past"),
        "{e}"
    );
}

/// A ball bouncing with restitution (an event that resets the state), on the fixed-step
/// grid.
struct Ball;

impl System for Ball {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = -9.81 - 0.1 * x[1];
        Ok(())
    }
    fn n_events(&self) -> usize {
        1
    }
    fn events(&mut self, _t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        g[0] = x[0];
        Ok(())
    }
    fn event_direction(&self, _k: usize) -> EventDirection {
        EventDirection::Falling
    }
    fn on_event(&mut self, _k: usize, _t: f64, x: &mut [f64]) -> EventAction {
        x[1] *= -0.8;
        EventAction::Reset
    }
}

/// A run cut into pieces of whole steps, each resumed with the first run's grid origin,
/// takes the same steps as one run, bounces included: the same rows, bit for bit.
#[test]
fn a_fixed_step_run_in_pieces_takes_the_same_steps_as_one_run() {
    let h = 0.01;
    let opts = Options::new(Method::Rk4).with_fixed_step(h);
    let times: Vec<f64> = (0..=50).map(|i| i as f64 * 0.1).collect();
    let mut whole = Vec::new();
    let stats = integrate(
        &mut Ball,
        &opts,
        0.0,
        &[1.0, 0.0],
        5.0,
        &Output::Times(times.clone()),
        |t, x| {
            whole.push((t, x.to_vec()));
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    assert!(stats.events.len() >= 3, "bounces: {:?}", stats.events);
    let opts = opts.with_grid_origin(0.0);
    let mut pieces = Vec::new();
    let (mut t, mut x) = (0.0f64, vec![1.0, 0.0]);
    // Pieces of 7, 13, 1, 29, ... steps.
    let mut steps = [7usize, 13, 1, 29, 4, 55, 17].into_iter().cycle();
    while t < 5.0 {
        let t_next = (t + steps.next().unwrap() as f64 * h).min(5.0);
        // Snap to the grid as a resumed run does.
        let t_next = if (t_next / h - (t_next / h).round()).abs() < 1e-6 {
            (t_next / h).round() * h
        } else {
            t_next
        };
        let outs: Vec<f64> = times
            .iter()
            .copied()
            .filter(|&o| o > t && o <= t_next || (t == 0.0 && o == 0.0))
            .collect();
        let s = integrate(
            &mut Ball,
            &opts,
            t,
            &x,
            t_next,
            &Output::Times(outs),
            |t, x| {
                pieces.push((t, x.to_vec()));
                ControlFlow::Continue(())
            },
        )
        .unwrap();
        (t, x) = (s.t_final, s.x_final);
    }
    assert_eq!(whole.len(), pieces.len());
    for (a, b) in whole.iter().zip(&pieces) {
        assert_eq!(a, b);
    }
}

/// At a sample instant only the held input changes: an adaptive method goes on with the step
/// its error control proposed. The held input's parabolas are integrated exactly, so nothing
/// holds the steps but the instants: after the first few, each period of 0.1 s is one step
/// landing on its instant. (A first step estimated anew at every instant took two a period:
/// DP5(4) 203 steps for the 100 instants.)
#[test]
fn an_adaptive_method_goes_on_through_a_sample_instant_with_its_proposed_step() {
    for method in [Method::Dp54, Method::Dop853, Method::Radau5] {
        let (_, stats) = sampled_run(method, 10.0);
        // A step landing on each of the 100 instants after the start (the run's end one).
        assert!(stats.steps_capped >= 100, "{method:?} {stats:?}");
        assert!(
            stats.steps_accepted <= stats.steps_capped + 10,
            "{method:?}: {} steps, {} landing",
            stats.steps_accepted,
            stats.steps_capped
        );
        let span = stats.capped_span;
        assert!(span <= 10.0 + 1e-9, "{span}");
    }
}

/// Rows every 0.1 s on a grid of 0.01 s: the rows are the grid's points, the doubles
/// nearest to their decimals (`0.3`, where `3 × 0.1` is `0.30000000000000004` and
/// `30 × 0.01` is `0.3`), and the run takes its 30 000 steps and no sliver between the two
/// (30 482 steps when the rows were products).
#[test]
fn rows_of_a_fixed_step_run_fall_on_its_grid_as_decimals() {
    let opts = Options::new(Method::Rk4).with_fixed_step(0.01);
    let mut times = Vec::new();
    let stats = integrate(
        &mut Smooth,
        &opts,
        0.0,
        &Smooth::X0,
        300.0,
        &Output::Interval(0.1),
        |t, _| {
            times.push(t);
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    assert_eq!(stats.steps_accepted, 30_000);
    assert_eq!(times.len(), 3001);
    for (k, t) in times.iter().enumerate() {
        let decimal: f64 = format!("{}.{}", k / 10, k % 10).parse().unwrap();
        assert_eq!(*t, decimal, "row {k}");
    }
    assert_eq!(times[3], 0.3);
}
