//! The integration driver: steps a method, emits outputs at the requested
//! times, locates and handles events.

use std::borrow::Cow;
use std::ops::ControlFlow;

use crate::{
    common::{Ctx, Stepper, all_finite},
    dop853::Dop853,
    dp54::Dp54,
    error::{IntegrateError, Num},
    events::locate,
    grid::DecimalGrid,
    options::{Method, Options, Output, OutputTimes},
    radau5::Radau5,
    rk4::Rk4,
    system::{EventAction, System, SystemError, stop_due},
};

/// Why an integration ended without error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// `t_end` was reached.
    Finished,
    /// [`System::on_events`] returned [`EventAction::Stop`] for a group of
    /// simultaneous events whose first (lowest index) is `k`.
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
    /// Jacobians the system brought to a new state in place of an evaluation
    /// ([`System::update_jacobian`]).
    pub jacobian_updates: usize,
    /// LU factorisations (implicit methods).
    pub lu_decompositions: usize,
    /// Accepted steps of an adaptive method that landed on a time stop
    /// ([`System::next_stop`]) or the run's end, or were cut short of the error control's
    /// proposal to keep within `h_max`. What held them was not the error control, nor a
    /// stiff motion.
    pub steps_capped: usize,
    /// The time those steps covered (s).
    pub capped_span: f64,
    /// Located events `(t, k)`, in order.
    pub events: Vec<(f64, usize)>,
    /// Time at which the run ended.
    pub t_final: f64,
    /// State at `t_final` (after any event reset or projection).
    pub x_final: Vec<f64>,
    /// Why the run ended.
    pub stop: StopReason,
}

/// The steps of an adaptive run, or of runs one after the other, over `span` seconds: what
/// tells whether a stiff motion held them ([`Stats::steps_capped`]). `Default` is none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Steps {
    /// The time the steps covered (s).
    pub span: f64,
    /// Accepted steps.
    pub accepted: usize,
    /// Those that landed on a time stop or the run's end, or that `h_max` cut.
    pub capped: usize,
    /// The time the capped steps covered (s).
    pub capped_span: f64,
}

impl Steps {
    /// The steps of a run that started at `t0` and finished with `stats`.
    pub fn of(stats: &Stats, t0: f64) -> Self {
        Self {
            span: stats.t_final - t0,
            accepted: stats.steps_accepted,
            capped: stats.steps_capped,
            capped_span: stats.capped_span,
        }
    }

    /// Adds the steps of a run that followed.
    pub fn add(&mut self, more: Steps) {
        self.span += more.span;
        self.accepted += more.accepted;
        self.capped += more.capped;
        self.capped_span += more.capped_span;
    }

    /// The mean of the steps the error control (or a stiff motion) set, the capped ones
    /// left out; `None` where every step was capped.
    pub fn mean_free(&self) -> Option<f64> {
        let free = self.accepted.checked_sub(self.capped).filter(|&n| n > 0)?;
        Some((self.span - self.capped_span) / free as f64)
    }

    /// The mean time between the capped steps: about how often time stops came (or
    /// `h_max`'s step); infinite where none was capped.
    pub fn mean_capped_spacing(&self) -> f64 {
        if self.capped == 0 {
            f64::INFINITY
        } else {
            self.span / self.capped as f64
        }
    }
}

/// Integrates `system` from `(t0, x0)` to `t_end`, calling `observer(t, x)`
/// at the times requested by `output`, in increasing order.
///
/// Adaptive methods produce outputs by dense output (they do not shorten
/// steps for them); fixed-step runs land steps exactly on output times.
/// Outputs up to an event are emitted before [`System::on_events`] is called.
/// A fixed-step run steps on the grid `origin + n · step` ([`Options::grid_origin`]).
/// Every method lands exactly on the system's time stops ([`System::next_stop`]) and
/// calls [`System::on_stop`] there, after the outputs up to the stop.
/// Every event whose function changes sign within a step is handled, in time
/// order; events that coincide to within `Options::event_tol` are handled
/// together at one instant (see [`System::on_events`]).
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
    let (outputs, ctx) = checked(&*system, options, t0, x0, t_end, Cow::Borrowed(output))?;
    run_method(system, options, ctx, outputs, observer, t0, x0, t_end).0
}

/// A checked run by `options.method`, from start to end; the system and the observer back.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_method<S: System, F: FnMut(f64, &[f64]) -> ControlFlow<()>>(
    system: S,
    options: &Options,
    ctx: Ctx,
    outputs: OutputTimes<'_>,
    observer: F,
    t0: f64,
    x0: &[f64],
    t_end: f64,
) -> (Result<Stats, IntegrateError>, S, F) {
    let n = system.dim();
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

/// The checks every run starts with: the options, `x0`'s length and finiteness, the time
/// span, the output times; then the run's counters.
pub(crate) fn checked<'o, S: System + ?Sized>(
    system: &S,
    options: &Options,
    t0: f64,
    x0: &[f64],
    t_end: f64,
    output: Cow<'o, Output>,
) -> Result<(OutputTimes<'o>, Ctx), IntegrateError> {
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
    if let Some(h) = options.fixed_step {
        // A fixed step that cannot cover the span within the step budget fails for certain:
        // refused now, not after `max_steps` steps.
        let steps = (t_end - t0) / h;
        // The slack: the step suggested, `span / max_steps`, may round to a hair more.
        if steps > options.max_steps as f64 * (1.0 + 1e-9) {
            return invalid(format!(
                "fixed_step = {} over the span {} (t0 = {}, t_end = {}) takes {} steps, more \
                 than max_steps = {}: the step must be at least {}, or max_steps larger",
                Num(h),
                Num(t_end - t0),
                Num(t0),
                Num(t_end),
                count(steps),
                options.max_steps,
                Num((t_end - t0) / options.max_steps as f64),
            ));
        }
    }
    if !all_finite(x0) {
        return Err(IntegrateError::non_finite_state(t0, x0));
    }
    let outputs = OutputTimes::new(output, t0, t_end)?;
    let ctx = Ctx::new(system, options, t_end)?;
    Ok((outputs, ctx))
}

/// One integration run: the stepper plus the driver's own workspace.
pub(crate) struct Run<'a, S, St, F> {
    sys: S,
    st: St,
    ctx: Ctx,
    outs: OutputTimes<'a>,
    observer: F,
    event_tol: f64,
    /// The fixed-step grid's origin (`None`: the run's start).
    grid_origin: Option<f64>,
    /// The fixed-step grid, set by [`Run::begin`].
    grid: Option<DecimalGrid>,
    events: Vec<(f64, usize)>,
    /// Event function values at the left end of the unprocessed interval,
    /// at the step end, and at a trial point.
    g_left: Vec<f64>,
    g_right: Vec<f64>,
    g_mid: Vec<f64>,
    /// Event function values after a reset at an event (chain detection).
    g_post: Vec<f64>,
    /// Located crossing time of each event in the unprocessed interval (NaN: none).
    t_loc: Vec<f64>,
    /// The events handled together at one instant, and the next such group.
    group: Vec<usize>,
    next_group: Vec<usize>,
    /// Interpolated state for outputs, root finding and events.
    buf: Vec<f64>,
    x_ev: Vec<f64>,
}

/// What comes next in a run, before a step.
pub(crate) enum Plan {
    /// A step ending at this time at the latest.
    Step(f64),
    /// The run is over.
    Done(Stats),
}

/// What the run does after handling events in a step.
enum Next {
    Proceed,
    Restarted,
    Done(Stats),
}

/// Where in a step (as fractions of it) the dense output is probed for an event that left
/// zero right after being handled and came back before the step's end. A return shorter
/// than the first probe's interval is missed; such a rebound moves the state by less than
/// `1e-3` of a step's motion.
const RETURN_PROBES: [f64; 5] = [1e-3, 0.125, 0.25, 0.5, 0.75];

impl<'a, S, St, F> Run<'a, S, St, F>
where
    S: System,
    St: Stepper,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
{
    pub(crate) fn new(
        sys: S,
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
            grid_origin: opts.grid_origin,
            grid: None,
            // Room for the events of most runs: handling one then allocates nothing.
            events: Vec::with_capacity(if ne > 0 { 64 } else { 0 }),
            g_left: vec![0.0; ne],
            g_right: vec![0.0; ne],
            g_mid: vec![0.0; ne],
            g_post: vec![0.0; ne],
            t_loc: vec![f64::NAN; ne],
            group: Vec::with_capacity(ne),
            next_group: Vec::with_capacity(ne),
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
            jacobian_updates: self.ctx.jacobian_updates,
            lu_decompositions: self.ctx.lu_decompositions,
            steps_capped: self.ctx.steps_capped,
            capped_span: self.ctx.capped_span,
            events: std::mem::take(&mut self.events),
            t_final: t,
            x_final: x.to_vec(),
            stop,
        }
    }

    fn go(mut self, t0: f64, x0: &[f64], t_end: f64) -> (Result<Stats, IntegrateError>, S, F) {
        let result = self.go_on(t0, x0, t_end);
        (result, self.sys, self.observer)
    }

    /// As `go`, giving back the stepper (its workspace, for a run that continues this one).
    pub(crate) fn go_keep(
        mut self,
        t0: f64,
        x0: &[f64],
        t_end: f64,
    ) -> (Result<Stats, IntegrateError>, St) {
        let result = self.go_on(t0, x0, t_end);
        (result, self.st)
    }

    fn go_on(&mut self, t0: f64, x0: &[f64], t_end: f64) -> Result<Stats, IntegrateError> {
        if let Some(stats) = self.begin(t0, x0)? {
            return Ok(stats);
        }
        loop {
            match self.plan(t_end)? {
                Plan::Done(stats) => return Ok(stats),
                Plan::Step(limit) => self.st.step(&mut self.sys, &mut self.ctx, limit)?,
            }
            if let Some(stats) = self.after_step()? {
                return Ok(stats);
            }
        }
    }

    /// The start: the stepper at `(t0, x0)`, the outputs due there, the event functions'
    /// first values. `Some` when the observer stopped the run already.
    pub(crate) fn begin(&mut self, t0: f64, x0: &[f64]) -> Result<Option<Stats>, IntegrateError> {
        self.grid = self
            .ctx
            .fixed
            .map(|h| DecimalGrid::new(self.grid_origin.unwrap_or(t0), h));
        self.st.restart(&mut self.sys, &mut self.ctx, t0, x0)?;
        while let Some(to) = self.outs.peek().filter(|to| *to <= t0) {
            if (self.observer)(to, x0).is_break() {
                return Ok(Some(self.finish(to, x0, StopReason::Observer)));
            }
            self.outs.advance();
        }
        if self.outs.every_step() && (self.observer)(t0, x0).is_break() {
            return Ok(Some(self.finish(t0, x0, StopReason::Observer)));
        }
        if !self.g_left.is_empty() {
            Self::eval_events(&mut self.sys, t0, x0, &mut self.g_left)?;
        }
        Ok(None)
    }

    /// Before a step: handles the time stops due now, then says where the next step may
    /// end at the latest (the next output time of a fixed-step run, time stop or grid
    /// point, and `t_end`), or that the run is over.
    pub(crate) fn plan(&mut self, t_end: f64) -> Result<Plan, IntegrateError> {
        let has_events = !self.g_left.is_empty();
        loop {
            let stop = self.sys.next_stop();
            if stop_due(self.st.t(), stop) {
                self.handle_stop(has_events)?;
                continue;
            }
            if self.st.t() >= t_end {
                let (t, x) = (self.st.t(), self.st.x().to_vec());
                return Ok(Plan::Done(self.finish(t, &x, StopReason::Finished)));
            }
            let mut limit = match self.outs.peek() {
                Some(to) if self.ctx.fixed.is_some() => to.min(t_end),
                _ => t_end,
            };
            limit = limit.min(stop);
            if let Some(grid) = &self.grid {
                // The next grid point, skipping one within `1e-9 h` of `t` (no sliver
                // steps): from its index, so every run on the grid meets the same points bit
                // for bit, and as a decimal, so it meets the rows and samples that are.
                limit = limit.min(grid.next_after(self.st.t(), 1e-9));
            }
            return Ok(Plan::Step(limit));
        }
    }

    /// After a step: the projection, the events in the step, the outputs up to its end.
    /// `Some` when the run ended in it (an event's stop, the observer).
    pub(crate) fn after_step(&mut self) -> Result<Option<Stats>, IntegrateError> {
        self.project_step();
        self.after_projection()
    }

    /// The first part of [`Self::after_step`]: the projection of the step's end state.
    pub(crate) fn project_step(&mut self) {
        // The copy tells whether cached derivatives went stale.
        self.buf.copy_from_slice(self.st.x());
        self.sys.project(self.st.x_mut());
        if self.buf != self.st.x() {
            self.st.state_modified();
        }
        self.sys.step_accepted(self.st.t(), self.st.x());
    }

    /// The projected step's end, as the rest of [`Self::after_step`] reads it: the system,
    /// the time and state, and whether the event functions evaluate the system there.
    pub(crate) fn step_end(&mut self) -> (&mut S, f64, &[f64], bool) {
        let events = !self.g_left.is_empty();
        (&mut self.sys, self.st.t(), self.st.x(), events)
    }

    /// The rest of [`Self::after_step`], after [`Self::project_step`]: events, output.
    pub(crate) fn after_projection(&mut self) -> Result<Option<Stats>, IntegrateError> {
        let has_events = !self.g_left.is_empty();
        if has_events {
            match self.handle_events()? {
                Next::Proceed => {}
                Next::Restarted => return Ok(None),
                Next::Done(stats) => return Ok(Some(stats)),
            }
        }
        let t = self.st.t();
        if let Some(stats) = self.emit_until(t)? {
            return Ok(Some(stats));
        }
        if self.outs.every_step() && (self.observer)(t, self.st.x()).is_break() {
            let x = self.st.x().to_vec();
            return Ok(Some(self.finish(t, &x, StopReason::Observer)));
        }
        if has_events {
            std::mem::swap(&mut self.g_left, &mut self.g_right);
        }
        Ok(None)
    }

    /// The stepper, its context and the system, for a step taken from outside (`lanes.rs`).
    pub(crate) fn parts(&mut self) -> (&mut St, &mut Ctx, &mut S) {
        (&mut self.st, &mut self.ctx, &mut self.sys)
    }

    /// The system and the observer, once the run is over.
    pub(crate) fn into_parts(self) -> (S, F) {
        (self.sys, self.observer)
    }

    /// Handles the time stop due at the stepper's time (see [`System::on_stop`]): restarts
    /// the stepper there when the system changed.
    fn handle_stop(&mut self, has_events: bool) -> Result<(), IntegrateError> {
        let t = self.st.t();
        self.x_ev.copy_from_slice(self.st.x());
        let changed = self
            .sys
            .on_stop(t, &mut self.x_ev)
            .map_err(|source| IntegrateError::System { t, source })?;
        let next = self.sys.next_stop();
        if stop_due(t, next) {
            return Err(IntegrateError::System {
                t,
                source: SystemError::new(format!(
                    "the time stop at {next} was handled at t = {t} but did not move past it"
                )),
            });
        }
        if changed {
            if !all_finite(&self.x_ev) {
                return Err(IntegrateError::non_finite_state(t, &self.x_ev));
            }
            // The solution goes on through the stop (only its right-hand side, or a state
            // the system set, changed): the step the error control proposed serves the next
            // step as well as an estimate from scratch would, which after every sample of a
            // law would take the steps down and grow them back.
            let h = self.st.proposed_step();
            if self.ctx.fixed.is_none() && h.is_finite() && h > 0.0 {
                self.ctx.h_resume = Some(h);
            }
            self.st
                .restart(&mut self.sys, &mut self.ctx, t, &self.x_ev)?;
            if has_events {
                Self::eval_events(&mut self.sys, t, &self.x_ev, &mut self.g_left)?;
            }
        }
        Ok(())
    }

    /// State at `t` within the last step into `self.buf`.
    fn interpolate(&mut self, t: f64) -> Result<(), IntegrateError> {
        if t == self.st.t() {
            self.buf.copy_from_slice(self.st.x());
        } else {
            self.st.prepare_dense(&mut self.sys, &mut self.ctx)?;
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

    /// Evaluates the event functions at `(t, x)` into `g`.
    fn eval_events(sys: &mut S, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), IntegrateError> {
        sys.events(t, x, g)
            .map_err(|source| IntegrateError::System { t, source })
    }

    /// Finds and handles every event crossing in the last step, in time order.
    ///
    /// The earliest crossing time `t_ev` is located; every event that has crossed by
    /// `t_ev`, or whose own crossing lies within `event_tol` of it, belongs to the same
    /// group and is handed to [`System::on_events`] together. When the group resets the
    /// state, events whose functions the reset itself made cross (a chain: one impulse
    /// triggering another event) are handled at the same instant, as further groups.
    /// Handled events restart from `g = 0`, so they do not fire twice for one crossing.
    fn handle_events(&mut self) -> Result<Next, IntegrateError> {
        let (mut t_left, t_right) = (self.st.t_old(), self.st.t());
        let slope = self.st.end_slope();
        self.sys
            .events_at_step_end(t_right, self.st.x(), slope, &mut self.g_right)
            .map_err(|source| IntegrateError::System { t: t_right, source })?;
        let ne = self.g_left.len();
        loop {
            // Locate every candidate; t_loc[k] is NaN where event k does not cross.
            let mut t_ev = f64::INFINITY;
            let mut prepared = false;
            for k in 0..ne {
                self.t_loc[k] = f64::NAN;
                let dir = self.sys.event_direction(k);
                let (g_l, g_r) = (self.g_left[k], self.g_right[k]);
                // An event handled at `t_left` restarts from g = 0. If it is past again at
                // the step's end, g may have left zero and come back inside the step (a
                // rebound shorter than the step): the end points alone cannot tell.
                let returned = g_l == 0.0 && dir.crosses(-g_r, g_r);
                if !dir.crosses(g_l, g_r) && !returned {
                    continue;
                }
                if !prepared {
                    self.st.prepare_dense(&mut self.sys, &mut self.ctx)?;
                    prepared = true;
                }
                let (sys, st, buf, g) = (&mut self.sys, &self.st, &mut self.buf, &mut self.g_mid);
                let mut g_at = |t: f64| {
                    if t == st.t() {
                        buf.copy_from_slice(st.x());
                    } else {
                        st.dense(t, buf);
                    }
                    sys.events(t, buf, g)
                        .map_err(|source| IntegrateError::System { t, source })?;
                    Ok::<f64, IntegrateError>(g[k])
                };
                // The bracket: the step, or for a return, from the last probe on the far
                // side of zero (the dense output sampled from just after t_left) to the next.
                let (mut t_a, mut g_a, mut t_b, mut g_b) = (t_left, g_l, t_right, g_r);
                if returned {
                    let mut bracket = None;
                    let mut before: Option<(f64, f64)> = None;
                    for f in RETURN_PROBES.iter().copied().chain([1.0]) {
                        let t = if f == 1.0 {
                            t_right
                        } else {
                            t_left + f * (t_right - t_left)
                        };
                        let gt = if f == 1.0 { g_r } else { g_at(t)? };
                        if let Some((tp, gp)) = before
                            && dir.crosses(gp, gt)
                        {
                            bracket = Some((tp, gp, t, gt));
                            break;
                        }
                        if dir.crosses(gt, -gt) {
                            before = Some((t, gt));
                        }
                    }
                    let Some(b) = bracket else { continue };
                    (t_a, g_a, t_b, g_b) = b;
                }
                let tk = locate(dir, t_a, g_a, t_b, g_b, self.event_tol, g_at)?;
                self.t_loc[k] = tk;
                t_ev = t_ev.min(tk);
            }
            if t_ev == f64::INFINITY {
                return Ok(Next::Proceed);
            }
            self.interpolate(t_ev)?;
            self.x_ev.copy_from_slice(&self.buf);
            Self::eval_events(&mut self.sys, t_ev, &self.x_ev, &mut self.g_mid)?;
            if let Some(stats) = self.emit_until(t_ev)? {
                return Ok(Next::Done(stats));
            }
            self.group.clear();
            for k in 0..ne {
                let dir = self.sys.event_direction(k);
                if self.t_loc[k] <= t_ev + self.event_tol
                    || dir.crosses(self.g_left[k], self.g_mid[k])
                {
                    self.group.push(k);
                }
            }
            // The group, then any chain of events its resets trigger at the same instant.
            // Each round fires only events not yet fired (they are zeroed), so there are at
            // most `ne` rounds.
            let mut reset = false;
            loop {
                for &k in &self.group {
                    self.events.push((t_ev, k));
                }
                // `buf` keeps the state before this round (a `Continue` must not change it).
                self.buf.copy_from_slice(&self.x_ev);
                let action = self
                    .sys
                    .on_events(&self.group, t_ev, &mut self.x_ev)
                    .map_err(|source| IntegrateError::System { t: t_ev, source })?;
                match action {
                    EventAction::Continue => {
                        self.x_ev.copy_from_slice(&self.buf);
                        for &k in &self.group {
                            self.g_mid[k] = 0.0;
                        }
                        break;
                    }
                    EventAction::Stop => {
                        let x = self.x_ev.clone();
                        if self.outs.every_step() {
                            // The stop point is the last "step" of the run.
                            let _ = (self.observer)(t_ev, &x);
                        }
                        let k = self.group[0];
                        return Ok(Next::Done(self.finish(t_ev, &x, StopReason::Event { k })));
                    }
                    EventAction::Reset => {
                        if !all_finite(&self.x_ev) {
                            return Err(IntegrateError::non_finite_state(t_ev, &self.x_ev));
                        }
                        reset = true;
                        Self::eval_events(&mut self.sys, t_ev, &self.x_ev, &mut self.g_post)?;
                        self.next_group.clear();
                        for k in 0..ne {
                            let dir = self.sys.event_direction(k);
                            if self.group.binary_search(&k).is_err()
                                && dir.crosses(self.g_mid[k], self.g_post[k])
                            {
                                self.next_group.push(k);
                            }
                        }
                        for &k in &self.group {
                            self.g_post[k] = 0.0;
                        }
                        std::mem::swap(&mut self.g_mid, &mut self.g_post);
                        std::mem::swap(&mut self.group, &mut self.next_group);
                        if self.group.is_empty() {
                            break;
                        }
                    }
                }
            }
            if reset {
                self.st
                    .restart(&mut self.sys, &mut self.ctx, t_ev, &self.x_ev)?;
                if self.outs.every_step() && (self.observer)(t_ev, &self.x_ev).is_break() {
                    let x = self.x_ev.clone();
                    return Ok(Next::Done(self.finish(t_ev, &x, StopReason::Observer)));
                }
                std::mem::swap(&mut self.g_left, &mut self.g_mid);
                return Ok(Next::Restarted);
            }
            t_left = t_ev;
            std::mem::swap(&mut self.g_left, &mut self.g_mid);
        }
    }
}

/// A count of steps as a message writes it: whole below 1e15, three significant digits in
/// exponent form above (not the 300 digits of `1e300`).
fn count(n: f64) -> String {
    if n < 1e15 {
        format!("{}", n.ceil())
    } else {
        format!("{n:.3e}")
    }
}
