//! The scene's `[sensors]` table (contract section 13): the seed and the arrays
//! `[[sensors.gyro]]`, `[[sensors.star_tracker]]`, `[[sensors.sun_sensor]]` and
//! `[[sensors.magnetometer]]`, read into one [`Sensors`] effect
//! ([`satsim_spacecraft::sensors`]). Every error names the scene file and the line.

use satsim_environment::Epoch;
use satsim_environment::shadow::ShadowModel;
use satsim_spacecraft::effects::{EffectSet, Magnetic, SceneText, SolarRadiation};
use satsim_spacecraft::sensors::{
    Gyro, Kind, Magnetometer, Sensor, Sensors, StarTracker, SunSensor,
};
use satsim_tree::Model;
use satsim_tree::error::Num;
use satsim_tree::io::{FileError, line_of};
use satsim_tree::spatial::Vec3;
use serde::Deserialize;
use std::ops::Range;
use toml::Spanned;

/// `[sensors]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorsFile {
    /// The noise seed (an integer >= 0, default 0); a campaign's run writes its own.
    #[serde(default)]
    pub seed: Option<Spanned<i64>>,
    /// Rate gyros.
    #[serde(default)]
    pub gyro: Vec<Spanned<GyroFile>>,
    /// Star trackers.
    #[serde(default)]
    pub star_tracker: Vec<Spanned<StarTrackerFile>>,
    /// Sun sensors.
    #[serde(default)]
    pub sun_sensor: Vec<Spanned<SunSensorFile>>,
    /// Magnetometers.
    #[serde(default)]
    pub magnetometer: Vec<Spanned<MagnetometerFile>>,
}

/// `[[sensors.gyro]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GyroFile {
    /// Unique name (the columns' prefix).
    pub name: Spanned<String>,
    /// The body it is fixed to.
    pub body: Spanned<String>,
    /// Sample period (s, > 0).
    pub period: Spanned<f64>,
    /// White noise density (rad/s/√Hz, default 0).
    #[serde(default)]
    pub noise_density: Option<Spanned<f64>>,
    /// Bias random walk (rad/s²/√Hz, default 0).
    #[serde(default)]
    pub bias_walk: Option<Spanned<f64>>,
    /// Initial bias, body axes (rad/s, default 0).
    #[serde(default)]
    pub bias: Option<Spanned<[f64; 3]>>,
}

/// `[[sensors.star_tracker]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StarTrackerFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// The body it is fixed to.
    pub body: Spanned<String>,
    /// Sample period (s, > 0).
    pub period: Spanned<f64>,
    /// Standard deviation about the body's x, y, z axes (arc seconds, default 0).
    #[serde(default)]
    pub noise_arcsec: Option<Spanned<[f64; 3]>>,
}

/// `[[sensors.sun_sensor]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunSensorFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// The body it is fixed to.
    pub body: Spanned<String>,
    /// Sample period (s, > 0).
    pub period: Spanned<f64>,
    /// Standard deviation of the direction's error about each body axis (rad, default 0).
    #[serde(default)]
    pub noise: Option<Spanned<f64>>,
}

/// `[[sensors.magnetometer]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MagnetometerFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// The body it is fixed to.
    pub body: Spanned<String>,
    /// Sample period (s, > 0).
    pub period: Spanned<f64>,
    /// Per-sample standard deviation on each axis (T, default 0).
    #[serde(default)]
    pub noise: Option<Spanned<f64>>,
}

/// What every sensor has, with where it is written.
struct Common<'a> {
    table: &'static str,
    span: Range<usize>,
    name: &'a Spanned<String>,
    body: &'a Spanned<String>,
    period: &'a Spanned<f64>,
}

/// Reads `[sensors]` against the scene's model, epoch and enabled effects (the orbit, the
/// magnetic field, the solar pressure's shadow model). `None` when it lists no sensor.
pub(crate) fn read(
    text: &SceneText,
    file: &Spanned<SensorsFile>,
    model: &Model,
    epoch: Option<Epoch>,
    effects: &EffectSet,
) -> Result<Option<Sensors>, FileError> {
    let f = file.get_ref();
    let seed = match &f.seed {
        None => 0,
        Some(s) => u64::try_from(*s.get_ref()).map_err(|_| {
            text.error(
                Some(s.span()),
                format!(
                    "`sensors.seed` must be an integer >= 0, got {}",
                    s.get_ref()
                ),
            )
        })?,
    };
    let non_negative = |x: &Option<Spanned<f64>>, what: &str| -> Result<f64, FileError> {
        x.as_ref().map_or(Ok(0.0), |x| text.non_negative(x, what))
    };
    // Every sensor with its kind, kind by kind (gyros, star trackers, Sun sensors,
    // magnetometers), each kind in file order: its index is its noise stream and places its
    // columns. Not the order of the tables in the text, which a rewritten scene (a campaign's
    // drawn run, `--set`) does not keep: the same sensors give the same columns and streams
    // however the file interleaves their kinds.
    let mut all: Vec<(Common, Kind)> = Vec::new();
    for g in &f.gyro {
        let r = g.get_ref();
        let bias = match &r.bias {
            None => Vec3::zeros(),
            Some(b) if b.get_ref().iter().all(|v| v.is_finite()) => Vec3::from(*b.get_ref()),
            Some(b) => {
                return Err(text.error(
                    Some(b.span()),
                    "`sensors.gyro.bias` must be finite numbers (rad/s)",
                ));
            }
        };
        let gyro = Gyro::new(
            non_negative(&r.noise_density, "sensors.gyro.noise_density")?,
            non_negative(&r.bias_walk, "sensors.gyro.bias_walk")?,
            bias,
        );
        all.push((
            common("gyro", g, &r.name, &r.body, &r.period),
            Kind::Gyro(gyro),
        ));
    }
    for s in &f.star_tracker {
        let r = s.get_ref();
        let noise = match &r.noise_arcsec {
            None => [0.0; 3],
            Some(n)
                if n.get_ref()
                    .iter()
                    .all(|v| (0.0..=StarTracker::MAX_NOISE_ARCSEC).contains(v)) =>
            {
                *n.get_ref()
            }
            Some(n) => {
                return Err(text.error(
                    Some(n.span()),
                    format!(
                        "`sensors.star_tracker.noise_arcsec` must be finite numbers >= 0 (arc seconds), at most {} (half a turn), got [{}]",
                        StarTracker::MAX_NOISE_ARCSEC,
                        n.get_ref().map(|v| Num(v).to_string()).join(", ")
                    ),
                ));
            }
        };
        all.push((
            common("star_tracker", s, &r.name, &r.body, &r.period),
            Kind::StarTracker(StarTracker::from_arcsec(noise)),
        ));
    }
    for s in &f.sun_sensor {
        let r = s.get_ref();
        let c = common("sun_sensor", s, &r.name, &r.body, &r.period);
        let epoch = epoch.ok_or_else(|| {
            text.error(
                Some(c.span.clone()),
                "[[sensors.sun_sensor]] needs the scene's `epoch` (t = 0 as a date): add e.g. `epoch = \"2026-03-20T12:00:00 UTC\"` at the top of the scene",
            )
        })?;
        needs_orbit(text, &c, effects)?;
        let shadow = effects
            .get::<SolarRadiation>()
            .map_or(ShadowModel::Conical, |s| s.shadow_model());
        let noise = non_negative(&r.noise, "sensors.sun_sensor.noise")?;
        all.push((
            c,
            Kind::SunSensor(SunSensor {
                epoch,
                shadow,
                noise,
            }),
        ));
    }
    for m in &f.magnetometer {
        let r = m.get_ref();
        let c = common("magnetometer", m, &r.name, &r.body, &r.period);
        let field = effects.get::<Magnetic>().ok_or_else(|| {
            text.error(
                Some(c.span.clone()),
                "[[sensors.magnetometer]] needs the geomagnetic field: enable [effects.magnetic] (its field model and the scene's epoch are the magnetometer's)",
            )
        })?;
        needs_orbit(text, &c, effects)?;
        let noise = non_negative(&r.noise, "sensors.magnetometer.noise")?;
        all.push((
            c,
            Kind::Magnetometer(Magnetometer {
                field: field.field().clone(),
                noise,
            }),
        ));
    }
    let mut set = Sensors::new(seed);
    for (c, kind) in all {
        let name = text.column_name(c.name, &format!("sensors.{}.name", c.table))?;
        if set.sensors().iter().any(|s| s.name() == name) {
            return Err(text.error(
                Some(c.name.span()),
                format!("sensor `{name}` is listed twice: sensor names must be unique"),
            ));
        }
        let body = model.body_index(c.body.get_ref()).ok_or_else(|| {
            text.error(
                Some(c.body.span()),
                format!(
                    "`sensors.{}.body`: unknown body `{}` (the model's bodies: {})",
                    c.table,
                    c.body.get_ref(),
                    model
                        .bodies()
                        .iter()
                        .map(|b| b.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })?;
        let period = text.positive(c.period, &format!("sensors.{}.period", c.table))?;
        let sensor = Sensor::new(name.clone(), body, period, kind)
            .expect("the period was checked finite and > 0");
        set.push(sensor);
    }
    Ok((!set.sensors().is_empty()).then_some(set))
}

fn common<'a, T>(
    table: &'static str,
    at: &Spanned<T>,
    name: &'a Spanned<String>,
    body: &'a Spanned<String>,
    period: &'a Spanned<f64>,
) -> Common<'a> {
    Common {
        table,
        span: at.span(),
        name,
        body,
        period,
    }
}

fn needs_orbit(text: &SceneText, c: &Common, effects: &EffectSet) -> Result<(), FileError> {
    if effects.contains("orbit") {
        return Ok(());
    }
    Err(text.error(
        Some(c.span.clone()),
        format!(
            "[[sensors.{}]] needs an [orbit] table (e.g. `[orbit]` with `altitude = 500e3`)",
            c.table
        ),
    ))
}

/// Each sensor's clock (its name and the line of its `period`), for
/// [`Scene::check_rows`](super::Scene::check_rows) to bound its samples.
pub(crate) fn clocks(text: &SceneText, file: &Spanned<SensorsFile>) -> Vec<super::Clock> {
    let f = file.get_ref();
    let named = f
        .gyro
        .iter()
        .map(|s| (&s.get_ref().name, &s.get_ref().period))
        .chain(
            f.star_tracker
                .iter()
                .map(|s| (&s.get_ref().name, &s.get_ref().period)),
        )
        .chain(
            f.sun_sensor
                .iter()
                .map(|s| (&s.get_ref().name, &s.get_ref().period)),
        )
        .chain(
            f.magnetometer
                .iter()
                .map(|s| (&s.get_ref().name, &s.get_ref().period)),
        );
    named
        .map(|(name, period)| super::Clock {
            what: format!("sensor `{}`", name.get_ref()),
            line: Some(line_of(text.text(), period.span().start)),
            period: *period.get_ref(),
        })
        .collect()
}

/// A sensor column that another column of the run already has (`omega_x` from a sensor
/// called `omega`): an error at the sensor's name.
pub(crate) fn check_columns(
    text: &SceneText,
    file: &Spanned<SensorsFile>,
    columns: &[String],
) -> Result<(), FileError> {
    let f = file.get_ref();
    let names = f
        .gyro
        .iter()
        .map(|s| &s.get_ref().name)
        .chain(f.star_tracker.iter().map(|s| &s.get_ref().name))
        .chain(f.sun_sensor.iter().map(|s| &s.get_ref().name))
        .chain(f.magnetometer.iter().map(|s| &s.get_ref().name));
    for name in names {
        let prefix = format!("{}_", name.get_ref());
        if let Some(c) = columns
            .iter()
            .filter(|c| c.starts_with(&prefix))
            .find(|c| columns.iter().filter(|o| o == c).count() > 1)
        {
            return Err(text.error(
                Some(name.span()),
                format!(
                    "sensor `{}` makes the column `{c}`, which the run already has: rename the sensor",
                    name.get_ref()
                ),
            ));
        }
    }
    Ok(())
}
