//! Quadrature states ([`System::quadratures`]): integrals of the other states that no
//! derivative reads. Radau IIA leaves them out of its Newton test and, after checking their
//! columns once, out of its finite-difference Jacobian: the other states' steps are then
//! those of the system without them, bit for bit.

use crate::common::run;
use satsim_integrate::{IntegrateError, Method, Options, System, SystemError};

/// Van der Pol at `μ = 1e3` (stiff, finite-difference Jacobian), and with `work`, a third
/// state integrating `μ x₁²` (the damping's power, large and kinked where `x₁` changes
/// sign); `declared`: whether that state is declared a quadrature.
struct Vdp {
    work: bool,
    declared: bool,
}

const MU: f64 = 1e3;

impl System for Vdp {
    fn dim(&self) -> usize {
        if self.work { 3 } else { 2 }
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = MU * (1.0 - x[0] * x[0]) * x[1] - x[0];
        if self.work {
            dx[2] = MU * x[1] * x[1];
        }
        Ok(())
    }
    fn error_weights(&self, w: &mut [f64]) {
        w.fill(1.0);
        if self.work {
            w[2] = 0.0;
        }
    }
    fn quadratures(&self, q: &mut [bool]) {
        if self.work && self.declared {
            q[2] = true;
        }
    }
}

#[test]
fn a_declared_quadrature_leaves_the_other_states_steps_bit_for_bit() {
    let opts = Options::new(Method::Radau5).with_tolerances(1e-6, 1e-6);
    let t_end = 1500.0;
    let plain = Vdp {
        work: false,
        declared: false,
    };
    let bare = run(&mut { plain }, &opts, &[2.0, 0.0], 0.0, t_end).unwrap();
    let x0 = [2.0, 0.0, 0.0];
    let declared = run(
        &mut Vdp {
            work: true,
            declared: true,
        },
        &opts,
        &x0,
        0.0,
        t_end,
    )
    .unwrap();
    let undeclared = run(
        &mut Vdp {
            work: true,
            declared: false,
        },
        &opts,
        &x0,
        0.0,
        t_end,
    )
    .unwrap();
    println!("bare {bare:?}\ndeclared {declared:?}\nundeclared {undeclared:?}");
    // The same steps and states; one right-hand side more, the first Jacobian's check of
    // the quadrature's column.
    assert_eq!(declared.x_final[..2], bare.x_final[..]);
    assert_eq!(
        (declared.steps_accepted, declared.steps_rejected),
        (bare.steps_accepted, bare.steps_rejected)
    );
    assert_eq!(declared.jacobian_evals, bare.jacobian_evals);
    assert_eq!(declared.rhs_evals, bare.rhs_evals + 1);
    // Undeclared, the work's increments count in the Newton test (and its column is
    // differenced at every Jacobian): more right-hand sides for the same motion.
    assert!(
        undeclared.rhs_evals > declared.rhs_evals,
        "{} against {}",
        undeclared.rhs_evals,
        declared.rhs_evals
    );
    // The work itself, against the same system at a tight tolerance.
    let tight = Options::new(Method::Dop853).with_tolerances(1e-12, 1e-12);
    let reference = run(
        &mut Vdp {
            work: true,
            declared: false,
        },
        &tight,
        &x0,
        0.0,
        t_end,
    )
    .unwrap();
    let w = reference.x_final[2];
    let rel = (declared.x_final[2] - w).abs() / w;
    println!("work {} against {w}: {rel:.2e}", declared.x_final[2]);
    assert!(rel < 1e-5, "work {} against {w}", declared.x_final[2]);
}

/// `x₀' = −x₀ + x₁`, `x₁' = 1`: `x₁` is read, so it is no quadrature.
struct Misdeclared;
impl System for Misdeclared {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = -x[0] + x[1];
        dx[1] = 1.0;
        Ok(())
    }
    fn quadratures(&self, q: &mut [bool]) {
        q[1] = true;
    }
}

#[test]
fn a_quadrature_some_derivative_reads_is_refused_at_the_first_jacobian() {
    let opts = Options::new(Method::Radau5);
    match run(&mut Misdeclared, &opts, &[0.0, 0.0], 0.0, 1.0) {
        Err(IntegrateError::InvalidOptions(msg)) => {
            assert!(msg.contains("state 1") && msg.contains("state 0"), "{msg}");
        }
        other => panic!("expected the quadrature refused, got {other:?}"),
    }
    // The explicit methods read no Jacobian: the declaration does not concern them.
    run(
        &mut Misdeclared,
        &Options::new(Method::Dp54),
        &[0.0, 0.0],
        0.0,
        1.0,
    )
    .unwrap();
}
