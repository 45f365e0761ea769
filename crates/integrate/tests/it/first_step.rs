//! The first step of the adaptive methods, at the start and at every restart: chosen within
//! the run, never by a right-hand side past its end.

use satsim_integrate::{Method, Options, System, SystemError};

use crate::common::run;

/// A slow circle, `x0' = ω x1, x1' = -ω x0`, that refuses times past `until` (a singular
/// configuration after the run's end), with a time stop that restarts the method at `stop`.
/// It remembers the latest time it was evaluated at.
struct Slow {
    until: f64,
    stop: f64,
    latest: f64,
}

impl Slow {
    const OMEGA: f64 = 1e-3;
}

impl System for Slow {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.latest = self.latest.max(t);
        if t > self.until {
            return Err(SystemError::new(format!("singular at t = {t}")));
        }
        dx[0] = Self::OMEGA * x[1];
        dx[1] = -Self::OMEGA * x[0];
        Ok(())
    }
    fn next_stop(&self) -> f64 {
        self.stop
    }
    fn on_stop(&mut self, _t: f64, _x: &mut [f64]) -> Result<bool, SystemError> {
        self.stop = f64::INFINITY;
        Ok(true)
    }
}

#[test]
fn no_method_evaluates_past_the_end_of_its_run_to_choose_a_first_step() {
    // At a pure absolute tolerance the trial step 0.01 ‖x‖ / ‖f‖ is 10 s: past the end of
    // the 2 s run, where the system refuses every state. The run never goes there, at its
    // start nor at the restart 0.5 s before its end.
    for method in [Method::Dp54, Method::Dop853, Method::Radau5] {
        for stop in [f64::INFINITY, 1.5] {
            let opts = Options::new(method).with_tolerances(0.0, 1e-10);
            let mut sys = Slow {
                until: 2.0,
                stop,
                latest: 0.0,
            };
            let stats = run(&mut sys, &opts, &[1.0, 0.0], 0.0, 2.0)
                .unwrap_or_else(|e| panic!("{method}, stop at {stop}: {e}"));
            assert_eq!(stats.t_final, 2.0);
            assert!(sys.latest <= 2.0, "{method}: evaluated at {}", sys.latest);
            let exact = [(Slow::OMEGA * 2.0).cos(), -(Slow::OMEGA * 2.0).sin()];
            for (x, e) in stats.x_final.iter().zip(exact) {
                assert!((x - e).abs() < 1e-8, "{method}: {:?}", stats.x_final);
            }
        }
    }
}
