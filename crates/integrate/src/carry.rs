//! An integration continued across calls ([`integrate_on`]): what one run leaves for the
//! next that starts where it ended.
//!
//! A simulation stepped from outside (flight software in the loop) integrates a piece at a
//! time, its inputs changed between pieces. Started afresh, each piece estimates a first
//! step (two right-hand sides, and a few steps to grow it back) and, under Radau IIA,
//! differences a new Jacobian (one right-hand side per state). Continued, the piece starts
//! with the step the last one proposed and Radau IIA keeps its Jacobian, as it keeps it
//! through an event's restart within a run ([`System::jacobian_survives_restart`]): the
//! simplified Newton iteration needs only an approximate Jacobian, and renews it where it
//! contracts too slowly. An input changed between pieces is a restart like an event's.

use std::borrow::Cow;
use std::ops::ControlFlow;

use crate::{
    common::Stepper,
    dop853::Dop853,
    dp54::Dp54,
    driver::{Run, Stats, checked, run_method},
    error::IntegrateError,
    options::{Method, Options, Output},
    radau5::Radau5,
    rk4::Rk4,
    system::System,
};

/// What an adaptive run leaves for a run that continues it from where it ended
/// ([`integrate_on`]): the step it proposed next and, for Radau IIA, its workspace with
/// its Jacobian and factorisations. Empty at first, and after a fixed-step run or a failed
/// one.
#[derive(Default)]
pub struct Carry {
    h: Option<f64>,
    radau: Option<(RadauKey, Radau5)>,
}

/// What a carried Radau IIA workspace was made for.
#[derive(Clone, Copy, PartialEq)]
struct RadauKey {
    n: usize,
    rtol: f64,
    atol: f64,
}

impl Carry {
    /// Nothing carried: the next run starts afresh.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets what was carried.
    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// The step the last run proposed next (`None` when nothing is carried).
    pub fn step(&self) -> Option<f64> {
        self.h
    }

    /// Whether a Radau IIA workspace (with its Jacobian) is carried.
    pub fn has_jacobian(&self) -> bool {
        self.radau.is_some()
    }
}

/// [`integrate`](crate::integrate) for a run that continues the one `carry` was last
/// given to, from where it ended (`t0` its end time, `x0` its end state, perhaps changed by
/// the caller as an event's handler may change it). An adaptive method starts with the step
/// that run proposed next, in place of its estimate of a first step (`options.h0`, when
/// set, still comes first); Radau IIA with that run's Jacobian and factorisations, where
/// the system says its Jacobian survived ([`System::jacobian_survives_restart`]) and the
/// dimension and tolerances are the same. A fixed-step run carries nothing: its steps are
/// on its grid ([`Options::grid_origin`]) whatever came before. What the run leaves is put
/// back in `carry` (cleared when it fails).
///
/// ```
/// use std::ops::ControlFlow;
/// use satsim_integrate::{Carry, Method, Options, Output, System, SystemError, integrate_on};
///
/// struct Decay;
/// impl System for Decay {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
///         dx[0] = -x[0];
///         Ok(())
///     }
///     // Nothing between the pieces changes the Jacobian.
///     fn jacobian_survives_restart(&mut self) -> bool { true }
/// }
/// let opts = Options { method: Method::Radau5, rtol: 1e-8, atol: 1e-10, ..Options::default() };
/// let (mut carry, mut x) = (Carry::new(), vec![1.0]);
/// for i in 0..10 {
///     let t = 0.1 * i as f64;
///     let stats = integrate_on(&mut Decay, &opts, t, &x, t + 0.1, &Output::Times(vec![]),
///                              |_, _| ControlFlow::Continue(()), &mut carry).unwrap();
///     // One Jacobian for the ten pieces.
///     assert_eq!(stats.jacobian_evals, usize::from(i == 0));
///     x = stats.x_final;
/// }
/// assert!((x[0] - (-1.0f64).exp()).abs() < 1e-8);
/// ```
#[allow(clippy::too_many_arguments)]
pub fn integrate_on<S, F>(
    system: &mut S,
    options: &Options,
    t0: f64,
    x0: &[f64],
    t_end: f64,
    output: &Output,
    observer: F,
    carry: &mut Carry,
) -> Result<Stats, IntegrateError>
where
    S: System + ?Sized,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
{
    let checked = checked(&*system, options, t0, x0, t_end, Cow::Borrowed(output));
    let (outputs, mut ctx) = match checked {
        Ok(c) => c,
        Err(e) => {
            carry.clear();
            return Err(e);
        }
    };
    let n = system.dim();
    if ctx.fixed.is_some() {
        carry.clear();
        return run_method(system, options, ctx, outputs, observer, t0, x0, t_end).0;
    }
    ctx.h_resume = carry.h.take();
    let (result, h) = match options.method {
        Method::Radau5 => {
            let key = RadauKey {
                n,
                rtol: options.rtol,
                atol: options.atol,
            };
            let st = match carry.radau.take() {
                Some((k, mut st)) if k == key => {
                    st.resume();
                    st
                }
                _ => Radau5::new(n, options.rtol, options.atol),
            };
            let (result, st) =
                Run::new(system, st, ctx, options, outputs, observer).go_keep(t0, x0, t_end);
            let h = st.proposed_step();
            if result.is_ok() {
                carry.radau = Some((key, st));
            }
            (result, h)
        }
        Method::Dp54 => proposed(
            Run::new(system, Dp54::new(n), ctx, options, outputs, observer).go_keep(t0, x0, t_end),
        ),
        Method::Dop853 => proposed(
            Run::new(system, Dop853::new(n), ctx, options, outputs, observer)
                .go_keep(t0, x0, t_end),
        ),
        // Not reached: `Options::validate` gives RK4 a fixed step (the return above).
        Method::Rk4 => proposed(
            Run::new(system, Rk4::new(n), ctx, options, outputs, observer).go_keep(t0, x0, t_end),
        ),
    };
    match &result {
        Ok(_) if h.is_finite() && h > 0.0 => carry.h = Some(h),
        _ => carry.clear(),
    }
    result
}

/// A finished run's result and the step its stepper proposed next.
fn proposed<St: Stepper>(
    (result, st): (Result<Stats, IntegrateError>, St),
) -> (Result<Stats, IntegrateError>, f64) {
    (result, st.proposed_step())
}
