//! The scene's `[fsw]` table (contract section 16): built-in flight software that reads the
//! scene's sensors (`[sensors]`), never the truth, read into a
//! [`satsim_spacecraft::fsw::Onboard`] hosted by the [`Sensors`] effect.
//!
//! ```toml
//! [fsw.estimator]          # MEKF: attitude and gyro bias
//! kind = "mekf"            # (default)
//! gyro = "gyro"            # a [[sensors.gyro]]
//! star_tracker = "st"      # a [[sensors.star_tracker]] on the gyro's body, or a list
//! period = 0.1             # optional: the gyro's period (the only one accepted)
//! sigma_attitude = 0.01    # rad, initial 1σ (default 0.01)
//! sigma_bias = 1e-4        # rad/s, initial 1σ (default 1e-4)
//! [fsw.guidance]
//! mode = "nadir"           # or "inertial" with attitude = [w, x, y, z]
//! [fsw.control]
//! kind = "pid"             # (default)
//! kp = [9.0, 9.0, 9.0]     # N m/rad
//! ki = [0.1, 0.1, 0.1]     # N m/(rad s) (default 0)
//! kd = [150.0, 150.0, 150.0]  # N m s/rad
//! period = 0.1             # s (default: the estimator's)
//! actuator = "wheels"      # (default), "torquers" (with magnetometer = "mag") or "thrusters"
//! inertia = [[...], [...], [...]]   # optional: the feed-forward ω × (J ω)
//! [fsw.bdot]               # B-dot on a magnetometer's readings, to the torquers
//! magnetometer = "mag"     # a [[sensors.magnetometer]] on the root body
//! gain = 4e5               # A m² s/T
//! period = 1.0             # optional: a whole multiple of the magnetometer's (default it)
//! [fsw.momentum]           # or: wheel momentum dumping through the torquers
//! gain = 1e-3              # 1/s
//! magnetometer = "mag"
//! ```
//!
//! `actuator = "thrusters"` needs `[effects.thrusters]` with thrusters on the root body (only
//! those are commanded) and a control `period` that is a whole multiple of the thrusters'
//! `period` (they latch its duties at their period starts); it may run beside
//! `[effects.attitude_control]` on the wheels. `[fsw.bdot]` and `[fsw.momentum]` need
//! magnetic torquers on the root body, and not `[effects.bdot]`. Every block accepts `enabled = false` (read and checked, then left
//! out).
//!
//! # Modes
//!
//! Without `[[fsw.mode]]` every enabled block runs from the start (at most one of B-dot and
//! momentum dumping). With modes, each `[[fsw.mode]]` lists the blocks it runs by kind
//! (`blocks = ["estimator", "guidance", "control", "bdot", "momentum"]`) and ends on
//! `until` (see [`satsim_spacecraft::fsw::modes`]); a mode may give a block of its own
//! (`[fsw.mode.guidance]`, `[fsw.mode.estimator]`, `[fsw.mode.control]`, same keys), used
//! instead of the scene's `[fsw.<kind>]` in that mode:
//!
//! ```toml
//! [[fsw.mode]]
//! name = "sun_acquisition"
//! blocks = ["estimator", "guidance", "control"]
//! until = "error < 0.05"
//! hold = 60.0              # s the condition must hold (default 0)
//! [fsw.mode.estimator]
//! kind = "sun_mag"
//! gyro = "gyro"
//! sun_sensor = "sun"
//! magnetometer = "mag"
//! [fsw.mode.guidance]
//! mode = "sun"
//! axis = [0.0, 0.0, -1.0]
//! secondary = [0.0, 1.0, 0.0]
//! ```
//!
//! A block the scene gives at the top and two modes run is one block, running on across
//! the switch; a mode's own block is its own. Every error names the scene file and the line.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use satsim_environment::Epoch;
use satsim_spacecraft::effects::{EffectSet, ReactionWheels, SceneText, Thrusters};
use satsim_spacecraft::fsw::{
    Actuator, Aiding, Condition, ControlSpec, DipoleLaw, DipoleSpec, EstimatorSpec, Guidance,
    MekfParams, Mode, Onboard, Pid, Slew,
};
use satsim_spacecraft::sensors::{Kind, Sensors};
use satsim_tree::error::Num;
use satsim_tree::io::{FileError, exact, line_of, near_unit_quaternion};
use satsim_tree::{BaseKind, Model};

use super::sampled_loop::PidLaw;
use serde::Deserialize;
use std::cell::RefCell;
use std::ops::Range;
use toml::Spanned;

/// `[fsw]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FswFile {
    /// `[fsw.estimator]`.
    #[serde(default)]
    pub estimator: Option<Spanned<EstimatorFile>>,
    /// `[fsw.guidance]`.
    #[serde(default)]
    pub guidance: Option<Spanned<GuidanceFile>>,
    /// `[fsw.control]`.
    #[serde(default)]
    pub control: Option<Spanned<ControlFile>>,
    /// `[fsw.momentum]`: wheel momentum dumping through the torquers.
    #[serde(default)]
    pub momentum: Option<Spanned<MagneticFile>>,
    /// `[fsw.bdot]`: B-dot on the magnetometer's readings.
    #[serde(default)]
    pub bdot: Option<Spanned<MagneticFile>>,
    /// `[[fsw.mode]]`: the modes, in order.
    #[serde(default)]
    pub mode: Option<Vec<Spanned<ModeFile>>>,
}

/// `[[fsw.mode]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModeFile {
    /// Its name (unique).
    pub name: Spanned<String>,
    /// The kinds of block it runs: `"estimator"`, `"guidance"`, `"control"`, `"bdot"`,
    /// `"momentum"`.
    pub blocks: Spanned<Vec<String>>,
    /// What ends it: `"rate < x"`, `"error < x"`, `"time > x"` (the last mode has none).
    #[serde(default)]
    pub until: Option<Spanned<String>>,
    /// How long the condition must hold (s, default 0).
    #[serde(default)]
    pub hold: Option<Spanned<f64>>,
    /// The gyro whose raw reading `rate < x` reads when the mode runs no estimator
    /// (default: the scene's only gyro on the root body).
    #[serde(default)]
    pub gyro: Option<Spanned<String>>,
    /// The mode's own estimator.
    #[serde(default)]
    pub estimator: Option<Spanned<EstimatorFile>>,
    /// The mode's own guidance.
    #[serde(default)]
    pub guidance: Option<Spanned<GuidanceFile>>,
    /// The mode's own control.
    #[serde(default)]
    pub control: Option<Spanned<ControlFile>>,
}

/// `[fsw.estimator]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorFile {
    /// `"mekf"` (the default: gyro and star trackers) or `"sun_mag"` (gyro, Sun sensor and
    /// magnetometer).
    #[serde(default)]
    pub kind: Option<Spanned<String>>,
    /// The gyro's name.
    pub gyro: Spanned<String>,
    /// `"mekf"`: a star tracker's name or a list of them.
    #[serde(default)]
    pub star_tracker: Option<Spanned<toml::Value>>,
    /// `"sun_mag"`: the Sun sensor's name.
    #[serde(default)]
    pub sun_sensor: Option<Spanned<String>>,
    /// `"sun_mag"`: the magnetometer's name.
    #[serde(default)]
    pub magnetometer: Option<Spanned<String>>,
    /// The filter's period (s): the gyro's (the default).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
    /// Initial 1σ of the attitude (rad, default 0.01).
    #[serde(default)]
    pub sigma_attitude: Option<Spanned<f64>>,
    /// Initial 1σ of the gyro bias (rad/s, default 1e-4).
    #[serde(default)]
    pub sigma_bias: Option<Spanned<f64>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[fsw.guidance]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuidanceFile {
    /// `"inertial"`, `"nadir"`, `"sun"` or `"target"`.
    pub mode: Spanned<String>,
    /// Inertial: the attitude `[w, x, y, z]` (body to inertial); nadir: an offset from the
    /// orbital frame (body to orbital, default none).
    #[serde(default, deserialize_with = "exact")]
    pub attitude: Option<Spanned<[f64; 4]>>,
    /// The largest rate of the reference relative to the law's (rad/s, default none).
    #[serde(default)]
    pub max_rate: Option<Spanned<f64>>,
    /// The largest acceleration of the reference relative to the law's (rad/s², default
    /// none).
    #[serde(default)]
    pub max_acceleration: Option<Spanned<f64>>,
    /// Sun and target: the body axis pointed (at the Sun, at the target).
    #[serde(default, deserialize_with = "exact")]
    pub axis: Option<Spanned<[f64; 3]>>,
    /// Sun and target: the body axis kept nearest the orbit normal.
    #[serde(default, deserialize_with = "exact")]
    pub secondary: Option<Spanned<[f64; 3]>>,
    /// Target: geodetic latitude (deg).
    #[serde(default)]
    pub latitude_deg: Option<Spanned<f64>>,
    /// Target: longitude (deg, east).
    #[serde(default)]
    pub longitude_deg: Option<Spanned<f64>>,
    /// Target: height above the WGS-84 ellipsoid (m, default 0).
    #[serde(default)]
    pub altitude: Option<Spanned<f64>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[fsw.control]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlFile {
    /// `"pid"` (the default and the only kind).
    #[serde(default)]
    pub kind: Option<Spanned<String>>,
    /// Proportional gains (N m/rad), body axes.
    #[serde(deserialize_with = "exact")]
    pub kp: Spanned<[f64; 3]>,
    /// Integral gains (N m/(rad s), default 0).
    #[serde(default, deserialize_with = "exact")]
    pub ki: Option<Spanned<[f64; 3]>>,
    /// Derivative gains (N m s/rad).
    #[serde(deserialize_with = "exact")]
    pub kd: Spanned<[f64; 3]>,
    /// Sample period (s, default the estimator's).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
    /// `"wheels"` (the default), `"torquers"` or `"thrusters"`.
    #[serde(default)]
    pub actuator: Option<Spanned<String>>,
    /// `actuator = "torquers"`: the magnetometer whose reading the dipole is worked out on.
    #[serde(default)]
    pub magnetometer: Option<Spanned<String>>,
    /// Inertia for the gyroscopic feed-forward `ω × (J ω)` (kg m², body axes; default none).
    #[serde(default, deserialize_with = "exact")]
    pub inertia: Option<Spanned<[[f64; 3]; 3]>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[fsw.bdot]` (gain in A m² s/T) or `[fsw.momentum]` (gain in 1/s).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MagneticFile {
    /// The magnetometer's name (a [[sensors.magnetometer]] on the root body).
    pub magnetometer: Spanned<String>,
    /// The gain k (> 0).
    pub gain: Spanned<f64>,
    /// Sample period (s, default the magnetometer's; a whole multiple of it).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

fn finite3(text: &SceneText, x: &Spanned<[f64; 3]>, what: &str) -> Result<[f64; 3], FileError> {
    let v = *x.get_ref();
    if v.iter().all(|g| g.is_finite() && *g >= 0.0) {
        Ok(v)
    } else {
        Err(text.error(
            Some(x.span()),
            format!(
                "`{what}` must be three finite numbers >= 0, got [{}]",
                v.map(|g| Num(g).to_string()).join(", ")
            ),
        ))
    }
}

/// The sensor called `name` of kind `kind` (`gyro`, `star_tracker`, `magnetometer`) that
/// `block`'s `key` names (`block` as `fsw.estimator`): its index in the set.
fn sensor(
    text: &SceneText,
    sensors: Option<&Sensors>,
    name: &str,
    span: Range<usize>,
    kind: &str,
    (block, key): (&str, &str),
) -> Result<usize, FileError> {
    let Some(set) = sensors else {
        return Err(text.error(
            Some(span),
            format!(
                "`{block}.{key}`: unknown sensor `{name}`: the scene has no sensors (add a [[sensors.{kind}]] named `{name}`)"
            ),
        ));
    };
    let list = set.sensors();
    let Some(i) = list.iter().position(|s| s.name() == name) else {
        let of_kind: Vec<&str> = list
            .iter()
            .filter(|s| s.kind().name() == kind)
            .map(|s| s.name())
            .collect();
        return Err(text.error(
            Some(span),
            format!(
                "`{block}.{key}`: unknown sensor `{name}` (the scene's {kind} sensors: {})",
                if of_kind.is_empty() {
                    "none".to_string()
                } else {
                    of_kind.join(", ")
                }
            ),
        ));
    };
    if list[i].kind().name() != kind {
        return Err(text.error(
            Some(span),
            format!(
                "`{block}.{key}`: sensor `{name}` is a {}, not a {kind}",
                list[i].kind().name()
            ),
        ));
    }
    Ok(i)
}

/// What a block reader reads against.
struct Within<'a> {
    text: &'a SceneText<'a>,
    model: &'a Model,
    effects: &'a EffectSet,
    epoch: Option<Epoch>,
    /// The controls on the wheels read so far, for the check of their sampled loops.
    wheel_laws: RefCell<Vec<WheelLaw>>,
    /// What the reader accepts but the user should hear about, `file:line: message`.
    warnings: RefCell<Vec<String>>,
}

/// A control table on the wheels: where it is (`[title]` and its line) and its law, whose
/// sampled loop the reader checks ([`super::sampled_loop::sampled_pid`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct WheelLaw {
    pub(crate) title: String,
    pub(crate) line: usize,
    pub(crate) law: PidLaw,
}

impl Within<'_> {
    fn sensors(&self) -> Option<&Sensors> {
        self.effects.get::<Sensors>()
    }

    /// Checks the root body's wheel `axes` that a control on the wheels allocates to (the
    /// wheels on other bodies turn out of the bus's axes and are left out): none is an error
    /// at the control's table; axes that span fewer than 3 directions are a warning there,
    /// naming each body axis about which no wheel torque reaches the bus.
    fn root_wheel_axes(
        &self,
        title: &str,
        span: Range<usize>,
        axes: &[Vector3<f64>],
    ) -> Result<(), FileError> {
        if axes.is_empty() {
            return Err(self.text.error(
                Some(span),
                format!(
                    "{title} actuator = \"wheels\" needs a wheel on the root body: the control allocates to the root body's wheels only (the others turn with their bodies, out of the bus's axes)"
                ),
            ));
        }
        // The directions the wheels reach: the eigenvectors of Σ a aᵀ whose eigenvalue is
        // not zero next to the largest.
        let m = axes
            .iter()
            .fold(nalgebra::Matrix3::zeros(), |m, a| m + a * a.transpose());
        let eig = m.symmetric_eigen();
        let largest = eig.eigenvalues.max();
        let unreached: Vec<String> = (0..3)
            .filter(|&i| eig.eigenvalues[i] <= 1e-9 * largest)
            .map(|i| {
                let v = eig.eigenvectors.column(i);
                // The sign that makes the largest component positive, rounded for reading.
                let s = if v
                    .iter()
                    .fold(0.0f64, |a, x| if x.abs() > a.abs() { *x } else { a })
                    < 0.0
                {
                    -1.0
                } else {
                    1.0
                };
                format!(
                    "[{}]",
                    v.iter()
                        .map(|x| Num(((s * x) * 1e6).round() / 1e6 + 0.0).to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
            .collect();
        if !unreached.is_empty() {
            self.warn(
                span,
                format!(
                    "{title} allocates to the root body's {} wheel{} only, which span {} of the 3 axes: no wheel torque reaches the bus about {} (body axes), so the control cannot hold the attitude about {}",
                    axes.len(),
                    if axes.len() == 1 { "" } else { "s" },
                    3 - unreached.len(),
                    unreached.join(" or "),
                    if unreached.len() == 1 { "it" } else { "them" },
                ),
            );
        }
        Ok(())
    }

    /// Notes a warning at the line of `span`.
    fn warn(&self, span: Range<usize>, message: String) {
        self.warnings.borrow_mut().push(format!(
            "{}:{}: {message}",
            self.text.path().display(),
            line_of(self.text.text(), span.start)
        ));
    }

    /// Whether `period` is a whole multiple (>= 1) of `base`.
    fn multiple(period: f64, base: f64) -> bool {
        let ratio = period / base;
        ratio.round() >= 1.0 && (ratio - ratio.round()).abs() <= 1e-9 * ratio
    }

    /// An estimator table (`at` names it: `fsw.estimator`, or `fsw.mode.estimator`).
    fn estimator(&self, e: &EstimatorFile, at: &str) -> Result<EstimatorSpec, FileError> {
        let text = self.text;
        let kind = e.kind.as_ref().map_or("mekf", |k| k.get_ref().as_str());
        if let Some(k) = &e.kind
            && !matches!(kind, "mekf" | "sun_mag")
        {
            return Err(text.error(
                Some(k.span()),
                format!(
                    "`{at}.kind`: unknown kind `{}`, expected \"mekf\" (gyro and star trackers) or \"sun_mag\" (gyro, Sun sensor and magnetometer)",
                    k.get_ref()
                ),
            ));
        }
        let sensors = self.sensors();
        let gyro = sensor(
            text,
            sensors,
            e.gyro.get_ref(),
            e.gyro.span(),
            "gyro",
            (at, "gyro"),
        )?;
        let list = sensors.expect("a sensor was found").sensors();
        let g = &list[gyro];
        let Kind::Gyro(gm) = g.kind() else {
            unreachable!("checked a gyro")
        };
        let period = g.period();
        let body = |b: usize| self.model.bodies()[b].name().to_owned();
        // A sensor aiding the gyro: on its body, sampling at its samples.
        let aid = |name: &str, span: Range<usize>, kind: &str, key: &str| {
            let i = sensor(text, sensors, name, span.clone(), kind, (at, key))?;
            let s = &list[i];
            if s.body() != g.body() {
                return Err(text.error(
                    Some(span),
                    format!(
                        "`{at}.{key}`: {} `{name}` is on body `{}`, the gyro `{}` on `{}`: the estimator needs them on the same body",
                        kind.replace('_', " "),
                        body(s.body()),
                        g.name(),
                        body(g.body())
                    ),
                ));
            }
            if !Self::multiple(s.period(), period) {
                return Err(text.error(
                    Some(span),
                    format!(
                        "`{at}.{key}`: {} `{name}` samples every {} s, not a whole multiple of the gyro's period {} s: the filter updates at the gyro's samples",
                        kind.replace('_', " "),
                        Num(s.period()),
                        Num(period)
                    ),
                ));
            }
            Ok(i)
        };
        let unused = |x: Option<Range<usize>>, key: &str| match x {
            Some(span) => Err(text.error(
                Some(span),
                format!(
                    "`{at}.{key}` belongs to kind = \"{}\", not to \"{kind}\"",
                    if kind == "mekf" { "sun_mag" } else { "mekf" }
                ),
            )),
            None => Ok(()),
        };
        let aiding = if kind == "mekf" {
            unused(e.sun_sensor.as_ref().map(|s| s.span()), "sun_sensor")?;
            unused(e.magnetometer.as_ref().map(|s| s.span()), "magnetometer")?;
            let Some(st) = &e.star_tracker else {
                return Err(text.error(
                    Some(e.gyro.span()),
                    format!("`{at}` kind = \"mekf\" needs `star_tracker` (a star tracker's name or a list of them)"),
                ));
            };
            let names: Vec<String> = match st.get_ref() {
                toml::Value::String(s) => vec![s.clone()],
                toml::Value::Array(a) if !a.is_empty() && a.iter().all(|v| v.is_str()) => a
                    .iter()
                    .map(|v| v.as_str().unwrap_or_default().to_owned())
                    .collect(),
                _ => {
                    return Err(text.error(
                        Some(st.span()),
                        format!("`{at}.star_tracker` must be a star tracker's name or a non-empty list of names"),
                    ));
                }
            };
            let mut trackers: Vec<(usize, [f64; 3])> = Vec::new();
            for name in &names {
                let i = aid(name, st.span(), "star_tracker", "star_tracker")?;
                if trackers.iter().any(|(j, _)| *j == i) {
                    return Err(text.error(
                        Some(st.span()),
                        format!("`{at}.star_tracker` lists `{name}` twice"),
                    ));
                }
                let Kind::StarTracker(s) = list[i].kind() else {
                    unreachable!("checked a star tracker")
                };
                trackers.push((i, s.noise));
            }
            Aiding::StarTrackers(trackers)
        } else {
            unused(e.star_tracker.as_ref().map(|s| s.span()), "star_tracker")?;
            let need = |x: &Option<Spanned<String>>, key: &str, kind: &str| match x {
                Some(n) => aid(n.get_ref(), n.span(), kind, key),
                None => Err(text.error(
                    Some(e.gyro.span()),
                    format!(
                        "`{at}` kind = \"sun_mag\" needs `{key}` (a [[sensors.{kind}]]'s name)"
                    ),
                )),
            };
            let sun_sensor = need(&e.sun_sensor, "sun_sensor", "sun_sensor")?;
            let magnetometer = need(&e.magnetometer, "magnetometer", "magnetometer")?;
            let (Kind::SunSensor(s), Kind::Magnetometer(m)) =
                (list[sun_sensor].kind(), list[magnetometer].kind())
            else {
                unreachable!("checked their kinds")
            };
            Aiding::SunMag {
                sun_sensor,
                magnetometer,
                sigma_sun: s.noise,
                field_noise: m.noise,
            }
        };
        if let Some(p) = &e.period {
            let v = text.positive(p, &format!("{at}.period"))?;
            if (v - period).abs() > 1e-9 * period {
                return Err(text.error(
                    Some(p.span()),
                    format!(
                        "`{at}.period` = {} s must be the gyro `{}`'s period, {} s: the filter propagates once per gyro sample (leave `period` out to take the gyro's)",
                        Num(v),
                        g.name(),
                        Num(period)
                    ),
                ));
            }
        }
        let sigma = |x: &Option<Spanned<f64>>, key: &str, default: f64| {
            x.as_ref()
                .map_or(Ok(default), |x| text.positive(x, &format!("{at}.{key}")))
        };
        let params = MekfParams {
            sigma_v: gm.noise_density,
            sigma_u: gm.bias_walk,
            sigma_attitude: sigma(&e.sigma_attitude, "sigma_attitude", 0.01)?,
            sigma_bias: sigma(&e.sigma_bias, "sigma_bias", 1e-4)?,
        };
        Ok(EstimatorSpec {
            gyro,
            period,
            aiding,
            body: g.body(),
            params,
        })
    }

    /// A guidance table.
    fn guidance(&self, g: &GuidanceFile, at: &str) -> Result<Shaped, FileError> {
        let text = self.text;
        let mode = g.mode.get_ref().as_str();
        if !matches!(mode, "inertial" | "nadir" | "sun" | "target") {
            return Err(text.error(
                Some(g.mode.span()),
                format!(
                    "`{at}.mode`: unknown mode `{mode}`, expected \"inertial\", \"nadir\", \"sun\" or \"target\""
                ),
            ));
        }
        let belongs: [Belongs; 6] = [
            (
                "attitude",
                g.attitude.as_ref().map(|x| x.span()),
                &["inertial", "nadir"],
            ),
            (
                "axis",
                g.axis.as_ref().map(|x| x.span()),
                &["sun", "target"],
            ),
            (
                "secondary",
                g.secondary.as_ref().map(|x| x.span()),
                &["sun", "target"],
            ),
            (
                "latitude_deg",
                g.latitude_deg.as_ref().map(|x| x.span()),
                &["target"],
            ),
            (
                "longitude_deg",
                g.longitude_deg.as_ref().map(|x| x.span()),
                &["target"],
            ),
            (
                "altitude",
                g.altitude.as_ref().map(|x| x.span()),
                &["target"],
            ),
        ];
        for (key, span, of) in belongs {
            if let Some(span) = span
                && !of.contains(&mode)
            {
                return Err(text.error(
                    Some(span),
                    format!(
                        "`{at}.{key}` belongs to mode = {}, not to \"{mode}\"",
                        of.iter()
                            .map(|m| format!("\"{m}\""))
                            .collect::<Vec<_>>()
                            .join(" or ")
                    ),
                ));
            }
        }
        if mode != "inertial" && !self.effects.contains("orbit") {
            return Err(text.error(
                Some(g.mode.span()),
                format!(
                    "`{at}` mode = \"{mode}\" needs an [orbit] table (e.g. `[orbit]` with `altitude = 500e3`)"
                ),
            ));
        }
        let epoch = || {
            self.epoch.ok_or_else(|| {
                text.error(
                    Some(g.mode.span()),
                    format!(
                        "`{at}` mode = \"{mode}\" needs the scene's `epoch` (t = 0 as a date): add e.g. `epoch = \"2026-03-20T12:00:00 UTC\"` at the top of the scene"
                    ),
                )
            })
        };
        let axis = |x: &Option<Spanned<[f64; 3]>>, key: &str, default: Option<[f64; 3]>| match (
            x, default,
        ) {
            (Some(v), _) => {
                let a = Vector3::from(*v.get_ref());
                if !(a.iter().all(|c| c.is_finite()) && a.norm() > 0.0) {
                    return Err(text.error(
                        Some(v.span()),
                        format!("`{at}.{key}` must be a finite non-zero vector (body axes)"),
                    ));
                }
                Ok((a, Some(v.span())))
            }
            (None, Some(d)) => Ok((Vector3::from(d), None)),
            (None, None) => Err(text.error(
                Some(g.mode.span()),
                format!("`{at}` mode = \"{mode}\" needs `{key} = [x, y, z]` (a body axis)"),
            )),
        };
        let law = match mode {
            "inertial" | "nadir" => {
                let attitude = match &g.attitude {
                    Some(q) => {
                        let ([w, x, y, z], off) =
                            near_unit_quaternion(*q.get_ref()).map_err(|m| {
                                text.error(Some(q.span()), format!("`{at}.attitude`: {m}"))
                            })?;
                        if let Some(n) = off {
                            self.warn(
                                q.span(),
                                format!(
                                    "`{at}.attitude`: quaternion norm {} is not 1; normalised",
                                    Num(n)
                                ),
                            );
                        }
                        UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z))
                    }
                    None if mode == "inertial" => {
                        return Err(text.error(
                            Some(g.mode.span()),
                            format!(
                                "`{at}` mode = \"inertial\" needs `attitude = [w, x, y, z]` (body to inertial)"
                            ),
                        ));
                    }
                    None => UnitQuaternion::identity(),
                };
                if mode == "nadir" {
                    Guidance::Nadir(attitude)
                } else {
                    Guidance::Inertial(attitude)
                }
            }
            "sun" => {
                let (a, _) = axis(&g.axis, "axis", None)?;
                let (s, span) = axis(&g.secondary, "secondary", None)?;
                Guidance::sun(a, s, epoch()?)
                    .map_err(|m| text.error(span.or(Some(g.mode.span())), format!("`{at}`: {m}")))?
            }
            _ => {
                let (a, _) = axis(&g.axis, "axis", Some([0.0, 0.0, 1.0]))?;
                let (s, span) = axis(&g.secondary, "secondary", Some([0.0, -1.0, 0.0]))?;
                let deg = |x: &Option<Spanned<f64>>, key: &str, max: f64| match x {
                    Some(v) if v.get_ref().is_finite() && v.get_ref().abs() <= max => {
                        Ok(*v.get_ref())
                    }
                    Some(v) => Err(text.error(
                        Some(v.span()),
                        format!(
                            "`{at}.{key}` must be a finite number within ±{max}, got {}",
                            Num(*v.get_ref())
                        ),
                    )),
                    None => Err(text.error(
                        Some(g.mode.span()),
                        format!("`{at}` mode = \"target\" needs `{key}`"),
                    )),
                };
                let lat = deg(&g.latitude_deg, "latitude_deg", 90.0)?;
                let lon = deg(&g.longitude_deg, "longitude_deg", 360.0)?;
                let alt = match &g.altitude {
                    Some(h) if h.get_ref().is_finite() && h.get_ref().abs() < 1e8 => *h.get_ref(),
                    Some(h) => {
                        return Err(text.error(
                            Some(h.span()),
                            format!("`{at}.altitude` must be a finite height (m) within ±1e8"),
                        ));
                    }
                    None => 0.0,
                };
                Guidance::target(lat, lon, alt, a, s, epoch()?)
                    .map_err(|m| text.error(span.or(Some(g.mode.span())), format!("`{at}`: {m}")))?
            }
        };
        let limit = |x: &Option<Spanned<f64>>, key: &str| {
            x.as_ref()
                .map(|v| text.positive(v, &format!("{at}.{key}")))
                .transpose()
        };
        let slew = match (
            limit(&g.max_rate, "max_rate")?,
            limit(&g.max_acceleration, "max_acceleration")?,
        ) {
            (None, None) => None,
            (r, a) => Some(
                Slew::new(r.unwrap_or(f64::INFINITY), a.unwrap_or(f64::INFINITY))
                    .map_err(|m| text.error(Some(g.mode.span()), format!("`{at}`: {m}")))?,
            ),
        };
        Ok((law, slew))
    }

    /// A control table, run with an estimator of period `est_period` (its default period).
    fn control(
        &self,
        c: &Spanned<ControlFile>,
        at: &str,
        est_period: Option<f64>,
        clocks: &mut Vec<super::Clock>,
    ) -> Result<ControlSpec, FileError> {
        let text = self.text;
        let span = c.span();
        let title = format!("[{at}]");
        let c = c.get_ref();
        if let Some(k) = &c.kind
            && k.get_ref() != "pid"
        {
            return Err(text.error(
                Some(k.span()),
                format!(
                    "`{at}.kind`: unknown kind `{}`, expected \"pid\"",
                    k.get_ref()
                ),
            ));
        }
        let actuator = c
            .actuator
            .as_ref()
            .map(|a| (a.get_ref().as_str(), a.span()));
        match actuator {
            None | Some(("wheels" | "torquers" | "thrusters", _)) => {}
            Some((other, span)) => {
                return Err(text.error(
                    Some(span),
                    format!(
                        "`{at}.actuator`: unknown actuator `{other}`, expected \"wheels\", \"torquers\" or \"thrusters\""
                    ),
                ));
            }
        }
        let torquers = matches!(actuator, Some(("torquers", _)));
        let thrusters = matches!(actuator, Some(("thrusters", _)));
        if let (Some(m), false) = (&c.magnetometer, torquers) {
            return Err(text.error(
                Some(m.span()),
                format!("`{at}.magnetometer` belongs to actuator = \"torquers\""),
            ));
        }
        let kp = finite3(text, &c.kp, &format!("{at}.kp"))?;
        let kd = finite3(text, &c.kd, &format!("{at}.kd"))?;
        let ki = match &c.ki {
            Some(k) => finite3(text, k, &format!("{at}.ki"))?,
            None => [0.0; 3],
        };
        let inertia = match &c.inertia {
            Some(j) => {
                let m = *j.get_ref();
                if !satsim_spacecraft::fsw::inertia_is_valid(&m) {
                    return Err(text.error(
                        Some(j.span()),
                        format!("`{at}.inertia` must be a symmetric positive definite 3 x 3 matrix of finite numbers (kg m², body axes)"),
                    ));
                }
                Some(m)
            }
            None => None,
        };
        if self.effects.contains("attitude_control") && !torquers && !thrusters {
            return Err(text.error(
                Some(span),
                format!("{title} and [effects.attitude_control] would both command the wheels: set `enabled = false` in one of them"),
            ));
        }
        if self.model.base() != BaseKind::Free {
            return Err(text.error(
                Some(span),
                format!(
                    "{title} needs a free-floating root (the model has [base] kind = \"fixed\")"
                ),
            ));
        }
        let actuator = if torquers {
            let Some(m) = &c.magnetometer else {
                return Err(text.error(
                    Some(span),
                    format!("{title} actuator = \"torquers\" needs `magnetometer` (the field the dipole is worked out on)"),
                ));
            };
            let i = sensor(
                text,
                self.sensors(),
                m.get_ref(),
                m.span(),
                "magnetometer",
                (at, "magnetometer"),
            )?;
            if self.sensors().expect("found").sensors()[i].body() != 0 {
                return Err(text.error(
                    Some(m.span()),
                    format!("`{at}.magnetometer`: `{}` is not on the root body, whose torquers it commands", m.get_ref()),
                ));
            }
            if !self
                .effects
                .iter()
                .any(|e| e.torquers().iter().any(|t| t.body == 0))
            {
                return Err(text.error(
                    Some(span),
                    format!("{title} actuator = \"torquers\" needs magnetic torquers on the root body: add [[effects.magnetic.torquer]] to [effects.magnetic]"),
                ));
            }
            if self.effects.contains("bdot") {
                return Err(text.error(
                    Some(span),
                    format!("{title} and [effects.bdot] would both command the torquers: set `enabled = false` in one of them"),
                ));
            }
            Actuator::Torquers { magnetometer: i }
        } else if thrusters {
            let owned: Vec<_> = self.effects.iter().flat_map(|e| e.thrusters()).collect();
            if owned.is_empty() {
                return Err(text.error(
                    Some(span),
                    format!("{title} actuator = \"thrusters\" needs [effects.thrusters] with at least one [[effects.thrusters.thruster]]"),
                ));
            }
            if !owned.iter().any(|t| t.body == 0) {
                return Err(text.error(
                    Some(span),
                    format!(
                        "{title} actuator = \"thrusters\" needs thrusters on the root body `{}` (the control torques it): none of [[effects.thrusters.thruster]] is on it",
                        self.model.bodies()[0].name()
                    ),
                ));
            }
            Actuator::Thrusters
        } else {
            match self.effects.get::<ReactionWheels>() {
                Some(w) if !w.wheels.is_empty() => Actuator::Wheels(
                    // The bus's wheels: a wheel on another body (a control-moment gyro's
                    // rotor) turns with it, out of the bus's fixed axes the PID allocates in.
                    w.wheels
                        .iter()
                        .filter(|w| w.body.is_none())
                        .map(|w| (format!("wheel_{}", w.name), w.max_torque))
                        .collect(),
                ),
                _ => {
                    return Err(text.error(
                        Some(span),
                        format!("{title} actuator = \"wheels\" needs [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]]"),
                    ));
                }
            }
        };
        if matches!(actuator, Actuator::Wheels(_)) {
            let axes: Vec<Vector3<f64>> = self
                .effects
                .get::<ReactionWheels>()
                .map(|w| {
                    w.wheels
                        .iter()
                        .filter(|w| w.body.is_none())
                        .map(|w| w.axis)
                        .collect()
                })
                .unwrap_or_default();
            self.root_wheel_axes(&title, span.clone(), &axes)?;
        }
        let period = match (&c.period, est_period) {
            (Some(p), _) => {
                let v = text.positive(p, &format!("{at}.period"))?;
                clocks.push(super::Clock {
                    what: format!("`{at}`"),
                    line: Some(line_of(text.text(), p.span().start)),
                    period: v,
                });
                v
            }
            (None, Some(p)) => p,
            (None, None) => {
                return Err(text.error(
                    Some(span),
                    format!("{title} needs `period` (s): no estimator runs with it to take the period of"),
                ));
            }
        };
        if thrusters
            && let Some(th) = self.effects.get::<Thrusters>()
            && !Self::multiple(period, th.period())
        {
            // A command sampled between the thrusters' period starts would wait for the
            // next one: the control's samples must be period starts.
            let at_line = c.period.as_ref().map_or(span, |p| p.span());
            return Err(text.error(
                Some(at_line),
                format!(
                    "`{at}.period` ({period} s{}) must be a whole multiple of [effects.thrusters] `period` ({} s): the thrusters latch the control's duties at their period starts",
                    if c.period.is_none() { ", the estimator's" } else { "" },
                    th.period()
                ),
            ));
        }
        if matches!(actuator, Actuator::Wheels(_)) {
            self.wheel_laws.borrow_mut().push(WheelLaw {
                title,
                line: line_of(text.text(), span.start),
                law: PidLaw { kp, ki, kd, period },
            });
        }
        Ok(ControlSpec {
            pid: Pid::new(kp, ki, kd, inertia),
            period,
            actuator,
        })
    }

    /// `[fsw.bdot]` or `[fsw.momentum]` (`block`), with its magnetometer, gain and period.
    fn magnetic(
        &self,
        block: &str,
        mag: &Spanned<String>,
        gain: &Spanned<f64>,
        period: &Option<Spanned<f64>>,
    ) -> Result<DipoleSpec, FileError> {
        let text = self.text;
        let name = format!("fsw.{block}");
        let sensors = self.sensors();
        let i = sensor(
            text,
            sensors,
            mag.get_ref(),
            mag.span(),
            "magnetometer",
            (&name, "magnetometer"),
        )?;
        let s = &sensors.expect("a sensor was found").sensors()[i];
        if s.body() != 0 {
            return Err(text.error(
                Some(mag.span()),
                format!(
                    "`{name}.magnetometer`: magnetometer `{}` is not on the root body: the torquers it commands are the bus's, put it on the root body",
                    s.name()
                ),
            ));
        }
        let k = text.positive(gain, &format!("{name}.gain"))?;
        let mag_period = s.period();
        let (period, every) = match period {
            Some(p) => {
                let v = text.positive(p, &format!("{name}.period"))?;
                if !Self::multiple(v, mag_period) {
                    return Err(text.error(
                        Some(p.span()),
                        format!(
                            "`{name}.period` = {} s is not a whole multiple of the magnetometer `{}`'s period {} s: the block runs at its samples",
                            Num(v),
                            s.name(),
                            Num(mag_period)
                        ),
                    ));
                }
                let n = (v / mag_period).round();
                (n * mag_period, n as u64)
            }
            None => (mag_period, 1),
        };
        Ok(DipoleSpec {
            law: if block == "bdot" {
                DipoleLaw::Bdot { gain: k }
            } else {
                DipoleLaw::Momentum { gain: k }
            },
            magnetometer: i,
            period,
            every,
            wheels: Vec::new(),
        })
    }

    /// What a magnetic block needs of the scene: torquers on the root body, no
    /// `[effects.bdot]`, and wheels to dump for momentum.
    fn magnetic_checks(
        &self,
        block: &str,
        span: Range<usize>,
        mut spec: DipoleSpec,
    ) -> Result<DipoleSpec, FileError> {
        let text = self.text;
        let title = format!("[fsw.{block}]");
        if !self
            .effects
            .iter()
            .any(|e| e.torquers().iter().any(|t| t.body == 0))
        {
            return Err(text.error(
                Some(span),
                format!(
                    "{title} commands the magnetic torquers, but the scene has none on the root body: add [[effects.magnetic.torquer]] to [effects.magnetic]"
                ),
            ));
        }
        if self.effects.contains("bdot") {
            return Err(text.error(
                Some(span),
                format!(
                    "{title} and [effects.bdot] would both command the torquers: set `enabled = false` in one of them"
                ),
            ));
        }
        if block == "momentum" {
            spec.wheels = match self.effects.get::<ReactionWheels>() {
                Some(w) if !w.wheels.is_empty() => w
                    .wheels
                    .iter()
                    .filter(|w| w.body.is_none())
                    .map(|w| format!("wheel_{}", w.name))
                    .collect(),
                _ => {
                    return Err(text.error(
                        Some(span),
                        "[fsw.momentum] dumps the reaction wheels' momentum: it needs [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]]",
                    ));
                }
            };
        }
        Ok(spec)
    }
}

/// A key, where it is written, and the modes it belongs to.
type Belongs<'a> = (&'a str, Option<Range<usize>>, &'a [&'a str]);

/// A guidance law and its shaper.
type Shaped = (Guidance, Option<Slew>);

/// The scene's own (top-level) blocks, read and checked, with where they are written.
struct TopBlocks {
    estimator: Option<(EstimatorSpec, Range<usize>, bool)>,
    guidance: Option<(Shaped, Range<usize>, bool)>,
    control: Option<(Spanned<ControlFile>, bool)>,
    bdot: Option<(DipoleSpec, Range<usize>, bool)>,
    momentum: Option<(DipoleSpec, Range<usize>, bool)>,
}

/// Reads `[fsw]` against the model, the epoch, the enabled effects and the sensors (in
/// `effects`), and hands the blocks to the sensors ([`Sensors::set_fsw`]); the controls'
/// clocks go to `clocks`, its warnings to `warnings`. Returns the controls on the wheels,
/// for the check of their sampled loops.
pub(crate) fn read(
    text: &SceneText,
    file: &Spanned<FswFile>,
    model: &Model,
    epoch: Option<Epoch>,
    effects: &mut EffectSet,
    clocks: &mut Vec<super::Clock>,
    warnings: &mut Vec<String>,
) -> Result<Vec<WheelLaw>, FileError> {
    let f = file.get_ref();
    let on = |e: Option<bool>| e != Some(false);
    let w = Within {
        text,
        model,
        effects,
        epoch,
        wheel_laws: RefCell::new(Vec::new()),
        warnings: RefCell::new(Vec::new()),
    };
    // A magnetic block: read, and checked against the scene when it is enabled.
    let magnetic = |block: &str, file: &Spanned<MagneticFile>| {
        let (r, span) = (file.get_ref(), file.span());
        let spec = w.magnetic(block, &r.magnetometer, &r.gain, &r.period)?;
        let spec = if on(r.enabled) {
            w.magnetic_checks(block, span.clone(), spec)?
        } else {
            spec
        };
        Ok::<_, FileError>((spec, span, on(r.enabled)))
    };
    let top = TopBlocks {
        estimator: f
            .estimator
            .as_ref()
            .map(|e| {
                Ok((
                    w.estimator(e.get_ref(), "fsw.estimator")?,
                    e.span(),
                    on(e.get_ref().enabled),
                ))
            })
            .transpose()?,
        guidance: f
            .guidance
            .as_ref()
            .map(|g| {
                Ok((
                    w.guidance(g.get_ref(), "fsw.guidance")?,
                    g.span(),
                    on(g.get_ref().enabled),
                ))
            })
            .transpose()?,
        control: f
            .control
            .as_ref()
            .map(|c| (c.clone(), on(c.get_ref().enabled))),
        bdot: f.bdot.as_ref().map(|b| magnetic("bdot", b)).transpose()?,
        momentum: f
            .momentum
            .as_ref()
            .map(|m| magnetic("momentum", m))
            .transpose()?,
    };
    let onboard = match &f.mode {
        None => without_modes(&w, &top, clocks)?,
        Some(modes) => with_modes(&w, &top, modes, clocks)?,
    };
    let laws = w.wheel_laws.take();
    warnings.extend(w.warnings.take());
    let Some(onboard) = onboard else {
        return Ok(laws);
    };
    effects
        .get_mut::<Sensors>()
        .expect("every block reads the sensors")
        .set_fsw(onboard);
    Ok(laws)
}

/// Every enabled block from the start (`None` when none is).
fn without_modes(
    w: &Within,
    top: &TopBlocks,
    clocks: &mut Vec<super::Clock>,
) -> Result<Option<Onboard>, FileError> {
    let text = w.text;
    let estimator = top.estimator.as_ref().filter(|e| e.2);
    let guidance = top.guidance.as_ref().filter(|g| g.2);
    let mut onboard = Onboard::new();
    let mut any = false;
    if let Some((c, true)) = &top.control {
        let span = c.span();
        let Some((est, _, _)) = estimator else {
            return Err(text.error(
                Some(span),
                "[fsw.control] needs an estimator: add [fsw.estimator] (the control acts on the estimate, never on the truth)",
            ));
        };
        if guidance.is_none() {
            return Err(text.error(
                Some(span),
                "[fsw.control] needs a reference: add [fsw.guidance]",
            ));
        }
        let spec = w.control(c, "fsw.control", Some(est.period), clocks)?;
        check_control_body(w, span, est)?;
        onboard.add_control(spec).expect("a period > 0");
        any = true;
    }
    if let Some((_, span, _)) = guidance
        && estimator.is_none()
    {
        return Err(text.error(
            Some(span.clone()),
            "[fsw.guidance] needs an estimator: add [fsw.estimator] (the guidance runs on its clock and points the body it estimates)",
        ));
    }
    if let Some((spec, _, _)) = estimator {
        onboard.add_estimator(spec.clone());
        any = true;
    }
    if let Some(((law, slew), _, _)) = guidance {
        onboard.add_guidance(*law, *slew);
    }
    let bdot = top.bdot.as_ref().filter(|b| b.2);
    let momentum = top.momentum.as_ref().filter(|m| m.2);
    if let (Some(_), Some((_, span, _))) = (bdot, momentum) {
        return Err(text.error(
            Some(span.clone()),
            "[fsw.momentum] and [fsw.bdot] would both command the torquers: set `enabled = false` in one of them, or run them in different [[fsw.mode]]s",
        ));
    }
    if let Some((spec, _, _)) = bdot.or(momentum) {
        onboard.add_magnetic(spec.clone());
        any = true;
    }
    if !any {
        return Ok(None);
    }
    onboard
        .finish()
        .map(Some)
        .map_err(|m| text.error(None, format!("[fsw]: {m}")))
}

/// A control flies the root body: its estimator's body must be the root.
fn check_control_body(
    w: &Within,
    span: Range<usize>,
    est: &EstimatorSpec,
) -> Result<(), FileError> {
    if est.body != 0 {
        return Err(w.text.error(
            Some(span),
            format!(
                "[fsw.control] torques the root body `{}`, but the estimator's gyro is on `{}`: put the gyro and the star trackers on the root body",
                w.model.bodies()[0].name(),
                w.model.bodies()[est.body].name()
            ),
        ));
    }
    Ok(())
}

/// The modes, in order.
fn with_modes(
    w: &Within,
    top: &TopBlocks,
    modes: &[Spanned<ModeFile>],
    clocks: &mut Vec<super::Clock>,
) -> Result<Option<Onboard>, FileError> {
    let text = w.text;
    let mut onboard = Onboard::new();
    // The top-level blocks, added when a mode first runs them.
    let (mut est_at, mut guid_at, mut ctrl_at, mut bdot_at, mut mom_at) =
        (None, None, None, None, None);
    let mut names: Vec<&str> = Vec::new();
    for (k, m) in modes.iter().enumerate() {
        let span = m.span();
        let m = m.get_ref();
        let name = m.name.get_ref().as_str();
        let at = |what: &str| format!("fsw.mode `{name}`: {what}");
        if names.contains(&name) {
            return Err(text.error(
                Some(m.name.span()),
                format!("`fsw.mode.name`: two modes are called `{name}`"),
            ));
        }
        names.push(name);
        let blocks = m.blocks.get_ref();
        let kinds = ["estimator", "guidance", "control", "bdot", "momentum"];
        for b in blocks {
            if !kinds.contains(&b.as_str()) {
                return Err(text.error(
                    Some(m.blocks.span()),
                    format!("`fsw.mode.blocks`: unknown block `{b}`, expected some of \"estimator\", \"guidance\", \"control\", \"bdot\", \"momentum\""),
                ));
            }
            if blocks.iter().filter(|x| *x == b).count() > 1 {
                return Err(text.error(
                    Some(m.blocks.span()),
                    format!("`fsw.mode.blocks` lists `{b}` twice"),
                ));
            }
        }
        let runs = |kind: &str| blocks.iter().any(|b| b == kind);
        if runs("bdot") && runs("momentum") {
            return Err(text.error(
                Some(m.blocks.span()),
                "`fsw.mode.blocks`: \"bdot\" and \"momentum\" would both command the torquers: run them in different modes",
            ));
        }
        for (kind, own) in [
            ("estimator", m.estimator.as_ref().map(|x| x.span())),
            ("guidance", m.guidance.as_ref().map(|x| x.span())),
            ("control", m.control.as_ref().map(|x| x.span())),
        ] {
            if let Some(s) = own
                && !runs(kind)
            {
                return Err(text.error(
                    Some(s),
                    format!("mode `{name}` gives its own [fsw.mode.{kind}] but its `blocks` do not list \"{kind}\""),
                ));
            }
        }
        // A top-level block: it must exist and be enabled.
        let top_block = |kind: &str, present: bool, enabled: bool| {
            if !present {
                Err(text.error(
                    Some(m.blocks.span()),
                    format!("mode `{name}` runs \"{kind}\" but the scene has no [fsw.{kind}] (and the mode gives no [fsw.mode.{kind}])"),
                ))
            } else if !enabled {
                Err(text.error(
                    Some(m.blocks.span()),
                    format!("mode `{name}` runs \"{kind}\" but [fsw.{kind}] has `enabled = false`"),
                ))
            } else {
                Ok(())
            }
        };
        let mut mode = Mode::new(name);
        // Estimator.
        let mut est_spec = None;
        if runs("estimator") {
            mode.estimator = Some(match &m.estimator {
                Some(e) => {
                    let spec = w.estimator(e.get_ref(), "fsw.mode.estimator")?;
                    est_spec = Some(spec.clone());
                    onboard.add_estimator(spec)
                }
                None => {
                    top_block(
                        "estimator",
                        top.estimator.is_some(),
                        top.estimator.as_ref().is_some_and(|e| e.2),
                    )?;
                    let (spec, _, _) = top.estimator.as_ref().expect("checked");
                    est_spec = Some(spec.clone());
                    *est_at.get_or_insert_with(|| onboard.add_estimator(spec.clone()))
                }
            });
        }
        if runs("guidance") {
            mode.guidance = Some(match &m.guidance {
                Some(g) => {
                    let (law, slew) = w.guidance(g.get_ref(), "fsw.mode.guidance")?;
                    onboard.add_guidance(law, slew)
                }
                None => {
                    top_block(
                        "guidance",
                        top.guidance.is_some(),
                        top.guidance.as_ref().is_some_and(|g| g.2),
                    )?;
                    let ((law, slew), _, _) = top.guidance.as_ref().expect("checked");
                    *guid_at.get_or_insert_with(|| onboard.add_guidance(*law, *slew))
                }
            });
        }
        if runs("control") {
            let Some(est) = &est_spec else {
                return Err(text.error(
                    Some(m.blocks.span()),
                    format!("mode `{name}` runs \"control\" without an \"estimator\" (the control acts on the estimate, never on the truth)"),
                ));
            };
            if mode.guidance.is_none() {
                return Err(text.error(
                    Some(m.blocks.span()),
                    format!(
                        "mode `{name}` runs \"control\" without a \"guidance\" (its reference)"
                    ),
                ));
            }
            let (c, shared) = match &m.control {
                Some(c) => (c.clone(), false),
                None => {
                    top_block(
                        "control",
                        top.control.is_some(),
                        top.control.as_ref().is_some_and(|c| c.1),
                    )?;
                    (top.control.as_ref().expect("checked").0.clone(), true)
                }
            };
            let title = if shared {
                "fsw.control"
            } else {
                "fsw.mode.control"
            };
            // The shared control's default period is the scene's estimator's.
            let est_period = if shared {
                top.estimator
                    .as_ref()
                    .map(|e| e.0.period)
                    .or(Some(est.period))
            } else {
                Some(est.period)
            };
            check_control_body(w, c.span(), est)?;
            mode.control = Some(if shared {
                match ctrl_at {
                    Some(i) => i,
                    None => {
                        let spec = w.control(&c, title, est_period, clocks)?;
                        let i = onboard.add_control(spec).expect("a period > 0");
                        ctrl_at = Some(i);
                        i
                    }
                }
            } else {
                let spec = w.control(&c, title, est_period, clocks)?;
                onboard.add_control(spec).expect("a period > 0")
            });
        }
        if runs("guidance") && mode.estimator.is_none() {
            return Err(text.error(
                Some(m.blocks.span()),
                format!("mode `{name}` runs \"guidance\" without an \"estimator\" (the guidance runs on its clock and points the body it estimates)"),
            ));
        }
        for (kind, block, at_) in [
            ("bdot", &top.bdot, &mut bdot_at),
            ("momentum", &top.momentum, &mut mom_at),
        ] {
            if runs(kind) {
                top_block(kind, block.is_some(), block.as_ref().is_some_and(|b| b.2))?;
                let (spec, _, _) = block.as_ref().expect("checked");
                mode.magnetic =
                    Some(*at_.get_or_insert_with(|| onboard.add_magnetic(spec.clone())));
            }
        }
        // What ends it.
        let last = k + 1 == modes.len();
        match (&m.until, last) {
            (Some(u), true) => {
                return Err(text.error(
                    Some(u.span()),
                    format!("`fsw.mode.until`: the last mode `{name}` has no mode to switch to (leave `until` out)"),
                ));
            }
            (None, false) => {
                return Err(text.error(
                    Some(span),
                    format!("mode `{name}` needs `until` (\"rate < x\", \"error < x\" or \"time > x\"): modes follow it"),
                ));
            }
            (Some(u), false) => {
                mode.until =
                    Some(Condition::parse(u.get_ref()).map_err(|e| {
                        text.error(Some(u.span()), format!("`fsw.mode.until`: {e}"))
                    })?);
            }
            (None, true) => {}
        }
        if let Some(h) = &m.hold {
            let v = *h.get_ref();
            if !(v.is_finite() && v >= 0.0) {
                return Err(text.error(
                    Some(h.span()),
                    format!(
                        "`fsw.mode.hold` must be a finite number >= 0 (s), got {}",
                        Num(v)
                    ),
                ));
            }
            mode.hold = v;
        }
        // The gyro of `rate < x` without an estimator.
        mode.gyro = match &m.gyro {
            Some(g) => Some(sensor(
                text,
                w.sensors(),
                g.get_ref(),
                g.span(),
                "gyro",
                ("fsw.mode", "gyro"),
            )?),
            None => w.sensors().and_then(|s| {
                let mut root = s
                    .sensors()
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| s.kind().name() == "gyro" && s.body() == 0);
                match (root.next(), root.next()) {
                    (Some((i, _)), None) => Some(i),
                    _ => None,
                }
            }),
        };
        if matches!(mode.until, Some(Condition::RateBelow(_)))
            && mode.estimator.is_none()
            && mode.gyro.is_none()
        {
            return Err(text.error(
                Some(m.until.as_ref().expect("a condition").span()),
                format!("mode `{name}`: \"rate < x\" reads the rate of the mode's estimator or of a gyro: give `gyro = \"name\"` (the scene has no single gyro on the root body)"),
            ));
        }
        onboard
            .add_mode(mode)
            .map_err(|e| text.error(Some(span.clone()), at(&e)))?;
    }
    // A top-level block no mode runs is a mistake, unless it is switched off.
    for (kind, span, used) in [
        (
            "estimator",
            top.estimator.as_ref().filter(|e| e.2).map(|e| e.1.clone()),
            est_at.is_some(),
        ),
        (
            "guidance",
            top.guidance.as_ref().filter(|g| g.2).map(|g| g.1.clone()),
            guid_at.is_some(),
        ),
        (
            "control",
            top.control.as_ref().filter(|c| c.1).map(|c| c.0.span()),
            ctrl_at.is_some(),
        ),
        (
            "bdot",
            top.bdot.as_ref().filter(|b| b.2).map(|b| b.1.clone()),
            bdot_at.is_some(),
        ),
        (
            "momentum",
            top.momentum.as_ref().filter(|m| m.2).map(|m| m.1.clone()),
            mom_at.is_some(),
        ),
    ] {
        if let (Some(span), false) = (span, used) {
            return Err(text.error(
                Some(span),
                format!("[fsw.{kind}] runs in no [[fsw.mode]]: list \"{kind}\" in a mode's `blocks`, or set `enabled = false`"),
            ));
        }
    }
    onboard
        .finish()
        .map(Some)
        .map_err(|m| text.error(None, format!("[[fsw.mode]]: {m}")))
}
