//! The integrators against published reference solutions of Hairer's test problems, computed
//! by independent codes:
//!
//! - Arenstorf orbit (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.0, eq. (0.1)): the
//!   restricted three-body orbit is periodic with period
//!   `T = 17.0652165601579625588917206249`, so `y(T) = y(0)`. Explicit methods.
//! - Van der Pol, `ε = 1e-6`, scaled (Hairer & Wanner, *Solving ODEs II*, §IV.10, VDPOL), and
//!   Robertson to `t = 1e11` (ROBER): reference values of the *Test Set for IVP Solvers*
//!   (Mazzia & Magherini, Bari), computed with RADAU in quadruple precision
//!   (`uround = 1e-19`, `rtol = atol = 1.1e-18`). Radau IIA.
//!
//! Each run must land within a small multiple of its requested tolerance of the reference,
//! and tightening the tolerance must shrink the error (tolerance proportionality), so a
//! wrong coefficient or a broken error estimate fails.
//!
//! Measured (`cargo test -p satsim-integrate --test it -- --nocapture hairer_reference::`):
//! Arenstorf `|y(T) − y(0)|` DP5(4) 7.4e-5 / 2.7e-7 at tol 1e-8 / 1e-11, DOP853 8.4e-5 /
//! 7.5e-9, RK4 5.3e-4 / 3.2e-5 at 1e5 / 2e5 steps (order 4.0); VDPOL 3.8e-7 / 3.8e-10 at tol
//! 1e-6 / 1e-9 (0.20 and 0.17 of the tolerance, scaled); ROBER at 1e11 relative 5.1e-10 (rtol
//! 1e-10).

use crate::common;

use common::run;
use satsim_integrate::{Method, Options, System, SystemError};

/// Arenstorf's orbit: `μ = 0.012277471`, `y = (y1, y2, y1', y2')`.
struct Arenstorf;
const MU: f64 = 0.012277471;
const ARENSTORF_T: f64 = 17.065_216_560_157_962_558_891_720_624_9;
/// `y2'(0) = −2.00158510637908252240537862224` (HNW I), rounded to the nearest double.
const ARENSTORF_Y0: [f64; 4] = [0.994, 0.0, 0.0, -2.001_585_106_379_082_4];
impl System for Arenstorf {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SystemError> {
        let mu1 = 1.0 - MU;
        let d1 = ((y[0] + MU).powi(2) + y[1] * y[1]).powf(1.5);
        let d2 = ((y[0] - mu1).powi(2) + y[1] * y[1]).powf(1.5);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = y[0] + 2.0 * y[3] - mu1 * (y[0] + MU) / d1 - MU * (y[0] - mu1) / d2;
        dy[3] = y[1] - 2.0 * y[2] - mu1 * y[1] / d1 - MU * y[1] / d2;
        Ok(())
    }
}

/// VDPOL: `y1' = y2`, `y2' = ((1 − y1²) y2 − y1) / ε`, `ε = 1e-6`, `y(0) = (2, 0)`.
struct VdPol;
const EPS: f64 = 1e-6;
impl System for VdPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SystemError> {
        dy[0] = y[1];
        dy[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / EPS;
        Ok(())
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, SystemError> {
        jac.copy_from_slice(&[
            0.0,
            1.0,
            (-2.0 * y[0] * y[1] - 1.0) / EPS,
            (1.0 - y[0] * y[0]) / EPS,
        ]);
        Ok(true)
    }
}
const VDPOL_REF: [f64; 2] = [1.706_167_732_170_483, -0.892_809_701_024_797_5];

/// ROBER: `k1 = 0.04`, `k2 = 3e7`, `k3 = 1e4`, `y(0) = (1, 0, 0)`.
struct Rober;
impl System for Rober {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SystemError> {
        dy[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
        dy[2] = 3e7 * y[1] * y[1];
        dy[1] = -dy[0] - dy[2];
        Ok(())
    }
}
const ROBER_REF: [f64; 3] = [
    0.208_334_014_970_125_5e-7,
    0.833_336_077_033_471_3e-13,
    0.999_999_979_166_505,
];

/// Largest error relative to `atol + rtol |ref|` (the test set's scaled error).
fn scaled_err(got: &[f64], reference: &[f64], rtol: f64, atol: f64) -> f64 {
    got.iter()
        .zip(reference)
        .map(|(g, r)| (g - r).abs() / (atol + rtol * r.abs()))
        .fold(0.0, f64::max)
}

fn abs_err(got: &[f64], reference: &[f64]) -> f64 {
    got.iter()
        .zip(reference)
        .map(|(g, r)| (g - r).abs())
        .fold(0.0, f64::max)
}

#[test]
fn arenstorf_orbit_closes_after_one_period() {
    for method in [Method::Dp54, Method::Dop853] {
        let mut errors = Vec::new();
        for tol in [1e-8, 1e-11] {
            let opts = Options::new(method).with_tolerances(tol, tol);
            let stats = run(&mut Arenstorf, &opts, &ARENSTORF_Y0, 0.0, ARENSTORF_T).unwrap();
            let err = abs_err(&stats.x_final, &ARENSTORF_Y0);
            println!("arenstorf {method:?} tol {tol:e}: |y(T) - y(0)| = {err:.2e}");
            errors.push(err);
        }
        // The orbit passes close to the moon, where local errors are amplified by ~1e4:
        // the global error is bounded by 1e5 times the tolerance.
        assert!(errors[0] < 1e-3, "{method:?}: {errors:?}");
        assert!(errors[1] < 1e-6, "{method:?}: {errors:?}");
        assert!(
            errors[1] < errors[0] / 30.0,
            "{method:?} not converging: {errors:?}"
        );
    }
    // RK4 with a fixed step (the close approaches to the moon need h of order 1e-4): the
    // error must fall 16-fold when h halves.
    let mut errors = Vec::new();
    for n in [100_000.0, 200_000.0] {
        let opts = Options::new(Method::Rk4).with_fixed_step(ARENSTORF_T / n);
        let stats = run(&mut Arenstorf, &opts, &ARENSTORF_Y0, 0.0, ARENSTORF_T).unwrap();
        errors.push(abs_err(&stats.x_final, &ARENSTORF_Y0));
    }
    println!("arenstorf rk4: {errors:?}");
    assert!(errors[1] < 1e-4, "{errors:?}");
    let order = (errors[0] / errors[1]).log2();
    assert!(
        (3.5..4.5).contains(&order),
        "RK4 observed order {order}: {errors:?}"
    );
}

#[test]
fn radau5_van_der_pol_matches_the_test_set_reference() {
    let mut errors = Vec::new();
    for tol in [1e-6, 1e-9] {
        let opts = Options::new(Method::Radau5).with_tolerances(tol, tol);
        let stats = run(&mut VdPol, &opts, &[2.0, 0.0], 0.0, 2.0).unwrap();
        let err = scaled_err(&stats.x_final, &VDPOL_REF, tol, tol);
        let abs = abs_err(&stats.x_final, &VDPOL_REF);
        println!(
            "vdpol tol {tol:e}: {:?}, scaled error {err:.2}, abs {abs:.2e}, {} steps",
            stats.x_final, stats.steps_accepted
        );
        errors.push(abs);
        // Measured 0.09 (tol 1e-6) and 0.19 (tol 1e-9) scaled units; the bound is under 10×
        // the smaller.
        assert!(err < 0.9, "tol {tol:e}: error {err} tolerances");
    }
    assert!(errors[1] < errors[0] / 100.0, "not converging: {errors:?}");
}

#[test]
fn radau5_robertson_to_1e11_matches_the_test_set_reference() {
    let (rtol, atol) = (1e-10, 1e-20);
    let opts = Options::new(Method::Radau5)
        .with_tolerances(rtol, atol)
        .with_max_steps(100_000);
    let stats = run(&mut Rober, &opts, &[1.0, 0.0, 0.0], 0.0, 1e11).unwrap();
    println!("rober: {:?}, {} steps", stats.x_final, stats.steps_accepted);
    for (i, (x, r)) in stats.x_final.iter().zip(ROBER_REF).enumerate() {
        let rel = (x - r).abs() / r;
        println!("rober y{}: relative error {rel:.2e}", i + 1);
        assert!(rel < 1e-8, "component {}: {x} vs {r} ({rel:e})", i + 1);
    }
}
