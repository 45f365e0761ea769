//! The state file (contract section 2): its schema ([`StateFile`], JSON or a scene's TOML
//! table) and its layout as the engine's `q`, `v`, `tau` ([`State`]).

use super::attitude::Attitude;
use super::error::FileError;
use super::model_file::schema_message;
use super::read_text;
use crate::error::Num;
use crate::model::{BaseKind, Model, UNIT_NORM_TOLERANCE};
use crate::spatial::Vec3;
use nalgebra::UnitQuaternion;
use serde::Deserialize;
use std::path::Path;
use thiserror::Error;

/// A state in the engine's layout (see [`crate::model`]): `q` (`nq`), `v` (`nv`) and the
/// generalised forces `tau` (`nv`, zero on the base coordinates, hinge torques after).
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Positions: `[attitude w x y z, position (zero), angles…]` or `[angles…]`.
    pub q: Vec<f64>,
    /// Velocities: `[ω, v, rates…]` or `[rates…]`.
    pub v: Vec<f64>,
    /// Generalised forces: zeros on the base, then the hinge torques.
    pub tau: Vec<f64>,
}

impl State {
    /// The state at rest in the neutral configuration, no torque.
    pub fn rest(model: &Model) -> Self {
        Self {
            q: model.neutral(),
            v: vec![0.0; model.nv()],
            tau: vec![0.0; model.nv()],
        }
    }
}

/// The state file (contract section 2), as written. Also deserialisable from TOML (a scene's
/// inline `[initial]` table).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StateFile {
    /// The root's state (free base; ignored for a fixed base).
    #[serde(default)]
    pub base: Option<BaseStateFile>,
    /// The hinges' state, in the model file's hinge order (may be omitted only for a model
    /// without hinges).
    #[serde(default)]
    pub hinges: Option<HingesStateFile>,
}

/// `base` of a state file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaseStateFile {
    /// Root body frame relative to inertial (maps root-body coordinates to inertial ones):
    /// a quaternion `[w, x, y, z]`, Euler angles or an axis and angle ([`Attitude`]); default
    /// identity.
    #[serde(default)]
    pub attitude: Option<Attitude>,
    /// Root angular velocity in root axes (rad/s), default zero.
    #[serde(default)]
    pub angular_velocity: Option<Vec<f64>>,
    /// Velocity of the root frame's origin in root axes (m/s), default zero.
    #[serde(default)]
    pub velocity: Option<Vec<f64>>,
    /// What `attitude` and `angular_velocity` are relative to; default
    /// [`BaseFrame::Inertial`].
    #[serde(default)]
    pub frame: Option<BaseFrame>,
}

/// The frame a state's `base.attitude` and `base.angular_velocity` are given in
/// (`base.frame`). `velocity` is the root origin's in root axes either way.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum BaseFrame {
    /// `"inertial"`: the attitude maps root-body coordinates to inertial ones, the angular
    /// velocity is the root's inertial rate in root axes.
    #[default]
    Inertial,
    /// `"orbital"`: relative to the local orbital frame at the start (which only a scene with
    /// an orbit knows, see [`StateFile::resolve_in_frame`]): the attitude maps root-body
    /// coordinates to orbital ones, the angular velocity is the root's rate relative to the
    /// orbital frame, in root axes. Identity and zero rate point the root at nadir and keep
    /// it there on a circular orbit.
    Orbital,
}

/// A moving reference frame at the start: its attitude (frame to inertial) and angular
/// velocity (inertial axes, rad/s), for [`StateFile::resolve_in_frame`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameMotion {
    /// Maps the frame's coordinates to inertial ones.
    pub attitude: UnitQuaternion<f64>,
    /// The frame's angular velocity, inertial axes (rad/s).
    pub angular_velocity: Vec3,
}

/// `hinges` of a state file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HingesStateFile {
    /// Angles (rad), one per hinge.
    pub angle: Vec<f64>,
    /// Rates (rad/s), one per hinge.
    pub rate: Vec<f64>,
    /// Torques (N m), one per hinge, default zeros.
    #[serde(default)]
    pub torque: Option<Vec<f64>>,
}

/// A state that does not fit its model: the field (such as `hinges.angle`) and the reason.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("{field}: {message}")]
pub struct FieldError {
    /// The field, such as `hinges.angle`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl FieldError {
    fn new(field: &str, message: impl Into<String>) -> Self {
        Self {
            field: field.to_owned(),
            message: message.into(),
        }
    }
    /// Names the file holding the state.
    pub fn in_file(self, origin: &Path) -> FileError {
        FileError::State {
            path: origin.to_path_buf(),
            field: self.field,
            message: self.message,
        }
    }
}

fn check_array(field: &str, x: &[f64], n: usize, what: &str) -> Result<(), FieldError> {
    if x.len() != n {
        return Err(FieldError::new(
            field,
            format!("expected {n} entries ({what}), got {}", x.len()),
        ));
    }
    if let Some(i) = x.iter().position(|x| !x.is_finite()) {
        return Err(FieldError::new(
            field,
            format!("entry {i} is not a finite number"),
        ));
    }
    Ok(())
}

/// How far from unit norm a state's attitude quaternion may be: it is normalised, silently
/// within [`UNIT_NORM_TOLERANCE`] (rounding), with a warning ([`StateFile::warnings`]) up to
/// this (a quaternion typed with a few digits), and refused beyond.
pub const STATE_ATTITUDE_TOLERANCE: f64 = 1e-3;

/// A quaternion `[w, x, y, z]` a user wrote (a state's or a scene's attitude, a guidance
/// target, a controller's): within [`STATE_ATTITUDE_TOLERANCE`] of unit norm it is
/// normalised, beyond it (or not finite) refused with a message that states the tolerance.
/// Returns the unit quaternion and, when its norm was more than [`UNIT_NORM_TOLERANCE`]
/// from 1 (more than rounding: a quaternion typed with a few digits), that norm, for the
/// reader to warn of.
pub fn near_unit_quaternion(a: [f64; 4]) -> Result<([f64; 4], Option<f64>), String> {
    let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !norm.is_finite() || (norm - 1.0).abs() > STATE_ATTITUDE_TOLERANCE {
        return Err(format!(
            "quaternion norm {} is not 1 (within 1e-3 of 1 it is normalised)",
            Num(norm)
        ));
    }
    let warn = ((norm - 1.0).abs() > UNIT_NORM_TOLERANCE).then_some(norm);
    Ok((a.map(|x| x / norm), warn))
}

/// The rate (rad/s) beyond which a state's angular velocity or hinge rate is warned about
/// ([`StateFile::warnings`]): degrees per second written as radians per second?
pub const RATE_WARNING: f64 = 2.0;

impl StateFile {
    /// What [`StateFile::resolve`] accepts but a user should hear about: an attitude
    /// quaternion normalised from a norm more than [`UNIT_NORM_TOLERANCE`] away from 1, a
    /// hinge angle beyond ±2π, a base angular velocity or hinge rate beyond
    /// ±[`RATE_WARNING`] (degrees written as radians?).
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(Attitude::Quaternion(a)) = self.base.as_ref().and_then(|b| b.attitude.as_ref())
        {
            let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > UNIT_NORM_TOLERANCE
                && (norm - 1.0).abs() <= STATE_ATTITUDE_TOLERANCE
            {
                out.push(format!(
                    "base.attitude: quaternion norm {norm} is not 1; normalised"
                ));
            }
        }
        // An angle beyond a turn is most likely degrees written where radians are meant.
        if let Some(h) = &self.hinges
            && let Some((k, a)) = h
                .angle
                .iter()
                .enumerate()
                .find(|(_, a)| a.abs() > std::f64::consts::TAU)
        {
            out.push(format!(
                "hinges.angle: entry {k} is {} rad, beyond ±2π: angles are in radians (for {} degrees write {:.6})",
                Num(*a),
                Num(*a),
                a.to_radians()
            ));
        }
        // Likewise a rate beyond 2 rad/s (115 deg/s, far above any bus's or deploying
        // panel's) is most likely degrees per second.
        let base_rates = self
            .base
            .as_ref()
            .and_then(|b| b.angular_velocity.as_deref());
        let hinge_rates = self.hinges.as_ref().map(|h| h.rate.as_slice());
        for (field, rates) in [
            ("base.angular_velocity", base_rates),
            ("hinges.rate", hinge_rates),
        ] {
            if let Some((k, w)) = rates
                .unwrap_or_default()
                .iter()
                .enumerate()
                .find(|(_, w)| w.abs() > RATE_WARNING)
            {
                out.push(format!(
                    "{field}: entry {k} is {} rad/s, beyond ±{RATE_WARNING} rad/s: rates are in rad/s (for {} deg/s write {:.6})",
                    Num(*w),
                    Num(*w),
                    w.to_radians()
                ));
            }
        }
        out
    }

    /// The frame of `base.attitude` and `base.angular_velocity` (default inertial).
    pub fn base_frame(&self) -> BaseFrame {
        self.base.as_ref().and_then(|b| b.frame).unwrap_or_default()
    }

    /// Checks the state against `model` and lays it out as the engine's `q`, `v`, `tau`.
    /// A state relative to the orbital frame (`base.frame = "orbital"`, free base) is an
    /// error here: only [`StateFile::resolve_in_frame`] with the orbit's frame resolves it.
    pub fn resolve(&self, model: &Model) -> Result<State, FieldError> {
        self.resolve_in_frame(model, None)
    }

    /// [`StateFile::resolve`], with `orbital`, the local orbital frame at the start, for a
    /// state given relative to it (`base.frame = "orbital"`): the root's inertial attitude
    /// is `q = q_orbital ⊗ q_given` and its inertial rate, root axes,
    /// `ω = ω_given + q⁻¹ ω_orbital q`. Without `orbital`, such a state is an error; with it,
    /// an inertial state is unchanged.
    pub fn resolve_in_frame(
        &self,
        model: &Model,
        orbital: Option<&FrameMotion>,
    ) -> Result<State, FieldError> {
        let mut state = self.resolve_as_given(model)?;
        if self.base_frame() == BaseFrame::Orbital && model.base == BaseKind::Free {
            let Some(frame) = orbital else {
                return Err(FieldError::new(
                    "base.frame",
                    "\"orbital\" needs an orbit: the attitude and angular velocity are then \
                     relative to the local orbital frame, which a scene's [orbit] table gives",
                ));
            };
            let a = &state.q[..4];
            let given =
                UnitQuaternion::new_normalize(nalgebra::Quaternion::new(a[0], a[1], a[2], a[3]));
            let q = frame.attitude * given;
            let omega = Vec3::new(state.v[0], state.v[1], state.v[2])
                + q.inverse_transform_vector(&frame.angular_velocity);
            state.q[..4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
            state.v[..3].copy_from_slice(omega.as_slice());
        }
        Ok(state)
    }

    /// The state laid out as written, whatever its frame.
    fn resolve_as_given(&self, model: &Model) -> Result<State, FieldError> {
        let mut state = State::rest(model);
        let nh = model.n_hinges();
        let (nq0, nv0) = (model.base_nq(), model.base_nv());
        // A fixed base ignores the `base` object.
        if let (BaseKind::Free, Some(base)) = (model.base, &self.base) {
            if let Some(rotation) = base.attitude.as_ref().and_then(Attitude::rotation) {
                let q = rotation.quaternion();
                state.q[..4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
            } else if let Some(Attitude::Quaternion(a)) = &base.attitude {
                check_array("base.attitude", a, 4, "a quaternion [w, x, y, z]")?;
                let (q, _) = near_unit_quaternion([a[0], a[1], a[2], a[3]])
                    .map_err(|m| FieldError::new("base.attitude", m))?;
                state.q[..4].copy_from_slice(&q);
            }
            if let Some(w) = &base.angular_velocity {
                check_array("base.angular_velocity", w, 3, "a vector")?;
                state.v[..3].copy_from_slice(w);
            }
            if let Some(u) = &base.velocity {
                check_array("base.velocity", u, 3, "a vector")?;
                state.v[3..6].copy_from_slice(u);
            }
        }
        match &self.hinges {
            Some(h) => {
                check_array("hinges.angle", &h.angle, nh, "one per hinge")?;
                check_array("hinges.rate", &h.rate, nh, "one per hinge")?;
                state.q[nq0..].copy_from_slice(&h.angle);
                state.v[nv0..].copy_from_slice(&h.rate);
                if let Some(t) = &h.torque {
                    check_array("hinges.torque", t, nh, "one per hinge")?;
                    state.tau[nv0..].copy_from_slice(t);
                }
            }
            None if nh == 0 => {}
            None => {
                return Err(FieldError::new(
                    "hinges",
                    format!(
                        "missing (the model has {nh} hinges: `hinges.angle` and `hinges.rate` are required)"
                    ),
                ));
            }
        }
        Ok(state)
    }
}

/// Parses a state file's JSON text for `model`. `origin` names the file in errors.
pub fn parse_state(text: &str, origin: &Path, model: &Model) -> Result<State, FileError> {
    parse_state_file(text, origin)?
        .resolve(model)
        .map_err(|e| e.in_file(origin))
}

/// Deserialises a state file's JSON text without checking it against a model.
pub fn parse_state_file(text: &str, origin: &Path) -> Result<StateFile, FileError> {
    let path = origin.to_path_buf();
    if text.trim().is_empty() {
        return Err(FileError::Empty { path });
    }
    serde_json::from_str::<StateFile>(text).map_err(|e| {
        let line = (e.line() > 0).then_some(e.line());
        // serde_json appends " at line L column C" to its messages: the line is ours.
        let full = e.to_string();
        let message = match full.rfind(" at line ") {
            Some(k) if line.is_some() => full[..k].to_owned(),
            _ => full,
        };
        match e.classify() {
            serde_json::error::Category::Data => FileError::Schema {
                path,
                line,
                message: schema_message(&message),
            },
            _ => FileError::Syntax {
                path,
                line,
                message,
            },
        }
    })
}

/// Reads the state file at `path` for `model`.
pub fn read_state(path: impl AsRef<Path>, model: &Model) -> Result<State, FileError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    parse_state(&text, path, model)
}
