//! Property tests: every adaptive method follows exp decay at arbitrary output
//! times, and outputs arrive exactly at the requested times, in order.

use std::ops::ControlFlow;

use proptest::prelude::*;
use satsim_integrate::{Method, Options, Output, System, SystemError, integrate};

struct Decay(f64);
impl System for Decay {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = -self.0 * x[0];
        Ok(())
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn decay_at_random_output_times(
        lambda in 0.1f64..5.0,
        x0 in -10.0f64..10.0,
        mut times in prop::collection::vec(0.0f64..3.0, 0..12),
        m in 1usize..4,
    ) {
        times.sort_by(f64::total_cmp);
        let method = Method::ALL[m];
        let opts = Options::new(method).with_tolerances(1e-9, 1e-12);
        let mut rows = Vec::new();
        let stats = integrate(&mut Decay(lambda), &opts, 0.0, &[x0], 3.0, &Output::Times(times.clone()), |t, x| {
            rows.push((t, x[0]));
            ControlFlow::Continue(())
        }).unwrap();
        prop_assert_eq!(rows.len(), times.len());
        for ((t, x), te) in rows.iter().zip(&times) {
            prop_assert_eq!(*t, *te);
            let exact = x0 * (-lambda * t).exp();
            prop_assert!((x - exact).abs() <= 1e-6 * (1.0 + exact.abs()), "{} at t={}: {} vs {}", method, t, x, exact);
        }
        prop_assert_eq!(stats.t_final, 3.0);
    }
}
