//! Shared test problems.
#![allow(dead_code)]

use std::ops::ControlFlow;

use satsim_integrate::{IntegrateError, Options, Output, Stats, System, SystemError, integrate};

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
