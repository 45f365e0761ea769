//! Runs of one fixed-step scene several at a time ([`integrate_lanes`]): a batch of runs
//! advances in lockstep, step by step, and the right-hand sides of each RK4 stage of all
//! its runs are evaluated together by a [`Batch`] (the dynamics of several runs in the SIMD
//! lanes of one core, in `satsim-spacecraft`). Everything else of a run (its time stops,
//! the projection, the events located in a step, the outputs) is the driver of one run
//! (`driver.rs`), run by run, with that run's own system: a run whose step holds an event
//! locates it alone, with its own right-hand sides, and rejoins the batch at the next step.
//! A run that ends gives its place to the next run at once.
//!
//! So each run's result is bit for bit what [`integrate`](crate::integrate) gives it,
//! provided the batch's right-hand sides are each run's own (the [`Batch`] contract): the
//! stages are RK4's own pieces, the checks of each evaluation those of one run.
//! Adaptive methods choose each run's steps from its own errors, so runs part ways at once:
//! with them the runs are integrated one after the other, as [`integrate`](crate::integrate)
//! does.

use crate::common::Ctx;
use crate::driver::{Plan, Run, Stats, checked, run_method};
use crate::error::IntegrateError;
use crate::options::{Method, Options, Output};
use crate::rk4::Rk4;
use crate::system::{System, SystemError};
use std::borrow::Cow;
use std::ops::ControlFlow;

/// One right-hand side of a batch: `dx = f(t, x)` of `system`, the outcome into `result`.
pub struct Lane<'a, S> {
    /// The run's system.
    pub system: &'a mut S,
    /// Time.
    pub t: f64,
    /// State.
    pub x: &'a [f64],
    /// Derivative, written by the batch.
    pub dx: &'a mut [f64],
    /// What `system.rhs(t, x, dx)` returns (`Ok` until the batch says otherwise).
    pub result: Result<(), SystemError>,
    /// The run's counters, to check the evaluation as one run checks it.
    ctx: &'a mut Ctx,
    /// The run's place in the batch.
    slot: usize,
}

/// What evaluates the right-hand sides of a batch of runs together.
///
/// The contract: after [`Batch::rhs`], each lane's `dx`, `result` and the state of its
/// `system` are exactly what `system.rhs(t, x, dx)` would have left (bit for bit), whatever
/// the other lanes hold. The simplest batch calls exactly that on each lane.
pub trait Batch<S> {
    /// Evaluates every lane (at most the batch's width of them, each a different run).
    fn rhs(&mut self, lanes: &mut [Lane<'_, S>]);

    /// The runs whose steps just ended (projected), before each goes on alone (its event
    /// functions, its output): what the batch may evaluate for them together. The contract
    /// is [`Batch::rhs`]'s: what each run then computes is, bit for bit, what it would have
    /// computed without this call. The default evaluates nothing.
    fn step_ends(&mut self, ends: &mut [StepEnd<'_, S>]) {
        let _ = ends;
    }
}

/// A run at the end of its step, for [`Batch::step_ends`].
pub struct StepEnd<'a, S> {
    /// Its system.
    pub system: &'a mut S,
    /// The step's end time.
    pub t: f64,
    /// The (projected) state there.
    pub x: &'a [f64],
    /// Whether its event functions evaluate the system at `(t, x)` next.
    pub events: bool,
}

/// A run handed to [`integrate_lanes`]: its system, start, end, output times and observer,
/// as [`integrate`](crate::integrate) takes them.
pub struct LaneRun<S, F> {
    /// The system (owned by the run; [`Runs::done`] hands it back).
    pub system: S,
    /// Start time.
    pub t0: f64,
    /// Initial state.
    pub x0: Vec<f64>,
    /// End time.
    pub t_end: f64,
    /// Output times.
    pub output: Output,
    /// The observer, called as [`integrate`](crate::integrate) calls it.
    pub observer: F,
}

/// Where the runs of [`integrate_lanes`] come from and go.
pub trait Runs<S, F> {
    /// The next run, `None` when there is none left.
    fn next(&mut self) -> Option<LaneRun<S, F>>;
    /// A run is over: its system, its observer and what [`integrate`](crate::integrate)
    /// would have returned for it. Runs end in any order.
    fn done(&mut self, system: S, observer: F, result: Result<Stats, IntegrateError>);
}

/// Integrates every run `runs` gives, `width` of them at a time (see the module
/// documentation), with `options` (the same for all). Each run's outcome goes to
/// [`Runs::done`], as [`integrate`](crate::integrate) would return it.
///
/// ```
/// use std::ops::ControlFlow;
/// use satsim_integrate::lanes::{Batch, Lane, LaneRun, Runs, integrate_lanes};
/// use satsim_integrate::{IntegrateError, Method, Options, Output, Stats, System, SystemError};
///
/// struct Decay(f64);
/// impl System for Decay {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
///         dx[0] = -self.0 * x[0];
///         Ok(())
///     }
/// }
/// // A batch that evaluates each lane on its own (a real one evaluates them together).
/// struct OneByOne;
/// impl Batch<Decay> for OneByOne {
///     fn rhs(&mut self, lanes: &mut [Lane<'_, Decay>]) {
///         for l in lanes {
///             l.result = l.system.rhs(l.t, l.x, l.dx);
///         }
///     }
/// }
/// type Observer = fn(f64, &[f64]) -> ControlFlow<()>;
/// struct Rates(Vec<f64>, Vec<f64>);
/// impl Runs<Decay, Observer> for Rates {
///     fn next(&mut self) -> Option<LaneRun<Decay, Observer>> {
///         let rate = self.0.pop()?;
///         let observer: Observer = |_, _| ControlFlow::Continue(());
///         Some(LaneRun { system: Decay(rate), t0: 0.0, x0: vec![1.0], t_end: 1.0,
///                        output: Output::Interval(0.5), observer })
///     }
///     fn done(&mut self, _: Decay, _: Observer, result: Result<Stats, IntegrateError>) {
///         self.1.push(result.unwrap().x_final[0]);
///     }
/// }
/// let opts = Options::new(Method::Rk4).with_fixed_step(0.01);
/// let mut rates = Rates(vec![1.0, 2.0, 3.0], Vec::new());
/// integrate_lanes(&opts, 2, &mut OneByOne, &mut rates);
/// let alone = satsim_integrate::integrate(&mut Decay(2.0), &opts, 0.0, &[1.0], 1.0,
///     &Output::Interval(0.5), |_, _| ControlFlow::Continue(()))?;
/// assert!(rates.1.contains(&alone.x_final[0])); // bit for bit
/// # Ok::<(), IntegrateError>(())
/// ```
pub fn integrate_lanes<S, F, B, R>(options: &Options, width: usize, batch: &mut B, runs: &mut R)
where
    S: System,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
    B: Batch<S>,
    R: Runs<S, F>,
{
    if options.method != Method::Rk4 || width < 2 {
        while let Some(run) = runs.next() {
            alone(options, run, runs);
        }
        return;
    }
    let mut slots: Vec<Option<Slot<S, F>>> = (0..width).map(|_| None).collect();
    let mut failed: Vec<Option<IntegrateError>> = (0..width).map(|_| None).collect();
    let mut lanes: Vec<Lane<'_, S>> = Vec::with_capacity(width);
    let mut ends: Vec<StepEnd<'_, S>> = Vec::with_capacity(width);
    let mut more = true;
    loop {
        // Every place holds a run about to step, or is empty for good.
        for slot in &mut slots {
            while more || slot.is_some() {
                let Some(s) = slot else {
                    *slot = runs.next().and_then(|run| start(options, run, runs));
                    more &= slot.is_some();
                    continue;
                };
                let planned = match s.run.plan(s.t_end) {
                    Ok(Plan::Step(limit)) => {
                        let (st, ctx, _) = s.run.parts();
                        st.begin_step(ctx, limit).map_err(Err)
                    }
                    Ok(Plan::Done(stats)) => Err(Ok(stats)),
                    Err(e) => Err(Err(e)),
                };
                match planned {
                    Ok(()) => break,
                    Err(outcome) => end(slot, outcome, runs),
                }
            }
        }
        if slots.iter().all(Option::is_none) {
            return;
        }
        for stage in 0..4 {
            let mut batch_lanes = recycle(std::mem::take(&mut lanes));
            for (i, slot) in slots.iter_mut().enumerate() {
                if let (Some(s), None) = (slot, &failed[i]) {
                    let (st, ctx, system) = s.run.parts();
                    if let Some((t, x, dx)) = st.stage(stage) {
                        batch_lanes.push(Lane {
                            system,
                            t,
                            x,
                            dx,
                            result: Ok(()),
                            ctx,
                            slot: i,
                        });
                    }
                }
            }
            if !batch_lanes.is_empty() {
                batch.rhs(&mut batch_lanes);
            }
            for l in batch_lanes.drain(..) {
                if let Err(e) = l.ctx.evaluated(l.t, l.x, l.dx, l.result) {
                    failed[l.slot] = Some(e);
                }
            }
            lanes = recycle(batch_lanes);
        }
        // Every step ends and is projected, then the batch sees them all (`step_ends`), then
        // each run goes on alone: each run's own sequence is `after_step`'s.
        for (slot, failure) in slots.iter_mut().zip(&mut failed) {
            let Some(s) = slot else { continue };
            let ended = match failure.take() {
                Some(e) => Err(e),
                None => {
                    let (st, ctx, _) = s.run.parts();
                    st.end_step(ctx)
                }
            };
            match ended {
                Ok(()) => s.run.project_step(),
                Err(e) => end(slot, Err(e), runs),
            }
        }
        let mut step_ends = recycle_ends(std::mem::take(&mut ends));
        step_ends.extend(slots.iter_mut().flatten().map(|s| {
            let (system, t, x, events) = s.run.step_end();
            StepEnd {
                system,
                t,
                x,
                events,
            }
        }));
        if step_ends.len() > 1 {
            batch.step_ends(&mut step_ends);
        }
        ends = recycle_ends(step_ends);
        for slot in &mut slots {
            let Some(s) = slot else { continue };
            let outcome = match s.run.after_projection() {
                Ok(None) => continue,
                Ok(Some(stats)) => Ok(stats),
                Err(e) => Err(e),
            };
            end(slot, outcome, runs);
        }
    }
}

/// A run of the batch, under way.
struct Slot<S, F> {
    run: Run<'static, S, Rk4, F>,
    t_end: f64,
}

/// A run's start as [`integrate`](crate::integrate) makes it: `None` when it is over already
/// (refused, or stopped at its first output).
fn start<S, F, R>(options: &Options, r: LaneRun<S, F>, runs: &mut R) -> Option<Slot<S, F>>
where
    S: System,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
    R: Runs<S, F>,
{
    let mut r = r;
    let (outputs, ctx) = match check(options, &mut r) {
        Ok(c) => c,
        Err(e) => {
            runs.done(r.system, r.observer, Err(e));
            return None;
        }
    };
    let n = r.system.dim();
    let mut run = Run::new(r.system, Rk4::new(n), ctx, options, outputs, r.observer);
    match run.begin(r.t0, &r.x0) {
        Ok(None) => Some(Slot {
            run,
            t_end: r.t_end,
        }),
        Ok(Some(stats)) => {
            let (system, observer) = run.into_parts();
            runs.done(system, observer, Ok(stats));
            None
        }
        Err(e) => {
            let (system, observer) = run.into_parts();
            runs.done(system, observer, Err(e));
            None
        }
    }
}

/// The run in `slot` is over: handed back, the place emptied.
fn end<S, F, R>(slot: &mut Option<Slot<S, F>>, outcome: Result<Stats, IntegrateError>, runs: &mut R)
where
    S: System,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
    R: Runs<S, F>,
{
    if let Some(s) = slot.take() {
        let (system, observer) = s.run.into_parts();
        runs.done(system, observer, outcome);
    }
}

/// One run from start to end, as [`integrate`](crate::integrate) runs it.
fn alone<S, F, R>(options: &Options, r: LaneRun<S, F>, runs: &mut R)
where
    S: System,
    F: FnMut(f64, &[f64]) -> ControlFlow<()>,
    R: Runs<S, F>,
{
    let mut r = r;
    match check(options, &mut r) {
        Ok((outputs, ctx)) => {
            let (result, system, observer) = run_method(
                r.system, options, ctx, outputs, r.observer, r.t0, &r.x0, r.t_end,
            );
            runs.done(system, observer, result);
        }
        Err(e) => runs.done(r.system, r.observer, Err(e)),
    }
}

/// A run's checks as [`integrate`](crate::integrate) makes them (its output times taken
/// into the result).
fn check<S: System, F>(
    options: &Options,
    r: &mut LaneRun<S, F>,
) -> Result<(crate::options::OutputTimes<'static>, Ctx), IntegrateError> {
    let output = std::mem::replace(&mut r.output, Output::Steps);
    checked(&r.system, options, r.t0, &r.x0, r.t_end, Cow::Owned(output))
}

/// An empty vector's allocation under another lifetime: the lanes' buffer is made once,
/// not at every stage (an in-place `collect` of an empty vector of the same layout keeps
/// its allocation).
fn recycle<'a, 'b, S>(mut v: Vec<Lane<'a, S>>) -> Vec<Lane<'b, S>> {
    v.clear();
    v.into_iter().map(|_| unreachable!("empty")).collect()
}

/// [`recycle`] for the step ends.
fn recycle_ends<'a, 'b, S>(mut v: Vec<StepEnd<'a, S>>) -> Vec<StepEnd<'b, S>> {
    v.clear();
    v.into_iter().map(|_| unreachable!("empty")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EventAction, EventDirection, StopReason, integrate};

    /// A ball bouncing on a spring floor, kicked by a sampled law: events (bounces that
    /// reset the velocity, a stop event), time stops, a failure at a chosen time, and an
    /// observer that may break, so that a run's path through the driver depends on its
    /// parameters.
    #[derive(Clone, Debug)]
    struct Ball {
        g: f64,
        restitution: f64,
        sample: f64,
        next_sample: f64,
        kick: f64,
        fail_at: f64,
        stop_at_height: f64,
        rhs_calls: usize,
    }

    impl System for Ball {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            self.rhs_calls += 1;
            if t >= self.fail_at {
                return Err(SystemError::new(format!("fails at {t}")));
            }
            dx[0] = x[1];
            dx[1] = -self.g + self.kick - 0.01 * x[1] * x[1].abs();
            Ok(())
        }
        fn n_events(&self) -> usize {
            2
        }
        fn events(&mut self, _t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
            g[0] = x[0];
            g[1] = x[0] - self.stop_at_height;
            Ok(())
        }
        fn event_direction(&self, k: usize) -> EventDirection {
            [EventDirection::Falling, EventDirection::Rising][k]
        }
        fn on_event(&mut self, k: usize, _t: f64, x: &mut [f64]) -> EventAction {
            if k == 1 {
                return EventAction::Stop;
            }
            x[1] *= -self.restitution;
            EventAction::Reset
        }
        fn next_stop(&self) -> f64 {
            self.next_sample
        }
        fn on_stop(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
            self.kick = 0.5 * x[1].signum();
            self.next_sample = t + self.sample;
            Ok(true)
        }
    }

    type Observer = Box<dyn FnMut(f64, &[f64]) -> ControlFlow<()>>;
    type Rows = std::rc::Rc<std::cell::RefCell<Vec<(f64, [u64; 2])>>>;

    fn ball(i: usize) -> (Ball, f64, f64) {
        let f = i as f64;
        let b = Ball {
            g: 9.81 + 0.1 * f,
            restitution: 0.5 + 0.04 * f,
            sample: 0.37 + 0.05 * f,
            next_sample: 0.37 + 0.05 * f,
            kick: 0.0,
            fail_at: if i % 5 == 3 { 2.1 } else { f64::INFINITY },
            stop_at_height: if i % 7 == 2 { 1.0 } else { f64::INFINITY },
            rhs_calls: 0,
        };
        (b, 1.0 + 0.1 * f, 3.0 + 0.25 * (i % 4) as f64)
    }

    fn observer(rows: &Rows, break_after: usize) -> Observer {
        let rows = rows.clone();
        Box::new(move |t, x| {
            let mut r = rows.borrow_mut();
            r.push((t, [x[0].to_bits(), x[1].to_bits()]));
            if r.len() >= break_after {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
    }

    fn break_after(i: usize) -> usize {
        if i % 6 == 4 { 9 } else { usize::MAX }
    }

    /// Everything one run leaves: its outcome, its rows, its system's final state.
    type Outcome = (
        Result<Stats, IntegrateError>,
        Vec<(f64, [u64; 2])>,
        usize,
        f64,
    );

    /// Evaluates the lanes in reverse order, each on its own.
    struct Reversed;
    impl Batch<Ball> for Reversed {
        fn rhs(&mut self, lanes: &mut [Lane<'_, Ball>]) {
            assert!(lanes.len() <= 4);
            for l in lanes.iter_mut().rev() {
                l.result = l.system.rhs(l.t, l.x, l.dx);
            }
        }
    }

    struct Balls {
        next: usize,
        n: usize,
        output: Output,
        done: Vec<Option<Outcome>>,
        rows: Vec<Rows>,
    }
    impl Runs<Ball, Observer> for Balls {
        fn next(&mut self) -> Option<LaneRun<Ball, Observer>> {
            let i = self.next;
            if i == self.n {
                return None;
            }
            self.next += 1;
            let (system, x0, t_end) = ball(i);
            self.rows.push(Rows::default());
            Some(LaneRun {
                system,
                t0: 0.0,
                x0: vec![x0, 0.0],
                t_end,
                output: self.output.clone(),
                observer: observer(&self.rows[i], break_after(i)),
            })
        }
        fn done(&mut self, system: Ball, _: Observer, result: Result<Stats, IntegrateError>) {
            // Which run: the one with this system's parameters.
            let i = (0..self.n).find(|&i| ball(i).0.g == system.g).unwrap();
            let rows = self.rows[i].borrow().clone();
            self.done[i] = Some((result, rows, system.rhs_calls, system.kick));
        }
    }

    #[test]
    fn runs_in_lanes_are_the_runs_alone_bit_for_bit() {
        let n = 23;
        for output in [Output::Interval(0.25), Output::Steps] {
            for options in [
                Options::new(Method::Rk4).with_fixed_step(0.01),
                Options::new(Method::Rk4)
                    .with_fixed_step(0.03)
                    .with_max_steps(150),
                Options::new(Method::Dp54).with_tolerances(1e-8, 1e-10),
            ] {
                let alone: Vec<Outcome> = (0..n)
                    .map(|i| {
                        let (mut sys, x0, t_end) = ball(i);
                        let rows = Rows::default();
                        let mut obs = observer(&rows, break_after(i));
                        let r = integrate(
                            &mut sys,
                            &options,
                            0.0,
                            &[x0, 0.0],
                            t_end,
                            &output,
                            &mut obs,
                        );
                        let rows = rows.borrow().clone();
                        (r, rows, sys.rhs_calls, sys.kick)
                    })
                    .collect();
                // The runs take every path: events, a stop event, failures, breaks.
                let ok = |o: &Outcome| o.0.as_ref().ok().map(|s| s.stop);
                assert!(alone.iter().any(|o| o.0.is_err()));
                assert!(
                    alone
                        .iter()
                        .any(|o| matches!(ok(o), Some(StopReason::Event { k: 1 })))
                );
                assert!(alone.iter().any(|o| ok(o) == Some(StopReason::Observer)));
                assert!(
                    alone
                        .iter()
                        .any(|o| o.0.as_ref().is_ok_and(|s| s.events.len() > 3))
                );
                for width in [2, 3, 4] {
                    let mut runs = Balls {
                        next: 0,
                        n,
                        output: output.clone(),
                        done: vec![None; n],
                        rows: Vec::new(),
                    };
                    integrate_lanes(&options, width, &mut Reversed, &mut runs);
                    for (i, (a, b)) in alone.iter().zip(&runs.done).enumerate() {
                        let b = b.as_ref().expect("every run ends");
                        assert_eq!(
                            format!("{:?}", a.0),
                            format!("{:?}", b.0),
                            "run {i}, width {width}"
                        );
                        assert_eq!(a.1, b.1, "run {i}'s rows, width {width}");
                        assert_eq!(
                            (a.2, a.3.to_bits()),
                            (b.2, b.3.to_bits()),
                            "run {i}'s system"
                        );
                    }
                }
            }
        }
    }
}
