//! Hinge controllers: PD tracking of a deployment profile, per hinge, with a torque limit.
//!
//! The profile is a smooth cosine ramp from `start` to `end` over `duration` seconds from
//! `t_start`: with `s = clamp((t − t_start) / duration, 0, 1)`,
//! `φ_ref = start + (end − start) (1 − cos π s) / 2`, `φ̇_ref = (end − start) π/(2 duration) sin π s`.
//! The torque `clamp(kp (φ_ref − φ) + kd (φ̇_ref − φ̇), ±torque_limit)` acts on the hinge.
//!
//! With a `period` ([`HingeControl::period`]) the law is discrete-time: evaluated at the
//! sample instants (`t = 0, period, 2 period, …`, see [`Sampling`]) and each torque held
//! in between (zero-order hold).

use super::{Context, Effect, Forces, Sampling, SceneEffect, Section};
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
    /// The sample instants of a discrete-time law (`None`: continuous).
    pub period: Option<Sampling>,
    /// The torques held since the last sample, one per entry of `hinges` (empty before the
    /// first).
    pub held: Vec<f64>,
}

impl HingeProfile {
    /// The torque at time `t` for the hinge at `angle` turning at `rate`.
    fn torque(&self, t: f64, angle: f64, rate: f64) -> f64 {
        let (reference, reference_rate) = self.reference(t);
        let u = self.kp * (reference - angle) + self.kd * (reference_rate - rate);
        u.clamp(-self.torque_limit, self.torque_limit)
    }
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
        if self.period.is_some() && self.held.len() == self.hinges.len() {
            for (p, u) in self.hinges.iter().zip(&self.held) {
                forces.hinge_torque[p.hinge] += u;
            }
            return Ok(());
        }
        for p in &self.hinges {
            forces.hinge_torque[p.hinge] +=
                p.torque(ctx.t, ctx.angles[p.hinge], ctx.rates[p.hinge]);
        }
        Ok(())
    }
    fn next_sample(&self) -> f64 {
        self.period.map_or(f64::INFINITY, |s| s.next())
    }
    fn sample(&mut self, ctx: &Context) -> Result<(), SystemError> {
        if let Some(s) = &mut self.period {
            self.held.clear();
            self.held.extend(
                self.hinges
                    .iter()
                    .map(|p| p.torque(ctx.t, ctx.angles[p.hinge], ctx.rates[p.hinge])),
            );
            s.taken(ctx.t);
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
    /// Sample period (s) of a discrete-time law (default: continuous).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
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
            for (key, v) in [("start", hf.start), ("end", hf.end)] {
                section.check_angle(h.span(), &format!("effects.hinge_control.hinge.{key}"), v);
            }
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
        let period = match &c.period {
            Some(p) => Sampling::new(section.positive(p, "period")?),
            None => None,
        };
        Ok(HingeControl {
            hinges,
            period,
            held: Vec::new(),
        })
    }
}
