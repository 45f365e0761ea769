//! [`Stepping`]: a [`Simulation`] advanced from outside, a piece at a time ("flight software
//! in the loop"), and the time stops of the effects' discrete-time laws.
//!
//! # The contract
//!
//! - **Resumable state**: the time `t`, the continuous state `x`, and what the simulation
//!   holds besides (the locks and modes of the effects, their held outputs, the inputs).
//! - [`Stepping::advance`]`(options, dt, sink)` integrates from `t` to `t + dt` with the
//!   scene's integrator, handling events inside, and returns the events that fired. A
//!   fixed-step method takes steps of its `step` on the grid anchored at the start
//!   ([`Options::grid_origin`]), the last one shortened to land on `t + dt`; an end within
//!   round-off of an output time or of a grid point is taken to be that point. So, with the
//!   inputs never set, stepping to the end in any pieces reproduces
//!   [`Simulation::run`]'s rows: bit for bit for a fixed-step method when each piece is a
//!   whole number of steps, within the tolerance for an adaptive method. An adaptive
//!   method goes on from one piece to the next as one run would ([`integrate_on`]): each
//!   piece starts with the step the last proposed and Radau IIA with its Jacobian, so a
//!   short piece (a 10 Hz control loop) costs a step or two, not a new Jacobian and a
//!   first step's estimate.
//! - **Rows** go to `sink(t, row)` at the times of the [`OutputGrid`] that fall in each
//!   piece (the first call also gives the row at the start), exactly as a run gives them.
//! - **Inputs** ([`Stepping::inputs`]): `torque_<hinge>` for each model hinge, a torque
//!   added to the initial state's constant `torque` (the linearisation's channel,
//!   [`Simulation::constant_torques_mut`]): held `u` acts exactly as the same constant in
//!   the initial state; and the rotors' hinge names (`wheel_<name>`), a motor command added
//!   to the wheel's command (the controller's, or its constant `torque`) before its torque
//!   and speed limits; `dipole_<torquer>` for each magnetic torquer, a dipole (A m²)
//!   added to its command before its clamp; and `thrust_<thruster>` for each thruster, a
//!   duty in [0, 1] added to its constant `duty` (and to the flight software's command,
//!   `[fsw.control] actuator = "thrusters"`) and latched at the first period start at
//!   or after the current time (set at a period start, it acts from that start).
//!   Held until changed (zero-order hold). An event whose function the
//!   change moves across zero (a wheel held at its speed limit whose command drops) is
//!   handled at once and reported by the next `advance`.
//! - **Errors**: an unknown input name, a non-finite value, a thruster's duty outside
//!   [0, 1], a `dt` that is not a finite
//!   number > 0: [`StepError::Input`], the simulation unchanged. A failure of the
//!   integration ([`StepError::Integrate`]) leaves the simulation at no consistent state:
//!   every later `advance` fails with [`StepError::Failed`].
//!
//! # Time stops
//!
//! An effect with a discrete-time law ([`Effect::next_sample`](crate::effects::Effect::next_sample))
//! makes the simulation a [`System`] with time stops: every integrator lands a step on each
//! sample instant, where [`Effect::sample`](crate::effects::Effect::sample) latches the law's
//! output (then the events its change moves across zero are handled, as for an input).

use super::Simulation;
use super::run::Shared;
use satsim_integrate::{
    Carry, DecimalGrid, IntegrateError, Options, Output, Steps, System, SystemError, integrate_on,
    stop_due,
};
use std::cell::RefCell;
use std::ops::ControlFlow;
use thiserror::Error;

/// One handled event: `(t, effect name, description)`.
pub type EventRecord = (f64, String, String);

/// The output times of a run from `t0` to `t_end` every `every` seconds, exactly as the
/// integrator's `Output::Interval(every)` gives them (`t0 + i · every` as decimals,
/// [`DecimalGrid`]; the last snapped to
/// `t_end` when within rounding of it, and `t_end` always), then continued past `t_end` on
/// the same grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputGrid {
    /// The first output time (the start).
    pub t0: f64,
    /// The interval (s, finite, > 0).
    pub every: f64,
    /// The end of the run the grid belongs to.
    pub t_end: f64,
}

/// Where the next output lies on an [`OutputGrid`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cursor {
    i: usize,
    /// Whether `t_end` was given.
    past_end: bool,
}

impl OutputGrid {
    /// The rounding scale of the times (as the integrator's).
    fn tol(&self) -> f64 {
        let span = self.t_end - self.t0;
        1e-12
            * self
                .t_end
                .abs()
                .max(self.t0.abs())
                .max(self.every.min(span.max(0.0)))
    }
    fn raw(&self, i: usize) -> f64 {
        DecimalGrid::new(self.t0, self.every).point(i as f64)
    }
    /// The time at `c`.
    fn time(&self, c: Cursor) -> f64 {
        let raw = self.raw(c.i);
        if !c.past_end && raw >= self.t_end - self.tol() {
            self.t_end
        } else {
            raw
        }
    }
    /// The cursor after `c`.
    fn after(&self, c: Cursor) -> Cursor {
        if !c.past_end && self.time(c) == self.t_end {
            let mut i = c.i;
            while self.raw(i) <= self.t_end + self.tol() {
                i += 1;
            }
            Cursor { i, past_end: true }
        } else {
            Cursor {
                i: c.i + 1,
                past_end: c.past_end,
            }
        }
    }
    /// The output times up to `t` (inclusive), from `c` on, into `out`; the cursor after
    /// them.
    fn take_until(&self, mut c: Cursor, t: f64, out: &mut Vec<f64>) -> Cursor {
        while self.time(c) <= t {
            out.push(self.time(c));
            c = self.after(c);
        }
        c
    }
    /// The output time nearest `t` within rounding of it, if any.
    fn near(&self, t: f64) -> Option<f64> {
        let i = ((t - self.t0) / self.every).round().max(0.0) as usize;
        let tol = self.tol().max(1e-12 * t.abs());
        [self.t_end, self.raw(i)]
            .into_iter()
            .find(|o| (o - t).abs() <= tol)
    }
}

/// Why [`Stepping::advance`] or [`Stepping::set_inputs`] refused or failed.
#[derive(Debug, Error)]
pub enum StepError<E> {
    /// Bad input (an unknown input name, a non-finite value, a thruster's duty outside
    /// [0, 1], a bad `dt`); nothing changed.
    #[error("{0}")]
    Input(String),
    /// The integration failed part-way (the simulation cannot continue).
    #[error("{0}")]
    Integrate(IntegrateError),
    /// The output sink failed at time `t` (the simulation cannot continue).
    #[error("output failed at t = {t}: {error}")]
    Sink {
        /// Time of the row.
        t: f64,
        /// The sink's error.
        error: E,
    },
    /// An earlier `advance` failed; the simulation cannot continue.
    #[error("the simulation cannot continue: {0}")]
    Failed(String),
}

/// A [`Simulation`] advanced from outside a piece at a time: see the module documentation.
pub struct Stepping {
    sim: Simulation,
    t: f64,
    x: Vec<f64>,
    /// The fixed-step grid's origin: the start.
    origin: f64,
    grid: OutputGrid,
    cursor: Cursor,
    /// The input names, their values, and the constant torques they are added to.
    inputs: Vec<String>,
    values: Vec<f64>,
    base_tau: Vec<f64>,
    /// Where the `thrust_<name>` inputs start, and each one's (effect, thruster) pair.
    first_thrust: usize,
    thrusters: Vec<(usize, usize)>,
    /// How many of the simulation's logged events were returned already.
    reported: usize,
    failed: Option<String>,
    row: Vec<f64>,
    outs: Vec<f64>,
    /// The steps of the advances so far ([`Stepping::steps`]).
    steps: Steps,
    /// What each piece leaves the next ([`integrate_on`]): an adaptive method's next step,
    /// Radau IIA's Jacobian.
    carry: Carry,
    work: StepWork,
}

/// The integrator's work over the advances so far ([`Stepping::work`]), as
/// [`Stats`](satsim_integrate::Stats) counts one run's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepWork {
    /// Right-hand side evaluations (finite-difference Jacobians' included).
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps_accepted: usize,
    /// Rejected step attempts.
    pub steps_rejected: usize,
    /// Jacobians (Radau IIA).
    pub jacobian_evals: usize,
    /// Jacobians brought to a new state through the mass matrix instead (Radau IIA on a
    /// tree with flexible bodies).
    pub jacobian_updates: usize,
    /// LU factorisations (Radau IIA).
    pub lu_decompositions: usize,
}

impl Stepping {
    /// Stepping `sim` from its initial state, rows on `grid`. A simulation that has run
    /// starts again as [`Simulation::run`] does (when it cannot, every `advance` fails).
    pub fn new(mut sim: Simulation, grid: OutputGrid) -> Self {
        let failed = sim.restart().err().map(|e| e.to_string());
        let n_user = sim.model.n_user;
        let names = sim.model.tree.hinge_names();
        let mut inputs: Vec<String> = names[..n_user]
            .iter()
            .map(|h| format!("torque_{h}"))
            .collect();
        inputs.extend(names[n_user..].iter().cloned());
        inputs.extend(
            sim.effects
                .iter()
                .flat_map(|e| e.torquers())
                .map(|t| format!("dipole_{}", t.name)),
        );
        let thrusters: Vec<(usize, usize)> = sim
            .effects
            .iter()
            .enumerate()
            .flat_map(|(i, e)| (0..e.thrusters().len()).map(move |j| (i, j)))
            .collect();
        let first_thrust = inputs.len();
        inputs.extend(
            sim.effects
                .iter()
                .flat_map(|e| e.thrusters())
                .map(|t| format!("thrust_{}", t.name)),
        );
        let base_tau = sim.constant_torques_mut().to_vec();
        let (t, x) = (sim.t0(), sim.x0().to_vec());
        let reported = sim.event_log().len();
        Self {
            values: vec![0.0; inputs.len()],
            inputs,
            first_thrust,
            thrusters,
            base_tau,
            sim,
            t,
            x,
            origin: t,
            grid,
            cursor: Cursor {
                i: 0,
                past_end: false,
            },
            reported,
            failed,
            row: Vec::new(),
            outs: Vec::new(),
            steps: Steps::default(),
            carry: Carry::new(),
            work: StepWork::default(),
        }
    }
    /// The simulation (its model, layout, effects, event log).
    pub fn simulation(&self) -> &Simulation {
        &self.sim
    }
    /// The output column names ([`Simulation::columns`]).
    pub fn columns(&self) -> Vec<String> {
        self.sim.columns()
    }
    /// The time (s).
    pub fn t(&self) -> f64 {
        self.t
    }
    /// The state at [`Stepping::t`] (see [`StateLayout`](super::StateLayout)).
    pub fn x(&self) -> &[f64] {
        &self.x
    }
    /// The steps of the advances so far: the time they covered, the accepted steps and
    /// those that landed on a piece's end or a time stop
    /// ([`Stats::steps_capped`](satsim_integrate::Stats::steps_capped)). Those the
    /// integrator set, and how often the pieces end, tell whether an explicit method's
    /// stability limit held them, as a run's steps do for `satsim run`'s warning of steps
    /// held by a stiff motion.
    pub fn steps(&self) -> Steps {
        self.steps
    }
    /// The integrator's work over the advances that finished so far.
    pub fn work(&self) -> StepWork {
        self.work
    }
    /// The output grid.
    pub fn output_grid(&self) -> OutputGrid {
        self.grid
    }
    /// The input names: `torque_<hinge>` per model hinge, then the rotors' hinge names, then
    /// `dipole_<torquer>` per magnetic torquer (A m², added to its command before the clamp),
    /// then `thrust_<thruster>` per thruster (a duty in [0, 1], added to its constant duty
    /// and latched at the first period start at or after the time it is set).
    pub fn inputs(&self) -> &[String] {
        &self.inputs
    }
    /// The inputs' held values, in the order of [`Stepping::inputs`].
    pub fn input_values(&self) -> &[f64] {
        &self.values
    }
    /// Marks the output times up to [`Stepping::t`] as given, for a caller that recorded
    /// the row at the start itself ([`Stepping::row`]); otherwise the next `advance` gives it.
    pub fn skip_outputs_until_now(&mut self) {
        while self.grid.time(self.cursor) <= self.t {
            self.cursor = self.grid.after(self.cursor);
        }
    }
    /// The output row at [`Stepping::t`] (the truth; see [`Simulation::columns`]).
    pub fn row(&mut self, row: &mut Vec<f64>) -> Result<(), SystemError> {
        self.sim.row(self.t, &self.x, row)
    }

    /// Every sensor's reading at [`Stepping::t`] (see [`crate::sensors`]), `(name, values)`
    /// in the scene's order: the reading last taken, or the one a sample due now takes (the
    /// first sample is at the start, so there is always one).
    pub fn measure(&mut self) -> Result<Vec<(String, Vec<f64>)>, SystemError> {
        let (t, x) = (self.t, &self.x);
        self.sim.check_len(x.len(), "measure")?;
        self.sim.prepare(t, x, true)?;
        let mut out = Vec::new();
        self.sim.with_context(t, x, true, |ctx, h| {
            for e in h.effects.iter() {
                e.measure(ctx, &mut out);
            }
        });
        Ok(out)
    }

    /// Sets inputs by name, held from now until changed. Every name and value is checked
    /// first: an unknown name or a non-finite value is an error naming it, and nothing is
    /// set. An event whose function the change moves across zero is handled now and
    /// reported by the next [`Stepping::advance`].
    pub fn set_inputs<E>(&mut self, values: &[(&str, f64)]) -> Result<(), StepError<E>> {
        if let Some(why) = &self.failed {
            return Err(StepError::Failed(why.clone()));
        }
        let mut at = Vec::with_capacity(values.len());
        for &(name, v) in values {
            let Some(k) = self.inputs.iter().position(|n| n == name) else {
                return Err(StepError::Input(format!(
                    "unknown input `{name}`; the inputs are: {}",
                    self.inputs.join(", ")
                )));
            };
            if !v.is_finite() {
                return Err(StepError::Input(format!(
                    "input `{name}` must be a finite number, got {v}"
                )));
            }
            if k >= self.first_thrust && !(0.0..=1.0).contains(&v) {
                return Err(StepError::Input(format!(
                    "input `{name}` is a thruster's duty cycle, in [0, 1], got {v}"
                )));
            }
            at.push((k, v));
        }
        if at.iter().all(|&(k, v)| self.values[k] == v) {
            return Ok(());
        }
        let before = self.event_values().map_err(|e| self.fail(e))?;
        for (k, v) in at {
            self.values[k] = v;
        }
        let (n_user, n_rotors) = (self.sim.model.n_user, self.sim.model.n_rotors);
        for (k, &v) in self.values.iter().enumerate() {
            if k < n_user {
                self.sim.data.base_tau[k] = self.base_tau[k] + v;
            } else if k < n_user + n_rotors {
                self.sim.data.forces.rotor_input[k - n_user] = v;
            } else if k < self.first_thrust {
                self.sim.data.forces.dipole_input[k - n_user - n_rotors] = v;
            } else {
                let (i, j) = self.thrusters[k - self.first_thrust];
                self.sim.effects[i].hold_thrust_input(j, v, self.t);
            }
        }
        self.sim.forget_ahead();
        let (t, mut x) = (self.t, std::mem::take(&mut self.x));
        let r = self.sim.settle_events(t, &mut x, &before);
        self.x = x;
        r.map_err(|e| self.fail(e))
    }

    /// The event functions at the current state (empty when there are none).
    fn event_values(&mut self) -> Result<Vec<f64>, SystemError> {
        let mut g = vec![0.0; self.sim.model.n_events];
        if !g.is_empty() {
            self.sim.events(self.t, &self.x, &mut g)?;
        }
        Ok(g)
    }

    fn fail<E>(&mut self, e: SystemError) -> StepError<E> {
        let e = IntegrateError::System {
            t: self.t,
            source: e,
        };
        self.failed = Some(e.to_string());
        StepError::Integrate(e)
    }

    /// Integrates from [`Stepping::t`] to `t + dt` (see the module documentation), calling
    /// `sink(t, row)` at the output times on the way, and returns the events that fired
    /// (with those an input change fired since the last call). `dt` must be finite and
    /// > 0; otherwise nothing changes.
    pub fn advance<E: std::fmt::Display>(
        &mut self,
        options: &Options,
        dt: f64,
        sink: impl FnMut(f64, &[f64]) -> Result<(), E>,
    ) -> Result<Vec<EventRecord>, StepError<E>> {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(StepError::Input(format!(
                "dt must be a finite number > 0, got {dt}"
            )));
        }
        self.advance_to(options, self.t + dt, sink)
    }

    /// As [`Stepping::advance`], to the time `t_end` (finite, after [`Stepping::t`]).
    pub fn advance_to<E: std::fmt::Display>(
        &mut self,
        options: &Options,
        t_end: f64,
        mut sink: impl FnMut(f64, &[f64]) -> Result<(), E>,
    ) -> Result<Vec<EventRecord>, StepError<E>> {
        if let Some(why) = &self.failed {
            return Err(StepError::Failed(why.clone()));
        }
        if let Err(e) = self.sim.takes(options) {
            return Err(StepError::Input(e.to_string()));
        }
        if !(t_end.is_finite() && t_end > self.t) {
            return Err(StepError::Input(format!(
                "the end time must be a finite number after t = {}, got {t_end}",
                self.t
            )));
        }
        let t_end = self.snap(options, t_end);
        let mut outs = std::mem::take(&mut self.outs);
        outs.clear();
        let cursor = self.grid.take_until(self.cursor, t_end, &mut outs);
        let options = Options {
            grid_origin: Some(self.origin),
            ..options.clone()
        };
        let columns_of = |sim: &Simulation, c: usize| sim.columns()[c].clone();
        let mut failure: Option<StepError<E>> = None;
        let mut row = std::mem::take(&mut self.row);
        let output = Output::Times(outs);
        let cell = RefCell::new(&mut self.sim);
        let result = integrate_on(
            &mut Shared(&cell),
            &options,
            self.t,
            &self.x,
            t_end,
            &output,
            |t, x| {
                let mut sim = cell.borrow_mut();
                if let Err(source) = sim.row(t, x, &mut row) {
                    failure = Some(StepError::Integrate(IntegrateError::System { t, source }));
                    return ControlFlow::Break(());
                }
                if let Some(c) = row.iter().position(|v| !v.is_finite()) {
                    let why = format!(
                        "`{}` is not finite: the computation overflowed",
                        columns_of(&sim, c)
                    );
                    failure = Some(StepError::Integrate(IntegrateError::System {
                        t,
                        source: SystemError::new(why),
                    }));
                    return ControlFlow::Break(());
                }
                if let Err(error) = sink(t, &row) {
                    failure = Some(StepError::Sink { t, error });
                    return ControlFlow::Break(());
                }
                ControlFlow::Continue(())
            },
            &mut self.carry,
        );
        self.row = row;
        if let Output::Times(outs) = output {
            self.outs = outs;
        }
        let failure = match (result, failure) {
            (_, Some(f)) => Some(f),
            (Err(e), None) => Some(StepError::Integrate(self.sim.explained(e, &options))),
            (Ok(stats), None) => {
                let w = &mut self.work;
                w.rhs_evals += stats.rhs_evals;
                w.steps_accepted += stats.steps_accepted;
                w.steps_rejected += stats.steps_rejected;
                w.jacobian_evals += stats.jacobian_evals;
                w.jacobian_updates += stats.jacobian_updates;
                w.lu_decompositions += stats.lu_decompositions;
                self.steps.add(Steps::of(&stats, self.t));
                self.t = stats.t_final;
                self.x = stats.x_final;
                self.cursor = cursor;
                (stats.t_final < t_end).then(|| {
                    StepError::Failed(format!(
                        "an event stopped the simulation at t = {}",
                        stats.t_final
                    ))
                })
            }
        };
        if let Some(f) = failure {
            self.failed = Some(f.to_string());
            return Err(f);
        }
        let events: Vec<EventRecord> = self
            .sim
            .event_records()
            .skip(self.reported)
            .map(|(t, e, what)| (t, e.to_string(), what.to_string()))
            .collect();
        self.reported += events.len();
        Ok(events)
    }

    /// How many rows [`Stepping::advance`]`(options, dt, ..)` would give (the output times
    /// after [`Stepping::t`] up to `t + dt`), counted no further than `cap + 1`: a caller
    /// that keeps rows checks a long `dt` against its room before integrating (the rows of
    /// one piece are listed in memory). 0 for a `dt` that `advance` refuses.
    pub fn rows_in(&self, options: &Options, dt: f64, cap: usize) -> usize {
        if !(dt > 0.0 && dt.is_finite() && (self.t + dt).is_finite()) {
            return 0;
        }
        let t_end = self.snap(options, self.t + dt);
        let (mut c, mut n) = (self.cursor, 0);
        while n <= cap && self.grid.time(c) <= t_end {
            n += 1;
            c = self.grid.after(c);
        }
        n
    }

    /// The end of a piece: an output time or (fixed step) a grid point within round-off of
    /// `t_end`, else `t_end`.
    fn snap(&self, options: &Options, t_end: f64) -> f64 {
        if let Some(o) = self.grid.near(t_end).filter(|&o| o > self.t) {
            return o;
        }
        if let Some(h) = options.fixed_step.filter(|h| *h > 0.0 && h.is_finite()) {
            let g = DecimalGrid::new(self.origin, h).point(((t_end - self.origin) / h).round());
            if (g - t_end).abs() <= 1e-9 * h && g > self.t {
                return g;
            }
        }
        t_end
    }
}

impl Simulation {
    /// The next sample instant of the effects' discrete-time laws (`∞` for none).
    pub(super) fn next_sample_stop(&self) -> f64 {
        self.effects
            .iter()
            .fold(f64::INFINITY, |s, e| s.min(e.next_sample()))
    }

    /// The time stop at `t`: every effect whose sample is due latches its law's output; then
    /// the events the change moved across zero are handled. Returns whether the dynamics
    /// changed (an effect that does not only observe was sampled: the integrator restarts).
    pub(super) fn sample_effects(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
        self.forget_ahead();
        let due = |e: &dyn crate::effects::Effect| stop_due(t, e.next_sample());
        if !self.effects.iter().any(|e| due(e.as_ref())) {
            return Ok(false);
        }
        self.check_len(x.len(), "on_stop")?;
        // A sensor's sample changes nothing the dynamics read: no events to settle, no
        // restart of the integrator.
        let changes = self
            .effects
            .iter()
            .any(|e| due(e.as_ref()) && !e.observes_only());
        let mut before = vec![0.0; if changes { self.model.n_events } else { 0 }];
        if !before.is_empty() {
            self.events(t, x, &mut before)?;
        }
        let kin = self.data.needs_kinematics
            || self
                .effects
                .iter()
                .any(|e| due(e.as_ref()) && e.sample_reads_kinematics());
        self.prepare(t, x, kin)?;
        self.with_context(t, x, kin, |ctx, h| {
            for e in h.effects.iter_mut() {
                if stop_due(t, e.next_sample()) {
                    e.sample(ctx)?;
                }
            }
            Ok::<(), SystemError>(())
        })?;
        self.hand_thrust_commands(t);
        let mut said = Vec::new();
        for (i, e) in self.effects.iter_mut().enumerate() {
            e.drain_sample_log(&mut said);
            for what in said.drain(..) {
                self.log.events.push((t, what));
                self.log.event_effects.push(i);
            }
        }
        self.settle_events(t, x, &before)?;
        Ok(changes)
    }

    /// The thrust commands of the effect that commands the thrusters (as sampled), held on
    /// the thrusters' owners at `t`: a period start at `t` already latched is latched again
    /// (so the order the effects sampled in does not matter), otherwise they wait for the
    /// next period start.
    fn hand_thrust_commands(&mut self, t: f64) {
        let Some(k) = self.model.thrust_commander else {
            return;
        };
        let commands = self.effects[k].thrust_commands().to_vec();
        for (&(i, j), &d) in self.model.thruster_owners.iter().zip(&commands) {
            self.effects[i].hold_thrust_command(j, d, t);
        }
    }

    /// Handles, at once, the events whose functions went from `before` to their values now
    /// across zero (in their directions): a jump of an input or a held output moved them.
    pub(super) fn settle_events(
        &mut self,
        t: f64,
        x: &mut [f64],
        before: &[f64],
    ) -> Result<(), SystemError> {
        if before.is_empty() {
            return Ok(());
        }
        let mut after = vec![0.0; before.len()];
        self.events(t, x, &mut after)?;
        let group: Vec<usize> = (0..before.len())
            .filter(|&k| self.event_direction(k).crosses(before[k], after[k]))
            .collect();
        if !group.is_empty() {
            self.on_events(&group, t, x)?;
        }
        Ok(())
    }
}
