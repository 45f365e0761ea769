//! Shared test problems.
#![allow(dead_code)]

use std::ops::ControlFlow;

use satsim_integrate::{
    EventAction, EventDirection, IntegrateError, Options, Output, Stats, System, SystemError,
    integrate,
};

/// Harmonic oscillator plus a forced decay, with a closed-form solution:
/// x0'' = -x0 and y' = -y + sin t.
pub struct Smooth;

impl Smooth {
    pub const X0: [f64; 3] = [1.0, 0.0, 1.0];
    pub fn exact(t: f64) -> [f64; 3] {
        // y = (sin t - cos t)/2 + (3/2) e^{-t} satisfies y(0) = 1.
        [
            t.cos(),
            -t.sin(),
            0.5 * (t.sin() - t.cos()) + 1.5 * (-t).exp(),
        ]
    }
}

impl System for Smooth {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = -x[0];
        dx[2] = -x[2] + t.sin();
        Ok(())
    }
}

pub fn max_err(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Runs to `t_end` without outputs.
pub fn run<S: System>(
    sys: &mut S,
    opts: &Options,
    x0: &[f64],
    t0: f64,
    t_end: f64,
) -> Result<Stats, IntegrateError> {
    integrate(sys, opts, t0, x0, t_end, &Output::Times(vec![]), |_, _| {
        ControlFlow::Continue(())
    })
}

/// Every `(t, x)` passed to the observer.
pub type Rows = Vec<(f64, Vec<f64>)>;

/// Runs and collects every output.
pub fn collect<S: System>(
    sys: &mut S,
    opts: &Options,
    x0: &[f64],
    t_end: f64,
    output: &Output,
) -> (Result<Stats, IntegrateError>, Rows) {
    let mut rows = Vec::new();
    let r = integrate(sys, opts, 0.0, x0, t_end, output, |t, x| {
        rows.push((t, x.to_vec()));
        ControlFlow::Continue(())
    });
    (r, rows)
}

pub const G: f64 = 9.81;

/// A ball dropped from rest at height `h`, bouncing on y = 0 with restitution `e`. State
/// `[y, v]`; event 0 is the touch-down. An impact answers `action`; with `Reset` the ball
/// rebounds at `−e v`, or stops the run when that is slower than `v_rest` (it rests on the
/// floor). `impacts` records every impact time.
pub struct Ball {
    pub h: f64,
    pub e: f64,
    pub v_rest: f64,
    pub action: EventAction,
    pub impacts: Vec<f64>,
}

impl Ball {
    pub fn new(h: f64, e: f64, action: EventAction) -> Self {
        Self {
            h,
            e,
            v_rest: 0.0,
            action,
            impacts: Vec::new(),
        }
    }
    /// The analytic impact times: the first `k`, fewer when a rebound falls below `v_rest`.
    pub fn expected(&self, k: usize) -> Vec<f64> {
        let mut t = (2.0 * self.h / G).sqrt();
        let mut v = G * t;
        let mut out = vec![t];
        while out.len() < k && self.e * v >= self.v_rest {
            v *= self.e;
            t += 2.0 * v / G;
            out.push(t);
        }
        out
    }
}

impl System for Ball {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = -G;
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
    fn on_event(&mut self, _k: usize, t: f64, x: &mut [f64]) -> EventAction {
        self.impacts.push(t);
        if self.action == EventAction::Reset {
            let after = -self.e * x[1];
            if after < self.v_rest {
                return EventAction::Stop;
            }
            x[1] = after;
        }
        self.action
    }
}
