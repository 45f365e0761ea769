//! An integration continued across calls (`integrate_on`): pieces that carry the proposed
//! step and Radau IIA's Jacobian cost less than pieces started afresh, give the one run's
//! solution within the tolerance, and start afresh where the system, the tolerances or a
//! failure say so.

use std::ops::ControlFlow;

use satsim_integrate::{
    Carry, IntegrateError, Method, Options, Output, Stats, System, SystemError, integrate,
    integrate_on,
};

/// A stiff oscillator and a slow forced mode: `x0'' = −k x0 − c x0'` (k = 1e4, c = 200: a
/// critically damped, stiff pair) driven by `x2`, `x2' = −0.1 x2 + sin t`. Its Jacobian is
/// constant, so a kept one is exact; `survives` says whether it may be kept.
struct Stiff {
    survives: bool,
    fail_after: Option<f64>,
}

impl System for Stiff {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        if self.fail_after.is_some_and(|f| t > f) {
            return Err(SystemError::new("refused"));
        }
        dx[0] = x[1];
        dx[1] = -1e4 * (x[0] - x[2]) - 200.0 * x[1];
        dx[2] = -0.1 * x[2] + t.sin();
        Ok(())
    }
    fn jacobian_survives_restart(&mut self) -> bool {
        self.survives
    }
}

fn stiff() -> Stiff {
    Stiff {
        survives: true,
        fail_after: None,
    }
}

fn options(method: Method) -> Options {
    Options {
        method,
        rtol: 1e-8,
        atol: 1e-10,
        ..Options::default()
    }
}

const X0: [f64; 3] = [0.0, 0.0, 0.0];

/// Totals over pieces of `dt` from 0 to `t_end`, continued (`carry`) or each afresh.
#[derive(Default, Debug)]
struct Totals {
    rhs: usize,
    steps: usize,
    jacobians: usize,
    x: Vec<f64>,
}

/// Totals over pieces of `dt` from 0 to `t_end`, each integrated by `piece(t, x, to)`.
fn in_pieces(dt: f64, t_end: f64, mut piece: impl FnMut(f64, &[f64], f64) -> Stats) -> Totals {
    let mut totals = Totals {
        x: X0.to_vec(),
        ..Totals::default()
    };
    let (mut t, n) = (0.0, (t_end / dt).round() as usize);
    for i in 0..n {
        let to = if i + 1 == n { t_end } else { t + dt };
        let stats = piece(t, &totals.x, to);
        totals.rhs += stats.rhs_evals;
        totals.steps += stats.steps_accepted;
        totals.jacobians += stats.jacobian_evals;
        totals.x = stats.x_final;
        t = to;
    }
    totals
}

fn none(_: f64, _: &[f64]) -> ControlFlow<()> {
    ControlFlow::Continue(())
}

/// The pieces, each going on from the last (`integrate_on`, with `carry` or its own).
fn pieces(
    sys: &mut Stiff,
    opts: &Options,
    dt: f64,
    t_end: f64,
    carry: Option<&mut Carry>,
) -> Totals {
    let mut own = Carry::new();
    let carry = carry.unwrap_or(&mut own);
    let times = Output::Times(vec![]);
    in_pieces(dt, t_end, |t, x, to| {
        integrate_on(&mut *sys, opts, t, x, to, &times, none, carry).unwrap()
    })
}

/// The same pieces, each started afresh (`integrate`).
fn afresh(sys: &mut Stiff, opts: &Options, dt: f64, t_end: f64) -> Totals {
    let times = Output::Times(vec![]);
    in_pieces(dt, t_end, |t, x, to| {
        integrate(&mut *sys, opts, t, x, to, &times, none).unwrap()
    })
}

/// Each end state within `1e-6` of the one run's.
fn near_run(ends: [&Totals; 2], run: &Stats) {
    for t in ends {
        let d = max_diff(&t.x, &run.x_final);
        assert!(d < 1e-6, "{t:?} against {:?}", run.x_final);
    }
}

fn one_run(sys: &mut Stiff, opts: &Options, t_end: f64) -> Stats {
    integrate(sys, opts, 0.0, &X0, t_end, &Output::Times(vec![]), none).unwrap()
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Radau IIA in 100 pieces of 0.1 s: one Jacobian where pieces afresh take one each, fewer
/// right-hand sides, and the one run's end state within the tolerance either way.
#[test]
fn radau5_pieces_carry_one_jacobian() {
    let opts = options(Method::Radau5);
    let run = one_run(&mut stiff(), &opts, 10.0);
    let mut carry = Carry::new();
    let on = pieces(&mut stiff(), &opts, 0.1, 10.0, Some(&mut carry));
    let fresh = afresh(&mut stiff(), &opts, 0.1, 10.0);
    assert_eq!(on.jacobians, 1, "{on:?}");
    assert_eq!(fresh.jacobians, 100, "{fresh:?}");
    assert!(carry.has_jacobian() && carry.step().is_some());
    // Each piece ends a step where the one run would not: at most one step more a piece.
    assert!(
        on.steps <= run.steps_accepted + 100,
        "{on:?} against {run:?}"
    );
    // The 99 Jacobians not taken (three columns each) and the first steps not estimated;
    // within twice the one run's (1 065 against 1 655 and 626).
    assert!(on.rhs + 99 * 3 < fresh.rhs, "{on:?} against {fresh:?}");
    assert!(on.rhs < 2 * run.rhs_evals, "{on:?} against {run:?}");
    near_run([&on, &fresh], &run);
}

/// Van der Pol's oscillator, `x0'' = μ (1 − x0²) x0' − x0` with μ = 10: nonlinear, so where
/// Newton starts decides how many iterations it takes.
struct VanDerPol;

impl System for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        dx[0] = x[1];
        dx[1] = 10.0 * (1.0 - x[0] * x[0]) * x[1] - x[0];
        Ok(())
    }
    fn jacobian_survives_restart(&mut self) -> bool {
        true
    }
}

/// A piece that starts where the last one ended, its state untouched, starts Newton from the
/// last step's collocation polynomial, as a step within a run does; one whose state the
/// caller changed (here by an ulp) starts it from zero, as after an event. Van der Pol's
/// oscillator in 200 pieces of 0.05 s: the untouched ones take fewer right-hand sides (3 933
/// against 5 092, the one run 2 786), and both end within the tolerance of the one run.
#[test]
fn radau5_pieces_untouched_go_on_from_the_last_steps_polynomial() {
    let (opts, times, x0) = (options(Method::Radau5), Output::Times(vec![]), [2.0, 0.0]);
    let run = integrate(&mut VanDerPol, &opts, 0.0, &x0, 10.0, &times, none).unwrap();
    let chain = |nudge: bool| {
        let (mut carry, mut x, mut rhs) = (Carry::new(), x0.to_vec(), 0);
        for i in 0..200 {
            let t = 0.05 * i as f64;
            if nudge {
                x[1] = x[1].next_up();
            }
            let to = if i == 199 { 10.0 } else { t + 0.05 };
            let s = integrate_on(&mut VanDerPol, &opts, t, &x, to, &times, none, &mut carry);
            let s = s.unwrap();
            rhs += s.rhs_evals;
            x = s.x_final;
        }
        (rhs, x)
    };
    let (on, nudged) = (chain(false), chain(true));
    assert!(on.0 < nudged.0, "{on:?} against {nudged:?}");
    for (_, x) in [&on, &nudged] {
        assert!(max_diff(x, &run.x_final) < 1e-6, "{x:?} against {run:?}");
    }
}

/// Where the system says its Jacobian did not survive, each piece takes a new one; where
/// the tolerances change, the carried workspace is not used.
#[test]
fn radau5_pieces_take_a_new_jacobian_where_the_system_or_the_tolerances_say_so() {
    let opts = options(Method::Radau5);
    let mut sys = Stiff {
        survives: false,
        fail_after: None,
    };
    let on = pieces(&mut sys, &opts, 0.1, 1.0, None);
    assert_eq!(on.jacobians, 10, "{on:?}");

    let mut carry = Carry::new();
    pieces(&mut stiff(), &opts, 0.1, 1.0, Some(&mut carry));
    assert!(carry.has_jacobian());
    let looser = Options {
        rtol: 1e-6,
        ..opts.clone()
    };
    let x = [0.0; 3];
    let s = integrate_on(
        &mut stiff(),
        &looser,
        1.0,
        &x,
        1.1,
        &Output::Times(vec![]),
        none,
        &mut carry,
    )
    .unwrap();
    assert_eq!(s.jacobian_evals, 1);
}

/// DP5(4) in pieces carries its proposed step: no first-step estimate per piece (two
/// right-hand sides and the short steps that follow it), so fewer right-hand sides than
/// pieces afresh, and the solution within the tolerance.
#[test]
fn dp54_pieces_carry_the_step_they_proposed() {
    let opts = options(Method::Dp54);
    let run = one_run(&mut stiff(), &opts, 10.0);
    let on = pieces(&mut stiff(), &opts, 0.5, 10.0, None);
    let fresh = afresh(&mut stiff(), &opts, 0.5, 10.0);
    assert!(on.rhs < fresh.rhs, "{on:?} against {fresh:?}");
    near_run([&on, &fresh], &run);
}

/// A failed piece leaves nothing to carry; a fixed-step run carries nothing.
#[test]
fn a_failed_or_fixed_step_piece_carries_nothing() {
    let opts = options(Method::Radau5);
    let mut carry = Carry::new();
    pieces(&mut stiff(), &opts, 0.1, 1.0, Some(&mut carry));
    assert!(carry.step().is_some());
    let mut failing = Stiff {
        survives: true,
        fail_after: Some(1.05),
    };
    let r = integrate_on(
        &mut failing,
        &opts,
        1.0,
        &X0,
        1.2,
        &Output::Times(vec![]),
        none,
        &mut carry,
    );
    assert!(matches!(r, Err(IntegrateError::System { .. })), "{r:?}");
    assert!(carry.step().is_none() && !carry.has_jacobian());

    pieces(&mut stiff(), &opts, 0.1, 1.0, Some(&mut carry));
    let rk4 = Options {
        method: Method::Rk4,
        fixed_step: Some(1e-3),
        ..Options::default()
    };
    integrate_on(
        &mut stiff(),
        &rk4,
        1.0,
        &X0,
        1.1,
        &Output::Times(vec![]),
        none,
        &mut carry,
    )
    .unwrap();
    assert!(carry.step().is_none() && !carry.has_jacobian());
}
