//! Hinge controllers: PD tracking of a deployment profile, per hinge, with a torque limit.
//!
//! The profile is a smooth cosine ramp from `start` to `end` over `duration` seconds from
//! `t_start`: with `s = clamp((t − t_start) / duration, 0, 1)`,
//! `φ_ref = start + (end − start) (1 − cos π s) / 2`, `φ̇_ref = (end − start) π/(2 duration) sin π s`.
//! The torque `clamp(kp (φ_ref − φ) + kd (φ̇_ref − φ̇), ±torque_limit)` acts on the hinge.

use super::{Context, Effect, Forces, SceneEffect, Section};
use satsim_integrate::SystemError;
use satsim_tree::io::FileError;
use serde::Deserialize;
use std::f64::consts::PI;
use toml::Spanned;

/// One controlled hinge.
#[derive(Clone, Debug, PartialEq)]
pub struct HingeProfile {
    /// The hinge (model file order).
    pub hinge: usize,
    /// Angle at the start of the ramp (rad).
    pub start: f64,
    /// Angle at its end (rad).
    pub end: f64,
    /// When the ramp starts (s).
    pub t_start: f64,
    /// How long it lasts (s, > 0).
    pub duration: f64,
    /// Proportional gain (N m/rad).
    pub kp: f64,
    /// Derivative gain (N m s/rad).
    pub kd: f64,
    /// Largest torque magnitude (N m; infinite for none).
    pub torque_limit: f64,
}

impl HingeProfile {
    /// The reference angle and rate at time `t`.
    ///
    /// ```
    /// use satsim_spacecraft::effects::HingeProfile;
    /// let p = HingeProfile { hinge: 0, start: 1.0, end: 0.0, t_start: 10.0, duration: 20.0,
    ///     kp: 1.0, kd: 1.0, torque_limit: f64::INFINITY };
    /// assert_eq!(p.reference(0.0), (1.0, 0.0));
    /// assert!((p.reference(20.0).0 - 0.5).abs() < 1e-12);
    /// assert_eq!(p.reference(40.0).0, 0.0);
    /// ```
    pub fn reference(&self, t: f64) -> (f64, f64) {
        let s = ((t - self.t_start) / self.duration).clamp(0.0, 1.0);
        let d = self.end - self.start;
        let angle = self.start + d * 0.5 * (1.0 - (PI * s).cos());
        let rate = if s > 0.0 && s < 1.0 {
            d * PI / (2.0 * self.duration) * (PI * s).sin()
        } else {
            0.0
        };
        (angle, rate)
    }
}

/// The hinge-control effect.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct HingeControl {
    /// The controlled hinges.
    pub hinges: Vec<HingeProfile>,
}

impl Effect for HingeControl {
    fn name(&self) -> &str {
        "hinge_control"
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        for p in &self.hinges {
            let (angle, rate) = p.reference(ctx.t);
            let u = p.kp * (angle - ctx.angles[p.hinge]) + p.kd * (rate - ctx.rates[p.hinge]);
            forces.hinge_torque[p.hinge] += u.clamp(-p.torque_limit, p.torque_limit);
        }
        Ok(())
    }
}

/// `[effects.hinge_control]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HingeControlFile {
    /// `[[effects.hinge_control.hinge]]`.
    #[serde(default)]
    pub hinge: Vec<Spanned<HingeProfileFile>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// One `[[effects.hinge_control.hinge]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HingeProfileFile {
    /// The hinge's name.
    pub name: Spanned<String>,
    /// Start angle (rad).
    pub start: f64,
    /// End angle (rad).
    pub end: f64,
    /// Ramp start (s, default 0).
    #[serde(default)]
    pub t_start: Option<f64>,
    /// Ramp duration (s, > 0).
    pub duration: Spanned<f64>,
    /// N m/rad.
    pub kp: f64,
    /// N m s/rad (default 0).
    #[serde(default)]
    pub kd: Option<f64>,
    /// N m (default unlimited).
    #[serde(default)]
    pub torque_limit: Option<Spanned<f64>>,
}

impl SceneEffect for HingeControl {
    const SECTION: &'static str = "hinge_control";
    type File = HingeControlFile;
    fn from_section(c: HingeControlFile, section: &Section) -> Result<Self, FileError> {
        let mut hinges = Vec::new();
        for h in &c.hinge {
            let hf = h.get_ref();
            let hinge = section.hinge_index(&hf.name)?;
            section.check_numbers(
                h.span(),
                "effects.hinge_control.hinge.",
                &[
                    ("start", Some(hf.start), false),
                    ("end", Some(hf.end), false),
                    ("t_start", hf.t_start, false),
                    ("kp", Some(hf.kp), true),
                    ("kd", hf.kd, true),
                ],
            )?;
            if hinges.iter().any(|p: &HingeProfile| p.hinge == hinge) {
                return Err(section.error(
                    Some(h.span()),
                    format!("hinge `{}` is controlled twice", hf.name.get_ref()),
                ));
            }
            let torque_limit = match &hf.torque_limit {
                Some(t) => section.positive(t, "torque_limit")?,
                None => f64::INFINITY,
            };
            hinges.push(HingeProfile {
                hinge,
                start: hf.start,
                end: hf.end,
                t_start: hf.t_start.unwrap_or(0.0),
                duration: section.positive(&hf.duration, "duration")?,
                kp: hf.kp,
                kd: hf.kd.unwrap_or(0.0),
                torque_limit,
            });
        }
        Ok(HingeControl { hinges })
    }
}
