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
//! actuator = "wheels"      # (default)
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
//! `[fsw.bdot]` and `[fsw.momentum]` need magnetic torquers on the root body; at most one of
//! them (and not `[effects.bdot]`) is enabled. Every block accepts `enabled = false` (read
//! and checked, then left out). Not yet supported, each refused at its line: guidance modes
//! `"sun"` and `"target"`, `max_rate` and `max_acceleration`, `actuator = "torquers"` and
//! `"thrusters"`, and `[[fsw.mode]]`. Every error names the scene file and the line.

use nalgebra::{Quaternion, UnitQuaternion};
use satsim_spacecraft::effects::{EffectSet, ReactionWheels, SceneText};
use satsim_spacecraft::fsw::{
    ControlSpec, DipoleLaw, DipoleSpec, EstimatorSpec, Guidance, MekfParams, Onboard, Pid,
};
use satsim_spacecraft::sensors::{Kind, Sensors};
use satsim_tree::error::Num;
use satsim_tree::io::{FileError, line_of};
use satsim_tree::{BaseKind, Model};
use serde::Deserialize;
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
    pub momentum: Option<Spanned<MomentumFile>>,
    /// `[fsw.bdot]`: B-dot on the magnetometer's readings.
    #[serde(default)]
    pub bdot: Option<Spanned<BdotFile>>,
    /// `[[fsw.mode]]`: not yet supported.
    #[serde(default)]
    pub mode: Option<Spanned<toml::Value>>,
}

/// `[fsw.estimator]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorFile {
    /// `"mekf"` (the default and the only kind).
    #[serde(default)]
    pub kind: Option<Spanned<String>>,
    /// The gyro's name.
    pub gyro: Spanned<String>,
    /// A star tracker's name or a list of them.
    pub star_tracker: Spanned<toml::Value>,
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
    /// `"inertial"` or `"nadir"` (`"sun"`, `"target"`: not yet supported).
    pub mode: Spanned<String>,
    /// Inertial: the attitude `[w, x, y, z]` (body to inertial); nadir: an offset from the
    /// orbital frame (body to orbital, default none).
    #[serde(default)]
    pub attitude: Option<Spanned<[f64; 4]>>,
    /// Slew shaping: not yet supported.
    #[serde(default)]
    pub max_rate: Option<Spanned<toml::Value>>,
    /// Slew shaping: not yet supported.
    #[serde(default)]
    pub max_acceleration: Option<Spanned<toml::Value>>,
    /// `"sun"` mode's keys: not yet supported.
    #[serde(default)]
    pub axis: Option<Spanned<toml::Value>>,
    /// `"sun"` mode's keys: not yet supported.
    #[serde(default)]
    pub secondary: Option<Spanned<toml::Value>>,
    /// `"target"` mode's keys: not yet supported.
    #[serde(default)]
    pub latitude_deg: Option<Spanned<toml::Value>>,
    /// `"target"` mode's keys: not yet supported.
    #[serde(default)]
    pub longitude_deg: Option<Spanned<toml::Value>>,
    /// `"target"` mode's keys: not yet supported.
    #[serde(default)]
    pub altitude: Option<Spanned<toml::Value>>,
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
    pub kp: Spanned<[f64; 3]>,
    /// Integral gains (N m/(rad s), default 0).
    #[serde(default)]
    pub ki: Option<Spanned<[f64; 3]>>,
    /// Derivative gains (N m s/rad).
    pub kd: Spanned<[f64; 3]>,
    /// Sample period (s, default the estimator's).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
    /// `"wheels"` (the default; `"torquers"`, `"thrusters"`: not yet supported).
    #[serde(default)]
    pub actuator: Option<Spanned<String>>,
    /// Inertia for the gyroscopic feed-forward `ω × (J ω)` (kg m², body axes; default none).
    #[serde(default)]
    pub inertia: Option<Spanned<[[f64; 3]; 3]>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[fsw.bdot]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BdotFile {
    /// The magnetometer's name (a [[sensors.magnetometer]] on the root body).
    pub magnetometer: Spanned<String>,
    /// The gain k (A m² s/T, > 0).
    pub gain: Spanned<f64>,
    /// Sample period (s, default the magnetometer's; a whole multiple of it).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[fsw.momentum]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MomentumFile {
    /// The gain k (1/s, > 0).
    pub gain: Spanned<f64>,
    /// The magnetometer's name (a [[sensors.magnetometer]] on the root body).
    pub magnetometer: Spanned<String>,
    /// Sample period (s, default the magnetometer's; a whole multiple of it).
    #[serde(default)]
    pub period: Option<Spanned<f64>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

fn not_yet(text: &SceneText, span: Range<usize>, what: &str) -> FileError {
    text.error(Some(span), format!("not yet supported: {what}"))
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

/// Reads `[fsw]` against the model, the enabled effects and the sensors (in `effects`), and
/// hands the blocks to the sensors ([`Sensors::set_fsw`]); the control's clock goes to
/// `clocks`.
pub(crate) fn read(
    text: &SceneText,
    file: &Spanned<FswFile>,
    model: &Model,
    effects: &mut EffectSet,
    clocks: &mut Vec<super::Clock>,
) -> Result<(), FileError> {
    let f = file.get_ref();
    if let Some(m) = &f.mode {
        return Err(not_yet(
            text,
            m.span(),
            "[[fsw.mode]] (mode switching): the enabled blocks run from the start",
        ));
    }
    let on = |e: Option<bool>| e != Some(false);
    let sensors = effects.get::<Sensors>();

    // Estimator.
    let mut estimator = None;
    if let Some(es) = f.estimator.as_ref() {
        let e = es.get_ref();
        if let Some(k) = &e.kind
            && k.get_ref() != "mekf"
        {
            return Err(text.error(
                Some(k.span()),
                format!(
                    "`fsw.estimator.kind`: unknown kind `{}`, expected \"mekf\"",
                    k.get_ref()
                ),
            ));
        }
        let gyro = sensor(
            text,
            sensors,
            e.gyro.get_ref(),
            e.gyro.span(),
            "gyro",
            ("fsw.estimator", "gyro"),
        )?;
        let list = sensors.expect("a sensor was found").sensors();
        let g = &list[gyro];
        let Kind::Gyro(gm) = g.kind() else {
            unreachable!("checked a gyro")
        };
        let names: Vec<String> = match e.star_tracker.get_ref() {
            toml::Value::String(s) => vec![s.clone()],
            toml::Value::Array(a) if !a.is_empty() && a.iter().all(|v| v.is_str()) => a
                .iter()
                .map(|v| v.as_str().unwrap_or_default().to_owned())
                .collect(),
            _ => {
                return Err(text.error(
                    Some(e.star_tracker.span()),
                    "`fsw.estimator.star_tracker` must be a star tracker's name or a non-empty list of names",
                ));
            }
        };
        let period = g.period();
        let mut trackers = Vec::new();
        for name in &names {
            let span = e.star_tracker.span();
            let i = sensor(
                text,
                sensors,
                name,
                span.clone(),
                "star_tracker",
                ("fsw.estimator", "star_tracker"),
            )?;
            let st = &list[i];
            if st.body() != g.body() {
                let body = |b: usize| model.bodies()[b].name().to_owned();
                return Err(text.error(
                    Some(span),
                    format!(
                        "`fsw.estimator.star_tracker`: star tracker `{name}` is on body `{}`, the gyro `{}` on `{}`: the estimator needs them on the same body",
                        body(st.body()),
                        g.name(),
                        body(g.body())
                    ),
                ));
            }
            let ratio = st.period() / period;
            if !(ratio.round() >= 1.0 && (ratio - ratio.round()).abs() <= 1e-9 * ratio) {
                return Err(text.error(
                    Some(span),
                    format!(
                        "`fsw.estimator.star_tracker`: star tracker `{name}` samples every {} s, not a whole multiple of the gyro's period {} s: the filter updates at the gyro's samples",
                        Num(st.period()),
                        Num(period)
                    ),
                ));
            }
            if trackers.iter().any(|(j, _)| *j == i) {
                return Err(text.error(
                    Some(span),
                    format!("`fsw.estimator.star_tracker` lists `{name}` twice"),
                ));
            }
            let Kind::StarTracker(s) = st.kind() else {
                unreachable!("checked a star tracker")
            };
            trackers.push((i, s.noise));
        }
        if let Some(p) = &e.period {
            let v = text.positive(p, "fsw.estimator.period")?;
            if (v - period).abs() > 1e-9 * period {
                return Err(text.error(
                    Some(p.span()),
                    format!(
                        "`fsw.estimator.period` = {} s must be the gyro `{}`'s period, {} s: the filter propagates once per gyro sample (leave `period` out to take the gyro's)",
                        Num(v),
                        g.name(),
                        Num(period)
                    ),
                ));
            }
        }
        let sigma = |x: &Option<Spanned<f64>>, what: &str, default: f64| {
            x.as_ref().map_or(Ok(default), |x| text.positive(x, what))
        };
        let params = MekfParams {
            sigma_v: gm.noise_density,
            sigma_u: gm.bias_walk,
            sigma_attitude: sigma(&e.sigma_attitude, "fsw.estimator.sigma_attitude", 0.01)?,
            sigma_bias: sigma(&e.sigma_bias, "fsw.estimator.sigma_bias", 1e-4)?,
        };
        if on(e.enabled) {
            estimator = Some((
                EstimatorSpec {
                    gyro,
                    period,
                    star_trackers: trackers,
                    body: g.body(),
                    params,
                },
                es.span(),
            ));
        }
    }

    // Guidance.
    let mut guidance = None;
    if let Some(gs) = f.guidance.as_ref() {
        let g = gs.get_ref();
        for (key, v) in [
            ("max_rate", &g.max_rate),
            ("max_acceleration", &g.max_acceleration),
        ] {
            if let Some(v) = v {
                return Err(not_yet(
                    text,
                    v.span(),
                    &format!(
                        "`fsw.guidance.{key}` (slew shaping): the reference steps at once; leave it out"
                    ),
                ));
            }
        }
        let mode = g.mode.get_ref().as_str();
        match mode {
            "inertial" | "nadir" => {}
            "sun" | "target" => {
                return Err(not_yet(
                    text,
                    g.mode.span(),
                    &format!(
                        "`fsw.guidance.mode` = \"{mode}\": the modes so far are \"inertial\" and \"nadir\""
                    ),
                ));
            }
            other => {
                return Err(text.error(
                    Some(g.mode.span()),
                    format!(
                        "`fsw.guidance.mode`: unknown mode `{other}`, expected \"inertial\" or \"nadir\" (\"sun\" and \"target\" are not yet supported)"
                    ),
                ));
            }
        }
        for (key, v, of) in [
            ("axis", &g.axis, "sun"),
            ("secondary", &g.secondary, "sun"),
            ("latitude_deg", &g.latitude_deg, "target"),
            ("longitude_deg", &g.longitude_deg, "target"),
            ("altitude", &g.altitude, "target"),
        ] {
            if let Some(v) = v {
                return Err(text.error(
                    Some(v.span()),
                    format!(
                        "`fsw.guidance.{key}` belongs to mode = \"{of}\" (not yet supported), not to \"{mode}\""
                    ),
                ));
            }
        }
        let attitude = match &g.attitude {
            Some(q) => {
                let [w, x, y, z] = *q.get_ref();
                let quat = Quaternion::new(w, x, y, z);
                let n = quat.norm();
                if !n.is_finite() || (n - 1.0).abs() > 1e-6 {
                    return Err(text.error(
                        Some(q.span()),
                        format!(
                            "`fsw.guidance.attitude`: quaternion norm {} is not 1",
                            Num(n)
                        ),
                    ));
                }
                UnitQuaternion::from_quaternion(quat)
            }
            None if mode == "inertial" => {
                return Err(text.error(
                    Some(g.mode.span()),
                    "`fsw.guidance` mode = \"inertial\" needs `attitude = [w, x, y, z]` (body to inertial)",
                ));
            }
            None => UnitQuaternion::identity(),
        };
        let law = if mode == "nadir" {
            if !effects.contains("orbit") {
                return Err(text.error(
                    Some(g.mode.span()),
                    "`fsw.guidance` mode = \"nadir\" needs an [orbit] table (e.g. `[orbit]` with `altitude = 500e3`)",
                ));
            }
            Guidance::Nadir(attitude)
        } else {
            Guidance::Inertial(attitude)
        };
        if on(g.enabled) {
            guidance = Some((law, gs.span()));
        }
    }

    // Control.
    let mut control = None;
    if let Some(cs) = f.control.as_ref() {
        let c = cs.get_ref();
        if let Some(k) = &c.kind
            && k.get_ref() != "pid"
        {
            return Err(text.error(
                Some(k.span()),
                format!(
                    "`fsw.control.kind`: unknown kind `{}`, expected \"pid\"",
                    k.get_ref()
                ),
            ));
        }
        match c
            .actuator
            .as_ref()
            .map(|a| (a.get_ref().as_str(), a.span()))
        {
            None | Some(("wheels", _)) => {}
            Some((a @ ("torquers" | "thrusters"), span)) => {
                return Err(not_yet(
                    text,
                    span,
                    &format!(
                        "`fsw.control.actuator` = \"{a}\": the control commands the reaction wheels (\"wheels\") so far"
                    ),
                ));
            }
            Some((other, span)) => {
                return Err(text.error(
                    Some(span),
                    format!(
                        "`fsw.control.actuator`: unknown actuator `{other}`, expected \"wheels\""
                    ),
                ));
            }
        }
        let kp = finite3(text, &c.kp, "fsw.control.kp")?;
        let kd = finite3(text, &c.kd, "fsw.control.kd")?;
        let ki = match &c.ki {
            Some(k) => finite3(text, k, "fsw.control.ki")?,
            None => [0.0; 3],
        };
        let inertia = match &c.inertia {
            Some(j) => {
                let m = *j.get_ref();
                let symmetric = (0..3).all(|r| (0..3).all(|k| m[r][k] == m[k][r]));
                if !m.iter().flatten().all(|v| v.is_finite()) || !symmetric {
                    return Err(text.error(
                        Some(j.span()),
                        "`fsw.control.inertia` must be a symmetric 3 x 3 matrix of finite numbers (kg m², body axes)",
                    ));
                }
                Some(m)
            }
            None => None,
        };
        let span = cs.span();
        if on(c.enabled) {
            let Some((est, _)) = &estimator else {
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
            if effects.contains("attitude_control") {
                return Err(text.error(
                    Some(span),
                    "[fsw.control] and [effects.attitude_control] would both command the wheels: set `enabled = false` in one of them",
                ));
            }
            if model.base() != BaseKind::Free {
                return Err(text.error(
                    Some(span),
                    "[fsw.control] needs a free-floating root (the model has [base] kind = \"fixed\")",
                ));
            }
            if est.body != 0 {
                return Err(text.error(
                    Some(span),
                    format!(
                        "[fsw.control] torques the root body `{}` through the wheels, but the estimator's gyro is on `{}`: put the gyro and the star trackers on the root body",
                        model.bodies()[0].name(),
                        model.bodies()[est.body].name()
                    ),
                ));
            }
            let wheels: Vec<(String, f64)> = match effects.get::<ReactionWheels>() {
                Some(w) if !w.wheels.is_empty() => w
                    .wheels
                    .iter()
                    .map(|w| (format!("wheel_{}", w.name), w.max_torque))
                    .collect(),
                _ => {
                    return Err(text.error(
                        Some(span),
                        "[fsw.control] actuator = \"wheels\" needs [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]]",
                    ));
                }
            };
            let period = match &c.period {
                Some(p) => {
                    let v = text.positive(p, "fsw.control.period")?;
                    clocks.push(super::Clock {
                        what: "`fsw.control`".into(),
                        line: Some(line_of(text.text(), p.span().start)),
                        period: v,
                    });
                    v
                }
                None => est.period,
            };
            control = Some(ControlSpec {
                pid: Pid::new(kp, ki, kd, inertia),
                period,
                wheels,
            });
        }
    }

    if let (Some((_, span)), None) = (&guidance, &estimator) {
        return Err(text.error(
            Some(span.clone()),
            "[fsw.guidance] needs an estimator: add [fsw.estimator] (the guidance runs on its clock and points the body it estimates)",
        ));
    }
    let magnetic = magnetic_block(text, f, effects)?;
    let Some(mut onboard) = Onboard::new(estimator.map(|e| e.0), guidance.map(|g| g.0), control)
    else {
        return Err(text.error(Some(file.span()), "[fsw]: inconsistent blocks"));
    };
    if let Some(spec) = magnetic {
        onboard = onboard.with_magnetic(spec);
    }
    if onboard.columns().is_empty() {
        return Ok(());
    }
    effects
        .get_mut::<Sensors>()
        .expect("every block reads the sensors")
        .set_fsw(onboard);
    Ok(())
}

/// `[fsw.bdot]` or `[fsw.momentum]` (at most one enabled), checked against the scene.
fn magnetic_block(
    text: &SceneText,
    f: &FswFile,
    effects: &EffectSet,
) -> Result<Option<DipoleSpec>, FileError> {
    let on = |e: Option<bool>| e != Some(false);
    // (block, its span, magnetometer, gain, period, enabled)
    let mut blocks = Vec::new();
    if let Some(b) = &f.bdot {
        let r = b.get_ref();
        blocks.push((
            "bdot",
            b.span(),
            &r.magnetometer,
            &r.gain,
            &r.period,
            r.enabled,
        ));
    }
    if let Some(m) = &f.momentum {
        let r = m.get_ref();
        blocks.push((
            "momentum",
            m.span(),
            &r.magnetometer,
            &r.gain,
            &r.period,
            r.enabled,
        ));
    }
    let mut spec = None;
    for (block, span, mag, gain, period, enabled) in blocks {
        let name = format!("fsw.{block}");
        let sensors = effects.get::<Sensors>();
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
                let ratio = v / mag_period;
                if !(ratio.round() >= 1.0 && (ratio - ratio.round()).abs() <= 1e-9 * ratio) {
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
                (ratio.round() * mag_period, ratio.round() as u64)
            }
            None => (mag_period, 1),
        };
        if !on(enabled) {
            continue;
        }
        let title = format!("[fsw.{block}]");
        if !effects
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
        if effects.contains("bdot") {
            return Err(text.error(
                Some(span),
                format!(
                    "{title} and [effects.bdot] would both command the torquers: set `enabled = false` in one of them"
                ),
            ));
        }
        if spec.is_some() {
            return Err(text.error(
                Some(span),
                "[fsw.momentum] and [fsw.bdot] would both command the torquers: set `enabled = false` in one of them (switching between them, [[fsw.mode]], is not yet supported)",
            ));
        }
        let (law, wheels) = if block == "bdot" {
            (DipoleLaw::Bdot { gain: k }, Vec::new())
        } else {
            let wheels: Vec<String> = match effects.get::<ReactionWheels>() {
                Some(w) if !w.wheels.is_empty() => w
                    .wheels
                    .iter()
                    .map(|w| format!("wheel_{}", w.name))
                    .collect(),
                _ => {
                    return Err(text.error(
                        Some(span),
                        "[fsw.momentum] dumps the reaction wheels' momentum: it needs [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]]",
                    ));
                }
            };
            (DipoleLaw::Momentum { gain: k }, wheels)
        };
        spec = Some(DipoleSpec {
            law,
            magnetometer: i,
            period,
            every,
            wheels,
        });
    }
    Ok(spec)
}
