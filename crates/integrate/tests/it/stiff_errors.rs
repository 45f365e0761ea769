//! Stiff problems, every error variant, and the projection hook.

use crate::common;

use common::{Smooth, run};
use satsim_integrate::{
    IntegrateError, Method, NonFiniteEntry, Options, Output, System, SystemError, integrate,
};

/// y' = -1e6 (y - cos t): solution hugs cos t after a 1 µs transient.
struct StiffScalar;
impl System for StiffScalar {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = -1e6 * (x[0] - t.cos());
        Ok(())
    }
}

/// Robertson's chemical kinetics (stiff, 3 species).
struct Robertson;
impl System for Robertson {
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

/// Van der Pol with mu = 1e3, with an analytic Jacobian.
struct VanDerPol;
const MU: f64 = 1e3;
impl System for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = MU * (1.0 - x[0] * x[0]) * x[1] - x[0];
        Ok(())
    }
    fn jacobian(&mut self, _t: f64, x: &[f64], jac: &mut [f64]) -> Result<bool, SystemError> {
        jac.copy_from_slice(&[
            0.0,
            1.0,
            -2.0 * MU * x[0] * x[1] - 1.0,
            MU * (1.0 - x[0] * x[0]),
        ]);
        Ok(true)
    }
}

#[test]
fn radau5_stable_on_stiff_scalar_with_large_steps() {
    let opts = Options::new(Method::Radau5).with_tolerances(1e-6, 1e-8);
    let stats = run(&mut StiffScalar, &opts, &[0.0], 0.0, 10.0).unwrap();
    println!("radau5 stiff scalar: {stats:?}");
    assert!((stats.x_final[0] - 10f64.cos()).abs() < 1e-5);
    assert!(stats.rhs_evals < 2000, "{} evals", stats.rhs_evals);
    // Far beyond the explicit stability limit (~3e-6): large steps were taken.
    assert!(stats.steps_accepted < 200);
}

#[test]
fn dp54_on_stiff_problem_hits_max_steps() {
    let opts = Options::new(Method::Dp54).with_max_steps(5000);
    match run(&mut StiffScalar, &opts, &[0.0], 0.0, 10.0) {
        Err(IntegrateError::MaxSteps { t, .. }) => assert!(t > 0.0 && t < 10.0),
        other => panic!("expected MaxSteps, got {other:?}"),
    }
}

#[test]
fn radau5_far_cheaper_than_dp54_when_stiff() {
    let opts = |m| Options::new(m).with_tolerances(1e-6, 1e-8);
    let radau = run(&mut StiffScalar, &opts(Method::Radau5), &[0.0], 0.0, 0.1).unwrap();
    let dp = run(&mut StiffScalar, &opts(Method::Dp54), &[0.0], 0.0, 0.1).unwrap();
    println!(
        "t_end 0.1: radau5 {} evals, dp54 {} evals",
        radau.rhs_evals, dp.rhs_evals
    );
    assert!(10 * radau.rhs_evals < dp.rhs_evals);
    assert!((radau.x_final[0] - dp.x_final[0]).abs() < 1e-5);
}

#[test]
fn radau5_robertson_reference() {
    let opts = Options::new(Method::Radau5).with_tolerances(1e-8, 1e-12);
    let stats = run(&mut Robertson, &opts, &[1.0, 0.0, 0.0], 0.0, 40.0).unwrap();
    println!("robertson: {stats:?}");
    // Reference values at t = 40 (Hairer & Wanner).
    let reference = [0.715_827_068_7, 9.185_534_765e-6, 0.284_163_745_7];
    for (i, (x, r)) in stats.x_final.iter().zip(reference).enumerate() {
        assert!((x - r).abs() / r < 1e-5, "component {i}: {x} vs {r}");
    }
    assert!(stats.steps_accepted < 200);
}

#[test]
fn radau5_van_der_pol_with_analytic_jacobian() {
    let opts = Options::new(Method::Radau5).with_tolerances(1e-6, 1e-6);
    let stats = run(&mut VanDerPol, &opts, &[2.0, 0.0], 0.0, 3000.0).unwrap();
    println!("vdp: {stats:?}");
    assert!(stats.steps_accepted < 2000);
    assert!(
        stats.jacobian_evals < stats.steps_accepted,
        "Jacobian reused across steps"
    );
    assert!(stats.x_final[0].abs() < 2.1);
    // Same run with a finite-difference Jacobian agrees.
    struct VdpFd;
    impl System for VdpFd {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            VanDerPol.rhs(t, x, dx)
        }
    }
    let fd = run(&mut VdpFd, &opts, &[2.0, 0.0], 0.0, 3000.0).unwrap();
    assert!((fd.x_final[0] - stats.x_final[0]).abs() < 1e-3);
}

#[test]
fn a_fixed_step_run_whose_steps_exceed_the_budget_is_refused_before_it_starts() {
    for method in [Method::Rk4, Method::Dp54, Method::Radau5] {
        let mut sys = Smooth;
        let opts = Options::new(method).with_fixed_step(1e-300);
        let e = run(&mut sys, &opts, &Smooth::X0, 0.0, 2.0).unwrap_err();
        let IntegrateError::InvalidOptions(m) = &e else {
            panic!("{method}: {e:?}")
        };
        for part in [
            "fixed_step = 1e-300",
            "takes 2.000e300 steps",
            "max_steps = 1000000",
            "at least 0.000002",
        ] {
            assert!(m.contains(part), "{method}: {m}");
        }
        // 200 steps of 0.01 fit a budget of 200, not of 199.
        let opts = Options::new(method).with_fixed_step(0.01);
        let stats = run(
            &mut sys,
            &opts.clone().with_max_steps(200),
            &Smooth::X0,
            0.0,
            2.0,
        );
        assert_eq!(stats.unwrap().steps_accepted, 200, "{method}");
        let e = run(&mut sys, &opts.with_max_steps(199), &Smooth::X0, 0.0, 2.0);
        assert!(
            matches!(e, Err(IntegrateError::InvalidOptions(_))),
            "{method}: {e:?}"
        );
    }
}

#[test]
fn error_messages_write_extreme_times_in_exponent_form() {
    let e = IntegrateError::MaxSteps {
        t: 1.5e-293,
        stepping: String::new(),
    };
    assert_eq!(
        e.to_string(),
        "maximum number of steps exceeded at t = 1.5e-293"
    );
    let e = IntegrateError::StepSizeUnderflow {
        t: 0.25,
        h: 1e-17,
        entry: None,
        what: String::new(),
    };
    assert_eq!(e.to_string(), "step size underflow at t = 0.25 (h = 1e-17)");
    let e = IntegrateError::System {
        t: f64::INFINITY,
        source: SystemError::new("no"),
    };
    assert_eq!(e.to_string(), "system error at t = inf: no");
}

#[test]
fn invalid_options_are_rejected() {
    let bad = [
        Options::new(Method::Dp54).with_tolerances(-1e-6, 1e-9),
        Options::new(Method::Dp54).with_tolerances(0.0, 0.0),
        Options::new(Method::Dp54).with_tolerances(1e-6, 0.0),
        Options::new(Method::Radau5).with_tolerances(1e-6, 0.0),
        Options::new(Method::Dp54).with_tolerances(f64::NAN, 1e-9),
        Options::new(Method::Dp54).with_fixed_step(0.0),
        Options::new(Method::Dp54).with_h0(-1.0),
        Options::new(Method::Dp54).with_max_steps(0),
        Options::new(Method::Rk4), // rk4 needs a fixed step
        Options::new(Method::Dp54).with_event_tol(0.0),
    ];
    for opts in bad {
        assert!(
            matches!(
                run(&mut Smooth, &opts, &Smooth::X0, 0.0, 1.0),
                Err(IntegrateError::InvalidOptions(_))
            ),
            "{opts:?}"
        );
    }
    let ok = Options::new(Method::Dp54);
    let cont = |_: f64, _: &[f64]| std::ops::ControlFlow::Continue(());
    // t_end before t0, wrong dimension, bad output requests.
    let cases: [(f64, &[f64], Output); 5] = [
        (-1.0, &Smooth::X0, Output::Steps),
        (1.0, &[1.0, 2.0], Output::Steps),
        (1.0, &Smooth::X0, Output::Interval(-0.1)),
        (1.0, &Smooth::X0, Output::Times(vec![0.5, 0.2])),
        (1.0, &Smooth::X0, Output::Times(vec![2.0])),
    ];
    for (t_end, x0, out) in cases {
        let r = integrate(&mut Smooth, &ok, 0.0, x0, t_end, &out, cont);
        assert!(
            matches!(r, Err(IntegrateError::InvalidOptions(_))),
            "{t_end} {x0:?} {out:?}: {r:?}"
        );
    }
    let err = "euler".parse::<Method>().unwrap_err().to_string();
    assert!(
        err.contains("rk4")
            && err.contains("dp54")
            && err.contains("dop853")
            && err.contains("radau5")
    );
    for m in Method::ALL {
        assert_eq!(m.name().parse::<Method>().unwrap(), m);
    }
}

/// Returns NaN (or an error) once t passes 0.5.
struct Faulty {
    fail_with_error: bool,
}
impl System for Faulty {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        if t > 0.5 {
            if self.fail_with_error {
                return Err(SystemError::new(format!("singular configuration at {t}")));
            }
            dx[0] = f64::NAN;
        } else {
            dx[0] = 1.0;
        }
        Ok(())
    }
}

fn options_for(method: Method) -> Options {
    let o = Options::new(method);
    if method == Method::Rk4 {
        o.with_fixed_step(0.01)
    } else {
        o
    }
}

#[test]
fn non_finite_rhs_is_reported() {
    for method in Method::ALL {
        match run(
            &mut Faulty {
                fail_with_error: false,
            },
            &options_for(method),
            &[0.0],
            0.0,
            1.0,
        ) {
            Err(e @ IntegrateError::NonFinite { t, entry, .. }) => {
                assert!(t > 0.5 && t <= 1.0, "{method}: t = {t}");
                // The entry is named: the derivative's, the state being finite.
                assert_eq!(entry, Some(NonFiniteEntry::Derivative(0)), "{method}");
                assert!(
                    e.to_string().ends_with(": the derivative of state entry 0"),
                    "{method}: {e}"
                );
            }
            other => panic!("{method}: expected NonFinite, got {other:?}"),
        }
    }
}

#[test]
fn system_error_propagates_with_time() {
    for method in Method::ALL {
        match run(
            &mut Faulty {
                fail_with_error: true,
            },
            &options_for(method),
            &[0.0],
            0.0,
            1.0,
        ) {
            Err(IntegrateError::System { t, source }) => {
                assert!(t > 0.5 && t <= 1.0);
                assert!(source.to_string().contains("singular"));
            }
            other => panic!("{method}: expected System, got {other:?}"),
        }
    }
}

/// The engine's error type, as a system's typed failure.
#[derive(Debug, Clone, PartialEq)]
struct Singular {
    hinge: usize,
}
impl std::fmt::Display for Singular {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "singular configuration at hinge {}", self.hinge)
    }
}
impl std::error::Error for Singular {}

/// Fails with a typed error once t passes 0.5.
struct TypedFailure;
impl System for TypedFailure {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        if t > 0.5 {
            return Err(SystemError::from_error(Singular { hinge: 4 }));
        }
        dx[0] = 1.0;
        Ok(())
    }
}

/// A typed system error reaches the caller typed, through every method, with the text it
/// had as a message (the integration error's text unchanged).
#[test]
fn typed_system_error_propagates() {
    use std::error::Error;
    for method in Method::ALL {
        let err = run(&mut TypedFailure, &options_for(method), &[0.0], 0.0, 1.0).unwrap_err();
        let IntegrateError::System { t, source } = &err else {
            panic!("{method}: expected System, got {err:?}");
        };
        assert_eq!(
            source.downcast_ref::<Singular>(),
            Some(&Singular { hinge: 4 })
        );
        assert!(!source.is_message());
        let typed = source.source().expect("the typed error");
        assert_eq!(typed.to_string(), "singular configuration at hinge 4");
        let as_message = IntegrateError::System {
            t: *t,
            source: SystemError::new(Singular { hinge: 4 }.to_string()),
        };
        assert_eq!(err.to_string(), as_message.to_string());
        assert_eq!(
            err.to_string(),
            format!("system error at t = {t}: singular configuration at hinge 4")
        );
        // Equal by text, and clones stay equal.
        assert_eq!(err, as_message);
        assert_eq!(err.clone(), err);
    }
}

/// y' = y², y(0) = 1 blows up at t = 1.
struct BlowUp;
impl System for BlowUp {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[0] * x[0];
        Ok(())
    }
}

#[test]
fn step_size_underflow_at_blow_up() {
    for method in [Method::Dp54, Method::Dop853, Method::Radau5] {
        match run(&mut BlowUp, &Options::new(method), &[1.0], 0.0, 2.0) {
            Err(IntegrateError::StepSizeUnderflow { t, h, .. }) => {
                assert!((t - 1.0).abs() < 1e-3 && h > 0.0, "{method}: t = {t}");
            }
            other => panic!("{method}: expected StepSizeUnderflow, got {other:?}"),
        }
    }
}

/// A constant, a decay and, last but one, [`BlowUp`]'s `y' = y²`, which blows up at t = 1.
struct BlowUpAmong;
impl System for BlowUpAmong {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = 0.0;
        dx[1] = -x[1];
        dx[2] = x[2] * x[2];
        dx[3] = -2.0 * x[3];
        Ok(())
    }
}

/// A step size underflow names the state entry whose error the steps were shortened for
/// (the one that weighs most in the last rejected step's error norm), through every
/// adaptive method.
#[test]
fn a_step_size_underflow_names_the_entry_whose_error_limited_it() {
    for method in [Method::Dp54, Method::Dop853, Method::Radau5] {
        let x0 = [1.0, 1.0, 1.0, 1.0];
        let err = run(&mut BlowUpAmong, &Options::new(method), &x0, 0.0, 2.0).unwrap_err();
        let IntegrateError::StepSizeUnderflow { t, entry, .. } = &err else {
            panic!("{method}: expected StepSizeUnderflow, got {err:?}");
        };
        assert!((t - 1.0).abs() < 1e-3, "{method}: {err}");
        assert_eq!(*entry, Some(2), "{method}: {err}");
        assert!(
            err.to_string()
                .ends_with("): the steps were last cut for state entry 2"),
            "{method}: {err}"
        );
    }
}

#[test]
fn radau5_fixed_step_newton_failure() {
    // A fixed step far past the blow-up: the implicit equations have no solution.
    let opts = Options::new(Method::Radau5).with_fixed_step(2.0);
    match run(&mut BlowUp, &opts, &[1.0], 0.0, 2.0) {
        Err(IntegrateError::ConvergenceFailure { t, h }) => assert!(t == 0.0 && h == 2.0),
        other => panic!("expected ConvergenceFailure, got {other:?}"),
    }
}

/// Rotation of a unit vector; the projection renormalises it and counts calls.
struct Spinner {
    projections: usize,
}
impl System for Spinner {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        let w = [0.3, -0.5, 1.1];
        dx[0] = w[1] * x[2] - w[2] * x[1];
        dx[1] = w[2] * x[0] - w[0] * x[2];
        dx[2] = w[0] * x[1] - w[1] * x[0];
        Ok(())
    }
    fn project(&mut self, x: &mut [f64]) {
        self.projections += 1;
        let n = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        x.iter_mut().for_each(|v| *v /= n);
    }
}

#[test]
fn projection_called_after_each_accepted_step() {
    for method in Method::ALL {
        let mut opts = Options::new(method).with_tolerances(1e-4, 1e-6);
        if method == Method::Rk4 {
            opts = opts.with_fixed_step(0.5);
        }
        let mut sys = Spinner { projections: 0 };
        let stats = run(&mut sys, &opts, &[1.0, 0.0, 0.0], 0.0, 50.0).unwrap();
        // (The norm of the final state is not asserted: `project` itself normalises, so it
        // could not fail. The count is what proves the projection runs after every step.)
        assert_eq!(sys.projections, stats.steps_accepted, "{method}");
    }
}

#[test]
fn error_weights_exclude_components() {
    // Component 2 is wild but excluded: the step count matches a run without it.
    struct Weighted(bool);
    impl System for Weighted {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            dx[0] = -x[0];
            dx[1] = (50.0 * t).sin() * 100.0;
            Ok(())
        }
        fn error_weights(&self, w: &mut [f64]) {
            w[0] = 1.0;
            w[1] = if self.0 { 0.0 } else { 1.0 };
        }
    }
    let opts = Options::new(Method::Dp54);
    let excluded = run(&mut Weighted(true), &opts, &[1.0, 0.0], 0.0, 5.0).unwrap();
    let included = run(&mut Weighted(false), &opts, &[1.0, 0.0], 0.0, 5.0).unwrap();
    assert!(excluded.steps_accepted * 3 < included.steps_accepted);
}

/// `y' = 1 − y` from 0, whose solution `1 − e^{−t}` stays below 1, refusing any state above
/// 1 (a state outside the system's domain, as a flexible body's indefinite mass matrix is):
/// a long step's trial stages overshoot there.
struct Bounded {
    refused: usize,
}
impl System for Bounded {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        if x[0] > 1.0 {
            self.refused += 1;
            return Err(SystemError::new(format!("y = {} is beyond 1", x[0])));
        }
        dx[0] = 1.0 - x[0];
        Ok(())
    }
}

#[test]
fn adaptive_methods_retry_a_step_whose_trial_stage_the_system_refuses() {
    for method in [Method::Dp54, Method::Dop853, Method::Radau5] {
        let mut sys = Bounded { refused: 0 };
        let opts = Options::new(method)
            .with_tolerances(1e-9, 1e-12)
            .with_h0(6.0);
        let stats =
            run(&mut sys, &opts, &[0.0], 0.0, 12.0).unwrap_or_else(|e| panic!("{method:?}: {e}"));
        assert!(sys.refused > 0, "{method:?}: no stage was refused");
        assert!(stats.steps_rejected >= sys.refused.min(1), "{method:?}");
        let mut last = 0.0;
        integrate(
            &mut Bounded { refused: 0 },
            &opts,
            0.0,
            &[0.0],
            12.0,
            &Output::Times(vec![12.0]),
            |_, x| {
                last = x[0];
                std::ops::ControlFlow::Continue(())
            },
        )
        .unwrap();
        let exact = 1.0 - (-12.0f64).exp();
        assert!((last - exact).abs() < 1e-7, "{method:?}: {last} vs {exact}");
    }
    // A fixed step is never shortened: the system's error ends the run.
    let opts = Options::new(Method::Rk4).with_fixed_step(6.0);
    let err = run(&mut Bounded { refused: 0 }, &opts, &[0.0], 0.0, 12.0).unwrap_err();
    assert!(err.to_string().contains("is beyond 1"), "{err}");
}

/// A system that refuses every state past t = 1: after the retries the run ends with its own
/// error, not with the step size's underflow.
struct Cliff;
impl System for Cliff {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        if t > 1.0 {
            return Err(SystemError::new("past the cliff"));
        }
        dx[0] = 1.0;
        Ok(())
    }
}

#[test]
fn a_system_that_keeps_refusing_ends_the_run_with_its_own_error() {
    for method in [Method::Dp54, Method::Dop853, Method::Radau5] {
        let err = run(&mut Cliff, &Options::new(method), &[0.0], 0.0, 3.0).unwrap_err();
        assert!(
            matches!(err, IntegrateError::System { .. })
                && err.to_string().contains("past the cliff"),
            "{method:?}: {err}"
        );
    }
}

/// A stiff spring-damper with Coulomb friction, `x'' = -k x - c x' - f s`, whose sign `s`
/// flips at each reversal (an event that resets): the derivative jumps, the Jacobian does
/// not. `survives` is its answer to [`System::jacobian_survives_restart`].
struct Coulomb {
    survives: bool,
    sign: f64,
    asked: usize,
}
impl System for Coulomb {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = -1e4 * x[0] - 20.0 * x[1] - 5.0 * self.sign;
        Ok(())
    }
    fn n_events(&self) -> usize {
        1
    }
    fn events(&mut self, _t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        g[0] = self.sign * x[1];
        Ok(())
    }
    fn event_direction(&self, _k: usize) -> satsim_integrate::EventDirection {
        satsim_integrate::EventDirection::Falling
    }
    fn on_event(&mut self, _k: usize, _t: f64, _x: &mut [f64]) -> satsim_integrate::EventAction {
        self.sign = -self.sign;
        satsim_integrate::EventAction::Reset
    }
    fn jacobian_survives_restart(&mut self) -> bool {
        self.asked += 1;
        self.survives
    }
}

#[test]
fn radau5_keeps_its_jacobian_through_a_restart_the_system_says_it_survives() {
    let opts = Options::new(Method::Radau5).with_tolerances(1e-8, 1e-10);
    let mut runs = [true, false].map(|survives| {
        let mut sys = Coulomb {
            survives,
            sign: -1.0,
            asked: 0,
        };
        let stats = run(&mut sys, &opts, &[0.01, 0.0], 0.0, 0.25).unwrap();
        (stats, sys.asked)
    });
    let [(kept, asked_kept), (renewed, asked_renewed)] = &mut runs;
    // Several reversals, each a restart that asked (the start asks too, and is not kept).
    assert!(kept.events.len() >= 5, "{} events", kept.events.len());
    assert_eq!(kept.events.len(), renewed.events.len());
    assert_eq!(
        (*asked_kept, *asked_renewed),
        (kept.events.len() + 1, renewed.events.len() + 1)
    );
    // Renewed at every restart; kept, the linear system's one Jacobian serves throughout.
    assert_eq!(renewed.jacobian_evals, renewed.events.len() + 1);
    assert_eq!(kept.jacobian_evals, 1, "{kept:?}");
    // The same trajectory to the tolerance.
    for (a, b) in kept.x_final.iter().zip(&renewed.x_final) {
        assert!((a - b).abs() < 1e-8, "{a} against {b}");
    }
    for ((ta, _), (tb, _)) in kept.events.iter().zip(&renewed.events) {
        assert!((ta - tb).abs() < 1e-8, "event at {ta} against {tb}");
    }
}
