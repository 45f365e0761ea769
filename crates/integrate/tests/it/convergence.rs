//! Measured order of convergence at fixed steps equals the theoretical order.

use crate::common;

use common::{Smooth, max_err, run};
use satsim_integrate::{Method, Options};

/// Error at t_end for fixed steps h = t_end / n.
fn error(method: Method, t_end: f64, n: usize) -> f64 {
    let opts = Options::new(method)
        .with_fixed_step(t_end / n as f64)
        .with_tolerances(1e-12, 1e-14);
    let stats = run(&mut Smooth, &opts, &Smooth::X0, 0.0, t_end).unwrap();
    assert_eq!(
        stats.steps_accepted, n,
        "fixed steps must land exactly on t_end"
    );
    assert_eq!(stats.t_final, t_end);
    max_err(&stats.x_final, &Smooth::exact(t_end))
}

/// Least-squares slope of log(err) against log(h) over a step sweep.
fn measured_order(method: Method, t_end: f64, ns: &[usize]) -> f64 {
    let pts: Vec<(f64, f64)> = ns
        .iter()
        .map(|&n| ((t_end / n as f64).ln(), error(method, t_end, n).ln()))
        .collect();
    let m = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (mx, my) = (sx / m, sy / m);
    let num: f64 = pts.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = pts.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let p = num / den;
    println!("{method}: measured order {p:.3} ({pts:?})");
    p
}

#[test]
fn rk4_order_4() {
    let p = measured_order(Method::Rk4, 4.0, &[20, 40, 80, 160]);
    assert!((p - 4.0).abs() < 0.3, "rk4 order {p}");
}

#[test]
fn dp54_order_5() {
    let p = measured_order(Method::Dp54, 4.0, &[10, 20, 40, 80]);
    assert!((p - 5.0).abs() < 0.3, "dp54 order {p}");
}

#[test]
fn dop853_order_8() {
    let p = measured_order(Method::Dop853, 4.0, &[4, 6, 8, 12]);
    assert!((p - 8.0).abs() < 0.3, "dop853 order {p}");
}

#[test]
fn radau5_order_5() {
    let p = measured_order(Method::Radau5, 4.0, &[10, 20, 40, 80]);
    assert!((p - 5.0).abs() < 0.3, "radau5 order {p}");
}

/// Adaptive runs: the global error follows the tolerance, and work grows
/// like tol^(-1/order): slope of log(err) against log(rhs evals) ≈ -order.
#[test]
fn adaptive_error_tracks_tolerance() {
    for method in [Method::Dp54, Method::Dop853, Method::Radau5] {
        let mut last = f64::INFINITY;
        for tol in [1e-4, 1e-6, 1e-8, 1e-10] {
            let opts = Options::new(method).with_tolerances(tol, tol);
            let stats = run(&mut Smooth, &opts, &Smooth::X0, 0.0, 10.0).unwrap();
            let err = max_err(&stats.x_final, &Smooth::exact(10.0));
            println!(
                "{method} tol {tol:e}: err {err:e}, {} evals",
                stats.rhs_evals
            );
            assert!(err < 100.0 * tol, "{method} tol {tol}: err {err}");
            assert!(err < last, "{method}: error must decrease with tolerance");
            last = err;
        }
    }
}
