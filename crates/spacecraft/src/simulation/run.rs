//! [`Simulation::run`]: integrate and stream rows to a sink.

use super::Simulation;
use satsim_integrate::{
    EventAction, EventDirection, IntegrateError, Method, NonFiniteEntry, Options, Output, Stats,
    System, SystemError,
};
use satsim_tree::error::Num;
use std::cell::{Ref, RefCell, RefMut};
use std::ops::ControlFlow;
use thiserror::Error;

impl Simulation {
    /// Integrates from the initial state to `t_end`, calling `sink(t, row)` with an output
    /// row (see [`Simulation::columns`]) at each output time. A sink error stops the run.
    /// Every row passed to `sink` is finite: a row with a non-finite entry stops the run with
    /// an error naming the column.
    ///
    /// Every run starts from the simulation as built: a second run starts from fresh copies
    /// of the effects (their modes, held outputs, sensor noise streams and thruster periods
    /// as new), the start's locks and an empty run log, so it gives the first's bits (the
    /// constant hinge torques stay as set). A simulation with an effect given without a copy
    /// ([`SimulationBuilder::boxed`](super::SimulationBuilder::boxed)) runs once: a second
    /// run is an error.
    pub fn run<E>(
        &mut self,
        options: &Options,
        t_end: f64,
        output: &Output,
        mut sink: impl FnMut(f64, &[f64]) -> Result<(), E>,
    ) -> Result<Stats, RunError<E>> {
        if let Err(source) = self.takes(options).and_then(|()| self.restart()) {
            return Err(RunError::Integrate(IntegrateError::System {
                t: self.t0,
                source,
            }));
        }
        let x0 = self.x0.clone();
        let t0 = self.t0;
        let columns = self.columns();
        let cell = RefCell::new(self);
        let mut shared = Shared(&cell);
        let mut row = Vec::new();
        let mut failure: Option<RunError<E>> = None;
        let result =
            satsim_integrate::integrate(&mut shared, options, t0, &x0, t_end, output, |t, x| {
                let mut sim = cell.borrow_mut();
                match deliver(&mut sim, &columns, &mut row, t, x, &mut sink) {
                    Ok(()) => ControlFlow::Continue(()),
                    Err(f) => {
                        failure = Some(f);
                        ControlFlow::Break(())
                    }
                }
            });
        outcome(result, failure, &cell.borrow(), options)
    }

    /// Whether `options` can integrate this simulation: not with the elastic coordinates out
    /// of the error ([`SimulationBuilder::elastic_error`](super::SimulationBuilder::elastic_error))
    /// under an explicit adaptive method, whose steps, no longer held by the modes, go past
    /// their stability limit ([`elastic_error_refusal`]).
    pub(super) fn takes(&self, options: &Options) -> Result<(), SystemError> {
        if self.model.flex.is_some()
            && !self.model.elastic_error
            && options.method.is_explicit_adaptive()
            && options.fixed_step.is_none()
        {
            return Err(SystemError::new(elastic_error_refusal(options.method)));
        }
        Ok(())
    }

    /// What a run that ran out of steps was stepping through, for its message: the effects
    /// whose events fired among the last [`STALL_EVENTS`] handled, with their counts and
    /// the time they span (events crowding a short span are a switching the steps could
    /// not get past), or that no event fired. A run at the fixed step `fixed` did not choose
    /// its steps: the message says what they were (the dynamics are not to blame).
    fn stepping_through(&self, fixed: Option<f64>) -> String {
        let events = &self.log.events;
        let owners = &self.log.event_effects;
        let n = events.len().min(owners.len());
        let fixed = fixed.map(|h| {
            format!(
                "; the step is fixed ({} s): the steps are those of its grid and those cut where an \
                 output time, a sample instant or an event falls inside one; raise the step or \
                 the maximum number of steps",
                Num(h)
            )
        });
        if n == 0 {
            return fixed.unwrap_or_else(|| {
                "; no event fired: the steps went into the dynamics themselves (a stiff \
                 spring or damper, or a discontinuity no effect makes an event of)"
                    .into()
            });
        }
        let from = n - n.min(STALL_EVENTS);
        let mut counts: Vec<(usize, usize)> = Vec::new();
        for &i in &owners[from..n] {
            match counts.iter_mut().find(|(e, _)| *e == i) {
                Some((_, c)) => *c += 1,
                None => counts.push((i, 1)),
            }
        }
        counts.sort_by_key(|&(_, c)| std::cmp::Reverse(c));
        let names: Vec<String> = counts
            .iter()
            .map(|&(i, c)| {
                let name = self.effects.get(i).map_or("?", |e| e.name());
                format!("{name} {c}")
            })
            .collect();
        format!(
            "{}; the last {} events (t = {} to {}) were {}; the last: {}",
            fixed.unwrap_or_default(),
            n - from,
            Num(events[from].0),
            Num(events[n - 1].0),
            names.join(", "),
            events[n - 1].1
        )
    }
}

/// An output row at `(t, x)` to `sink`: the row (see [`Simulation::columns`]), refused when
/// an entry is not finite (an error naming the column), then the sink's.
pub(super) fn deliver<E>(
    sim: &mut Simulation,
    columns: &[String],
    row: &mut Vec<f64>,
    t: f64,
    x: &[f64],
    sink: &mut impl FnMut(f64, &[f64]) -> Result<(), E>,
) -> Result<(), RunError<E>> {
    let system = |source| RunError::Integrate(IntegrateError::System { t, source });
    sim.row(t, x, row).map_err(system)?;
    // A non-finite quantity is never presented as a result.
    if let Some(c) = row.iter().position(|v| !v.is_finite()) {
        let why = format!("`{}` is not finite: the computation overflowed", columns[c]);
        return Err(system(SystemError::new(why)));
    }
    sink(t, row).map_err(|error| RunError::Sink { t, error })
}

/// A run's outcome from the integrator's result and the failure its observer kept, under
/// the run's `options`.
pub(super) fn outcome<E>(
    result: Result<Stats, IntegrateError>,
    failure: Option<RunError<E>>,
    sim: &Simulation,
    options: &Options,
) -> Result<Stats, RunError<E>> {
    match (result, failure) {
        (_, Some(f)) => Err(f),
        (Ok(stats), None) => Ok(stats),
        (Err(IntegrateError::MaxSteps { t, .. }), None) => {
            Err(RunError::Integrate(IntegrateError::MaxSteps {
                t,
                stepping: sim.stepping_through(options.fixed_step),
            }))
        }
        (Err(e), None) => Err(RunError::Integrate(sim.explained(e, options))),
    }
}

impl Simulation {
    /// `e` as a run under `options` reports it: a state named as its column
    /// ([`Self::named`]), and a step size underflow with what the steps were shortened for
    /// and why ([`Self::underflow`]).
    pub(super) fn explained(&self, e: IntegrateError, options: &Options) -> IntegrateError {
        match e {
            IntegrateError::StepSizeUnderflow { t, h, entry, .. } => {
                self.underflow(t, h, entry, options)
            }
            e => self.named(e),
        }
    }

    /// A step size underflow at `t` (step `h`) under `options`, the steps last shortened
    /// for state entry `entry` where the integrator knows it: that state named as its
    /// column, then why. Where a flexible body had been bent past a tenth of its size, the
    /// motion left what the model holds, and the body is named (the solve's own failure
    /// says it at its state, `SimModel::flexible_error`); else the error control shortened
    /// the steps for a motion far faster than the rest or a jump, and the message says what
    /// to try: an implicit method for an explicit one, looser tolerances, the initial state.
    fn underflow(&self, t: f64, h: f64, entry: Option<usize>, options: &Options) -> IntegrateError {
        let state = entry
            .map(|i| {
                format!(
                    ": the steps were last shortened for `{}`",
                    self.state_name(i)
                )
            })
            .unwrap_or_default();
        let what = match self.deflection_failure() {
            Some(why) => format!(
                "{state}, after the flexible bodies were deflected beyond what their modal model holds: {why}"
            ),
            None => {
                let tolerances = format!(
                    "looser tolerances (`integrator.rtol` = {:e} and `atol` = {:e} now)",
                    options.rtol, options.atol
                );
                let what_to_try = match options.method {
                    Method::Radau5 => format!("Try {tolerances}"),
                    m => format!(
                        "The method `{}` is explicit and must follow every motion: try `integrator.method = \"radau5\"` (implicit, it steps over fast motions), or {tolerances}",
                        m.name()
                    ),
                };
                format!(
                    "{state}; the error control shortened the steps until they no longer moved the time on: the motion there is far faster than the rest (a stiff spring or damper, a high mode, a huge initial rate or deformation), or it runs into a singularity or a jump in the forces. {what_to_try}, and check the initial state for a value far too large"
                )
            }
        };
        IntegrateError::StepSizeUnderflow { t, h, entry, what }
    }

    /// `e` with the state it found not finite named as a column is (`rate_h4`, not "state
    /// entry 11"), and where that comes from: the first entry to overflow points at the
    /// value that drove it.
    pub(super) fn named(&self, e: IntegrateError) -> IntegrateError {
        let IntegrateError::NonFinite {
            t,
            entry: Some(entry),
            ..
        } = e
        else {
            return e;
        };
        let what = match entry {
            NonFiniteEntry::State(i) => format!(": `{}` is not finite", self.state_name(i)),
            NonFiniteEntry::Derivative(i) => format!(
                ": the rate of change of `{}` is not finite",
                self.state_name(i)
            ),
        };
        let what = format!(
            "{what} (the forces or the motion overflowed: look for a huge value in the scene)"
        );
        IntegrateError::NonFinite {
            t,
            entry: Some(entry),
            what,
        }
    }

    /// The name of state entry `i` (see [`StateLayout`](super::StateLayout)): its output
    /// column's where it has one.
    fn state_name(&self, i: usize) -> String {
        let l = &self.model.layout;
        let hinges = self.model.tree.hinge_names();
        let elastic = self.elastic_names();
        let at = |r: &std::ops::Range<usize>| r.contains(&i).then(|| i - r.start);
        if let Some(k) = at(&l.attitude) {
            return format!("q_{}", ["w", "x", "y", "z"][k]);
        }
        if let Some(k) = at(&l.omega) {
            return format!("omega_{}", ["x", "y", "z"][k]);
        }
        if let Some(k) = at(&l.velocity) {
            return format!("v_{}", ["x", "y", "z"][k]);
        }
        if let Some(k) = at(&l.angles) {
            return format!("angle_{}", hinges[k]);
        }
        if let Some(k) = at(&l.rates) {
            return format!("rate_{}", hinges[k]);
        }
        if let Some(k) = at(&l.eta) {
            return format!("eta_{}", elastic[k]);
        }
        if let Some(k) = at(&l.etadot) {
            return format!("etadot_{}", elastic[k]);
        }
        for (name, r) in &l.effects {
            if let Some(k) = at(r) {
                let names = self.effect(name).map(|e| e.state_names());
                return names
                    .and_then(|n| n.get(k).cloned())
                    .unwrap_or_else(|| format!("{name}_{k}"));
            }
        }
        if let Some(k) = at(&self.model.work) {
            return ["work_actuators", "energy_dissipated"][k].to_string();
        }
        format!("state entry {i}")
    }
}

/// How many of the last handled events a run out of steps reports on.
pub const STALL_EVENTS: usize = 1000;

/// Why [`Simulation::run`] stopped early.
#[derive(Debug, Error)]
pub enum RunError<E> {
    /// The integrator (or the dynamics) failed.
    #[error("{0}")]
    Integrate(IntegrateError),
    /// The output sink failed at time `t`.
    #[error("output failed at t = {t}: {error}")]
    Sink {
        /// Time of the row.
        t: f64,
        /// The sink's error.
        error: E,
    },
}

/// A simulation seen as the integrators' [`System`] while an observer also reads it: through
/// a [`RefCell`], borrowed for each call.
pub(super) struct Shared<C>(pub(super) C);

/// Where a [`Shared`] finds its simulation.
pub(super) trait SimCell {
    fn sim(&self) -> Ref<'_, Simulation>;
    fn sim_mut(&self) -> RefMut<'_, Simulation>;
}

impl SimCell for &RefCell<&mut Simulation> {
    fn sim(&self) -> Ref<'_, Simulation> {
        Ref::map(self.borrow(), |s| &**s)
    }
    fn sim_mut(&self) -> RefMut<'_, Simulation> {
        RefMut::map(self.borrow_mut(), |s| &mut **s)
    }
}

impl<C: SimCell> System for Shared<C> {
    fn dim(&self) -> usize {
        self.0.sim().model.layout.len
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.0.sim_mut().rhs(t, x, dx)
    }
    fn project(&mut self, x: &mut [f64]) {
        self.0.sim_mut().project(x)
    }
    fn step_accepted(&mut self, t: f64, x: &[f64]) {
        self.0.sim_mut().step_accepted(t, x)
    }
    fn holds_rhs(&self, t: f64, x: &[f64]) -> bool {
        self.0.sim().holds_rhs(t, x)
    }
    fn error_weights(&self, w: &mut [f64]) {
        self.0.sim().error_weights(w)
    }
    fn quadratures(&self, q: &mut [bool]) {
        self.0.sim().quadratures(q)
    }
    fn n_events(&self) -> usize {
        self.0.sim().model.n_events
    }
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        self.0.sim_mut().events(t, x, g)
    }
    fn events_at_step_end(
        &mut self,
        t: f64,
        x: &[f64],
        slope: Option<&[f64]>,
        g: &mut [f64],
    ) -> Result<(), SystemError> {
        self.0.sim_mut().events_at_step_end(t, x, slope, g)
    }
    fn event_direction(&self, k: usize) -> EventDirection {
        self.0.sim().event_direction(k)
    }
    fn on_event(&mut self, k: usize, t: f64, x: &mut [f64]) -> EventAction {
        self.0.sim_mut().on_event(k, t, x)
    }
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        self.0.sim_mut().on_events(ks, t, x)
    }
    fn next_stop(&self) -> f64 {
        self.0.sim().next_stop()
    }
    fn on_stop(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
        self.0.sim_mut().on_stop(t, x)
    }
    fn update_jacobian(
        &mut self,
        t0: f64,
        x0: &[f64],
        t: f64,
        x: &[f64],
        jac: &mut [f64],
    ) -> Result<bool, SystemError> {
        self.0.sim_mut().update_jacobian(t0, x0, t, x, jac)
    }
    fn jacobian_survives_restart(&mut self) -> bool {
        self.0.sim_mut().jacobian_survives_restart()
    }
}

/// Why the elastic coordinates left out of the error need an implicit method, with `method`
/// the explicit one given: the scene reader's message at `integrator.elastic_error` and a run's
/// ([`Simulation::run`], [`Stepping`](super::Stepping), [`Simulation::run_lanes`]). Left out,
/// the modes must be stable at whatever steps the rigid motion takes: Radau IIA's
/// L-stability damps them. An explicit method goes past its stability limit on them, and they
/// grow until what they pollute holds the steps (the shipped flexible deployment with `dp54`:
/// 35 719 steps, and the energy budget from 20 J to 7 580 J, where Radau IIA's moves by the
/// 0.14 J it damps).
pub fn elastic_error_refusal(method: Method) -> String {
    format!(
        "`integrator.elastic_error = false` needs `method = \"radau5\"`: it leaves the steps to the rigid motion, which only an implicit method keeps stable on the structural modes those steps go past; with `{}` the modes grow without bound. Keep the elastic coordinates in the error (`elastic_error = true`, the default) or use `radau5`",
        method.name()
    )
}
