//! Reaction wheels, any number, as axisymmetric rotor bodies in the tree.
//!
//! Each wheel is a rotor hinged to the bus (the root) about its axis; its spin rate relative
//! to the bus, `Ω`, is the wheel's state. Because a rotor is axisymmetric about its axis (and
//! its centre of mass lies on it), the dynamics do not depend on its angle, which is not a
//! state. The motor torque acts on the rotor about the axis and reacts on the bus, exactly
//! like a hinge torque: the articulated-body algorithm then gives the exact coupled motion
//! (the preprint's momentum-exchange form `M_rw = −Ḣ − ω × H` is what this reduces to when
//! the rotors' transverse inertia is lumped into the bus), and the kinetic energy and
//! angular momentum of the tree include the wheels with no special case.
//!
//! Friction (preprint section 2): `I dΩ/dt = τ − (α0 + α1 exp(−(Ω/Ω0)²)) sgn Ω − α2 Ω`.
//! The sign discontinuity at `Ω = 0` is treated as stick/slip with events (Karnopp's
//! model made exact), not smoothed:
//!
//! - while a wheel slips, `sgn Ω` is replaced by its **slip direction** `d = ±1`, held
//!   constant between events, so that the right-hand side is smooth inside a slip phase and
//!   the integrators keep their order (a sign that flips inside a step would cost them it);
//! - a slipping wheel whose speed crosses zero against `d` (event `d·Ω = 0`, falling) is
//!   examined there: the **hold torque** `H`, the total torque its hinge must receive to stay
//!   at rest with everything else moving as it does (hybrid dynamics + RNEA, see
//!   [`Context::hold_torque`]), gives the friction needed to stick, `H − τ`. If
//!   `|H − τ| ≤ α0 + α1` the wheel sticks: its hinge is locked (a momentum-conserving
//!   impulse removes the residual rate, of the size of the event tolerance) and it stays at
//!   rest; otherwise it slips on with `d = sgn(τ − H)`;
//! - a stuck wheel breaks free when the friction it needs exceeds the static friction
//!   (event `α0 + α1 − |H − τ| = 0`), and slips in the direction `sgn(τ − H)`.
//!
//! The hold torque includes the rotor's inertial reaction to the bus's motion, so neither
//! decision is fooled by it (comparing `τ` alone with the static friction is not enough: a
//! wheel released with `|τ|` barely above it can be driven backwards by the bus and would
//! chatter about zero speed). Wheels without Coulomb or Stribeck friction have no events.
//!
//! Limits: the command is clamped to `±max_torque`; a wheel at or beyond `max_speed` gets
//! no torque that would speed it up further. The speed limit is a discontinuity of the
//! motor torque too, and is treated with events and a mode held between them in the same
//! way (cutting the torque wherever `|Ω| ≥ max_speed` made the adaptive integrators chatter
//! on the limit: a wheel driven into it slowed by friction, got its torque back, sped up,
//! lost it, and a run stalled on millions of rejected steps):
//!
//! - each wheel with `0 < max_speed < ∞` is **inside** its limits or **at** one, `s = ±1`
//!   (`s·Ω ≥ max_speed`), a mode held between events; at a limit, a command `c` with
//!   `c·s > 0` gives no torque. Inside, the event is `max_speed − |Ω| = 0` (falling: the
//!   wheel reaches a limit), at a limit `s·Ω − max_speed = 0` (falling: it leaves it);
//! - a wheel that reaches a limit with a command that would drive it further is **held**
//!   there when the motor can do it, as a speed controller would: with `H` its hold torque
//!   and `f` its friction, the motor torque that keeps its speed, `τₘ = H + f`, must lie
//!   between 0 and the command (`0 ≤ s·τₘ ≤ s·c`). A held wheel's hinge is locked at its
//!   limit speed (the sliding motion of the limit, made exact) until the command falls
//!   below `τₘ` (it slows down with the command's torque) or `τₘ` changes sign (the bus
//!   drives it beyond the limit with no motor torque): event
//!   `min(s·(c − τₘ), s·τₘ) = 0`, falling. Both releases leave the motor torque continuous.
//!
//! A wheel with `max_speed` 0 keeps the plain rule (no torque that speeds it up).
//!
//! Faults ([`super::faults`]): a `wheel_off` wheel's motor gives no torque (its speed-limit
//! events then stay off; friction goes on); a `wheel_stuck` wheel's hinge is locked for good
//! by a momentum-conserving impulse, with no stick/slip or speed-limit events. Each fault's
//! time is a stop where its event function falls through zero, so that the simulation
//! carries out the lock as it does a stiction's.

use super::faults::{FaultKind, Schedule};
use super::{
    Context, EVENT_TEXT, Effect, EventReads, Forces, HoldReads, Links, Needs, Power, Request,
    Rotor, SceneEffect, Section, set_text,
};
use satsim_integrate::{EventAction, EventDirection, SystemError};
use satsim_tree::io::{FileError, exact};
use satsim_tree::spatial::Vec3;
use serde::Deserialize;
use toml::Spanned;

/// One reaction wheel.
#[derive(Clone, Debug, PartialEq)]
pub struct Wheel {
    /// Name (the rotor body is `wheel_<name>`).
    pub name: String,
    /// The body that carries it (`None`: the bus, the root). A wheel on a gimbal body driven
    /// by a hinge controller is a control-moment gyro.
    pub body: Option<String>,
    /// Unit spin axis as designed, the carrier's axes (what the flight software assumes).
    pub axis: Vec3,
    /// Rotation vector of the mounting error (rad, the carrier's axes): the true spin axis is
    /// `exp([r]×) axis`. `None`: mounted as designed.
    pub misalignment: Option<Vec3>,
    /// Centre of the rotor in the carrier's frame (m).
    pub at: Vec3,
    /// Rotor mass (kg; default 0, the wheel's mass being part of the bus).
    pub mass: f64,
    /// Axial moment of inertia (kg m², > 0).
    pub inertia: f64,
    /// Transverse moment of inertia (kg m²; `>= inertia / 2`).
    pub transverse: f64,
    /// Largest motor torque (N m).
    pub max_torque: f64,
    /// Largest speed the motor drives the wheel to (rad/s).
    pub max_speed: f64,
    /// Coulomb friction α0 (N m).
    pub coulomb: f64,
    /// Stribeck friction α1 (N m).
    pub stribeck: f64,
    /// Stribeck speed Ω0 (rad/s, > 0 when α1 > 0).
    pub stribeck_speed: f64,
    /// Viscous friction α2 (N m s/rad).
    pub viscous: f64,
    /// Initial speed relative to the bus (rad/s).
    pub speed: f64,
    /// Constant motor torque when no controller commands the wheel (N m).
    pub torque: f64,
}

impl Wheel {
    /// A frictionless, unlimited wheel at rest.
    pub fn new(name: impl Into<String>, axis: Vec3, inertia: f64) -> Self {
        Self {
            name: name.into(),
            body: None,
            axis: axis.normalize(),
            misalignment: None,
            at: Vec3::zeros(),
            mass: 0.0,
            inertia,
            transverse: 0.5 * inertia,
            max_torque: f64::INFINITY,
            max_speed: f64::INFINITY,
            coulomb: 0.0,
            stribeck: 0.0,
            stribeck_speed: 1.0,
            viscous: 0.0,
            speed: 0.0,
            torque: 0.0,
        }
    }
    /// The true spin axis (unit, the carrier's axes): the designed one turned by the
    /// misalignment.
    pub fn true_axis(&self) -> Vec3 {
        match self.misalignment {
            Some(r) => nalgebra::UnitQuaternion::from_scaled_axis(r) * self.axis,
            None => self.axis,
        }
    }
    /// Static friction `α0 + α1` (N m).
    pub fn static_friction(&self) -> f64 {
        self.coulomb + self.stribeck
    }
    /// The friction torque at speed `omega` while slipping in direction `dir` (±1; it takes
    /// the place of `sgn Ω`, see the module's documentation).
    pub fn friction(&self, omega: f64, dir: f64) -> f64 {
        let s = dir;
        let stribeck = if self.stribeck != 0.0 {
            let x = omega / self.stribeck_speed;
            self.stribeck * (-x * x).exp()
        } else {
            0.0
        };
        (self.coulomb + stribeck) * s + self.viscous * omega
    }
    /// The motor torque after the torque and speed limits, the limit decided by the
    /// speed `omega` itself (what [`ReactionWheels`] does for a wheel with `max_speed` 0;
    /// the others hold the limit's side as a mode between events).
    pub fn limited(&self, command: f64, omega: f64) -> f64 {
        let t = command.clamp(-self.max_torque, self.max_torque);
        if omega.abs() >= self.max_speed && t * omega > 0.0 {
            0.0
        } else {
            t
        }
    }
    /// Whether the wheel, uncommanded, adds no torque at all: no constant motor torque and
    /// no friction.
    fn idle(&self) -> bool {
        self.torque == 0.0 && self.coulomb == 0.0 && self.stribeck == 0.0 && self.viscous == 0.0
    }
    /// Whether the speed limit is handled with events (`0 < max_speed < ∞`).
    fn limit_events(&self) -> bool {
        self.max_speed > 0.0 && self.max_speed.is_finite()
    }
}

/// The reaction-wheel effect.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ReactionWheels {
    /// The wheels.
    pub wheels: Vec<Wheel>,
    /// Whether a controller writes the commands into [`Forces::rotor_command`] (otherwise
    /// each wheel's `torque`); set when the simulation is built ([`Effect::connect`]).
    /// Either way [`Forces::rotor_input`] (the stepping API's held inputs) is added to the
    /// command before the limits.
    pub commanded: bool,
    /// Set when the simulation is built ([`Effect::connect`]): no controller commands the
    /// wheels and every wheel is [`Wheel::idle`] (free wheels that only carry momentum, as
    /// in the peer benchmark), so `apply` adds nothing while no stepping input is held.
    pub(crate) idle: bool,
    stuck: Vec<bool>,
    /// Slip direction of each slipping wheel (±1).
    dir: Vec<f64>,
    motor: Vec<f64>,
    /// The speed limit each wheel is at (±1) or 0 inside its limits (wheels with
    /// [`Wheel::limit_events`]; see the module documentation).
    side: Vec<f64>,
    /// Whether each wheel is held at its speed limit (its hinge locked there).
    held: Vec<bool>,
    last: String,
    /// Faults on the wheels ([`super::faults`]): each a time stop, and an event function
    /// (after the stick/slip and speed-limit ones) that falls through zero when its stop
    /// marks it due, so that it is carried out as an event (a seized wheel's lock is an
    /// impulse).
    faults: Schedule,
    /// Whether each wheel's motor gives no torque (a `wheel_off` or `wheel_stuck` fault).
    motor_off: Vec<bool>,
    /// Whether each wheel is seized (`wheel_stuck`): its hinge locked for good.
    seized: Vec<bool>,
}

impl ReactionWheels {
    /// The effect for these wheels.
    pub fn new(wheels: Vec<Wheel>) -> Self {
        let n = wheels.len();
        Self {
            wheels,
            commanded: false,
            idle: false,
            stuck: vec![false; n],
            dir: vec![1.0; n],
            motor: vec![0.0; n],
            side: vec![0.0; n],
            held: vec![false; n],
            last: String::with_capacity(EVENT_TEXT),
            faults: Schedule::default(),
            motor_off: vec![false; n],
            seized: vec![false; n],
        }
    }
    /// Adds the fault `kind` (`wheel_stuck` or `wheel_off`) on wheel `target` (index in
    /// `wheels`) at `at` (s, finite, >= 0); refused, with the reason, otherwise.
    pub fn add_fault(&mut self, at: f64, target: usize, kind: FaultKind) -> Result<(), String> {
        if target >= self.wheels.len() {
            return Err(format!("no wheel {target}"));
        }
        if !(at.is_finite() && at >= 0.0) {
            return Err(format!("`at` must be a finite time >= 0 (s), got {at}"));
        }
        if !matches!(kind, FaultKind::WheelStuck | FaultKind::WheelOff) {
            return Err(format!("a wheel cannot have a `{}` fault", kind.name()));
        }
        self.faults.push(at, target, kind);
        Ok(())
    }
    /// Whether wheel `j` is seized (a `wheel_stuck` fault happened).
    pub fn is_seized(&self, j: usize) -> bool {
        self.seized[j]
    }
    /// The event functions before the faults' (stick/slip, then speed limits).
    fn n_mode_events(&self) -> usize {
        self.n_stick_events()
            + if self.has_limits() {
                self.wheels.len()
            } else {
                0
            }
    }
    /// Carries out fault `k` at its event (its stop marked it due).
    fn on_fault(&mut self, k: usize, ctx: &Context, own: &[f64], requests: &mut Vec<Request>) {
        let f = &self.faults.list()[k];
        let j = f.target;
        let name = &self.wheels[j].name;
        self.motor_off[j] = true;
        self.motor[j] = 0.0;
        self.side[j] = 0.0;
        let h = ctx.rotor_hinge(j);
        if f.kind == FaultKind::WheelStuck {
            // The impulse that locks the hinge removes the speed, conserving momentum.
            let lost = own[j];
            (self.seized[j], self.stuck[j], self.held[j]) = (true, false, false);
            requests.push(Request::Lock(h));
            set_text(
                &mut self.last,
                format_args!("fault: wheel `{name}` stuck (speed {lost} rad/s lost)"),
            );
            return;
        }
        if self.held[j] {
            self.held[j] = false;
            requests.push(Request::Unlock(h));
        }
        set_text(
            &mut self.last,
            format_args!("fault: wheel `{name}` off (its motor gives no torque)"),
        );
    }
    /// Whether wheel `j` is stuck (at rest under static friction).
    pub fn is_stuck(&self, j: usize) -> bool {
        self.stuck[j]
    }
    /// Whether wheel `j` is held at its speed limit.
    pub fn is_held(&self, j: usize) -> bool {
        self.held[j]
    }
    fn has_stiction(&self) -> bool {
        self.wheels.iter().any(|w| w.static_friction() > 0.0)
    }
    fn has_limits(&self) -> bool {
        self.wheels.iter().any(Wheel::limit_events)
    }
    /// Events before the speed limits' (one per wheel with stiction anywhere, else none).
    fn n_stick_events(&self) -> usize {
        if self.has_stiction() {
            self.wheels.len()
        } else {
            0
        }
    }
    /// The motor torque of wheel `j` for the command `c` at speed `omega` in its mode.
    fn torque(&self, j: usize, c: f64, omega: f64) -> f64 {
        let w = &self.wheels[j];
        if self.motor_off[j] {
            return 0.0;
        }
        if !w.limit_events() {
            return w.limited(c, omega);
        }
        let t = c.clamp(-w.max_torque, w.max_torque);
        if t * self.side[j] > 0.0 { 0.0 } else { t }
    }
    /// The clamped command of wheel `j` (before the speed limit).
    fn clamped(&self, j: usize, forces: &Forces) -> f64 {
        let w = &self.wheels[j];
        let c = if self.commanded {
            forces.rotor_command[j]
        } else {
            w.torque
        } + forces.rotor_input.get(j).copied().unwrap_or(0.0);
        c.clamp(-w.max_torque, w.max_torque)
    }
    /// The motor torque that keeps wheel `j` at its speed `omega`: `τₘ = H + f` (NaN if
    /// the hold torque is unknown).
    fn holding_torque(&self, j: usize, ctx: &Context, omega: f64) -> f64 {
        ctx.hold_torque[ctx.rotor_hinge(j)] + self.wheels[j].friction(omega, self.dir[j])
    }
    /// Wheel `j` at its limit `s` (speed `s·max_speed`): held there when the command drives
    /// it outwards and the motor can keep its speed (`0 ≤ s·τₘ ≤ s·c`), otherwise at the
    /// limit (no torque outwards) when the bus drives it beyond, otherwise inside.
    fn settle_at_limit(
        &mut self,
        j: usize,
        s: f64,
        ctx: &Context,
        forces: &Forces,
        omega: f64,
        requests: &mut Vec<Request>,
    ) {
        let c = self.clamped(j, forces);
        let tm = self.holding_torque(j, ctx, omega);
        let name = &self.wheels[j].name;
        let limit = s * self.wheels[j].max_speed;
        if c * s > 0.0 && s * tm >= 0.0 && s * tm <= s * c {
            self.held[j] = true;
            self.side[j] = s;
            requests.push(Request::Hold {
                hinge: ctx.rotor_hinge(j),
                rate: limit,
            });
            set_text(
                &mut self.last,
                format_args!(
                    "wheel `{name}` reached its speed limit {limit} rad/s and is held there ({tm:.4} N m of {c:.4} commanded)"
                ),
            );
        } else if s * tm < 0.0 {
            self.side[j] = s;
            set_text(
                &mut self.last,
                format_args!("wheel `{name}` is driven beyond its speed limit {limit} rad/s"),
            );
        } else {
            self.side[j] = 0.0;
            set_text(
                &mut self.last,
                format_args!("wheel `{name}` is inside its speed limits"),
            );
        }
    }
    /// The friction wheel `j` needs to stay at rest, `H − τ` (NaN if the hold torque is
    /// unknown).
    fn needed_friction(&self, j: usize, ctx: &Context, forces: &Forces) -> f64 {
        ctx.hold_torque[ctx.rotor_hinge(j)] - self.command(j, forces, 0.0)
    }
    fn command(&self, j: usize, forces: &Forces, omega: f64) -> f64 {
        let c = if self.commanded {
            forces.rotor_command[j]
        } else {
            self.wheels[j].torque
        } + forces.rotor_input.get(j).copied().unwrap_or(0.0);
        self.torque(j, c, omega)
    }
}

impl Effect for ReactionWheels {
    fn name(&self) -> &str {
        "reaction_wheels"
    }
    fn needs(&self) -> Needs {
        Needs {
            hold_torques: self.has_stiction() || self.has_limits(),
            ..Needs::default()
        }
    }
    fn n_states(&self) -> usize {
        self.wheels.len()
    }
    fn state_names(&self) -> Vec<String> {
        self.wheels
            .iter()
            .map(|w| format!("wheel_{}_speed", w.name))
            .collect()
    }
    fn initial_state(&self, own: &mut [f64]) {
        for (o, w) in own.iter_mut().zip(&self.wheels) {
            *o = w.speed;
        }
    }
    fn rotors(&self) -> Vec<Rotor> {
        self.wheels
            .iter()
            .map(|w| Rotor {
                name: format!("wheel_{}", w.name),
                body: w.body.clone(),
                axis: w.true_axis(),
                nominal: w.axis,
                at: w.at,
                mass: w.mass,
                axial: w.inertia,
                transverse: w.transverse,
            })
            .collect()
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let n = ctx.rotor_hinge(0);
        // Inputs of `+0.0` (the bits: a `-0.0` could make a motor torque of `-0.0`).
        if self.idle && forces.rotor_input.iter().all(|u| u.to_bits() == 0) {
            // What the loop below computes for such wheels, without its branches: a motor
            // torque of +0 and a friction of ±0, so each free rotor's torque gets `+ 0.0`
            // (kept: it turns a `-0.0` into `+0.0`, as the loop does).
            self.motor.fill(0.0);
            let rotors = forces.hinge_torque[n..].iter_mut().zip(&ctx.locked[n..]);
            for (torque, &locked) in rotors {
                if !locked {
                    *torque += 0.0;
                }
            }
            return Ok(());
        }
        // Zipped rather than indexed: no bounds checks per wheel.
        let rotors = forces.hinge_torque[n..].iter_mut().zip(&ctx.locked[n..]);
        let commands = &forces.rotor_command;
        let inputs = &forces.rotor_input;
        let (side, off) = (&self.side, &self.motor_off);
        let wheels = self
            .wheels
            .iter()
            .zip(own)
            .zip(&mut self.motor)
            .zip(&self.dir);
        for (j, ((((w, &omega), motor), &dir), (torque, &locked))) in wheels.zip(rotors).enumerate()
        {
            let c = if self.commanded {
                commands[j]
            } else {
                w.torque
            } + inputs.get(j).copied().unwrap_or(0.0);
            let tau = if off[j] {
                0.0
            } else if !w.limit_events() {
                w.limited(c, omega)
            } else {
                let t = c.clamp(-w.max_torque, w.max_torque);
                if t * side[j] > 0.0 { 0.0 } else { t }
            };
            *motor = tau;
            if !locked {
                *torque += tau - w.friction(omega, dir);
            }
        }
        Ok(())
    }
    /// The motors' power `τ Ω` is an actuator's, the friction's `f Ω` is dissipated (a
    /// stuck wheel gets neither).
    fn power(&self, ctx: &Context, own: &[f64], _applied: f64) -> Power {
        let mut p = Power::default();
        for (j, w) in self.wheels.iter().enumerate() {
            let omega = own[j];
            if !ctx.locked[ctx.rotor_hinge(j)] {
                p.actuator += self.motor[j] * omega;
                p.dissipated += w.friction(omega, self.dir[j]) * omega;
            } else if self.held[j] {
                // The simulation books the locked hinge's work `H Ω`; the motor also
                // supplies the friction's loss, `τₘ Ω = H Ω + f Ω`.
                let loss = w.friction(omega, self.dir[j]) * omega;
                p.actuator += loss;
                p.dissipated += loss;
            }
        }
        p
    }

    fn connect(&mut self, links: &Links) {
        self.commanded = links.rotors_commanded;
        self.idle = !self.commanded && self.wheels.iter().all(Wheel::idle);
    }
    fn output_columns(&self) -> Vec<String> {
        self.wheels
            .iter()
            .map(|w| format!("wheel_{}_torque", w.name))
            .collect()
    }
    fn output(&self, _ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        row.extend_from_slice(&self.motor);
    }
    fn start(
        &mut self,
        ctx: &Context,
        forces: &Forces,
        own: &[f64],
        requests: &mut Vec<Request>,
    ) -> Result<(), SystemError> {
        // Room for the events' descriptions (a clone keeps none): no allocation at an event.
        self.last.reserve(EVENT_TEXT);
        for (j, &speed) in own.iter().enumerate().take(self.wheels.len()) {
            let (limited, max) = (self.wheels[j].limit_events(), self.wheels[j].max_speed);
            if limited && speed.abs() >= max {
                self.dir[j] = speed.signum();
                self.settle_at_limit(j, speed.signum(), ctx, forces, speed, requests);
                if !self.held[j] && speed.abs() > max {
                    // Beyond the limit from the start: at it until it comes back.
                    self.side[j] = speed.signum();
                }
                continue;
            }
            let fs = self.wheels[j].static_friction();
            if speed != 0.0 {
                self.dir[j] = speed.signum();
                continue;
            }
            if fs == 0.0 {
                continue;
            }
            let need = self.needed_friction(j, ctx, forces);
            if need.abs() <= fs {
                self.stuck[j] = true;
                requests.push(Request::Lock(ctx.rotor_hinge(j)));
            } else {
                self.dir[j] = (-need).signum();
            }
        }
        Ok(())
    }
    /// One stick/slip event per wheel when any has stiction, then one speed-limit event per
    /// wheel when any has a limit (see the module documentation).
    /// Then one per fault, `1` until its stop marks it due, then `-1`.
    fn n_events(&self) -> usize {
        self.n_mode_events() + self.faults.len()
    }
    fn events(&self, ctx: &Context, forces: &Forces, own: &[f64], g: &mut [f64]) {
        let nf = self.n_mode_events();
        for (g, f) in g[nf..].iter_mut().zip(self.faults.list()) {
            *g = if f.done { -1.0 } else { 1.0 };
        }
        let n = self.n_stick_events();
        if self.has_limits() {
            for (j, w) in self.wheels.iter().enumerate() {
                let s = self.side[j];
                // A motor that is off has no speed limit to keep.
                g[n + j] = if !w.limit_events() || self.motor_off[j] {
                    1.0
                } else if self.held[j] {
                    let c = self.clamped(j, forces);
                    let tm = self.holding_torque(j, ctx, own[j]);
                    (s * (c - tm)).min(s * tm)
                } else if s == 0.0 {
                    (w.max_speed - own[j]).min(w.max_speed + own[j])
                } else {
                    s * own[j] - w.max_speed
                };
            }
        }
        // Without stiction the wheels have no stick/slip events.
        if n == 0 {
            return;
        }
        for (j, w) in self.wheels.iter().enumerate() {
            let fs = w.static_friction();
            g[j] = if fs == 0.0 || self.seized[j] {
                1.0
            } else if self.stuck[j] {
                fs - self.needed_friction(j, ctx, forces).abs()
            } else {
                self.dir[j] * own[j]
            };
        }
    }
    /// A slipping wheel's event is `d·Ω` (its own state), a free wheel's speed limit too; a
    /// stuck wheel's, or one held at its speed limit, reads its hold torque and its motor
    /// command (the controller's, in `forces`).
    fn event_reads(&self) -> EventReads {
        let stuck = self
            .wheels
            .iter()
            .zip(&self.stuck)
            .any(|(w, &s)| s && w.static_friction() > 0.0)
            || self.held.iter().any(|&h| h);
        EventReads {
            forces: stuck,
            hold_torques: stuck,
            kinematics: false,
        }
    }
    /// A wheel reads its own rotor's hold torque only.
    fn hold_reads(&self) -> HoldReads {
        HoldReads::Rotors
    }
    fn on_event(
        &mut self,
        j: usize,
        ctx: &Context,
        forces: &Forces,
        own: &mut [f64],
        requests: &mut Vec<Request>,
    ) -> EventAction {
        let nf = self.n_mode_events();
        if j >= nf {
            self.on_fault(j - nf, ctx, own, requests);
            return EventAction::Reset;
        }
        let n = self.n_stick_events();
        if j >= n {
            self.on_limit(j - n, ctx, forces, own, requests);
            return EventAction::Reset;
        }
        let fs = self.wheels[j].static_friction();
        let need = self.needed_friction(j, ctx, forces);
        let h = ctx.rotor_hinge(j);
        let name = &self.wheels[j].name;
        if self.stuck[j] {
            self.stuck[j] = false;
            self.dir[j] = (-need).signum();
            requests.push(Request::Unlock(h));
            set_text(
                &mut self.last,
                format_args!(
                    "wheel `{name}` broke free (needs {:.4} N m of friction, static {fs:.4})",
                    need.abs()
                ),
            );
        } else if need.abs() <= fs {
            self.stuck[j] = true;
            own[j] = 0.0;
            requests.push(Request::Lock(h));
            set_text(
                &mut self.last,
                format_args!("wheel `{name}` stopped and stuck"),
            );
        } else {
            let dir = (-need).signum();
            if dir == self.dir[j] {
                set_text(
                    &mut self.last,
                    format_args!("wheel `{name}` touched zero speed and slips on"),
                );
            } else {
                set_text(
                    &mut self.last,
                    format_args!("wheel `{name}` reversed through zero speed"),
                );
            }
            self.dir[j] = dir;
        }
        EventAction::Reset
    }
    fn event_direction(&self, _k: usize) -> EventDirection {
        // Stuck: the needed friction grows past the static one; slipping: d·Ω falls through 0;
        // the speed limits' functions fall through 0 when the mode ends; a fault's when due.
        EventDirection::Falling
    }
    fn next_sample(&self) -> f64 {
        self.faults.next()
    }
    /// Marks the faults due: their event functions fall through zero, and the events carry
    /// them out.
    fn sample(&mut self, ctx: &Context) -> Result<(), SystemError> {
        while self.faults.take_due(ctx.t).is_some() {}
        Ok(())
    }
    fn describe_event(&self, _k: usize) -> String {
        self.last.clone()
    }
    fn describe_event_into(&self, _k: usize, out: &mut String) {
        out.push_str(&self.last);
    }
}

impl ReactionWheels {
    /// Wheel `j`'s speed-limit event: a held wheel is released (inside its limits when the
    /// command no longer keeps its speed, at the limit when the bus drives it beyond);
    /// a free wheel reaching a limit, or coming back to it from beyond, is settled there.
    fn on_limit(
        &mut self,
        j: usize,
        ctx: &Context,
        forces: &Forces,
        own: &mut [f64],
        requests: &mut Vec<Request>,
    ) {
        let omega = own[j];
        let name = self.wheels[j].name.clone();
        if self.held[j] {
            let s = self.side[j];
            let c = self.clamped(j, forces);
            let tm = self.holding_torque(j, ctx, omega);
            self.held[j] = false;
            requests.push(Request::Unlock(ctx.rotor_hinge(j)));
            if s * (c - tm) <= s * tm {
                self.side[j] = 0.0;
                set_text(
                    &mut self.last,
                    format_args!(
                        "wheel `{name}` left its speed limit (command {c:.4} N m below the {tm:.4} that held it)"
                    ),
                );
            } else {
                set_text(
                    &mut self.last,
                    format_args!("wheel `{name}` is driven beyond its speed limit"),
                );
            }
            return;
        }
        if self.side[j] != 0.0 {
            let s = self.side[j];
            // Back inside from beyond: the limit again, held if the command drives it.
            self.settle_at_limit(j, s, ctx, forces, omega, requests);
            if !self.held[j] {
                self.side[j] = 0.0;
                set_text(
                    &mut self.last,
                    format_args!("wheel `{name}` came back inside its speed limits"),
                );
            }
            return;
        }
        let s = if omega == 0.0 { 1.0 } else { omega.signum() };
        self.settle_at_limit(j, s, ctx, forces, omega, requests);
    }
}

/// `[effects.reaction_wheels]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelsFile {
    /// `[[effects.reaction_wheels.wheel]]`.
    #[serde(default)]
    pub wheel: Vec<Spanned<WheelFile>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// One `[[effects.reaction_wheels.wheel]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// Spin axis, bus axes (normalised).
    #[serde(deserialize_with = "exact")]
    pub axis: Spanned<[f64; 3]>,
    /// Axial inertia (kg m², > 0).
    pub inertia: Spanned<f64>,
    /// Transverse inertia (kg m², default inertia / 2, >= inertia / 2).
    #[serde(default)]
    pub transverse: Option<f64>,
    /// Rotor mass (kg, default 0).
    #[serde(default)]
    pub mass: Option<f64>,
    /// Rotor centre, bus frame (m, default origin).
    #[serde(default, deserialize_with = "exact")]
    pub at: Option<[f64; 3]>,
    /// The carrier body's name (default the root).
    #[serde(default)]
    pub body: Option<Spanned<String>>,
    /// Mounting error, a rotation vector (rad, the carrier's axes; default none).
    #[serde(default, deserialize_with = "exact")]
    pub misalignment: Option<[f64; 3]>,
    /// Torque limit (N m, default unlimited).
    #[serde(default)]
    pub max_torque: Option<f64>,
    /// Speed limit (rad/s, default unlimited).
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// Coulomb friction α0 (N m, default 0).
    #[serde(default)]
    pub coulomb: Option<f64>,
    /// Stribeck friction α1 (N m, default 0).
    #[serde(default)]
    pub stribeck: Option<f64>,
    /// Stribeck speed Ω0 (rad/s, default 1).
    #[serde(default)]
    pub stribeck_speed: Option<f64>,
    /// Viscous friction α2 (N m s/rad, default 0).
    #[serde(default)]
    pub viscous: Option<f64>,
    /// Initial speed relative to the bus (rad/s, default 0).
    #[serde(default)]
    pub speed: Option<f64>,
    /// Constant motor torque without a controller (N m, default 0).
    #[serde(default)]
    pub torque: Option<f64>,
}

impl SceneEffect for ReactionWheels {
    const SECTION: &'static str = "reaction_wheels";
    type File = WheelsFile;
    fn from_section(w: WheelsFile, section: &Section) -> Result<Self, FileError> {
        let mut wheels: Vec<Wheel> = Vec::new();
        for wf in &w.wheel {
            let span = Some(wf.span());
            let f = wf.get_ref();
            let name = section
                .column_name(&f.name, "effects.reaction_wheels.wheel.name")?
                .clone();
            let at = |k: usize| f.at.map(|a| a[k]);
            section.check_numbers(
                wf.span(),
                "effects.reaction_wheels.wheel.",
                &[
                    ("transverse", f.transverse, true),
                    ("at", at(0), false),
                    ("at", at(1), false),
                    ("at", at(2), false),
                    ("coulomb", f.coulomb, true),
                    ("stribeck", f.stribeck, true),
                    ("viscous", f.viscous, true),
                    ("speed", f.speed, false),
                    ("torque", f.torque, false),
                ],
            )?;
            if wheels.iter().any(|o| o.name == name) {
                return Err(section.error(
                    Some(f.name.span()),
                    format!("duplicate wheel name `{name}`"),
                ));
            }
            let axis = Vec3::from(*f.axis.get_ref());
            if !axis.iter().all(|x| x.is_finite()) || axis.norm() <= 1e-9 {
                return Err(section.error(
                    Some(f.axis.span()),
                    "`axis` must be a non-zero finite vector",
                ));
            }
            let inertia = section.positive(&f.inertia, "inertia")?;
            let mut wheel = Wheel::new(name, axis, inertia);
            if let Some(t) = f.transverse {
                if t < 0.5 * inertia * (1.0 - 1e-9) {
                    return Err(section.error(span, "`transverse` must be >= inertia / 2 (a rotor's moments obey the triangle inequality)"));
                }
                wheel.transverse = t;
            }
            let nn = |v: Option<f64>, what: &str, default: f64| -> Result<f64, FileError> {
                match v {
                    Some(x) if x.is_nan() || x < 0.0 => {
                        Err(section.error(span.clone(), format!("`{what}` must be >= 0, got {x}")))
                    }
                    Some(x) => Ok(x),
                    None => Ok(default),
                }
            };
            wheel.mass = nn(f.mass, "mass", 0.0)?;
            wheel.at = f.at.map(Vec3::from).unwrap_or_else(Vec3::zeros);
            if let Some(b) = &f.body {
                let model = section.model();
                if model.body_index(b.get_ref()).is_none() {
                    let names: Vec<&str> = model.bodies().iter().map(|b| b.name()).collect();
                    return Err(section.error(
                        Some(b.span()),
                        format!(
                            "wheel `{}`: unknown body `{}` (the model's bodies: {})",
                            wheel.name,
                            b.get_ref(),
                            names.join(", ")
                        ),
                    ));
                }
                if model.body_index(b.get_ref()) != Some(0) {
                    wheel.body = Some(b.get_ref().clone());
                }
            }
            if let Some(m) = f.misalignment {
                if !m
                    .iter()
                    .all(|x| x.is_finite() && x.abs() <= std::f64::consts::PI)
                {
                    return Err(section.error(
                        span.clone(),
                        "`misalignment` must be three finite angles within ±π (rad)",
                    ));
                }
                wheel.misalignment = Some(Vec3::from(m));
            }
            wheel.max_torque = nn(f.max_torque, "max_torque", f64::INFINITY)?;
            wheel.max_speed = nn(f.max_speed, "max_speed", f64::INFINITY)?;
            wheel.coulomb = nn(f.coulomb, "coulomb", 0.0)?;
            wheel.stribeck = nn(f.stribeck, "stribeck", 0.0)?;
            wheel.viscous = nn(f.viscous, "viscous", 0.0)?;
            wheel.stribeck_speed = f.stribeck_speed.unwrap_or(1.0);
            if !(wheel.stribeck_speed.is_finite() && wheel.stribeck_speed > 0.0) {
                return Err(section.error(span, "`stribeck_speed` must be a finite number > 0"));
            }
            wheel.speed = f.speed.unwrap_or(0.0);
            wheel.torque = f.torque.unwrap_or(0.0);
            wheels.push(wheel);
        }
        if wheels.is_empty() {
            return Err(section.error_here(
                "[effects.reaction_wheels] needs at least one [[effects.reaction_wheels.wheel]]",
            ));
        }
        Ok(ReactionWheels::new(wheels))
    }
}

#[cfg(test)]
mod tests {
    use super::{Effect, Links, ReactionWheels, Wheel, WheelsFile};
    use crate::effects::section::SceneText;
    use satsim_tree::spatial::Vec3;
    use satsim_tree::{BaseKind, samples};
    use std::path::Path;

    /// A wheel's `axis`, `at` or `misalignment` with too many entries is refused at its line,
    /// as one with too few: `[0, 0, 1, "junk"]` is not read as `[0, 0, 1]`.
    #[test]
    fn wheel_vectors_of_the_wrong_length_are_refused_at_their_line() {
        let read = |line: &str| {
            let text = format!(
                "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"w\"\ninertia = 0.1\naxis = [0, 0, 1]\n{line}\n"
            );
            let scene = SceneText::new(&text, Path::new("s.toml"));
            match scene.effect_section::<WheelsFile>("reaction_wheels") {
                Ok(_) => "accepted".to_owned(),
                Err(e) => e.to_string(),
            }
        };
        assert_eq!(read(""), "accepted");
        let key = "s.toml:6: `effects.reaction_wheels.wheel";
        let three = "expected an array of length 3";
        for (line, expected) in [
            (
                "at = [0, 0, 1, 2]",
                format!("{key}.at`: invalid length 4, {three}"),
            ),
            (
                "at = [0, 0]",
                format!("{key}.at`: invalid length 2, {three}"),
            ),
            (
                "misalignment = [0, 0, 0, 0, 0]",
                format!("{key}.misalignment`: invalid length 5, {three}"),
            ),
        ] {
            assert_eq!(read(line), expected);
        }
        let text = "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"w\"\n\
                    axis = [0, 0, 1, \"junk\"]\ninertia = 0.1\n";
        let err = SceneText::new(text, Path::new("s.toml"))
            .effect_section::<WheelsFile>("reaction_wheels")
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            format!("s.toml:4: `effects.reaction_wheels.wheel.axis`: invalid length 4, {three}")
        );
    }

    /// Only wheels that add no torque at all, uncommanded, take `apply`'s idle path.
    #[test]
    fn only_torque_free_uncommanded_wheels_are_idle() {
        let model = samples::chain(1, BaseKind::Free);
        let links = |commanded| Links {
            rotors: &[],
            rotors_commanded: commanded,
            torquers: &[],
            dipoles_commanded: false,
            thrusters: &[],
            model: &model,
            flex: None,
        };
        let free = Wheel::new("w", Vec3::z(), 0.1);
        let idle = |w: &Wheel, commanded| {
            let mut e = ReactionWheels::new(vec![free.clone(), w.clone()]);
            e.connect(&links(commanded));
            e.idle
        };
        assert!(idle(&free, false));
        assert!(!idle(&free, true));
        let mut limited = free.clone();
        (limited.max_speed, limited.max_torque) = (10.0, 0.1);
        assert!(idle(&limited, false));
        for set in [
            |w: &mut Wheel| w.torque = 0.01,
            |w: &mut Wheel| w.coulomb = 0.01,
            |w: &mut Wheel| w.stribeck = 0.01,
            |w: &mut Wheel| w.viscous = 0.01,
        ] {
            let mut w = free.clone();
            set(&mut w);
            assert!(!idle(&w, false), "{w:?}");
        }
        // Not connected (an effect applied by hand): the full loop.
        assert!(!ReactionWheels::new(vec![free]).idle);
    }
}
