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
//! no torque that would speed it up further.

use super::{
    Context, Effect, EventReads, Forces, Links, Needs, Power, Request, Rotor, SceneEffect, Section,
};
use satsim_integrate::{EventAction, EventDirection, SystemError};
use satsim_tree::io::FileError;
use satsim_tree::spatial::Vec3;
use serde::Deserialize;
use toml::Spanned;

/// One reaction wheel.
#[derive(Clone, Debug, PartialEq)]
pub struct Wheel {
    /// Name (the rotor body is `wheel_<name>`).
    pub name: String,
    /// Unit spin axis, bus axes.
    pub axis: Vec3,
    /// Centre of the rotor in the bus frame (m).
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
            axis: axis.normalize(),
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
    /// The motor torque after the torque and speed limits.
    pub fn limited(&self, command: f64, omega: f64) -> f64 {
        let t = command.clamp(-self.max_torque, self.max_torque);
        if omega.abs() >= self.max_speed && t * omega > 0.0 {
            0.0
        } else {
            t
        }
    }
}

/// The reaction-wheel effect.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ReactionWheels {
    /// The wheels.
    pub wheels: Vec<Wheel>,
    /// Whether a controller writes the commands into [`Forces::rotor_command`] (otherwise
    /// each wheel's `torque`); set when the simulation is built ([`Effect::connect`]).
    pub commanded: bool,
    stuck: Vec<bool>,
    /// Slip direction of each slipping wheel (±1).
    dir: Vec<f64>,
    motor: Vec<f64>,
    last: String,
}

impl ReactionWheels {
    /// The effect for these wheels.
    pub fn new(wheels: Vec<Wheel>) -> Self {
        let n = wheels.len();
        Self {
            wheels,
            commanded: false,
            stuck: vec![false; n],
            dir: vec![1.0; n],
            motor: vec![0.0; n],
            last: String::new(),
        }
    }
    /// Whether wheel `j` is stuck (at rest under static friction).
    pub fn is_stuck(&self, j: usize) -> bool {
        self.stuck[j]
    }
    fn has_stiction(&self) -> bool {
        self.wheels.iter().any(|w| w.static_friction() > 0.0)
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
        };
        self.wheels[j].limited(c, omega)
    }
}

impl Effect for ReactionWheels {
    fn name(&self) -> &str {
        "reaction_wheels"
    }
    fn needs(&self) -> Needs {
        Needs {
            hold_torques: self.has_stiction(),
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
                axis: w.axis,
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
        // Zipped rather than indexed: no bounds checks per wheel.
        let n = ctx.rotor_hinge(0);
        let rotors = forces.hinge_torque[n..].iter_mut().zip(&ctx.locked[n..]);
        let commands = &forces.rotor_command;
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
            };
            let tau = w.limited(c, omega);
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
            if !ctx.locked[ctx.rotor_hinge(j)] {
                let omega = own[j];
                p.actuator += self.motor[j] * omega;
                p.dissipated += w.friction(omega, self.dir[j]) * omega;
            }
        }
        p
    }

    fn connect(&mut self, links: &Links) {
        self.commanded = links.rotors_commanded;
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
        for (j, &speed) in own.iter().enumerate().take(self.wheels.len()) {
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
    fn n_events(&self) -> usize {
        if self.has_stiction() {
            self.wheels.len()
        } else {
            0
        }
    }
    fn events(&self, ctx: &Context, forces: &Forces, own: &[f64], g: &mut [f64]) {
        // Without stiction the wheels have no events (and `g` is empty).
        if !self.has_stiction() {
            return;
        }
        for (j, w) in self.wheels.iter().enumerate() {
            let fs = w.static_friction();
            g[j] = if fs == 0.0 {
                1.0
            } else if self.stuck[j] {
                fs - self.needed_friction(j, ctx, forces).abs()
            } else {
                self.dir[j] * own[j]
            };
        }
    }
    /// A slipping wheel's event is `d·Ω` (its own state); a stuck wheel's reads its hold
    /// torque and its motor command (the controller's, in `forces`).
    fn event_reads(&self) -> EventReads {
        let stuck = self
            .wheels
            .iter()
            .zip(&self.stuck)
            .any(|(w, &s)| s && w.static_friction() > 0.0);
        EventReads {
            forces: stuck,
            hold_torques: stuck,
            kinematics: false,
        }
    }
    fn on_event(
        &mut self,
        j: usize,
        ctx: &Context,
        forces: &Forces,
        own: &mut [f64],
        requests: &mut Vec<Request>,
    ) -> EventAction {
        let fs = self.wheels[j].static_friction();
        let need = self.needed_friction(j, ctx, forces);
        let h = ctx.rotor_hinge(j);
        let name = &self.wheels[j].name;
        if self.stuck[j] {
            self.stuck[j] = false;
            self.dir[j] = (-need).signum();
            requests.push(Request::Unlock(h));
            self.last = format!(
                "wheel `{name}` broke free (needs {:.4} N m of friction, static {fs:.4})",
                need.abs()
            );
        } else if need.abs() <= fs {
            self.stuck[j] = true;
            own[j] = 0.0;
            requests.push(Request::Lock(h));
            self.last = format!("wheel `{name}` stopped and stuck");
        } else {
            let dir = (-need).signum();
            self.last = if dir == self.dir[j] {
                format!("wheel `{name}` touched zero speed and slips on")
            } else {
                format!("wheel `{name}` reversed through zero speed")
            };
            self.dir[j] = dir;
        }
        EventAction::Reset
    }
    fn event_direction(&self, _k: usize) -> EventDirection {
        // Stuck: the needed friction grows past the static one; slipping: d·Ω falls through 0.
        EventDirection::Falling
    }
    fn describe_event(&self, _k: usize) -> String {
        self.last.clone()
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
    #[serde(default)]
    pub at: Option<[f64; 3]>,
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
            let name = f.name.get_ref().clone();
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
