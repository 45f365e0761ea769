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
//! Targets: [`Target::Inertial`] (a fixed attitude, `ω_t = 0`) or [`Target::Orbital`]: the
//! local orbital frame (z towards the Earth's centre, y along the negative orbit normal, x
//! completing the triad, close to the velocity) times a fixed offset, turning at the orbit's
//! rate `ω_t = r × v / r²`.

use super::{Context, Effect, Forces, Needs};
use nalgebra::{DMatrix, Matrix3, Rotation3, UnitQuaternion};
use satsim_integrate::SystemError;
use satsim_tree::spatial::Vec3;

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
    /// `A⁺` (k x 3), from the wheel axes.
    allocation: DMatrix<f64>,
}

impl AttitudeControl {
    /// A controller for wheels with these axes (bus frame), one per wheel of the scene's
    /// reaction wheels, in their order: building a simulation whose wheels differ in number
    /// is an error ([`crate::simulation::SimError::Needs`]).
    pub fn new(target: Target, kp: f64, kd: f64, axes: &[Vec3]) -> Self {
        let a = DMatrix::from_fn(3, axes.len(), |r, c| axes[c][r]);
        let allocation = if axes.is_empty() {
            DMatrix::zeros(0, 3)
        } else {
            a.pseudo_inverse(1e-12)
                .unwrap_or_else(|_| DMatrix::zeros(axes.len(), 3))
        };
        Self {
            target,
            kp,
            kd,
            allocation,
        }
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

impl Effect for AttitudeControl {
    fn name(&self) -> &str {
        "attitude_control"
    }
    fn needs(&self) -> Needs {
        Needs {
            wheels: true,
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
        if forces.wheel_command.len() != self.allocation.nrows() {
            return Err(SystemError::new(format!(
                "attitude_control: gains for {} wheels, but there are {}",
                self.allocation.nrows(),
                forces.wheel_command.len()
            )));
        }
        let u = self.torque(ctx)?;
        for (j, c) in forces.wheel_command.iter_mut().enumerate() {
            let row = self.allocation.row(j);
            *c = -(row[0] * u.x + row[1] * u.y + row[2] * u.z);
        }
        Ok(())
    }
    fn wheel_commands(&self) -> Option<usize> {
        Some(self.allocation.nrows())
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
