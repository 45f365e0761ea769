//! Times each method on a 20-dimensional test system (10 coupled damped
//! oscillators) over the same span and tolerance.

use std::{hint::black_box, ops::ControlFlow};

use criterion::{Criterion, criterion_group, criterion_main};
use satsim_integrate::{Method, Options, Output, System, SystemError, integrate};

struct Chain;

impl System for Chain {
    fn dim(&self) -> usize {
        20
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        let m = 10;
        for i in 0..m {
            let left = if i > 0 { x[i - 1] } else { 0.0 };
            let right = if i + 1 < m { x[i + 1] } else { 0.0 };
            dx[i] = x[m + i];
            dx[m + i] = -2.0 * x[i] + left + right - 0.05 * x[m + i];
        }
        Ok(())
    }
}

fn bench(c: &mut Criterion) {
    let x0: Vec<f64> = (0..20)
        .map(|i| if i < 10 { (i as f64 * 0.3).sin() } else { 0.0 })
        .collect();
    let mut group = c.benchmark_group("chain20_t10");
    for method in Method::ALL {
        let opts = match method {
            Method::Rk4 => Options::new(method).with_fixed_step(0.01),
            _ => Options::new(method).with_tolerances(1e-8, 1e-10),
        };
        group.bench_function(method.name(), |b| {
            b.iter(|| {
                integrate(
                    &mut Chain,
                    &opts,
                    0.0,
                    black_box(&x0),
                    10.0,
                    &Output::Interval(0.1),
                    |_, x| {
                        black_box(x);
                        ControlFlow::Continue(())
                    },
                )
                .unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
