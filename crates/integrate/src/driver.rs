//! The integration driver: steps a method, emits outputs at the requested
//! times, locates and handles events.

use std::ops::ControlFlow;

use crate::{
    common::{Ctx, Stepper, all_finite},
    dop853::Dop853,
    dp54::Dp54,
    error::IntegrateError,
    events::locate,
    options::{Method, Options, Output, OutputTimes},
    radau5::Radau5,
    rk4::Rk4,
    system::{EventAction, System},
};

/// Why an integration ended without error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// `t_end` was reached.
    Finished,
    /// [`System::on_event`] returned [`EventAction::Stop`] for event `k`.
    Event {
        /// Index of the event.
        k: usize,
    },
    /// The observer returned `ControlFlow::Break`.
    Observer,
}

/// Counters and final state of an integration.
#[derive(Debug, Clone, PartialEq)]
pub struct Stats {
    /// Right-hand side evaluations (including finite-difference Jacobians).
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps_accepted: usize,
    /// Rejected step attempts (error test or Newton failure).
    pub steps_rejected: usize,
    /// Jacobian evaluations (implicit methods).
    pub jacobian_evals: usize,
    /// LU factorisations (implicit methods).
    pub lu_decompositions: usize,
    /// Located events `(t, k)`, in order.
    pub events: Vec<(f64, usize)>,
    /// Time at which the run ended.
    pub t_final: f64,
    /// State at `t_final` (after any event reset or projection).
    pub x_final: Vec<f64>,
    /// Why the run ended.
    pub stop: StopReason,
}

/// Integrates `system` from `(t0, x0)` to `t_end`, calling `observer(t, x)`
/// at the times requested by `output`, in increasing order.
///
/// Adaptive methods produce outputs by dense output (they do not shorten
/// steps for them); fixed-step runs land steps exactly on output times.
/// Outputs up to an event are emitted before [`System::on_event`] is called.
/// The observer may return `ControlFlow::Break(())` to stop cleanly: the run
/// then returns `Ok` with [`StopReason::Observer`] and every output before
/// the break has been delivered.
///
/// ```
/// use std::ops::ControlFlow;
/// use satsim_integrate::{integrate, Method, Options, Output, System, SystemError};
///
/// struct Decay;
/// impl System for Decay {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
///         dx[0] = -x[0];
///         Ok(())
///     }
/// }
///
/// let opts = Options::new(Method::Dop853).with_tolerances(1e-10, 1e-12);
/// let mut rows = Vec::new();
/// let stats = integrate(&mut Decay, &opts, 0.0, &[1.0], 2.0, &Output::Interval(0.5), |t, x| {
///     rows.push((t, x[0]));
///     ControlFlow::Continue(())
/// })?;
/// assert_eq!(rows.len(), 5);
/// assert!((rows[4].1 - (-2.0f64).exp()).abs() < 1e-9);
/// assert_eq!(stats.t_final, 2.0);
/// # Ok::<(), satsim_integrate::IntegrateError>(())
/// ```
pub fn integrate<S, F>(
    system: &mut S,
    options: &Options,
    t0: f64,
    x0: &[f64],
    t_end: f64,
    output: &Output,
    observer: F,
) -> Result<Stats, IntegrateError>
where
    S: System + ?Sized,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
{
    options.validate()?;
    let n = system.dim();
    let invalid = |m: String| Err(IntegrateError::InvalidOptions(m));
    if x0.len() != n {
        return invalid(format!(
            "x0 has length {} but the system dimension is {n}",
            x0.len()
        ));
    }
    if !(t0.is_finite() && t_end.is_finite()) {
        return invalid(format!("t0 and t_end must be finite (got {t0}, {t_end})"));
    }
    if t_end < t0 {
        return invalid(format!("t_end ({t_end}) must not precede t0 ({t0})"));
    }
    if !all_finite(x0) {
        return Err(IntegrateError::NonFinite { t: t0 });
    }
    let outputs = OutputTimes::new(output, t0, t_end)?;
    let ctx = Ctx::new(system, options)?;
    match options.method {
        Method::Rk4 => {
            Run::new(system, Rk4::new(n), ctx, options, outputs, observer).go(t0, x0, t_end)
        }
        Method::Dp54 => {
            Run::new(system, Dp54::new(n), ctx, options, outputs, observer).go(t0, x0, t_end)
        }
        Method::Dop853 => {
            Run::new(system, Dop853::new(n), ctx, options, outputs, observer).go(t0, x0, t_end)
        }
        Method::Radau5 => {
            let st = Radau5::new(n, options.rtol, options.atol);
            Run::new(system, st, ctx, options, outputs, observer).go(t0, x0, t_end)
        }
    }
}

/// One integration run: the stepper plus the driver's own workspace.
struct Run<'a, S: ?Sized, St, F> {
    sys: &'a mut S,
    st: St,
    ctx: Ctx,
    outs: OutputTimes<'a>,
    observer: F,
    event_tol: f64,
    events: Vec<(f64, usize)>,
    /// Event function values at the left end of the unprocessed interval,
    /// at the step end, and at a trial point.
    g_left: Vec<f64>,
    g_right: Vec<f64>,
    g_mid: Vec<f64>,
    /// Interpolated state for outputs, root finding and events.
    buf: Vec<f64>,
    x_ev: Vec<f64>,
}

/// What the run does after handling events in a step.
enum Next {
    Proceed,
    Restarted,
    Done(Stats),
}

impl<'a, S, St, F> Run<'a, S, St, F>
where
    S: System + ?Sized,
    St: Stepper,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
{
    fn new(
        sys: &'a mut S,
        st: St,
        ctx: Ctx,
        opts: &Options,
        outs: OutputTimes<'a>,
        observer: F,
    ) -> Self {
        let (n, ne) = (sys.dim(), sys.n_events());
        Self {
            sys,
            st,
            ctx,
            outs,
            observer,
            event_tol: opts.event_tol,
            events: Vec::new(),
            g_left: vec![0.0; ne],
            g_right: vec![0.0; ne],
            g_mid: vec![0.0; ne],
            buf: vec![0.0; n],
            x_ev: vec![0.0; n],
        }
    }

    fn finish(&mut self, t: f64, x: &[f64], stop: StopReason) -> Stats {
        Stats {
            rhs_evals: self.ctx.rhs_evals,
            steps_accepted: self.ctx.steps_accepted,
            steps_rejected: self.ctx.steps_rejected,
            jacobian_evals: self.ctx.jacobian_evals,
            lu_decompositions: self.ctx.lu_decompositions,
            events: std::mem::take(&mut self.events),
            t_final: t,
            x_final: x.to_vec(),
            stop,
        }
    }

    fn go(mut self, t0: f64, x0: &[f64], t_end: f64) -> Result<Stats, IntegrateError> {
        let fixed = self.ctx.fixed.is_some();
        let has_events = !self.g_left.is_empty();
        self.st.restart(self.sys, &mut self.ctx, t0, x0)?;
        while let Some(to) = self.outs.peek().filter(|to| *to <= t0) {
            if (self.observer)(to, x0).is_break() {
                return Ok(self.finish(to, x0, StopReason::Observer));
            }
            self.outs.advance();
        }
        if self.outs.every_step() && (self.observer)(t0, x0).is_break() {
            return Ok(self.finish(t0, x0, StopReason::Observer));
        }
        if has_events {
            self.sys.events(t0, x0, &mut self.g_left);
        }
        while self.st.t() < t_end {
            let limit = match self.outs.peek() {
                Some(to) if fixed => to.min(t_end),
                _ => t_end,
            };
            self.st.step(self.sys, &mut self.ctx, limit)?;

            // Projection; the copy tells whether cached derivatives went stale.
            self.buf.copy_from_slice(self.st.x());
            self.sys.project(self.st.x_mut());
            if self.buf != self.st.x() {
                self.st.state_modified();
            }

            if has_events {
                match self.handle_events()? {
                    Next::Proceed => {}
                    Next::Restarted => continue,
                    Next::Done(stats) => return Ok(stats),
                }
            }
            let t = self.st.t();
            if let Some(stats) = self.emit_until(t)? {
                return Ok(stats);
            }
            if self.outs.every_step() && (self.observer)(t, self.st.x()).is_break() {
                let x = self.st.x().to_vec();
                return Ok(self.finish(t, &x, StopReason::Observer));
            }
            if has_events {
                std::mem::swap(&mut self.g_left, &mut self.g_right);
            }
        }
        let (t, x) = (self.st.t(), self.st.x().to_vec());
        Ok(self.finish(t, &x, StopReason::Finished))
    }

    /// State at `t` within the last step into `self.buf`.
    fn interpolate(&mut self, t: f64) -> Result<(), IntegrateError> {
        if t == self.st.t() {
            self.buf.copy_from_slice(self.st.x());
        } else {
            self.st.prepare_dense(self.sys, &mut self.ctx)?;
            self.st.dense(t, &mut self.buf);
        }
        Ok(())
    }

    /// Emits pending outputs at times `<= bound` (within the last step).
    fn emit_until(&mut self, bound: f64) -> Result<Option<Stats>, IntegrateError> {
        while let Some(to) = self.outs.peek().filter(|to| *to <= bound) {
            self.interpolate(to)?;
            if (self.observer)(to, &self.buf).is_break() {
                let x = self.buf.clone();
                return Ok(Some(self.finish(to, &x, StopReason::Observer)));
            }
            self.outs.advance();
        }
        Ok(None)
    }

    /// Finds and handles event crossings in the last step, in time order.
    fn handle_events(&mut self) -> Result<Next, IntegrateError> {
        let (mut t_left, t_right) = (self.st.t_old(), self.st.t());
        self.sys.events(t_right, self.st.x(), &mut self.g_right);
        let ne = self.g_left.len();
        loop {
            let crossing = |k: usize, sys: &S, gl: &[f64], gr: &[f64]| {
                sys.event_direction(k).crosses(gl[k], gr[k])
            };
            if !(0..ne).any(|k| crossing(k, self.sys, &self.g_left, &self.g_right)) {
                return Ok(Next::Proceed);
            }
            self.st.prepare_dense(self.sys, &mut self.ctx)?;
            // Earliest crossing among the candidates.
            let mut first: Option<(f64, usize)> = None;
            for k in 0..ne {
                if !crossing(k, self.sys, &self.g_left, &self.g_right) {
                    continue;
                }
                let dir = self.sys.event_direction(k);
                let (sys, st, buf, g) = (&mut *self.sys, &self.st, &mut self.buf, &mut self.g_mid);
                let tk = locate(
                    dir,
                    t_left,
                    self.g_left[k],
                    t_right,
                    self.g_right[k],
                    self.event_tol,
                    |t| {
                        if t == st.t() {
                            buf.copy_from_slice(st.x());
                        } else {
                            st.dense(t, buf);
                        }
                        sys.events(t, buf, g);
                        g[k]
                    },
                );
                if first.is_none_or(|(tf, _)| tk < tf) {
                    first = Some((tk, k));
                }
            }
            let (t_ev, k_first) = first.expect("a crossing was detected");
            self.interpolate(t_ev)?;
            self.x_ev.copy_from_slice(&self.buf);
            self.sys.events(t_ev, &self.x_ev, &mut self.g_mid);
            if let Some(stats) = self.emit_until(t_ev)? {
                return Ok(Next::Done(stats));
            }
            // Every event that has crossed by t_ev fires now, in index order
            // (they coincide to within the location tolerance).
            for k in 0..ne {
                if !(k == k_first || crossing(k, self.sys, &self.g_left, &self.g_mid)) {
                    continue;
                }
                self.events.push((t_ev, k));
                match self.sys.on_event(k, t_ev, &mut self.x_ev) {
                    EventAction::Continue => {
                        // Modifications are not allowed to stick without a reset.
                        self.x_ev.copy_from_slice(&self.buf);
                    }
                    EventAction::Reset => {
                        if !all_finite(&self.x_ev) {
                            return Err(IntegrateError::NonFinite { t: t_ev });
                        }
                        self.st.restart(self.sys, &mut self.ctx, t_ev, &self.x_ev)?;
                        if self.outs.every_step() && (self.observer)(t_ev, &self.x_ev).is_break() {
                            let x = self.x_ev.clone();
                            return Ok(Next::Done(self.finish(t_ev, &x, StopReason::Observer)));
                        }
                        self.sys.events(t_ev, &self.x_ev, &mut self.g_left);
                        return Ok(Next::Restarted);
                    }
                    EventAction::Stop => {
                        let x = self.x_ev.clone();
                        if self.outs.every_step() {
                            // The stop point is the last "step" of the run.
                            let _ = (self.observer)(t_ev, &x);
                        }
                        return Ok(Next::Done(self.finish(t_ev, &x, StopReason::Event { k })));
                    }
                }
            }
            t_left = t_ev;
            std::mem::swap(&mut self.g_left, &mut self.g_mid);
        }
    }
}
