//! Events that fall together: every crossing in a step is handled, coincident ones at the
//! same instant and together, whatever the others do; a reset that makes another event cross
//! fires it at the same instant (a chain); a failing event evaluation is an error.

use crate::common;

use common::collect;
use satsim_integrate::{
    EventAction, EventDirection, IntegrateError, Method, Options, Output, StopReason, System,
    SystemError,
};

const G: f64 = 9.81;
const E: f64 = 0.8;

/// `n` balls falling side by side from heights `h[i]`, each bouncing on y = 0 with
/// restitution `E`. State `[y_0, v_0, y_1, v_1, ...]`; event `i` is ball `i` touching down.
/// `actions[i]` is what ball `i`'s impact answers; `groups` records each `on_events` call.
struct Balls {
    n: usize,
    actions: Vec<EventAction>,
    groups: Vec<(f64, Vec<usize>)>,
}

impl Balls {
    fn new(n: usize, action: EventAction) -> Self {
        Self {
            n,
            actions: vec![action; n],
            groups: Vec::new(),
        }
    }
}

impl System for Balls {
    fn dim(&self) -> usize {
        2 * self.n
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        for i in 0..self.n {
            dx[2 * i] = x[2 * i + 1];
            dx[2 * i + 1] = -G;
        }
        Ok(())
    }
    fn n_events(&self) -> usize {
        self.n
    }
    fn events(&mut self, _t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        for i in 0..self.n {
            g[i] = x[2 * i];
        }
        Ok(())
    }
    fn event_direction(&self, _k: usize) -> EventDirection {
        EventDirection::Falling
    }
    fn on_event(&mut self, k: usize, _t: f64, x: &mut [f64]) -> EventAction {
        if self.actions[k] == EventAction::Reset {
            x[2 * k + 1] *= -E;
        }
        self.actions[k]
    }
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        self.groups.push((t, ks.to_vec()));
        let mut action = EventAction::Continue;
        for &k in ks {
            action = action.combine(self.on_event(k, t, x));
        }
        Ok(action)
    }
}

fn options(method: Method) -> Options {
    let opts = Options::new(method).with_tolerances(1e-10, 1e-12);
    if method == Method::Rk4 {
        opts.with_fixed_step(0.05)
    } else {
        opts
    }
}

/// Impact times of a ball dropped from `h` at rest.
fn impacts(h: f64, k: usize) -> Vec<f64> {
    let t1 = (2.0 * h / G).sqrt();
    let v1 = G * t1;
    let mut t = t1;
    let mut out = vec![t1];
    for j in 1..k {
        t += 2.0 * E.powi(j as i32) * v1 / G;
        out.push(t);
    }
    out
}

#[test]
fn identical_balls_all_bounce_at_every_impact_under_every_method() {
    let expected = impacts(10.0, 4);
    let t_end = expected[3] + 0.1;
    for n in [2, 4] {
        for method in Method::ALL {
            let mut balls = Balls::new(n, EventAction::Reset);
            let x0: Vec<f64> = (0..n).flat_map(|_| [10.0, 0.0]).collect();
            let (r, rows) = collect(
                &mut balls,
                &options(method),
                &x0,
                t_end,
                &Output::Interval(0.01),
            );
            let stats = r.unwrap();
            assert_eq!(stats.stop, StopReason::Finished);
            // One group of all n balls at each impact.
            assert_eq!(
                balls.groups.len(),
                4,
                "{method}, {n} balls: {:?}",
                balls.groups
            );
            for ((t, ks), te) in balls.groups.iter().zip(&expected) {
                assert_eq!(*ks, (0..n).collect::<Vec<_>>(), "{method}");
                assert!(
                    (t - te).abs() < 1e-9,
                    "{method}: impact at {t}, expected {te}"
                );
            }
            // The event log lists each.
            assert_eq!(stats.events.len(), 4 * n, "{method}: {:?}", stats.events);
            // No ball ever goes through the floor, and they stay together.
            for (t, x) in &rows {
                for i in 0..n {
                    assert!(
                        x[2 * i] > -1e-6,
                        "{method}: ball {i} at {} at t = {t}",
                        x[2 * i]
                    );
                    assert_eq!(x[2 * i], x[0], "{method}: balls differ at t = {t}");
                }
            }
        }
    }
}

/// A second ball whose impact is 1e-12 s after the first's (well within the event
/// tolerance) is handled in the same group, at the same instant.
#[test]
fn impacts_within_the_event_tolerance_are_one_group() {
    let h2 = 10.0 + 1e-11; // impact about 7e-13 s later
    for method in Method::ALL {
        let mut balls = Balls::new(2, EventAction::Reset);
        let (r, rows) = collect(
            &mut balls,
            &options(method),
            &[10.0, 0.0, h2, 0.0],
            1.6,
            &Output::Interval(0.01),
        );
        r.unwrap();
        assert_eq!(balls.groups.len(), 1, "{method}: {:?}", balls.groups);
        assert_eq!(balls.groups[0].1, [0, 1]);
        assert!(rows.iter().all(|(_, x)| x[0] > -1e-6 && x[2] > -1e-6));
    }
}

/// Whatever one event answers, a coincident one is handled too.
#[test]
fn a_coincident_event_is_handled_whatever_the_other_answers() {
    for first in [EventAction::Stop, EventAction::Continue, EventAction::Reset] {
        for method in Method::ALL {
            let mut balls = Balls::new(2, EventAction::Reset);
            balls.actions[0] = first;
            let (r, _) = collect(
                &mut balls,
                &options(method),
                &[10.0, 0.0, 10.0, 0.0],
                2.0,
                &Output::Interval(0.1),
            );
            let stats = r.unwrap();
            let t1 = impacts(10.0, 1)[0];
            let ks: Vec<usize> = stats.events.iter().map(|e| e.1).collect();
            assert!(ks.starts_with(&[0, 1]), "{first:?}, {method}: {ks:?}");
            assert!(stats.events[..2].iter().all(|e| (e.0 - t1).abs() < 1e-9));
            match first {
                EventAction::Stop => {
                    assert_eq!(stats.stop, StopReason::Event { k: 0 });
                    assert_eq!(stats.events.len(), 2);
                }
                _ => {
                    assert_eq!(stats.stop, StopReason::Finished);
                    // Ball 1 bounced (the reset of the group applied), ball 0 only if it
                    // reset too: a `Continue` leaves it falling through the floor.
                    assert!(stats.x_final[2] > 0.0, "{first:?}, {method}");
                }
            }
        }
    }
}

/// A particle hits a wall (event 0 reverses its velocity); event 1 watches for the
/// velocity turning positive, which only the reset at event 0 does: both fire at the
/// same instant, in that order.
#[test]
fn a_reset_that_makes_another_event_cross_fires_it_at_the_same_instant() {
    struct Wall {
        seen: Vec<(f64, Vec<usize>, f64)>,
    }
    impl System for Wall {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, _x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            dx[0] = _x[1];
            dx[1] = 0.0;
            Ok(())
        }
        fn n_events(&self) -> usize {
            2
        }
        fn events(&mut self, _t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
            g[0] = x[0];
            g[1] = x[1];
            Ok(())
        }
        fn event_direction(&self, k: usize) -> EventDirection {
            [EventDirection::Falling, EventDirection::Rising][k]
        }
        fn on_events(
            &mut self,
            ks: &[usize],
            t: f64,
            x: &mut [f64],
        ) -> Result<EventAction, SystemError> {
            self.seen.push((t, ks.to_vec(), x[1]));
            if ks.contains(&0) {
                x[1] = -x[1];
                Ok(EventAction::Reset)
            } else {
                Ok(EventAction::Continue)
            }
        }
    }
    for method in Method::ALL {
        let mut wall = Wall { seen: Vec::new() };
        let (r, _) = collect(
            &mut wall,
            &options(method),
            &[1.0, -1.0],
            3.0,
            &Output::Interval(0.5),
        );
        let stats = r.unwrap();
        let ev: Vec<usize> = stats.events.iter().map(|e| e.1).collect();
        assert_eq!(ev, [0, 1], "{method}: {:?}", stats.events);
        assert!(stats.events.iter().all(|e| (e.0 - 1.0).abs() < 1e-9));
        assert_eq!(wall.seen.len(), 2);
        assert_eq!(wall.seen[1].1, [1]);
        assert_eq!(
            wall.seen[1].2, 1.0,
            "event 1 sees the state after the reset"
        );
        assert!((stats.x_final[0] - 2.0).abs() < 1e-9);
    }
}

/// An event function that cannot be evaluated stops the run with an error instead of
/// skipping the event.
#[test]
fn a_failing_event_evaluation_is_an_error() {
    struct Fails;
    impl System for Fails {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, _x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            dx[0] = 1.0;
            Ok(())
        }
        fn n_events(&self) -> usize {
            1
        }
        fn events(&mut self, _t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
            if x[0] > 0.5 {
                return Err("cannot evaluate".into());
            }
            g[0] = 0.75 - x[0];
            Ok(())
        }
    }
    let err = collect(
        &mut Fails,
        &options(Method::Dp54),
        &[0.0],
        1.0,
        &Output::Times(vec![]),
    )
    .0
    .unwrap_err();
    let IntegrateError::System { source, .. } = &err else {
        panic!("{err:?}");
    };
    assert_eq!(source.to_string(), "cannot evaluate", "{err:?}");
}
