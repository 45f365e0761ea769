//! The scene's `[sensors]` table (contract sections 13 and 17): the seed and the arrays
//! `[[sensors.gyro]]`, `[[sensors.star_tracker]]`, `[[sensors.sun_sensor]]`,
//! `[[sensors.magnetometer]]`, `[[sensors.coarse_sun]]` and `[[sensors.gps]]`, read into one
//! [`Sensors`] effect ([`satsim_spacecraft::sensors`]). Every error names the scene file and
//! the line.

use satsim_environment::Epoch;
use satsim_environment::shadow::ShadowModel;
use satsim_spacecraft::effects::{EffectSet, Magnetic, SceneText, SolarRadiation};
use satsim_spacecraft::sensors::star_tracker::Exclusion;
use satsim_spacecraft::sensors::{
    CoarseSun, Gps, Gyro, Kind, Magnetometer, Misalignment, Sensor, Sensors, StarTracker, SunSensor,
};
use satsim_tree::Model;
use satsim_tree::error::Num;
use satsim_tree::io::{FileError, exact, line_of};
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
    /// Coarse Sun sensors (photodiodes).
    #[serde(default)]
    pub coarse_sun: Vec<Spanned<CoarseSunFile>>,
    /// GPS receivers.
    #[serde(default)]
    pub gps: Vec<Spanned<GpsFile>>,
}

/// A gyro's `scale_factor`: one relative error for the three axes, or one per axis.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(
    untagged,
    expecting = "a number or an array of three numbers (relative scale factor errors)"
)]
pub enum ScaleFactorFile {
    /// The same error on the three axes.
    All(f64),
    /// One per axis (x, y, z).
    PerAxis([f64; 3]),
}

/// A star tracker's `exclusion_deg`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExclusionFile {
    /// The least angle between the boresight and the Sun (degrees).
    #[serde(default)]
    pub sun: Option<Spanned<f64>>,
    /// The least angle between the boresight and the Earth's limb (degrees).
    #[serde(default)]
    pub earth: Option<Spanned<f64>>,
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
    /// Initial bias, sensor axes (rad/s, default 0).
    #[serde(default, deserialize_with = "exact")]
    pub bias: Option<Spanned<[f64; 3]>>,
    /// Scale factor error (relative; a number or one per axis, default none).
    #[serde(default)]
    pub scale_factor: Option<Spanned<ScaleFactorFile>>,
    /// Misalignment, a rotation vector (rad, default none).
    #[serde(default, deserialize_with = "exact")]
    pub misalignment: Option<Spanned<[f64; 3]>>,
    /// Quantisation step (rad/s, default none).
    #[serde(default)]
    pub quantization: Option<Spanned<f64>>,
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
    /// Standard deviation about the sensor's x, y, z axes (arc seconds, default 0).
    #[serde(default, deserialize_with = "exact")]
    pub noise_arcsec: Option<Spanned<[f64; 3]>>,
    /// Misalignment, a rotation vector (rad, default none).
    #[serde(default, deserialize_with = "exact")]
    pub misalignment: Option<Spanned<[f64; 3]>>,
    /// Quantisation step of the quaternion's components (default none).
    #[serde(default)]
    pub quantization: Option<Spanned<f64>>,
    /// Exclusion angles (degrees, default none: always valid, no `_valid` column).
    #[serde(default)]
    pub exclusion_deg: Option<Spanned<ExclusionFile>>,
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
    /// Standard deviation of the direction's error about each sensor axis (rad, default 0).
    #[serde(default)]
    pub noise: Option<Spanned<f64>>,
    /// Misalignment, a rotation vector (rad, default none).
    #[serde(default, deserialize_with = "exact")]
    pub misalignment: Option<Spanned<[f64; 3]>>,
    /// Quantisation step of the unit vector's components (default none).
    #[serde(default)]
    pub quantization: Option<Spanned<f64>>,
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
    /// Misalignment, a rotation vector (rad, default none).
    #[serde(default, deserialize_with = "exact")]
    pub misalignment: Option<Spanned<[f64; 3]>>,
    /// Quantisation step (T, default none).
    #[serde(default)]
    pub quantization: Option<Spanned<f64>>,
}

/// `[[sensors.coarse_sun]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoarseSunFile {
    /// Unique name (the column).
    pub name: Spanned<String>,
    /// The body it is fixed to.
    pub body: Spanned<String>,
    /// Sample period (s, > 0).
    pub period: Spanned<f64>,
    /// The photodiode's normal, body axes (non-zero; normalised).
    #[serde(deserialize_with = "exact")]
    pub normal: Spanned<[f64; 3]>,
    /// The field of view's half-angle (degrees, in (0, 90], default 90).
    #[serde(default)]
    pub fov_deg: Option<Spanned<f64>>,
    /// The reading at normal incidence in full sunlight (default 1).
    #[serde(default)]
    pub scale: Option<Spanned<f64>>,
    /// Per-sample standard deviation of the additive noise (default 0).
    #[serde(default)]
    pub noise: Option<Spanned<f64>>,
    /// Whether the Earth's albedo is seen (default false).
    #[serde(default)]
    pub albedo: Option<bool>,
    /// Misalignment, a rotation vector (rad, default none).
    #[serde(default, deserialize_with = "exact")]
    pub misalignment: Option<Spanned<[f64; 3]>>,
    /// Quantisation step (default none).
    #[serde(default)]
    pub quantization: Option<Spanned<f64>>,
}

/// `[[sensors.gps]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GpsFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// The body it is fixed to.
    pub body: Spanned<String>,
    /// Sample period (s, > 0).
    pub period: Spanned<f64>,
    /// Per-sample standard deviation of the position on each axis (m, default 0).
    #[serde(default)]
    pub noise_position: Option<Spanned<f64>>,
    /// Per-sample standard deviation of the velocity on each axis (m/s, default 0).
    #[serde(default)]
    pub noise_velocity: Option<Spanned<f64>>,
}

/// What every sensor has, with where it is written.
struct Common<'a> {
    table: &'static str,
    span: Range<usize>,
    name: &'a Spanned<String>,
    body: &'a Spanned<String>,
    period: &'a Spanned<f64>,
    /// The misalignment and quantisation step (checked).
    mount: Option<Misalignment>,
    quantization: Option<f64>,
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
        let mut gyro = Gyro::new(
            non_negative(&r.noise_density, "sensors.gyro.noise_density")?,
            non_negative(&r.bias_walk, "sensors.gyro.bias_walk")?,
            bias,
        );
        if let Some(k) = &r.scale_factor {
            let v = match *k.get_ref() {
                ScaleFactorFile::All(v) => [v; 3],
                ScaleFactorFile::PerAxis(v) => v,
            };
            if !v.iter().all(|x| x.is_finite() && *x > -1.0) {
                return Err(text.error(
                    Some(k.span()),
                    format!(
                        "`sensors.gyro.scale_factor` must be finite numbers > -1 (relative errors: the rate read is (1 + s) times the rate), got [{}]",
                        v.map(|x| Num(x).to_string()).join(", ")
                    ),
                ));
            }
            gyro = gyro.with_scale_factor(Vec3::from(v));
        }
        let c = common("gyro", g, &r.name, &r.body, &r.period);
        let c = c.mounted(text, &r.misalignment, &r.quantization)?;
        all.push((c, Kind::Gyro(gyro)));
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
        let c = common("star_tracker", s, &r.name, &r.body, &r.period);
        let c = c.mounted(text, &r.misalignment, &r.quantization)?;
        let mut tracker = StarTracker::from_arcsec(noise);
        if let Some(ex) = &r.exclusion_deg {
            tracker = tracker.with_exclusion(exclusion(text, ex, &c, epoch, effects)?);
        }
        all.push((c, Kind::StarTracker(tracker)));
    }
    for s in &f.sun_sensor {
        let r = s.get_ref();
        let c = common("sun_sensor", s, &r.name, &r.body, &r.period);
        let epoch = needs_epoch(text, &c, epoch)?;
        needs_orbit(text, &c, effects)?;
        let noise = non_negative(&r.noise, "sensors.sun_sensor.noise")?;
        let c = c.mounted(text, &r.misalignment, &r.quantization)?;
        all.push((
            c,
            Kind::SunSensor(SunSensor {
                epoch,
                shadow: shadow(effects),
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
        let c = c.mounted(text, &r.misalignment, &r.quantization)?;
        all.push((
            c,
            Kind::Magnetometer(Magnetometer {
                field: field.field().clone(),
                noise,
            }),
        ));
    }
    for s in &f.coarse_sun {
        let r = s.get_ref();
        let c = common("coarse_sun", s, &r.name, &r.body, &r.period);
        let epoch = needs_epoch(text, &c, epoch)?;
        needs_orbit(text, &c, effects)?;
        let n = Vec3::from(*r.normal.get_ref());
        if !(n.iter().all(|v| v.is_finite()) && n.norm() > 0.0) {
            return Err(text.error(
                Some(r.normal.span()),
                "`sensors.coarse_sun.normal` must be three finite numbers, not all zero (the photodiode's normal in body axes)",
            ));
        }
        let fov = match &r.fov_deg {
            None => 90.0,
            Some(x) => {
                let v = text.positive(x, "sensors.coarse_sun.fov_deg")?;
                if v > 90.0 {
                    return Err(text.error(
                        Some(x.span()),
                        format!(
                            "`sensors.coarse_sun.fov_deg` is the field of view's half-angle, in (0, 90] degrees, got {}",
                            Num(v)
                        ),
                    ));
                }
                v
            }
        };
        let scale = match &r.scale {
            None => 1.0,
            Some(x) => text.positive(x, "sensors.coarse_sun.scale")?,
        };
        let noise = non_negative(&r.noise, "sensors.coarse_sun.noise")?;
        let c = c.mounted(text, &r.misalignment, &r.quantization)?;
        all.push((
            c,
            Kind::CoarseSun(CoarseSun {
                epoch,
                shadow: shadow(effects),
                normal: n.normalize(),
                fov: fov.to_radians(),
                scale,
                noise,
                albedo: r.albedo.unwrap_or(false),
            }),
        ));
    }
    for g in &f.gps {
        let r = g.get_ref();
        let c = common("gps", g, &r.name, &r.body, &r.period);
        needs_orbit(text, &c, effects)?;
        all.push((
            c,
            Kind::Gps(Gps {
                noise_position: non_negative(&r.noise_position, "sensors.gps.noise_position")?,
                noise_velocity: non_negative(&r.noise_velocity, "sensors.gps.noise_velocity")?,
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
        let mut sensor = Sensor::new(name.clone(), body, period, kind)
            .expect("the period was checked finite and > 0");
        if let Some(m) = c.mount {
            sensor = sensor.with_misalignment(m);
        }
        if let Some(q) = c.quantization {
            sensor = sensor
                .with_quantization(q)
                .expect("the step was checked finite and > 0");
        }
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
        mount: None,
        quantization: None,
    }
}

impl Common<'_> {
    /// With the sensor's `misalignment` (finite, at most half a turn) and `quantization` (> 0).
    fn mounted(
        mut self,
        text: &SceneText,
        misalignment: &Option<Spanned<[f64; 3]>>,
        quantization: &Option<Spanned<f64>>,
    ) -> Result<Self, FileError> {
        let table = self.table;
        if let Some(m) = misalignment {
            let v = Vec3::from(*m.get_ref());
            if !(v.iter().all(|x| x.is_finite()) && v.norm() <= std::f64::consts::PI) {
                return Err(text.error(
                    Some(m.span()),
                    format!(
                        "`sensors.{table}.misalignment` must be a rotation vector [rx, ry, rz] of finite numbers (rad), at most half a turn (|r| <= pi), got [{}]",
                        m.get_ref().map(|x| Num(x).to_string()).join(", ")
                    ),
                ));
            }
            self.mount = Some(Misalignment::new(v));
        }
        if let Some(q) = quantization {
            self.quantization = Some(text.positive(q, &format!("sensors.{table}.quantization"))?);
        }
        Ok(self)
    }
}

fn needs_epoch(text: &SceneText, c: &Common, epoch: Option<Epoch>) -> Result<Epoch, FileError> {
    epoch.ok_or_else(|| {
        text.error(
            Some(c.span.clone()),
            format!(
                "[[sensors.{}]] needs the scene's `epoch` (t = 0 as a date): add e.g. `epoch = \"2026-03-20T12:00:00 UTC\"` at the top of the scene",
                c.table
            ),
        )
    })
}

/// The Sun sensors' shadow model: the solar pressure's when it is enabled, else conical.
fn shadow(effects: &EffectSet) -> ShadowModel {
    effects
        .get::<SolarRadiation>()
        .map_or(ShadowModel::Conical, |s| s.shadow_model())
}

/// A star tracker's `exclusion_deg`: `sun` and `earth` in [0, 180] degrees, at least one;
/// the Sun's needs the epoch, either the orbit.
fn exclusion(
    text: &SceneText,
    ex: &Spanned<ExclusionFile>,
    c: &Common,
    epoch: Option<Epoch>,
    effects: &EffectSet,
) -> Result<Exclusion, FileError> {
    let e = ex.get_ref();
    let angle = |x: &Spanned<f64>, key: &str| -> Result<f64, FileError> {
        let v = text.non_negative(x, &format!("sensors.star_tracker.exclusion_deg.{key}"))?;
        if v > 180.0 {
            return Err(text.error(
                Some(x.span()),
                format!(
                    "`sensors.star_tracker.exclusion_deg.{key}` must be an angle in [0, 180] degrees, got {}",
                    Num(v)
                ),
            ));
        }
        Ok(v.to_radians())
    };
    if e.sun.is_none() && e.earth.is_none() {
        return Err(text.error(
            Some(ex.span()),
            "`sensors.star_tracker.exclusion_deg` needs `sun` or `earth` (degrees), e.g. `{ sun = 30.0, earth = 20.0 }`",
        ));
    }
    let sun = match &e.sun {
        None => None,
        Some(x) => {
            let a = angle(x, "sun")?;
            let epoch = epoch.ok_or_else(|| {
                text.error(
                    Some(x.span()),
                    "`sensors.star_tracker.exclusion_deg.sun` needs the scene's `epoch` (t = 0 as a date): add e.g. `epoch = \"2026-03-20T12:00:00 UTC\"` at the top of the scene",
                )
            })?;
            Some((a, epoch))
        }
    };
    let earth = e.earth.as_ref().map(|x| angle(x, "earth")).transpose()?;
    if !effects.contains("orbit") {
        return Err(text.error(
            Some(ex.span()),
            format!(
                "`sensors.star_tracker.exclusion_deg` needs an [orbit] table (the Sun and the Earth seen from the orbit), for star tracker `{}`",
                c.name.get_ref()
            ),
        ));
    }
    Ok(Exclusion { sun, earth })
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
        )
        .chain(
            f.coarse_sun
                .iter()
                .map(|s| (&s.get_ref().name, &s.get_ref().period)),
        )
        .chain(
            f.gps
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
        .chain(f.magnetometer.iter().map(|s| &s.get_ref().name))
        .chain(f.coarse_sun.iter().map(|s| &s.get_ref().name))
        .chain(f.gps.iter().map(|s| &s.get_ref().name));
    for name in names {
        let prefix = format!("{}_", name.get_ref());
        if let Some(c) = columns
            .iter()
            .filter(|c| c.starts_with(&prefix) || *c == name.get_ref())
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
