//! [`Simulation::run`]: integrate and stream rows to a sink.

use super::Simulation;
use satsim_integrate::{
    EventAction, EventDirection, IntegrateError, Options, Output, Stats, System, SystemError,
};
use std::cell::RefCell;
use std::ops::ControlFlow;
use thiserror::Error;

impl Simulation {
    /// Integrates from the initial state to `t_end`, calling `sink(t, row)` with an output
    /// row (see [`Simulation::columns`]) at each output time. A sink error stops the run.
    /// Every row passed to `sink` is finite: a row with a non-finite entry stops the run with
    /// an error naming the column.
    pub fn run<E>(
        &mut self,
        options: &Options,
        t_end: f64,
        output: &Output,
        mut sink: impl FnMut(f64, &[f64]) -> Result<(), E>,
    ) -> Result<Stats, RunError<E>> {
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
                if let Err(e) = sim.row(t, x, &mut row) {
                    failure = Some(RunError::Integrate(IntegrateError::System { t, source: e }));
                    return ControlFlow::Break(());
                }
                // A non-finite quantity is never presented as a result.
                if let Some(c) = row.iter().position(|v| !v.is_finite()) {
                    let why = format!("`{}` is not finite: the computation overflowed", columns[c]);
                    failure = Some(RunError::Integrate(IntegrateError::System {
                        t,
                        source: SystemError::new(why),
                    }));
                    return ControlFlow::Break(());
                }
                if let Err(e) = sink(t, &row) {
                    failure = Some(RunError::Sink { t, error: e });
                    return ControlFlow::Break(());
                }
                ControlFlow::Continue(())
            });
        match (result, failure) {
            (_, Some(f)) => Err(f),
            (Ok(stats), None) => Ok(stats),
            (Err(IntegrateError::MaxSteps { t, .. }), None) => {
                Err(RunError::Integrate(IntegrateError::MaxSteps {
                    t,
                    stepping: cell.borrow().stepping_through(),
                }))
            }
            (Err(e), None) => Err(RunError::Integrate(e)),
        }
    }

    /// What a run that ran out of steps was stepping through, for its message: the effects
    /// whose events fired among the last [`STALL_EVENTS`] handled, with their counts and
    /// the time they span (events crowding a short span are a switching the steps could
    /// not get past), or that no event fired.
    fn stepping_through(&self) -> String {
        let events = &self.log.events;
        let owners = &self.log.event_effects;
        let n = events.len().min(owners.len());
        if n == 0 {
            return "; no event fired: the steps went into the dynamics themselves (a stiff \
                    spring or damper, or a discontinuity no effect makes an event of)"
                .into();
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
            "; the last {} events (t = {} to {}) were {}; the last: {}",
            n - from,
            events[from].0,
            events[n - 1].0,
            names.join(", "),
            events[n - 1].1
        )
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

pub(super) struct Shared<'a, 'b>(pub(super) &'a RefCell<&'b mut Simulation>);

impl System for Shared<'_, '_> {
    fn dim(&self) -> usize {
        self.0.borrow().model.layout.len
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.0.borrow_mut().rhs(t, x, dx)
    }
    fn project(&mut self, x: &mut [f64]) {
        self.0.borrow_mut().project(x)
    }
    fn error_weights(&self, w: &mut [f64]) {
        self.0.borrow().error_weights(w)
    }
    fn n_events(&self) -> usize {
        self.0.borrow().model.n_events
    }
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        self.0.borrow_mut().events(t, x, g)
    }
    fn event_direction(&self, k: usize) -> EventDirection {
        self.0.borrow().event_direction(k)
    }
    fn on_event(&mut self, k: usize, t: f64, x: &mut [f64]) -> EventAction {
        self.0.borrow_mut().on_event(k, t, x)
    }
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        self.0.borrow_mut().on_events(ks, t, x)
    }
    fn next_stop(&self) -> f64 {
        self.0.borrow().next_stop()
    }
    fn on_stop(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
        self.0.borrow_mut().on_stop(t, x)
    }
}
