//! [`Onboard`]: a scene's built-in flight software (`[fsw]`, contract section 16), its
//! estimator, guidance, control and magnetic blocks wired to the scene's sensors and run in
//! modes ([`crate::fsw::modes`]).
//!
//! # Reading the sensors at the instant they sample
//!
//! The blocks live inside the scene's [`Sensors`](crate::sensors::Sensors) effect
//! ([`Sensors::set_fsw`](crate::sensors::Sensors::set_fsw)): at a sample
//! instant that effect first takes every sensor sample due, then runs the blocks on the
//! readings just taken — the same values the sensors' columns and `measure()` show, noise
//! included — so the flight software never sees the truth and never reads a reading one
//! sample late, whatever order the effects run in. Without `[fsw]` the sensors do exactly what
//! they did (no block, no cost).
//!
//! # Timing (zero-order hold)
//!
//! - **Estimator** ([`crate::fsw::estimator`]): at its gyro's samples.
//! - **Guidance**: evaluated at the control's samples (without a control, at the
//!   estimator's), from the orbit; held in between. With slew limits it is shaped by a
//!   [`Slew`] stepped at those samples.
//! - **Control**: at its own samples (`t = 0, period, …`); the estimate it reads is the last
//!   one, turned on to the control instant by the gyro's rate less the estimated bias when
//!   the instant lies between gyro samples. Without an estimate yet (a Sun and field
//!   estimator before the Sun is seen) it commands nothing. Its commands are held in
//!   between.
//!   A control on the thrusters ([`Actuator::Thrusters`]) hands its duties to the
//!   thrusters through [`Onboard::thrust_commands`]: the simulation holds them on the
//!   thrusters right after the sample ([`Effect::hold_thrust_command`]), which latch them at
//!   their period start at that instant (the scene asks the control's period to be a whole
//!   multiple of theirs) or, between period starts, at the next. Where the current mode
//!   runs no thruster control the commands are zeros.
//! - **Magnetic** ([`crate::fsw::magnetic`]): at its magnetometer's samples, after the
//!   other blocks.
//! - **Modes**: checked last, at every sample instant.
//!
//! A row written at a sample instant holds what that sample latches (the sensors' readings
//! taken there, the estimate after its update, the mode after its check), as the sensors'
//! columns do: [`Sensors`](crate::sensors::Sensors) works it out on a copy.
//!
//! # Columns
//!
//! With an estimator: `est_q_w..z` (the estimate, body to inertial, `w >= 0`),
//! `est_bias_x..z` (rad/s), `est_sigma_x..z` (1σ of the attitude error about the body's
//! axes, rad), `est_error` (rad: the angle between the estimate and the true attitude of
//! the estimator's body — a diagnostic, the only place the truth is read). With guidance:
//! `ref_q_w..z`, `ref_omega_x..z` (rad/s, the reference's axes), `ref_alpha_x..z` (rad/s²,
//! likewise) and `pointing_error` (rad: the angle between the true attitude and the
//! reference). With `[fsw.bdot]` or `[fsw.momentum]`: `fsw_dipole_x..z` (A m², body axes:
//! the dipole commanded, before the torquers clamp it). With `[[fsw.mode]]`: `fsw_mode`
//! (the mode's index, from 0). Where the current mode runs no estimator (or its estimator has
//! no estimate yet: a Sun and field estimator before it saw the Sun) the `est_` columns are
//! all zero, `est_q` included (no attitude); likewise the `ref_` columns and
//! `pointing_error` without a guidance, and the dipole without a magnetic block.

use super::control::{Allocation, Pid};
use super::estimator::{Estimator, EstimatorSpec};
use super::guidance::{Guidance, Reference};
use super::magnetic::{DipoleBlock, DipoleSpec};
use super::mekf::log_rotation;
use super::modes::{Condition, Mode};
use super::slew::Slew;
use super::thrust::ThrustAllocation;
#[cfg(doc)]
use crate::effects::Effect;
use crate::effects::{Context, Forces, Links, Needs, Sampling};
use crate::sensors::{Pose, Sensor};
use nalgebra::{UnitQuaternion, Vector3};
use satsim_integrate::{SystemError, stop_due};

/// What a control commands.
#[derive(Clone, Debug, PartialEq)]
pub enum Actuator {
    /// Reaction wheels: rotor names (`wheel_<name>`) and `max_torque` (N m). The body torque
    /// is allocated over their axes by least squares ([`Pid::commands`]).
    Wheels(Vec<(String, f64)>),
    /// The magnetic torquers on the root body, on the reading of this magnetometer (index in
    /// the sensor set): the dipole `m = (B × u) / |B|²`, whose torque `m × B` is the part of
    /// `u` across the field (the part along it cannot be made), allocated over the torquers'
    /// axes by least squares within their `max_dipole`.
    Torquers {
        /// The magnetometer.
        magnetometer: usize,
    },
    /// The thrusters on the root body ([`Links::thrusters`] whose `body` is 0): the body
    /// torque about the system's centre of mass is allocated as non-negative forces by
    /// [`ThrustAllocation`], then duties (each in [0, 1], scaled down as a whole when one
    /// would exceed 1). The duties leave through [`Onboard::thrust_commands`] and are
    /// latched by the thrusters at their period starts (see the module documentation).
    Thrusters,
}

/// A control block: its law, clock and actuator.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlSpec {
    /// The law.
    pub pid: Pid,
    /// Sample period (s).
    pub period: f64,
    /// What it commands.
    pub actuator: Actuator,
}

#[derive(Clone, Debug, PartialEq)]
struct Control {
    pid: Pid,
    clock: Sampling,
    actuator: Actuator,
    /// Rotor indices (wheels) or torquer indices (torquers) of the commanded actuators,
    /// from `connect`.
    targets: Vec<usize>,
    /// The torquers' allocation (torquers only).
    dipoles: Allocation,
    /// The thrusters' allocation (thrusters only).
    thrust: ThrustAllocation,
    /// The commands held: one per rotor (wheels), per torquer (torquers) or per thruster
    /// (thrusters: the duties).
    held: Vec<f64>,
    /// One sample's commands, in `targets` order.
    scratch: Vec<f64>,
    /// The body torque wanted at the last sample (N m, body axes).
    torque: Vector3<f64>,
}

impl Control {
    fn reset(&mut self) {
        self.pid.reset();
        self.held.fill(0.0);
        self.torque = Vector3::zeros();
    }
}

/// A guidance block: its law, its slew shaper and the reference it holds.
#[derive(Clone, Debug)]
struct GuidanceBlock {
    law: Guidance,
    slew: Option<Slew>,
    /// Whether the shaper starts from the estimate at its next evaluation.
    restart: bool,
    /// The reference held (shaped).
    held: Option<Reference>,
    /// The law's own reference at the same instant (unshaped): what `error < x` reads.
    target: Option<Reference>,
}

/// A scene's flight software: see the module documentation.
#[derive(Clone, Debug)]
pub struct Onboard {
    estimators: Vec<Estimator>,
    guidances: Vec<GuidanceBlock>,
    controls: Vec<Control>,
    magnetics: Vec<DipoleBlock>,
    modes: Vec<Mode>,
    /// Whether the modes were given (`fsw_mode` column), rather than the one of every block.
    moded: bool,
    /// The current mode and when it began.
    mode: usize,
    since: f64,
    /// Since when the current mode's condition has held (its `hold`).
    holding: Option<f64>,
    /// Mode switches not yet logged.
    log: Vec<String>,
    /// The duties commanded to the thrusters, one per thruster of [`Links::thrusters`]:
    /// the current mode's thruster control's, zeros without one (empty when no control
    /// commands the thrusters).
    thrust: Vec<f64>,
}

impl Default for Onboard {
    fn default() -> Self {
        Self::new()
    }
}

impl Onboard {
    /// No block yet: add them, then the modes that run them (or none: one mode of every
    /// block, see [`Onboard::finish`]).
    pub fn new() -> Self {
        Self {
            estimators: Vec::new(),
            guidances: Vec::new(),
            controls: Vec::new(),
            magnetics: Vec::new(),
            modes: Vec::new(),
            moded: false,
            mode: 0,
            since: 0.0,
            holding: None,
            log: Vec::new(),
            thrust: Vec::new(),
        }
    }

    /// Adds an estimator; its index.
    pub fn add_estimator(&mut self, spec: EstimatorSpec) -> usize {
        self.estimators.push(Estimator::new(spec));
        self.estimators.len() - 1
    }
    /// Adds a guidance law, shaped by `slew` when given; its index.
    pub fn add_guidance(&mut self, law: Guidance, slew: Option<Slew>) -> usize {
        self.guidances.push(GuidanceBlock {
            law,
            slew,
            restart: true,
            held: None,
            target: None,
        });
        self.guidances.len() - 1
    }
    /// Adds a control; its index (`None` for a period that is not finite and > 0).
    pub fn add_control(&mut self, spec: ControlSpec) -> Option<usize> {
        self.controls.push(Control {
            pid: spec.pid,
            clock: Sampling::new(spec.period)?,
            actuator: spec.actuator,
            targets: Vec::new(),
            dipoles: Allocation::new(&[], &[]),
            thrust: ThrustAllocation::new(&[], &[], &[]),
            held: Vec::new(),
            scratch: Vec::new(),
            torque: Vector3::zeros(),
        });
        Some(self.controls.len() - 1)
    }
    /// Adds a magnetic block (`[fsw.bdot]` or `[fsw.momentum]`, see
    /// [`crate::fsw::magnetic`]); its index.
    pub fn add_magnetic(&mut self, spec: DipoleSpec) -> usize {
        self.magnetics.push(DipoleBlock::new(spec));
        self.magnetics.len() - 1
    }

    /// Adds a mode (they run in the order added). An error when it names a block that does
    /// not exist, runs a guidance without an estimator or a control without both, has its
    /// control and a magnetic block both command the torquers, or follows a mode that lasts.
    pub fn add_mode(&mut self, mode: Mode) -> Result<(), String> {
        let name = &mode.name;
        let exists = |i: Option<usize>, n: usize, what: &str| match i {
            Some(i) if i >= n => Err(format!("mode `{name}`: no {what} {i}")),
            _ => Ok(()),
        };
        exists(mode.estimator, self.estimators.len(), "estimator")?;
        exists(mode.guidance, self.guidances.len(), "guidance")?;
        exists(mode.control, self.controls.len(), "control")?;
        exists(mode.magnetic, self.magnetics.len(), "magnetic block")?;
        if mode.guidance.is_some() && mode.estimator.is_none() {
            return Err(format!(
                "mode `{name}` runs a guidance without an estimator (the guidance runs on its clock and points the body it estimates)"
            ));
        }
        if mode.control.is_some() && (mode.estimator.is_none() || mode.guidance.is_none()) {
            return Err(format!(
                "mode `{name}` runs a control without an estimator and a guidance"
            ));
        }
        if let (Some(c), Some(_)) = (mode.control, mode.magnetic)
            && matches!(self.controls[c].actuator, Actuator::Torquers { .. })
        {
            return Err(format!(
                "mode `{name}`: its control and its magnetic block would both command the torquers"
            ));
        }
        if let Some(last) = self.modes.last()
            && last.until.is_none()
        {
            return Err(format!(
                "mode `{name}` follows `{}`, which has no `until`: it would never begin",
                last.name
            ));
        }
        match mode.until {
            Some(Condition::RateBelow(_)) if mode.estimator.is_none() && mode.gyro.is_none() => {
                return Err(format!(
                    "mode `{name}`: `rate < x` needs a gyro or an estimator in the mode"
                ));
            }
            Some(Condition::ErrorBelow(_))
                if mode.estimator.is_none() || mode.guidance.is_none() =>
            {
                return Err(format!(
                    "mode `{name}`: `error < x` needs an estimator and a guidance in the mode"
                ));
            }
            _ => {}
        }
        if !(mode.hold.is_finite() && mode.hold >= 0.0) {
            return Err(format!("mode `{name}`: `hold` must be finite and >= 0"));
        }
        self.modes.push(mode);
        self.moded = true;
        Ok(())
    }

    /// Ends the building: without modes, one mode that runs every block (at most one of each
    /// kind, an error otherwise) and lasts. The blocks of the first mode start.
    pub fn finish(mut self) -> Result<Self, String> {
        if self.modes.is_empty() {
            let one = |n: usize, what: &str| match n {
                0 => Ok(None),
                1 => Ok(Some(0)),
                _ => Err(format!(
                    "{n} {what} blocks but no [[fsw.mode]] to say which runs when"
                )),
            };
            let mode = Mode {
                estimator: one(self.estimators.len(), "estimator")?,
                guidance: one(self.guidances.len(), "guidance")?,
                control: one(self.controls.len(), "control")?,
                magnetic: one(self.magnetics.len(), "magnetic")?,
                ..Mode::new("all")
            };
            self.add_mode(mode)?;
            self.moded = false;
        }
        if let Some(last) = self.modes.last()
            && let Some(c) = last.until
        {
            return Err(format!(
                "the last mode `{}` has `until = \"{c}\"` but no mode follows it",
                last.name
            ));
        }
        Ok(self)
    }

    /// The current mode's index and name.
    pub fn mode(&self) -> (usize, &str) {
        (self.mode, &self.modes[self.mode].name)
    }
    /// The modes.
    pub fn modes(&self) -> &[Mode] {
        &self.modes
    }
    fn current(&self) -> &Mode {
        &self.modes[self.mode]
    }

    /// The dipole the current mode's magnetic block holds (body axes, A m²), if it runs one.
    pub fn dipole(&self) -> Option<[f64; 3]> {
        self.current()
            .magnetic
            .map(|m| self.magnetics[m].dipole().into())
    }
    /// Whether a block commands the torquers.
    pub fn commands_dipoles(&self) -> bool {
        !self.magnetics.is_empty()
            || self
                .controls
                .iter()
                .any(|c| matches!(c.actuator, Actuator::Torquers { .. }))
    }
    /// The current mode's filter as of its last sample (`None` before the first, or
    /// without an estimator).
    pub fn filter(&self) -> Option<&super::Mekf> {
        self.estimators[self.current().estimator?].filter.as_ref()
    }
    /// The reference the current mode's guidance holds.
    pub fn reference(&self) -> Option<Reference> {
        self.guidances[self.current().guidance?].held
    }
    /// The body torque the current mode's control wanted at its last sample (N m, body
    /// axes).
    pub fn control_torque(&self) -> Option<[f64; 3]> {
        self.current()
            .control
            .map(|c| self.controls[c].torque.into())
    }
    /// Whether a control commands the thrusters.
    pub fn commands_thrusters(&self) -> bool {
        self.controls
            .iter()
            .any(|c| matches!(c.actuator, Actuator::Thrusters))
    }
    /// The duties commanded to the thrusters (one per thruster of [`Links::thrusters`], each
    /// in [0, 1]) as of the last sample: the current mode's thruster control's, zeros
    /// where the current mode runs none (so that a mode that stops the control stops the
    /// thrusters from their next period start). Empty when no control commands them.
    pub fn thrust_commands(&self) -> &[f64] {
        &self.thrust
    }
    /// Whether a control commands the wheels.
    pub fn commands_rotors(&self) -> bool {
        self.controls
            .iter()
            .any(|c| matches!(c.actuator, Actuator::Wheels(_)))
    }
    /// What the blocks need of the scene.
    pub fn needs(&self) -> Needs {
        Needs {
            orbit: self.guidances.iter().any(|g| g.law.needs_orbit()),
            rotors: self.commands_rotors(),
            free_base: !self.controls.is_empty(),
            com: self.commands_thrusters(),
            ..Needs::default()
        }
    }
    /// The next control sample (`∞` without a control; the other blocks run on the
    /// sensors' samples).
    pub fn next_sample(&self) -> f64 {
        self.controls
            .iter()
            .fold(f64::INFINITY, |m, c| m.min(c.clock.next()))
    }
    /// The actuators' axes and indices from the simulation.
    pub fn connect(&mut self, links: &Links) {
        for c in &mut self.controls {
            c.targets.clear();
            let mut axes = Vec::new();
            let mut limits = Vec::new();
            match &c.actuator {
                Actuator::Wheels(wheels) => {
                    for (name, max) in wheels {
                        if let Some(j) = links.rotors.iter().position(|r| &r.name == name) {
                            c.targets.push(j);
                            axes.push(links.rotors[j].nominal);
                            limits.push(*max);
                        }
                    }
                    c.pid.allocate(&axes, &limits);
                    c.held = vec![0.0; links.rotors.len()];
                }
                Actuator::Torquers { .. } => {
                    for (j, t) in links.torquers.iter().enumerate() {
                        if t.body == 0 {
                            c.targets.push(j);
                            axes.push(t.axis);
                            limits.push(t.max_dipole);
                        }
                    }
                    c.pid.allocate(&[], &[]);
                    c.dipoles = Allocation::new(&axes, &limits);
                    c.held = vec![0.0; links.torquers.len()];
                }
                Actuator::Thrusters => {
                    let (mut at, mut thrust) = (Vec::new(), Vec::new());
                    for (j, t) in links.thrusters.iter().enumerate() {
                        if t.body == 0 {
                            c.targets.push(j);
                            at.push(t.at);
                            axes.push(t.nominal);
                            thrust.push(t.thrust);
                        }
                    }
                    c.pid.allocate(&[], &[]);
                    c.thrust = ThrustAllocation::new(&at, &axes, &thrust);
                    c.held = vec![0.0; links.thrusters.len()];
                }
            }
            c.scratch = vec![0.0; c.targets.len()];
        }
        for m in &mut self.magnetics {
            m.connect(links);
        }
        self.thrust = if self.commands_thrusters() {
            vec![0.0; links.thrusters.len()]
        } else {
            Vec::new()
        };
    }

    /// Runs the current mode's blocks due at `ctx.t`, after the sensors took their samples
    /// there, then checks its condition.
    pub fn sample(&mut self, ctx: &Context, sensors: &[Sensor]) -> Result<(), SystemError> {
        let t = ctx.t;
        let mode = self.modes[self.mode].clone();
        let mut estimated = false;
        if let Some(e) = mode.estimator {
            estimated = self.estimators[e]
                .sample(t, sensors, ctx.orbit.as_ref())
                .map_err(|m| SystemError::new(format!("fsw.estimator at t = {t} s: {m}")))?;
        }
        let control_due = mode
            .control
            .is_some_and(|c| stop_due(t, self.controls[c].clock.next()));
        if let Some(g) = mode.guidance
            && (control_due || (mode.control.is_none() && estimated))
        {
            let dt = match mode.control {
                Some(c) => self.controls[c].clock.period(),
                None => mode
                    .estimator
                    .map_or(0.0, |e| self.estimators[e].spec.period),
            };
            let est = mode.estimator.map(|e| &self.estimators[e]);
            let block = &mut self.guidances[g];
            let target = block
                .law
                .reference_at(t, ctx.orbit.as_ref())
                .map_err(|m| SystemError::new(format!("fsw.guidance at t = {t} s: {m}")))?;
            block.target = Some(target);
            block.held = Some(match &mut block.slew {
                Some(slew) => {
                    if block.restart {
                        block.restart = false;
                        // From the estimate now; without one, from the law's reference.
                        match est.and_then(|e| Some((e.filter.as_ref()?, e.rate()?))) {
                            Some((f, w)) => slew.reset(f.unit_attitude(), w),
                            None => {
                                *slew = Slew::new(slew.max_rate(), slew.max_acceleration())
                                    .expect("limits already checked")
                            }
                        }
                    }
                    slew.step(&target, dt)
                }
                None => target,
            });
        }
        if let Some(ci) = mode.control
            && control_due
        {
            let e = &self.estimators[mode.estimator.expect("a control has an estimator")];
            let r = self.guidances[mode.guidance.expect("a control has a guidance")]
                .held
                .expect("evaluated above");
            let c = &mut self.controls[ci];
            c.held.fill(0.0);
            c.torque = Vector3::zeros();
            if let (Some(f), Some(omega)) = (e.filter.as_ref(), e.rate()) {
                let ahead = t - e.t;
                let q = if ahead > 0.0 {
                    f.unit_attitude() * UnitQuaternion::from_scaled_axis(omega * ahead)
                } else {
                    f.unit_attitude()
                };
                // The centre of mass in the root's frame (thrusters only).
                let com = match c.actuator {
                    Actuator::Thrusters => {
                        let com = ctx.com_or_err("fsw.control")?;
                        let rot = &ctx.data.rotation[0];
                        let c0 = rot.tr_mul(&(com - ctx.data.position[0]));
                        if c.pid.ki.iter().any(|&k| k > 0.0) {
                            c.pid.set_capability(c.thrust.capability(&c0));
                        }
                        c0
                    }
                    _ => Vector3::zeros(),
                };
                c.torque = c
                    .pid
                    .torque(&q, &omega, &r.attitude, &r.rate, c.clock.period());
                match &c.actuator {
                    Actuator::Wheels(_) => c.pid.commands(&c.torque, &mut c.scratch),
                    Actuator::Torquers { magnetometer } => {
                        let b = reading3(&sensors[*magnetometer]);
                        let b2 = b.norm_squared();
                        let m = if b2 > 0.0 {
                            b.cross(&c.torque) / b2
                        } else {
                            Vector3::zeros()
                        };
                        c.dipoles.solve(&m, &mut c.scratch);
                    }
                    Actuator::Thrusters => c.thrust.duties(&com, &c.torque, &mut c.scratch),
                }
                for (&j, &cmd) in c.targets.iter().zip(&c.scratch) {
                    c.held[j] = cmd;
                }
            }
        }
        // Every control's clock moves on, running or not, so that none is ever behind.
        for c in &mut self.controls {
            if stop_due(t, c.clock.next()) {
                c.clock.taken(t);
            }
        }
        if let Some(m) = mode.magnetic {
            self.magnetics[m].sample(sensors, ctx.rotor_rates);
        }
        self.check_mode(t, sensors);
        if !self.thrust.is_empty() {
            self.thrust.fill(0.0);
            if let Some(c) = self.current().control
                && matches!(self.controls[c].actuator, Actuator::Thrusters)
            {
                self.thrust.copy_from_slice(&self.controls[c].held);
            }
        }
        Ok(())
    }

    /// The current mode's condition, then the switch when it has held long enough.
    fn check_mode(&mut self, t: f64, sensors: &[Sensor]) {
        let mode = &self.modes[self.mode];
        let Some(until) = mode.until else {
            return;
        };
        let est = mode.estimator.map(|e| &self.estimators[e]);
        let rate = match (est.and_then(|e| e.rate()), mode.gyro) {
            (Some(w), _) => Some(w.norm()),
            (None, Some(g)) if sensors[g].samples_taken() > 0 => Some(reading3(&sensors[g]).norm()),
            _ => None,
        };
        let error = match (est.and_then(|e| e.filter.as_ref()), mode.guidance) {
            (Some(f), Some(g)) => self.guidances[g]
                .target
                .map(|r| log_rotation(&(r.attitude.inverse() * f.unit_attitude())).norm()),
            _ => None,
        };
        if !until.holds(rate, error, t - self.since) {
            self.holding = None;
            return;
        }
        let from = *self.holding.get_or_insert(t);
        if t - from < mode.hold {
            return;
        }
        let seen = match until {
            Condition::RateBelow(_) => format!("rate {} rad/s", rate.unwrap_or(f64::NAN)),
            Condition::ErrorBelow(_) => format!("error {} rad", error.unwrap_or(f64::NAN)),
            Condition::TimeAfter(_) => format!("{} s in the mode", t - self.since),
        };
        let next = self.mode + 1;
        self.log.push(format!(
            "fsw mode {next} `{}` after `{}`: {until} ({seen})",
            self.modes[next].name, mode.name
        ));
        self.switch(next, t, sensors);
    }

    /// Makes mode `next` the current one at `t`: the blocks not in both start afresh.
    fn switch(&mut self, next: usize, t: f64, sensors: &[Sensor]) {
        let (a, b) = (&self.modes[self.mode], &self.modes[next]);
        let fresh = |x: Option<usize>, y: Option<usize>, i: usize| x != Some(i) || y != Some(i);
        for (i, e) in self.estimators.iter_mut().enumerate() {
            if fresh(a.estimator, b.estimator, i) {
                e.reset(sensors);
            }
        }
        for (i, g) in self.guidances.iter_mut().enumerate() {
            if fresh(a.guidance, b.guidance, i) {
                g.held = None;
                g.target = None;
                g.restart = true;
            }
        }
        for (i, c) in self.controls.iter_mut().enumerate() {
            if fresh(a.control, b.control, i) {
                c.reset();
            }
        }
        for (i, m) in self.magnetics.iter_mut().enumerate() {
            if fresh(a.magnetic, b.magnetic, i) {
                m.reset(sensors);
            }
        }
        self.mode = next;
        self.since = t;
        self.holding = None;
    }

    /// Moves the mode switches not yet logged into `out`.
    pub fn drain_log(&mut self, out: &mut Vec<String>) {
        out.append(&mut self.log);
    }

    /// Writes the held commands of the current mode: the wheels' (set) and the torquers'
    /// (added).
    pub fn apply(&self, forces: &mut Forces) {
        let mode = self.current();
        if let Some(c) = mode.control {
            let c = &self.controls[c];
            match c.actuator {
                Actuator::Wheels(_) => {
                    for (out, held) in forces.rotor_command.iter_mut().zip(&c.held) {
                        *out = *held;
                    }
                }
                Actuator::Torquers { .. } => {
                    for (out, held) in forces.dipole_command.iter_mut().zip(&c.held) {
                        *out += *held;
                    }
                }
                // The duties leave through `thrust_commands`, latched by the thrusters.
                Actuator::Thrusters => {}
            }
        }
        if let Some(m) = mode.magnetic {
            self.magnetics[m].apply(forces);
        }
    }

    /// The output columns (see the module documentation).
    pub fn columns(&self) -> Vec<String> {
        let mut c = Vec::new();
        let add = |c: &mut Vec<String>, p: &str, s: &[&str]| {
            c.extend(s.iter().map(|s| format!("{p}_{s}")));
        };
        if !self.estimators.is_empty() {
            add(&mut c, "est_q", &["w", "x", "y", "z"]);
            add(&mut c, "est_bias", &["x", "y", "z"]);
            add(&mut c, "est_sigma", &["x", "y", "z"]);
            c.push("est_error".into());
        }
        if !self.guidances.is_empty() {
            add(&mut c, "ref_q", &["w", "x", "y", "z"]);
            add(&mut c, "ref_omega", &["x", "y", "z"]);
            add(&mut c, "ref_alpha", &["x", "y", "z"]);
            c.push("pointing_error".into());
        }
        if !self.magnetics.is_empty() {
            add(&mut c, "fsw_dipole", &["x", "y", "z"]);
        }
        if self.moded {
            c.push("fsw_mode".into());
        }
        c
    }

    /// The columns' values at `ctx` of what the blocks hold (at a sample instant, call it on
    /// the copy that sampled there).
    pub fn output(&self, ctx: &Context, row: &mut Vec<f64>) {
        let mode = self.current();
        if !self.estimators.is_empty() {
            let est = mode.estimator.map(|e| &self.estimators[e]);
            match est.and_then(|e| Some((e, e.filter.as_ref()?))) {
                Some((e, f)) => {
                    let truth = Pose::of(ctx, e.spec.body).attitude;
                    row.extend_from_slice(&f.attitude());
                    row.extend_from_slice(&f.bias());
                    row.extend_from_slice(&f.sigma_attitude());
                    row.push(log_rotation(&(f.unit_attitude().inverse() * truth)).norm());
                }
                None => row.extend_from_slice(&[0.0; 11]),
            }
        }
        if !self.guidances.is_empty() {
            let body = mode.estimator.map_or(0, |e| self.estimators[e].spec.body);
            match mode.guidance.and_then(|g| self.guidances[g].held) {
                Some(r) => {
                    let truth = Pose::of(ctx, body).attitude;
                    let q = r.attitude.quaternion();
                    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
                    row.extend_from_slice(&[s * q.w, s * q.i, s * q.j, s * q.k]);
                    row.extend_from_slice(r.rate.as_slice());
                    row.extend_from_slice(r.acceleration.as_slice());
                    row.push(log_rotation(&(r.attitude.inverse() * truth)).norm());
                }
                None => row.extend_from_slice(&[0.0; 11]),
            }
        }
        if !self.magnetics.is_empty() {
            let d = self.dipole().unwrap_or([0.0; 3]);
            row.extend_from_slice(&d);
        }
        if self.moded {
            row.push(self.mode as f64);
        }
    }

    /// The current mode's guidance law's reference at `t` and an orbit, unshaped (for
    /// checks against it).
    pub fn reference_at(
        &self,
        t: f64,
        orbit: Option<&crate::effects::OrbitState>,
    ) -> Option<Reference> {
        self.guidances[self.current().guidance?]
            .law
            .reference_at(t, orbit)
            .ok()
    }
}

fn reading3(s: &Sensor) -> Vector3<f64> {
    let r = s.last_reading();
    Vector3::new(r[0], r[1], r[2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fsw::estimator::tests::spec;

    fn control() -> ControlSpec {
        ControlSpec {
            pid: Pid::new([1.0; 3], [0.0; 3], [1.0; 3], None),
            period: 0.1,
            actuator: Actuator::Wheels(vec![("wheel_x".into(), 1.0)]),
        }
    }

    #[test]
    fn a_block_without_what_it_reads_is_refused_and_the_columns_follow_the_blocks() {
        let inertial = Guidance::Inertial(UnitQuaternion::identity());
        let mut g = Onboard::new();
        g.add_guidance(inertial, None);
        assert!(g.finish().is_err());
        let mut c = Onboard::new();
        c.add_estimator(spec());
        c.add_control(control()).unwrap();
        assert!(c.finish().is_err());
        let mut est = Onboard::new();
        est.add_estimator(spec());
        let est = est.finish().unwrap();
        assert_eq!(est.columns().len(), 11);
        assert!(!est.commands_rotors() && est.next_sample() == f64::INFINITY);
        let mut all = Onboard::new();
        all.add_estimator(spec());
        all.add_guidance(inertial, None);
        all.add_control(control()).unwrap();
        let all = all.finish().unwrap();
        assert_eq!(all.columns().len(), 22);
        assert!(all.commands_rotors() && all.needs().rotors && !all.needs().orbit);
        assert_eq!(all.next_sample(), f64::NEG_INFINITY);
        // Two of a kind need modes.
        let mut two = Onboard::new();
        two.add_estimator(spec());
        two.add_estimator(spec());
        assert!(two.finish().unwrap_err().contains("2 estimator blocks"));
    }

    #[test]
    fn modes_are_checked_as_they_are_added() {
        let mut o = Onboard::new();
        let e = o.add_estimator(spec());
        let g = o.add_guidance(Guidance::Inertial(UnitQuaternion::identity()), None);
        let c = o.add_control(control()).unwrap();
        let bad = |o: &mut Onboard, m: Mode| o.clone().add_mode(m).unwrap_err();
        let m = |until| Mode {
            until,
            ..Mode::new("m")
        };
        assert!(
            bad(
                &mut o,
                Mode {
                    guidance: Some(g),
                    ..m(None)
                }
            )
            .contains("without an estimator")
        );
        assert!(
            bad(
                &mut o,
                Mode {
                    estimator: Some(e),
                    control: Some(c),
                    ..m(None)
                }
            )
            .contains("without an estimator and a guidance")
        );
        assert!(bad(&mut o, m(Some(Condition::RateBelow(0.1)))).contains("needs a gyro"));
        assert!(bad(&mut o, m(Some(Condition::ErrorBelow(0.1)))).contains("needs an estimator"));
        assert!(
            bad(
                &mut o,
                Mode {
                    estimator: Some(3),
                    ..m(None)
                }
            )
            .contains("no estimator 3")
        );
        o.add_mode(m(None)).unwrap();
        assert!(bad(&mut o, m(None)).contains("never begin"));
        let mut p = Onboard::new();
        p.add_mode(m(Some(Condition::TimeAfter(1.0)))).unwrap();
        assert!(p.finish().unwrap_err().contains("no mode follows"));
    }

    #[test]
    fn a_magnetic_block_adds_the_dipole_columns_and_has_the_sensors_command_the_torquers() {
        use crate::effects::Effect;
        use crate::fsw::{DipoleLaw, DipoleSpec};
        let spec = DipoleSpec {
            law: DipoleLaw::Bdot { gain: 1e6 },
            magnetometer: 0,
            period: 1.0,
            every: 1,
            wheels: Vec::new(),
        };
        let mut b = Onboard::new();
        b.add_magnetic(spec);
        let b = b.finish().unwrap();
        assert_eq!(
            b.columns(),
            ["fsw_dipole_x", "fsw_dipole_y", "fsw_dipole_z"]
        );
        assert!(b.commands_dipoles() && !b.commands_rotors());
        assert_eq!(b.dipole(), Some([0.0; 3]));
        let mut set = crate::sensors::Sensors::new(1);
        assert!(set.observes_only() && !set.commands_dipoles());
        set.set_fsw(b);
        assert!(!set.observes_only() && set.commands_dipoles());
        assert_eq!(set.before(), ["magnetic"]);
    }
}
