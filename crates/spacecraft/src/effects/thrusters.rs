//! Thrusters: a force of fixed magnitude at a point of a body, switched on and off by a
//! duty cycle per control period (pulse-width modulation), contract section 13.
//!
//! Thruster `j` pushes with `thrust · direction` (N, body axes, `direction` a unit vector) at
//! the point `at` of its body (m, body frame): the wrench `(at × f, f)` about the body's
//! origin. The net force moves the orbit ([`Needs::net_force`]: with an `[orbit]` and a free
//! root the centre of mass falls with the orbit and the orbit's acceleration gains `F / M`;
//! without an orbit the force accelerates the tree's own velocity state, the free root's
//! linear velocity; on a fixed root the base reacts it). No propellant is spent: the mass
//! and inertia are constant.
//!
//! # Commands, latched per period
//!
//! At the start of the run and at every multiple of `period` after it (`t = 0, period,
//! 2 period, …`, the time stops of a [`Sampling`] clock) each thruster latches its duty
//! `d = clamp(duty + input + command, 0, 1)`, `duty` its constant, `input` the stepping
//! API's held `thrust_<name>` and `command` the flight software's (`[fsw.control] actuator =
//! "thrusters"`, [`Effect::hold_thrust_command`]), each 0 unless set and latched at the
//! first period start at or after the time it is set (so that a loop stepping by whole
//! periods, or a control sampled at period starts, commands each period from its start;
//! [`Effect::hold_thrust_input`]), and holds it for the period. The three add, as a wheel's
//! input adds to its controller's command. Its on-time is then
//!
//! - `"pwm"` (default): `d · period`, from the period's start;
//! - `"on_off"`: the whole period when `d >= 0.5`, else none;
//!
//! with two rules: an on-time within [`ROUNDOFF`] of a period of zero counts as zero and one
//! that reaches to within `ROUNDOFF` of a period of the next period start fires to that start
//! (so a duty of 1 is a continuous thrust, with no switch-off); and an on-time shorter than
//! the minimum impulse bit's, `min_impulse / thrust`, is not fired at all (a valve cannot
//! open for less). The switch-off instant `start + on-time` is a time stop too, so the force
//! is exactly a rectangle in time whatever the integrator: the impulse of a period is
//! `thrust · on-time` to round-off.
//!
//! Output: `thrust_<name>`, the force's magnitude at the row's time (N: `thrust` or 0). A row
//! at a switching instant is written before the switch (as every row at a time stop), so it
//! shows the value just before it.
//!
//! Energy: the thrust's work is an actuator's (the default [`Power`](super::Power)); with an
//! orbit only its part in the falling frame counts (the work on the orbit is the orbit's).
//!
//! Faults ([`super::faults`]): from a `thruster_stuck_on` fault's time a thruster fires
//! whatever its duty, from a `thruster_off` fault's it never fires; each fault's time is a
//! time stop, logged in the run's events.

use super::faults::{FaultKind, Schedule};
use super::{Bound, Context, Effect, Forces, Needs, Sampling, SceneEffect, Section};
use nalgebra::UnitQuaternion;
use satsim_integrate::{SystemError, stop_due};
use satsim_tree::io::{FileError, exact};
use satsim_tree::spatial::{Force, Vec3};
use serde::Deserialize;
use std::f64::consts::PI;
use std::ops::Range;
use toml::Spanned;

/// The fraction of a period within which an on-time counts as zero or as reaching the next
/// period start (the round-off of `duty · period` and of the stops' times).
pub const ROUNDOFF: f64 = 1e-9;

/// The largest `thrust` a scene accepts: ten times the strongest rocket motor built.
pub const MAX_THRUST: Bound = Bound {
    max: 1e8,
    unit: "N",
    why: "ten times the strongest rocket motor ever built",
};

/// How a duty becomes an on-time (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThrustMode {
    /// On for `duty · period` from each period start.
    Pwm,
    /// On for the whole period when `duty >= 0.5`.
    OnOff,
}

/// One thruster.
#[derive(Clone, Debug, PartialEq)]
pub struct Thruster {
    /// Its name (input and column `thrust_<name>`).
    pub name: String,
    /// The body that carries it (index in the model's bodies).
    pub body: usize,
    /// Point of application, body frame (m).
    pub at: Vec3,
    /// Unit direction of the force on the spacecraft, body axes: the true one, misalignment
    /// included.
    pub direction: Vec3,
    /// The unit direction the flight software assumes (body axes): `direction` without its
    /// misalignment. The thrusters' allocation uses this one.
    pub nominal: Vec3,
    /// The force while on (N, > 0).
    pub thrust: f64,
    /// The minimum impulse bit (N s, >= 0): a shorter pulse is not fired.
    pub min_impulse: f64,
    /// How a duty becomes an on-time.
    pub mode: ThrustMode,
}

impl Thruster {
    /// The on-time (s) of duty `d` (in [0, 1]) over a period of `period` s from `start`,
    /// with the next period start at `next`: `None` when it does not fire, `Some(INFINITY)`
    /// when it fires to `next`, else `Some(seconds)`.
    pub fn on_time(&self, d: f64, period: f64, start: f64, next: f64) -> Option<f64> {
        let on = match self.mode {
            ThrustMode::Pwm => d * period,
            ThrustMode::OnOff if d >= 0.5 => period,
            ThrustMode::OnOff => 0.0,
        };
        if on <= ROUNDOFF * period
            || stop_due(start, start + on)
            || on < self.min_impulse / self.thrust
        {
            return None;
        }
        let off = start + on;
        if off >= next - ROUNDOFF * period || stop_due(off, next) {
            Some(f64::INFINITY)
        } else {
            Some(on)
        }
    }
}

/// The thrusters effect.
#[derive(Clone, Debug)]
pub struct Thrusters {
    thrusters: Vec<Thruster>,
    sampling: Sampling,
    /// Each thruster's constant duty (in [0, 1]).
    duty: Vec<f64>,
    /// Each thruster's duty held from outside (`thrust_<name>`), latched at a period start.
    input: Vec<f64>,
    /// Each thruster's duty commanded by the flight software, latched likewise.
    command: Vec<f64>,
    /// Whether each thruster fires now.
    firing: Vec<bool>,
    /// Each thruster's pending switch-off instant (`∞` when none).
    off_at: Vec<f64>,
    /// The last period start latched (`-∞` before the first).
    latched_at: f64,
    /// Faults on the thrusters ([`super::faults`]), each a time stop.
    faults: Schedule,
    /// Each thruster's fault once it happened: `Some(true)` stuck on, `Some(false)` off.
    failed: Vec<Option<bool>>,
    /// Faults happened and not yet logged.
    said: Vec<String>,
    /// Per thruster on a flexible body: how its force bends it (set by `connect`).
    modal: Vec<Option<ModalPoint>>,
}

/// A thruster's point on a flexible body.
#[derive(Clone, Debug)]
struct ModalPoint {
    /// Where the body's modes lie among the elastic coordinates.
    range: Range<usize>,
    /// The translation `φₖ` of each mode at the point (body axes): the force `f` loads mode
    /// `k` with `φₖ · f`.
    phi: Vec<Vec3>,
    /// On a stiffened beam, its axis `a` and the foreshortening `C` at the point (`m × m`,
    /// row-major; [`satsim_tree::flexible::Beam::foreshortening`]): the point drawn in by
    /// `½ ηᵀ C η` along `a`, the force's axial part does the work `−(a · f) (C η)ₖ` on mode
    /// `k` (a thrust towards the root compresses the beam and softens it).
    shortening: Option<(Vec3, Vec<f64>)>,
}

impl Thrusters {
    /// `thrusters` commanded every `period` seconds; `None` unless `period` is finite and > 0.
    /// Every constant duty starts at 0.
    pub fn new(thrusters: Vec<Thruster>, period: f64) -> Option<Self> {
        let n = thrusters.len();
        Some(Self {
            thrusters,
            sampling: Sampling::new(period)?,
            duty: vec![0.0; n],
            input: vec![0.0; n],
            command: vec![0.0; n],
            firing: vec![false; n],
            off_at: vec![f64::INFINITY; n],
            latched_at: f64::NEG_INFINITY,
            faults: Schedule::default(),
            failed: vec![None; n],
            said: Vec::new(),
            modal: vec![None; n],
        })
    }
    /// Adds the fault `kind` (`thruster_stuck_on` or `thruster_off`) on thruster `target`
    /// (index in [`Thrusters::list`]) at `at` (s, finite, >= 0); refused, with the reason,
    /// otherwise.
    pub fn add_fault(&mut self, at: f64, target: usize, kind: FaultKind) -> Result<(), String> {
        if target >= self.thrusters.len() {
            return Err(format!("no thruster {target}"));
        }
        if !(at.is_finite() && at >= 0.0) {
            return Err(format!("`at` must be a finite time >= 0 (s), got {at}"));
        }
        if !matches!(kind, FaultKind::ThrusterStuckOn | FaultKind::ThrusterOff) {
            return Err(format!("a thruster cannot have a `{}` fault", kind.name()));
        }
        self.faults.push(at, target, kind);
        Ok(())
    }
    /// The control period (s).
    pub fn period(&self) -> f64 {
        self.sampling.period()
    }
    /// The thrusters.
    pub fn list(&self) -> &[Thruster] {
        &self.thrusters
    }
    /// The constant duties (in [`Thrusters::list`] order, each in [0, 1]), to change between
    /// runs.
    pub fn duty_mut(&mut self) -> &mut [f64] {
        &mut self.duty
    }
    /// Whether each thruster fires now.
    pub fn firing(&self) -> &[bool] {
        &self.firing
    }
    /// Latches every thruster's duty at the period start `t`.
    fn latch(&mut self, t: f64) {
        self.sampling.taken(t);
        self.latched_at = t;
        for j in 0..self.thrusters.len() {
            self.latch_one(j, t);
        }
    }
    /// Thruster `j`'s duty changed at `t`: set at the period start just latched (a loop
    /// stepping by whole periods, a control sampled there), it acts from that start, as a
    /// law sampled there would.
    fn relatch(&mut self, j: usize, t: f64) {
        if stop_due(t, self.latched_at) && stop_due(self.latched_at, t) {
            self.latch_one(j, self.latched_at);
        }
    }
    /// Latches thruster `j`'s duty at the period start `t` (the clock already moved on).
    fn latch_one(&mut self, j: usize, t: f64) {
        let d = (self.duty[j] + self.input[j] + self.command[j]).clamp(0.0, 1.0);
        let (period, next) = (self.sampling.period(), self.sampling.next());
        let on = self.thrusters[j].on_time(d, period, t, next);
        self.firing[j] = on.is_some();
        self.off_at[j] = match on {
            Some(s) if s.is_finite() => t + s,
            _ => f64::INFINITY,
        };
        // A failed valve ignores its duty.
        if let Some(on) = self.failed[j] {
            self.firing[j] = on;
            self.off_at[j] = f64::INFINITY;
        }
    }
}

impl Effect for Thrusters {
    fn name(&self) -> &str {
        "thrusters"
    }
    fn needs(&self) -> Needs {
        Needs {
            kinematics: true,
            net_force: true,
            ..Needs::default()
        }
    }
    fn thrusters(&self) -> Vec<Thruster> {
        self.thrusters.clone()
    }
    fn hold_thrust_input(&mut self, j: usize, duty: f64, t: f64) {
        if j >= self.input.len() {
            return;
        }
        self.input[j] = duty;
        self.relatch(j, t);
    }
    fn hold_thrust_command(&mut self, j: usize, duty: f64, t: f64) {
        if j >= self.command.len() || self.command[j] == duty {
            return;
        }
        self.command[j] = duty;
        self.relatch(j, t);
    }
    fn next_sample(&self) -> f64 {
        self.off_at
            .iter()
            .fold(self.sampling.next().min(self.faults.next()), |s, &t| {
                s.min(t)
            })
    }
    fn sample(&mut self, ctx: &Context) -> Result<(), SystemError> {
        let t = ctx.t;
        for (f, off) in self.firing.iter_mut().zip(self.off_at.iter_mut()) {
            if stop_due(t, *off) {
                *f = false;
                *off = f64::INFINITY;
            }
        }
        if stop_due(t, self.sampling.next()) {
            self.latch(t);
        }
        // Faults after the latch: they override its duty from `t` on.
        while let Some(k) = self.faults.take_due(t) {
            let f = &self.faults.list()[k];
            let (j, on) = (f.target, f.kind == FaultKind::ThrusterStuckOn);
            self.failed[j] = Some(on);
            self.firing[j] = on;
            self.off_at[j] = f64::INFINITY;
            let what = if on {
                "stuck on (full thrust)"
            } else {
                "off (fires no more)"
            };
            let name = &self.thrusters[j].name;
            self.said.push(format!("fault: thruster `{name}` {what}"));
        }
        Ok(())
    }
    fn drain_sample_log(&mut self, out: &mut Vec<String>) {
        out.append(&mut self.said);
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        for ((th, &on), modal) in self.thrusters.iter().zip(&self.firing).zip(&self.modal) {
            if on {
                let f = th.thrust * th.direction;
                forces.add_wrench(th.body, Force::new(th.at.cross(&f), f));
                // On a flexible body the force also bends it: its work on each mode.
                if let Some(m) = modal {
                    for (q, p) in forces.elastic[m.range.clone()].iter_mut().zip(&m.phi) {
                        *q += p.dot(&f);
                    }
                    if let Some((axis, c)) = &m.shortening {
                        let (eta, pull) = (&ctx.eta[m.range.clone()], axis.dot(&f));
                        let q = &mut forces.elastic[m.range.clone()];
                        for (row, q) in c.chunks_exact(eta.len()).zip(q) {
                            *q -= pull * row.iter().zip(eta).map(|(c, e)| c * e).sum::<f64>();
                        }
                    }
                }
            }
        }
        Ok(())
    }
    fn connect(&mut self, links: &super::Links) {
        self.modal = self
            .thrusters
            .iter()
            .map(|th| {
                let flex = links.flex?;
                let (range, shape) = flex.point_shape(th.body, &th.at)?;
                Some(ModalPoint {
                    range,
                    phi: shape.phi,
                    shortening: flex.point_shortening(th.body, &th.at),
                })
            })
            .collect();
    }
    fn output_columns(&self) -> Vec<String> {
        self.thrusters
            .iter()
            .map(|t| format!("thrust_{}", t.name))
            .collect()
    }
    fn output(&self, _ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        for (th, &on) in self.thrusters.iter().zip(&self.firing) {
            row.push(if on { th.thrust } else { 0.0 });
        }
    }
}

/// `[[effects.thrusters.thruster]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThrusterFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// The body that carries it (default the root).
    #[serde(default)]
    pub body: Option<Spanned<String>>,
    /// Point of application, body frame (m).
    #[serde(deserialize_with = "exact")]
    pub at: Spanned<[f64; 3]>,
    /// Direction of the force on the spacecraft, body axes (normalised; not zero).
    #[serde(deserialize_with = "exact")]
    pub direction: Spanned<[f64; 3]>,
    /// Mounting error, a rotation vector (rad, body axes; default none): the true direction
    /// is `exp([r]×) direction`.
    #[serde(default, deserialize_with = "exact")]
    pub misalignment: Option<Spanned<[f64; 3]>>,
    /// The force while on (N, > 0).
    pub thrust: Spanned<f64>,
    /// The minimum impulse bit (N s, >= 0, default 0).
    #[serde(default)]
    pub min_impulse: Option<Spanned<f64>>,
    /// `"pwm"` (default) or `"on_off"`.
    #[serde(default)]
    pub mode: Option<Spanned<String>>,
    /// A constant duty in [0, 1] (default 0), added to the input.
    #[serde(default)]
    pub duty: Option<Spanned<f64>>,
}

/// `[effects.thrusters]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThrustersFile {
    /// The control (PWM) period (s, > 0).
    pub period: Spanned<f64>,
    /// The thrusters.
    #[serde(default)]
    pub thruster: Vec<ThrusterFile>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for Thrusters {
    const SECTION: &'static str = "thrusters";
    type File = ThrustersFile;
    fn from_section(file: ThrustersFile, section: &Section) -> Result<Self, FileError> {
        let period = section.positive(&file.period, "effects.thrusters.period")?;
        let mut thrusters: Vec<Thruster> = Vec::new();
        let mut duty = Vec::new();
        for t in &file.thruster {
            let name = section.column_name(&t.name, "effects.thrusters.thruster.name")?;
            if thrusters.iter().any(|o| &o.name == name) {
                return Err(section.error(
                    Some(t.name.span()),
                    format!("thruster `{name}` is listed twice"),
                ));
            }
            let body = match &t.body {
                None => 0,
                Some(b) => section.model().body_index(b.get_ref()).ok_or_else(|| {
                    section.error(
                        Some(b.span()),
                        format!(
                            "thruster `{name}`: unknown body `{}` (the model's bodies: {})",
                            b.get_ref(),
                            section
                                .model()
                                .bodies()
                                .iter()
                                .map(|b| b.name())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                })?,
            };
            let at = Vec3::from(*t.at.get_ref());
            if !at.iter().all(|x| x.is_finite()) {
                return Err(section.error(
                    Some(t.at.span()),
                    format!("thruster `{name}`: `at` must be finite (m)"),
                ));
            }
            let direction = Vec3::from(*t.direction.get_ref());
            let norm = direction.norm();
            if !(norm > 0.0 && norm.is_finite()) {
                return Err(section.error(
                    Some(t.direction.span()),
                    format!(
                        "thruster `{name}`: `direction` must be a finite, non-zero vector, its norm is {norm}"
                    ),
                ));
            }
            let thrust = section.positive_within(
                &t.thrust,
                "effects.thrusters.thruster.thrust",
                MAX_THRUST,
            )?;
            let min_impulse = match &t.min_impulse {
                None => 0.0,
                Some(m) => section.non_negative(m, "effects.thrusters.thruster.min_impulse")?,
            };
            let mode = match &t.mode {
                None => ThrustMode::Pwm,
                Some(m) => match m.get_ref().as_str() {
                    "pwm" => ThrustMode::Pwm,
                    "on_off" => ThrustMode::OnOff,
                    other => {
                        return Err(section.error(
                            Some(m.span()),
                            format!(
                                "thruster `{name}`: unknown `mode` `{other}`, expected \"pwm\" or \"on_off\""
                            ),
                        ));
                    }
                },
            };
            let d = match &t.duty {
                None => 0.0,
                Some(d) if (0.0..=1.0).contains(d.get_ref()) => *d.get_ref(),
                Some(d) => {
                    return Err(section.error(
                        Some(d.span()),
                        format!(
                            "thruster `{name}`: `duty` must be a number in [0, 1], got {}",
                            d.get_ref()
                        ),
                    ));
                }
            };
            let nominal = direction / norm;
            let true_direction = match &t.misalignment {
                None => nominal,
                Some(m) if m.get_ref().iter().all(|x| x.is_finite() && x.abs() <= PI) => {
                    UnitQuaternion::from_scaled_axis(Vec3::from(*m.get_ref())) * nominal
                }
                Some(m) => {
                    return Err(section.error(
                        Some(m.span()),
                        format!(
                            "thruster `{name}`: `misalignment` must be three finite angles within ±π (rad)"
                        ),
                    ));
                }
            };
            thrusters.push(Thruster {
                name: name.clone(),
                body,
                at,
                direction: true_direction,
                nominal,
                thrust,
                min_impulse,
                mode,
            });
            duty.push(d);
        }
        let mut e = Thrusters::new(thrusters, period)
            .ok_or_else(|| section.error(Some(file.period.span()), "bad period"))?;
        e.duty = duty;
        Ok(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn thruster(mode: ThrustMode, min_impulse: f64) -> Thruster {
        Thruster {
            name: "a".into(),
            body: 0,
            at: Vec3::zeros(),
            direction: Vec3::z(),
            nominal: Vec3::z(),
            thrust: 2.0,
            min_impulse,
            mode,
        }
    }

    #[test]
    fn on_time_follows_the_duty_the_minimum_impulse_and_the_round_off_rules() {
        let p = thruster(ThrustMode::Pwm, 0.02);
        // 0.02 N s at 2 N: 0.01 s is the shortest pulse.
        assert_eq!(p.on_time(0.25, 0.1, 0.0, 0.1), Some(0.025));
        assert_eq!(p.on_time(0.0999, 0.1, 0.0, 0.1), None);
        assert_eq!(p.on_time(0.1, 0.1, 0.0, 0.1), Some(0.1 * 0.1));
        assert_eq!(p.on_time(0.0, 0.1, 0.0, 0.1), None);
        assert_eq!(p.on_time(1.0, 0.1, 0.0, 0.1), Some(f64::INFINITY));
        // Within round-off of the period end: fires to the next start.
        assert_eq!(p.on_time(1.0 - 1e-12, 0.1, 0.0, 0.1), Some(f64::INFINITY));
        let z = thruster(ThrustMode::Pwm, 0.0);
        assert_eq!(z.on_time(1e-12, 0.1, 0.0, 0.1), None);
        assert_eq!(z.on_time(1e-6, 0.1, 0.0, 0.1), Some(1e-7));
        let o = thruster(ThrustMode::OnOff, 0.0);
        assert_eq!(o.on_time(0.5, 0.1, 0.0, 0.1), Some(f64::INFINITY));
        assert_eq!(o.on_time(0.4999, 0.1, 0.0, 0.1), None);
        // A period longer than the minimum pulse never fires on_off below it.
        let big = thruster(ThrustMode::OnOff, 1.0);
        assert_eq!(big.on_time(1.0, 0.1, 0.0, 0.1), None);
    }

    #[test]
    fn a_period_start_latches_and_the_switch_off_is_the_next_stop() {
        let mut e = Thrusters::new(vec![thruster(ThrustMode::Pwm, 0.0)], 0.1).unwrap();
        e.hold_thrust_input(0, 0.3, 0.0);
        assert_eq!(e.next_sample(), f64::NEG_INFINITY);
        e.latch(0.0);
        assert!(e.firing[0]);
        assert_eq!(e.next_sample(), 0.3 * 0.1);
        // Within the period, an input change waits for the next period start.
        e.hold_thrust_input(0, 0.0, 0.01);
        assert!(e.firing[0] && e.next_sample() == 0.3 * 0.1);
        // At the period start just latched, it acts from that start.
        e.hold_thrust_input(0, 0.5, 0.0);
        assert_eq!(e.next_sample(), 0.5 * 0.1);
        e.hold_thrust_input(0, 0.0, 0.0);
        assert!(!e.firing[0] && e.next_sample() == 0.1);
        e.duty[0] = 0.9;
        e.hold_thrust_input(0, 0.5, 0.05);
        e.latch(0.1);
        assert!(e.firing[0]);
        // 0.9 + 0.5 clamps to 1: on to the next start, no switch-off stop.
        assert_eq!(e.next_sample(), 2.0 * 0.1);
    }

    #[test]
    fn a_commanded_duty_adds_to_the_input_and_relatches_only_at_the_start_just_latched() {
        let mut e = Thrusters::new(vec![thruster(ThrustMode::Pwm, 0.0)], 0.1).unwrap();
        e.latch(0.0);
        assert!(!e.firing[0]);
        // Commanded at the start just latched: fires from it.
        e.hold_thrust_command(0, 0.2, 0.0);
        assert!(e.firing[0] && e.next_sample() == 0.2 * 0.1);
        // Between starts: waits for the next.
        e.hold_thrust_command(0, 0.6, 0.05);
        assert_eq!(e.next_sample(), 0.2 * 0.1);
        e.hold_thrust_input(0, 0.3, 0.05);
        e.latch(0.1);
        // 0.6 + 0.3: both count.
        assert!((e.next_sample() - (0.1 + 0.9 * 0.1)).abs() < 1e-15);
        e.hold_thrust_command(0, 0.0, 0.1);
        assert!((e.next_sample() - (0.1 + 0.3 * 0.1)).abs() < 1e-15);
    }
}
