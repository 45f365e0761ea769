//! Pieces shared by the steppers: the evaluation context, error norm,
//! initial step selection and the explicit methods' step-size controller.

use crate::{
    error::{IntegrateError, NonFiniteEntry},
    options::Options,
    system::{System, SystemError},
};

/// Counters and settings shared by the driver and a stepper.
#[derive(Debug)]
pub(crate) struct Ctx {
    pub rtol: f64,
    pub atol: f64,
    pub h0: Option<f64>,
    /// The first step of a run that continues another ([`crate::integrate_on`]): the step
    /// that run proposed next, taken by the first [`Ctx::initial_step`] in place of its
    /// estimate (the restarts after it estimate theirs).
    pub h_resume: Option<f64>,
    pub h_max: f64,
    /// The run's end: no first step looks past it.
    pub t_end: f64,
    pub fixed: Option<f64>,
    pub max_steps: usize,
    /// Error-norm weights and their sum (the norm is a weighted RMS).
    pub weights: Vec<f64>,
    pub wsum: f64,
    /// The quadrature states ([`System::quadratures`]) and how many there are.
    pub quadrature: Vec<bool>,
    pub n_quadrature: usize,
    pub rhs_evals: usize,
    pub steps_accepted: usize,
    pub steps_rejected: usize,
    pub jacobian_evals: usize,
    pub jacobian_updates: usize,
    pub lu_decompositions: usize,
    /// Accepted steps that landed on a time stop or the run's end, or that `h_max` cut
    /// ([`crate::Stats::steps_capped`]), and the time they covered.
    pub steps_capped: usize,
    pub capped_span: f64,
    /// Trial stages the system refused ([`Ctx::stage_refused`]) since the steps last went
    /// past the earliest of them.
    pub stages_refused: u32,
    /// The time of the earliest of those refused stages.
    pub refused_at: f64,
    /// The state entry the step was last shortened for: the one whose error estimate was
    /// the largest against its tolerance where the error control last shortened it
    /// ([`Ctx::shortened`]; radau5's Newton increment too), or the first entry that was not
    /// finite in a refused stage; `None` where it was last cut for another reason. A step
    /// size underflow names it.
    pub rejected_by: Option<usize>,
}

/// How many trial stages in a row the system may refuse before its error ends the run: each
/// retry quarters the step, so 12 take it below 1e-7 of where it started.
pub(crate) const STAGE_RETRIES: u32 = 12;

/// The factor a step is cut by when the system refuses one of its trial stages.
pub(crate) const STAGE_RETRY_FACTOR: f64 = 0.25;

/// How many times [`Ctx::initial_step`] shortens its trial step tenfold when the system
/// refuses the trial state, before the system's error ends the run.
pub(crate) const TRIAL_RETRIES: u32 = 4;

impl Ctx {
    /// Counts an accepted step of `h` whose attempt was `capped` ([`Ctx::steps_capped`]).
    pub fn count_capped(&mut self, capped: bool, h: f64) {
        if capped {
            self.steps_capped += 1;
            self.capped_span += h;
        }
    }

    /// The context of a run of `sys` under `opts` that ends at `t_end`.
    pub fn new<S: System + ?Sized>(
        sys: &S,
        opts: &Options,
        t_end: f64,
    ) -> Result<Self, IntegrateError> {
        let mut weights = vec![1.0; sys.dim()];
        sys.error_weights(&mut weights);
        if weights.iter().any(|w| !(*w >= 0.0 && w.is_finite())) {
            return Err(IntegrateError::InvalidOptions(
                "error weights must be finite and >= 0".into(),
            ));
        }
        let wsum = weights.iter().sum();
        let mut quadrature = vec![false; sys.dim()];
        sys.quadratures(&mut quadrature);
        let n_quadrature = quadrature.iter().filter(|q| **q).count();
        Ok(Self {
            rtol: opts.rtol,
            atol: opts.atol,
            h0: opts.h0,
            h_resume: None,
            h_max: opts.h_max,
            t_end,
            fixed: opts.fixed_step,
            max_steps: opts.max_steps,
            weights,
            wsum,
            quadrature,
            n_quadrature,
            rhs_evals: 0,
            steps_accepted: 0,
            steps_rejected: 0,
            jacobian_evals: 0,
            jacobian_updates: 0,
            lu_decompositions: 0,
            steps_capped: 0,
            capped_span: 0.0,
            stages_refused: 0,
            refused_at: f64::INFINITY,
            rejected_by: None,
        })
    }

    /// Evaluates `f(t, x)`. A non-finite derivative of a finite state is the
    /// system's doing and is reported; a non-finite state comes from a trial
    /// step that blew up, which the step control rejects.
    #[inline]
    pub fn eval<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        t: f64,
        x: &[f64],
        dx: &mut [f64],
    ) -> Result<(), IntegrateError> {
        let result = sys.rhs(t, x, dx);
        self.evaluated(t, x, dx, result)
    }

    /// Counts an evaluation of `dx = f(t, x)` made elsewhere (a batch's, `lanes.rs`) and
    /// checks it as [`Ctx::eval`] does.
    #[inline]
    pub fn evaluated(
        &mut self,
        t: f64,
        x: &[f64],
        dx: &[f64],
        result: Result<(), SystemError>,
    ) -> Result<(), IntegrateError> {
        self.rhs_evals += 1;
        result.map_err(|source| IntegrateError::System { t, source })?;
        if !all_finite(dx) && all_finite(x) {
            return Err(IntegrateError::non_finite_derivative(t, dx));
        }
        Ok(())
    }

    /// An adaptive step's trial stage (a state the step reached towards, not an accepted one)
    /// that the system refused: a state outside its domain (a flexible body's mass matrix
    /// indefinite at a deformation the step overshot to, a derivative that is not finite).
    /// `Ok` when the step is to be retried shorter (by [`STAGE_RETRY_FACTOR`]; the caller
    /// counts the rejection); the error itself with a fixed step, after [`STAGE_RETRIES`]
    /// refusals in a row, or for an error that is not the system's.
    ///
    /// The refusals count until an accepted step goes past the earliest of them: a state the
    /// steps overshot to is left behind at once, while a system that refuses everything past
    /// some time (a singular configuration ahead) ends the run there with its own error.
    pub fn stage_refused(&mut self, e: IntegrateError) -> Result<(), IntegrateError> {
        let t = match &e {
            IntegrateError::System { t, .. } | IntegrateError::NonFinite { t, .. } => *t,
            _ => return Err(e),
        };
        if self.fixed.is_some() || self.stages_refused >= STAGE_RETRIES {
            return Err(e);
        }
        // A stage with a value that is not finite: its entry is what the step was cut for.
        self.rejected_by = match &e {
            IntegrateError::NonFinite {
                entry: Some(NonFiniteEntry::State(i) | NonFiniteEntry::Derivative(i)),
                ..
            } => Some(*i),
            _ => None,
        };
        self.stages_refused += 1;
        self.refused_at = self.refused_at.min(t);
        Ok(())
    }

    /// A step accepted up to `t`: the refusals it went past are forgotten.
    pub fn passed(&mut self, t: f64) {
        if t > self.refused_at {
            self.stages_refused = 0;
            self.refused_at = f64::INFINITY;
        }
    }

    /// A step the error control shortened (rejected, or accepted with a shorter step next)
    /// on the estimate `e` of the step from `x0` to `x1`: records the entry that weighed
    /// most in it ([`largest_error`], the scale of [`Ctx::norm`]). Only where the step
    /// shrinks, so that the steps that keep or grow it pay nothing.
    pub fn shortened(&mut self, e: &[f64], x0: &[f64], x1: &[f64]) {
        let (rtol, atol) = (self.rtol, self.atol);
        self.rejected_by = largest_error(&self.weights, e, |i| {
            atol + rtol * x0[i].abs().max(x1[i].abs())
        });
    }

    /// Fails when `h` is too small to change `t`, naming the entry the steps were last
    /// rejected for.
    #[inline]
    pub fn check_step_size(&self, t: f64, h: f64) -> Result<(), IntegrateError> {
        if h <= 8.0 * f64::EPSILON * t.abs() || h < f64::MIN_POSITIVE * 1e10 {
            Err(IntegrateError::step_size_underflow(t, h, self.rejected_by))
        } else {
            Ok(())
        }
    }

    /// Fails once the step budget is spent.
    #[inline]
    pub fn check_budget(&self, t: f64) -> Result<(), IntegrateError> {
        if self.steps_accepted + self.steps_rejected >= self.max_steps {
            Err(IntegrateError::MaxSteps {
                t,
                stepping: String::new(),
            })
        } else {
            Ok(())
        }
    }

    /// Weighted RMS of `e_i / (atol + rtol * max(|x0_i|, |x1_i|))`.
    /// Non-finite input yields `f64::INFINITY` (forcing a rejection).
    pub fn norm(&self, e: &[f64], x0: &[f64], x1: &[f64]) -> f64 {
        scaled_norm(e, x0, x1, &self.weights, self.wsum, self.rtol, self.atol)
    }

    /// Starts an explicit method of order `order` at `(t, x)`: evaluates `f(t, x)` into
    /// `k[0]` (the stage the next step begins with) and returns the first step, the fixed
    /// step if there is one, otherwise [`Ctx::initial_step`]'s (with `k[1]`, `k[2]` as scratch).
    pub fn start_explicit<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        order: usize,
        t: f64,
        x: &[f64],
        k: &mut [Vec<f64>],
    ) -> Result<f64, IntegrateError> {
        self.eval(sys, t, x, &mut k[0])?;
        match self.fixed {
            Some(h) => Ok(h),
            None => {
                let (f0, rest) = k.split_at_mut(1);
                let (a, b) = rest.split_at_mut(1);
                self.initial_step(sys, order, t, x, &f0[0], &mut a[0], &mut b[0])
            }
        }
    }

    /// Hairer's starting step (HINIT in DOPRI5) for a method of order `order`;
    /// `f0 = f(t, x)`, `x1` and `f1` are scratch. Respects `h0`, `h_max` and
    /// the distance to `t_end`: as HINIT's `hmax` (the span by default), the distance caps
    /// both the trial step, an Euler step whose right-hand side estimates the second
    /// derivative, and the result, so the trial never evaluates the system past the run.
    ///
    /// The trial is a heuristic, not part of the solution: where the system refuses the trial
    /// state (a flexible body's mass matrix indefinite at a deformation the Euler step
    /// overshot to, a derivative that is not finite), the trial is retried ten times shorter,
    /// [`TRIAL_RETRIES`] times, before the system's error ends the run.
    ///
    /// The result is always finite and > 0: where the scaled norms overflow (a derivative
    /// vast against its error scale) the estimate falls back to Hairer's `1e-6` for the
    /// trial and to the trial step for the result, and the error control takes it from
    /// there (a step it cannot shorten enough ends in a step size underflow at `t`).
    #[allow(clippy::too_many_arguments)]
    pub fn initial_step<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        order: usize,
        t: f64,
        x: &[f64],
        f0: &[f64],
        x1: &mut [f64],
        f1: &mut [f64],
    ) -> Result<f64, IntegrateError> {
        if let Some(h0) = self.h0 {
            return Ok(h0.min(self.h_max));
        }
        if let Some(h) = self.h_resume.take() {
            return Ok(h.min(self.h_max));
        }
        // At the end already (a restart there), the distance is no bound: the step is unused.
        let to_end = self.t_end - t;
        let h_max = if to_end > 0.0 {
            self.h_max.min(to_end)
        } else {
            self.h_max
        };
        let dnf = self.norm(f0, x, x);
        let dny = self.norm(x, x, x);
        let mut h = if dnf <= 1e-5 || dny <= 1e-5 {
            1e-6
        } else {
            0.01 * dny / dnf
        };
        if !(h > 0.0 && h.is_finite()) {
            h = 1e-6;
        }
        h = h.min(h_max);
        let mut retries = 0;
        loop {
            for i in 0..x.len() {
                x1[i] = x[i] + h * f0[i];
            }
            match self.eval(sys, t + h, x1, f1) {
                Ok(()) => break,
                Err(IntegrateError::System { .. } | IntegrateError::NonFinite { .. })
                    if retries < TRIAL_RETRIES =>
                {
                    retries += 1;
                    h *= 0.1;
                }
                Err(e) => return Err(e),
            }
        }
        for i in 0..x.len() {
            x1[i] = f1[i] - f0[i];
        }
        let der2 = self.norm(x1, x, x) / h;
        let der12 = der2.max(dnf);
        let h1 = if der12 <= 1e-15 {
            (h * 1e-3).max(1e-6)
        } else {
            (0.01 / der12).powf(1.0 / (order as f64 + 1.0))
        };
        let h_new = (100.0 * h).min(h1).min(h_max);
        Ok(if h_new > 0.0 && h_new.is_finite() {
            h_new
        } else {
            h
        })
    }
}

pub(crate) fn scaled_norm(
    e: &[f64],
    x0: &[f64],
    x1: &[f64],
    w: &[f64],
    wsum: f64,
    rtol: f64,
    atol: f64,
) -> f64 {
    if wsum == 0.0 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..e.len() {
        if w[i] != 0.0 {
            let sc = atol + rtol * x0[i].abs().max(x1[i].abs());
            let r = e[i] / sc;
            s += w[i] * r * r;
        }
    }
    let n = (s / wsum).sqrt();
    if n.is_finite() { n } else { f64::INFINITY }
}

/// Whether no entry is infinite or NaN (all exponent bits set). It runs after every
/// right-hand side: without an early exit, and with integer operations that baseline SSE2
/// has for 64-bit lanes (and, xor, subtract, or; not a 64-bit compare), the compiler
/// vectorises it, where `iter().all(is_finite)` cost 4 instructions per entry. For an
/// exponent field `e`, `(e ^ EXPONENT) - 1` wraps to a set top bit exactly when `e` is all
/// ones.
#[inline]
pub(crate) fn all_finite(x: &[f64]) -> bool {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    let any = x.iter().fold(0u64, |any, v| {
        any | ((v.to_bits() & EXPONENT) ^ EXPONENT).wrapping_sub(1)
    });
    any >> 63 == 0
}

/// The weighted entry of the error estimate `e` that weighs most in the error norm,
/// `wᵢ (eᵢ / scaleᵢ)²` (a non-finite one first): what a rejected step was rejected for.
/// `None` without a weighted entry.
pub(crate) fn largest_error(
    weights: &[f64],
    e: &[f64],
    scale: impl Fn(usize) -> f64,
) -> Option<usize> {
    let mut largest: Option<(usize, f64)> = None;
    for (i, (&w, &ei)) in weights.iter().zip(e).enumerate() {
        if w == 0.0 {
            continue;
        }
        let r = ei / scale(i);
        let size = w * r * r;
        let size = if size.is_nan() { f64::INFINITY } else { size };
        if largest.is_none_or(|(_, s)| size > s) {
            largest = Some((i, size));
        }
    }
    largest.map(|(i, _)| i)
}

/// Chooses the step toward `limit`: the whole remainder when it is within a
/// hair of `h` (or below), so we never leave a sliver step behind.
#[inline]
pub(crate) fn clamp_to_limit(t: f64, h: f64, limit: f64) -> (f64, bool) {
    let rest = limit - t;
    if rest <= h * (1.0 + 1e-9) {
        (rest, true)
    } else {
        (h, false)
    }
}

/// Hairer's PI step-size controller of DOPRI5/DOP853 (Lund stabilisation).
#[derive(Debug, Clone)]
pub(crate) struct PiController {
    expo1: f64,
    beta: f64,
    safe: f64,
    /// `1 / facmin` and `1 / facmax` in Hairer's notation (facc1, facc2).
    facc1: f64,
    facc2: f64,
    facold: f64,
    pub rejected_last: bool,
}

impl PiController {
    /// `order` is the exponent order q in `err^(1/q)` (5 for DOPRI5, 8 for DOP853).
    pub fn new(order: f64, beta: f64, facmin: f64, facmax: f64) -> Self {
        Self {
            expo1: 1.0 / order - beta * 0.75,
            beta,
            safe: 0.9,
            facc1: 1.0 / facmin,
            facc2: 1.0 / facmax,
            facold: 1e-4,
            rejected_last: false,
        }
    }

    pub fn reset(&mut self) {
        self.facold = 1e-4;
        self.rejected_last = false;
    }

    /// Returns `(accepted, h_new)` for a step `h` with scaled error `err`.
    pub fn control(&mut self, err: f64, h: f64) -> (bool, f64) {
        if !err.is_finite() {
            self.rejected_last = true;
            return (false, h / self.facc1);
        }
        let fac11 = err.powf(self.expo1);
        if err <= 1.0 {
            let fac = fac11 / self.facold.powf(self.beta);
            let fac = (fac / self.safe).clamp(self.facc2, self.facc1);
            let mut h_new = h / fac;
            if self.rejected_last {
                h_new = h_new.min(h);
            }
            self.facold = err.max(1e-4);
            self.rejected_last = false;
            (true, h_new)
        } else {
            self.rejected_last = true;
            (false, h / self.facc1.min(fac11 / self.safe))
        }
    }
}

/// Interface between the driver and one method. The stepper owns the current
/// state and the data for dense output over its last step `[t_old, t]`.
pub(crate) trait Stepper {
    /// (Re)starts at `(t, x)`: discards FSAL/history and picks a first step.
    fn restart<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        t: f64,
        x: &[f64],
    ) -> Result<(), IntegrateError>;

    /// Advances by one accepted step, ending at or before `limit` (ending
    /// exactly on `limit` when the step reaches it).
    fn step<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        limit: f64,
    ) -> Result<(), IntegrateError>;

    /// Makes [`Stepper::dense`] usable for the last step (some methods need
    /// extra stages, evaluated only when interpolation is actually needed).
    fn prepare_dense<S: System + ?Sized>(
        &mut self,
        _sys: &mut S,
        _ctx: &mut Ctx,
    ) -> Result<(), IntegrateError> {
        Ok(())
    }

    /// Interpolated state at `t` in `[t_old, t]` of the last step.
    fn dense(&self, t: f64, out: &mut [f64]);

    /// The step the method would take next (after its last accepted or rejected one).
    fn proposed_step(&self) -> f64;

    fn t(&self) -> f64;
    fn t_old(&self) -> f64;
    fn x(&self) -> &[f64];
    fn x_mut(&mut self) -> &mut [f64];

    /// The state was modified outside the stepper (projection): cached
    /// derivatives at the current point are stale.
    fn state_modified(&mut self);

    /// The method's own approximation of `f(t, x)` at the end of its last accepted step,
    /// where it holds one that it did not evaluate (for [`System::events_at_step_end`]).
    fn end_slope(&self) -> Option<&[f64]> {
        None
    }
}

/// `out = h * Σ_j coeffs[j] * ks[j]`; zero coefficients are skipped.
#[inline]
pub(crate) fn lincomb(out: &mut [f64], h: f64, coeffs: &[f64], ks: &[Vec<f64>]) {
    out.fill(0.0);
    for (a, k) in coeffs.iter().zip(ks) {
        if *a != 0.0 {
            for (o, ki) in out.iter_mut().zip(k) {
                *o += a * ki;
            }
        }
    }
    for o in out.iter_mut() {
        *o *= h;
    }
}

/// `out = x + h * Σ_j coeffs[j] * ks[j]` (explicit Runge-Kutta stage input
/// or solution update).
#[inline]
pub(crate) fn combine(out: &mut [f64], x: &[f64], h: f64, coeffs: &[f64], ks: &[Vec<f64>]) {
    lincomb(out, h, coeffs, ks);
    for (o, xi) in out.iter_mut().zip(x) {
        *o += xi;
    }
}

#[cfg(test)]
mod tests {
    use super::{Ctx, all_finite};
    use crate::{
        error::IntegrateError,
        options::{Method, Options},
        system::{System, SystemError},
    };

    /// `x0' = ω x1, x1' = -ω x0` (a circle of radius 1 from `[1, 0]`), refusing states
    /// outside `radius` and times past `until`, remembering the times it is evaluated at.
    struct Swing {
        omega: f64,
        radius: f64,
        until: f64,
        times: Vec<f64>,
    }

    impl Swing {
        fn new(omega: f64) -> Self {
            Self {
                omega,
                radius: f64::INFINITY,
                until: f64::INFINITY,
                times: Vec::new(),
            }
        }
    }

    impl System for Swing {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            self.times.push(t);
            if t > self.until || x[0].hypot(x[1]) > self.radius {
                return Err(SystemError::new("outside the domain"));
            }
            dx[0] = self.omega * x[1];
            dx[1] = -self.omega * x[0];
            Ok(())
        }
    }

    /// The first step of `sys` from `x = [1, 0]` at t = 0 under `opts` (not validated) for
    /// a run ending at `t_end`.
    fn first_step(sys: &mut Swing, opts: &Options, t_end: f64) -> Result<f64, IntegrateError> {
        let mut ctx = Ctx::new(&*sys, opts, t_end).unwrap();
        let x = [1.0, 0.0];
        let mut k = vec![vec![0.0; 2]; 3];
        ctx.start_explicit(sys, 5, 0.0, &x, &mut k)
    }

    #[test]
    fn the_first_step_is_finite_where_a_zero_state_has_no_error_scale() {
        // atol = 0 (refused by the options' validation) gives the state at zero an infinite
        // scaled norm; a vanishing atol overflows it. Neither may become h = inf or NaN,
        // nor a right-hand side evaluated at t = inf.
        for atol in [0.0, 1e-320] {
            let opts = Options {
                atol,
                ..Options::new(Method::Dp54)
            };
            let mut sys = Swing::new(1.0);
            let h = first_step(&mut sys, &opts, f64::INFINITY).unwrap();
            assert!(h > 0.0 && h.is_finite(), "atol {atol}: h = {h}");
            assert!(
                sys.times.iter().all(|t| t.is_finite()),
                "atol {atol}: {:?}",
                sys.times
            );
        }
    }

    #[test]
    fn the_first_step_never_looks_past_the_end_of_the_run() {
        // A slow motion at a pure absolute tolerance: the trial step 0.01 ‖x‖ / ‖f‖ is 10 s,
        // past the end of a 2 s run and into times the system refuses.
        let opts = Options::new(Method::Dp54).with_tolerances(0.0, 1e-10);
        for t_end in [2.0, 1e-3] {
            let mut sys = Swing {
                until: 3.0,
                ..Swing::new(1e-3)
            };
            let h = first_step(&mut sys, &opts, t_end).unwrap();
            assert!(h > 0.0 && h <= t_end, "t_end {t_end}: h = {h}");
            assert!(
                sys.times.iter().all(|t| *t <= t_end),
                "t_end {t_end}: {:?}",
                sys.times
            );
        }
        // h_max caps it too.
        let mut sys = Swing::new(1e-3);
        let h = first_step(&mut sys, &opts.clone().with_h_max(0.5), 2.0).unwrap();
        assert!(h <= 0.5 && sys.times.iter().all(|t| *t <= 0.5), "{h}");
    }

    #[test]
    fn a_refused_trial_state_is_retried_shorter_before_it_ends_the_run() {
        // The trial's Euler step leaves the circle by h² ω² / 2 of its radius: the 10 s
        // trial (5e-5 out) and the 1 s one (5e-7) are refused, the 0.1 s one (5e-9) is not.
        let opts = Options::new(Method::Dp54).with_tolerances(0.0, 1e-10);
        let mut sys = Swing {
            radius: 1.0 + 1e-7,
            ..Swing::new(1e-3)
        };
        let h = first_step(&mut sys, &opts, 1e6).unwrap();
        assert!(h > 0.0 && h.is_finite(), "{h}");
        assert_eq!(sys.times.len(), 4, "{:?}", sys.times);
        for (t, want) in sys.times[1..].iter().zip([10.0, 1.0, 0.1]) {
            assert!((t / want - 1.0).abs() < 1e-12, "{:?}", sys.times);
        }
        // A system that refuses every trial still ends the run with its own error, after
        // the retries.
        let mut sys = Swing {
            until: 0.0,
            ..Swing::new(1e-3)
        };
        let e = first_step(&mut sys, &opts, 1e6).unwrap_err();
        assert!(matches!(e, IntegrateError::System { .. }), "{e:?}");
        assert_eq!(sys.times.len(), 2 + super::TRIAL_RETRIES as usize);
    }

    #[test]
    fn all_finite_refuses_every_infinity_and_nan_and_nothing_else() {
        let finite = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            5e-324,
        ];
        assert!(all_finite(&finite));
        assert!(all_finite(&[]));
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN] {
            for at in 0..finite.len() {
                let mut x = finite;
                x[at] = bad;
                assert!(!all_finite(&x), "{bad} at {at}");
            }
        }
        // A NaN with a payload (any mantissa bits) is still a NaN.
        assert!(!all_finite(&[1.0, f64::from_bits(0x7ff0_0000_0000_0001)]));
    }
}
