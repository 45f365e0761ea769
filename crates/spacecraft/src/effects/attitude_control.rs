//! Bus attitude control: a PD law on the quaternion error to a target attitude, realised by
//! the reaction wheels.
//!
//! With `q` the bus attitude (bus to inertial), `q_t` the target and `q_e = q_t⁻¹ ⊗ q`, the
//! wanted torque on the bus (bus axes) is
//! `u = −kp · 2 sgn(q_e,w) q_e,xyz − kd (ω − ω_t)`, so that `kp` is in N m/rad for small
//! errors (`2 q_e,xyz ≈` the rotation vector) and the shorter way round is taken. The wheels
//! apply `−Σ τ_j a_j` to the bus; the motor commands are `τ = −A⁺ u` with `A = [a_1 … a_k]`
//! the wheel axes and `A⁺` its pseudo-inverse (least squares with fewer than three wheels).
//! Torque and speed limits are then applied by the wheels.
//!
//! The commands go through [`Forces::rotor_command`], one per rotor of the tree; the
//! controller runs before the wheels ([`Effect::before`]) and takes their axes from the
//! rotors when the simulation is built ([`Effect::connect`]).
//!
//! With a `period` ([`AttitudeControl::with_period`]) the law is discrete-time: evaluated
//! at the sample instants (`t = 0, period, 2 period, …`, see [`Sampling`]) and the bus
//! torque `u` held in between (zero-order hold); the allocation to the wheels and their
//! limits still act continuously on the held `u`.
//!
//! Targets: [`Target::Inertial`] (a fixed attitude, `ω_t = 0`) or [`Target::Orbital`]: the
//! local orbital frame (z towards the Earth's centre, y along the negative orbit normal, x
//! completing the triad, close to the velocity) times a fixed offset, turning at the orbit's
//! rate `ω_t = r × v / r²`.

use super::{
    Context, Effect, EffectSet, Forces, Links, Needs, Rotor, Sampling, SceneEffect, Section,
    needs_met,
};
use nalgebra::{DMatrix, Matrix3, Quaternion, Rotation3, UnitQuaternion};
use satsim_integrate::SystemError;
use satsim_tree::error::Num;
use satsim_tree::io::{FileError, exact, near_unit_quaternion};
use satsim_tree::spatial::Vec3;
use serde::Deserialize;
use toml::Spanned;

/// What the controller points the bus at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A fixed inertial attitude (bus to inertial).
    Inertial(UnitQuaternion<f64>),
    /// The orbital frame times this offset (bus to orbital).
    Orbital(UnitQuaternion<f64>),
}

/// The attitude controller.
#[derive(Clone, Debug, PartialEq)]
pub struct AttitudeControl {
    /// The target.
    pub target: Target,
    /// Proportional gain (N m/rad).
    pub kp: f64,
    /// Derivative gain (N m s/rad).
    pub kd: f64,
    /// `A⁺` (k x 3), from the rotor axes ([`Effect::connect`]).
    allocation: DMatrix<f64>,
    /// The sample instants of the discrete-time law (`None`: continuous).
    sampling: Option<Sampling>,
    /// The torque `u` held since the last sample (`None` before the first).
    held: Option<Vec3>,
}

impl AttitudeControl {
    /// A controller; it commands every rotor of the simulation it is built into (their
    /// axes set its allocation, [`AttitudeControl::allocate`]).
    pub fn new(target: Target, kp: f64, kd: f64) -> Self {
        Self {
            target,
            kp,
            kd,
            allocation: DMatrix::zeros(0, 3),
            sampling: None,
            held: None,
        }
    }
    /// The same law, discrete-time: evaluated every `period` seconds and held in between
    /// (see the module documentation); `None` unless `period` is finite and > 0.
    pub fn with_period(mut self, period: f64) -> Option<Self> {
        self.sampling = Some(Sampling::new(period)?);
        Some(self)
    }
    /// The sample period (s) of a discrete-time law; `None` for a continuous one.
    pub fn period(&self) -> Option<f64> {
        self.sampling.map(|s| s.period())
    }
    /// Sets the allocation `A⁺` for rotors with these axes (bus frame), in their order.
    pub fn allocate(&mut self, axes: &[Vec3]) {
        self.allocation = pseudo_inverse(axes);
    }
    /// The allocation `A⁺` (a row per rotor, bus axes) that the controller takes when built
    /// into a simulation with these rotors: the bus's wheels as designed (their nominal
    /// axes); a rotor on another body (a control-moment gyro's) gets no command (a zero
    /// row). Its motor commands are `τ = −A⁺ u`.
    pub fn allocation_for(rotors: &[Rotor]) -> DMatrix<f64> {
        let axes: Vec<Vec3> = rotors
            .iter()
            .map(|r| {
                if r.on_root() {
                    r.nominal
                } else {
                    Vec3::zeros()
                }
            })
            .collect();
        pseudo_inverse(&axes)
    }
    /// The target attitude (bus to inertial) and rate (inertial axes) at this context.
    pub fn target_state(&self, ctx: &Context) -> Result<(UnitQuaternion<f64>, Vec3), SystemError> {
        match self.target {
            Target::Inertial(q) => Ok((q, Vec3::zeros())),
            Target::Orbital(offset) => {
                let o = ctx.orbit_or_err("attitude_control with an orbital target")?;
                let h = o.r.cross(&o.v);
                let z = -o.r.normalize();
                let y = -h.normalize();
                let x = y.cross(&z);
                let rot = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
                let q = UnitQuaternion::from_rotation_matrix(&rot) * offset;
                Ok((q, h / o.r.norm_squared()))
            }
        }
    }
    /// The wanted torque on the bus, bus axes.
    pub fn torque(&self, ctx: &Context) -> Result<Vec3, SystemError> {
        let (qt, wt) = self.target_state(ctx)?;
        let qe = qt.inverse() * ctx.attitude;
        let s = if qe.w < 0.0 { -1.0 } else { 1.0 };
        let wt_bus = ctx.attitude.inverse_transform_vector(&wt);
        Ok(-self.kp * 2.0 * s * qe.imag() - self.kd * (ctx.omega - wt_bus))
    }
}

/// `A⁺` for the axes `A = [a_1 … a_k]` (bus frame): a row per axis, least squares with fewer
/// than three.
fn pseudo_inverse(axes: &[Vec3]) -> DMatrix<f64> {
    if axes.is_empty() {
        return DMatrix::zeros(0, 3);
    }
    DMatrix::from_fn(3, axes.len(), |r, c| axes[c][r])
        .pseudo_inverse(1e-12)
        .unwrap_or_else(|_| DMatrix::zeros(axes.len(), 3))
}

impl Effect for AttitudeControl {
    fn name(&self) -> &str {
        "attitude_control"
    }
    fn needs(&self) -> Needs {
        Needs {
            rotors: true,
            free_base: true,
            orbit: matches!(self.target, Target::Orbital(_)),
            kinematics: false,
            ..Needs::default()
        }
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        if forces.rotor_command.len() != self.allocation.nrows() {
            return Err(SystemError::new(format!(
                "attitude_control: gains for {} rotors, but there are {}",
                self.allocation.nrows(),
                forces.rotor_command.len()
            )));
        }
        let u = match self.held {
            Some(u) if self.sampling.is_some() => u,
            _ => self.torque(ctx)?,
        };
        for (j, c) in forces.rotor_command.iter_mut().enumerate() {
            let row = self.allocation.row(j);
            *c = -(row[0] * u.x + row[1] * u.y + row[2] * u.z);
        }
        Ok(())
    }
    fn commands_rotors(&self) -> bool {
        true
    }
    fn next_sample(&self) -> f64 {
        self.sampling.map_or(f64::INFINITY, |s| s.next())
    }
    fn sample(&mut self, ctx: &Context) -> Result<(), SystemError> {
        if self.sampling.is_some() {
            self.held = Some(self.torque(ctx)?);
        }
        if let Some(s) = &mut self.sampling {
            s.taken(ctx.t);
        }
        Ok(())
    }
    fn before(&self) -> &[&str] {
        &["reaction_wheels"]
    }
    fn connect(&mut self, links: &Links) {
        self.allocation = Self::allocation_for(links.rotors);
    }
    fn output_columns(&self) -> Vec<String> {
        vec!["pointing_error_deg".into()]
    }
    fn output(&self, ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        let err = self
            .target_state(ctx)
            .map(|(qt, _)| (qt.inverse() * ctx.attitude).angle().to_degrees())
            .unwrap_or(f64::NAN);
        row.push(err);
    }
}

/// `[effects.attitude_control]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttitudeFile {
    /// `"inertial"` (default) or `"orbital"`.
    #[serde(default)]
    pub target: Option<Spanned<String>>,
    /// Target attitude (inertial) or offset from the orbital frame, `[w, x, y, z]`.
    #[serde(default, deserialize_with = "exact")]
    pub attitude: Option<Spanned<[f64; 4]>>,
    /// Proportional gain (N m/rad).
    pub kp: f64,
    /// Derivative gain (N m s/rad).
    pub kd: f64,
    /// Sample period (s) of a discrete-time law (default: continuous).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for AttitudeControl {
    const SECTION: &'static str = "attitude_control";
    type File = AttitudeFile;
    fn from_section(af: AttitudeFile, section: &Section) -> Result<Self, FileError> {
        section.check_numbers(
            section.span(),
            "effects.attitude_control.",
            &[("kp", Some(af.kp), true), ("kd", Some(af.kd), true)],
        )?;
        let q = match &af.attitude {
            Some(q) => {
                let ([w, x, y, z], off) = near_unit_quaternion(*q.get_ref())
                    .map_err(|m| section.error(Some(q.span()), format!("`attitude`: {m}")))?;
                if let Some(n) = off {
                    section.warn(
                        q.span(),
                        format!(
                            "`effects.attitude_control.attitude`: quaternion norm {} is not 1; normalised",
                            Num(n)
                        ),
                    );
                }
                UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z))
            }
            None => UnitQuaternion::identity(),
        };
        let target = match af.target.as_ref().map(|t| (t.get_ref().as_str(), t.span())) {
            None | Some(("inertial", _)) => Target::Inertial(q),
            Some(("orbital", _)) => Target::Orbital(q),
            Some((other, s)) => {
                return Err(section.error(
                    Some(s),
                    format!(
                        "`target`: unknown value `{other}`, expected \"inertial\" or \"orbital\""
                    ),
                ));
            }
        };
        let mut control = AttitudeControl::new(target, af.kp, af.kd);
        if let Some(p) = &af.period {
            control.sampling = Sampling::new(section.positive(p, "period")?);
        }
        Ok(control)
    }
    fn check(&self, enabled: &EffectSet) -> Result<(), String> {
        if matches!(self.target, Target::Orbital(_)) && !enabled.contains("orbit") {
            return Err(
                "effects.attitude_control with target = \"orbital\" needs an [orbit] table".into(),
            );
        }
        if !enabled.contains("reaction_wheels") {
            return Err("effects.attitude_control needs [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]] to command".into());
        }
        needs_met(self, enabled)
    }
}
